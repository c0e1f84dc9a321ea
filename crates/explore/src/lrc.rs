//! The Laser Range Classifier as a run builds it (A§3.3, App. B), in one
//! place for whoever needs the run's own: its validity domain from
//! `[explore.pose]` ([`lrc_config`]), its training ([`training_config`],
//! [`train_lrc`]), the patch of a sweep that forms an observation of a
//! surface point ([`PatchIndex`]) and the belief at which a material counts
//! as identified ([`IDENTIFIED_P`], SPEC §6). The material oracle
//! (`sim::material_oracle`) judges Stage Two with exactly this classifier.

use crate::ExploreError;
use geom::{Point3, Real, UnitVector3};
use sensor::SweepPoint;
use sensor::classifier::{LrcConfig, ObservedReturn, TrainingConfig};
use std::path::Path;

/// A surface's material is *identified* when its most probable material has
/// at least this probability (SPEC §6, issue 44).
pub const IDENTIFIED_P: Real = 0.8;

/// Simulated observations per material the LRC is trained on.
pub const LRC_TRAINING_OBSERVATIONS: usize = 60;

/// The LRC's validity domain: Stage Two's constraints (A Table 6.1: `φ_max`,
/// `d_min`, `d_max`), read from one place, `[explore.pose]`; every other
/// field the LRC's default.
pub fn lrc_config(pose: &plan::PoseConfig) -> LrcConfig {
    LrcConfig {
        min_range_m: pose.d_min_m,
        max_range_m: pose.d_max_m,
        max_incidence_deg: pose.phi_max_deg,
        ..LrcConfig::default()
    }
}

/// How the run's LRC is trained: [`LRC_TRAINING_OBSERVATIONS`] per
/// material, the rest the training's default.
pub fn training_config() -> TrainingConfig {
    TrainingConfig {
        observations_per_material: LRC_TRAINING_OBSERVATIONS,
        ..TrainingConfig::default()
    }
}

/// Radius of the patch of returns that forms an observation, metres: the
/// training's target patch ([`TrainingConfig::patch_radius_m`]).
pub fn patch_radius_m() -> Real {
    training_config().patch_radius_m
}

/// The run's LRC: [`lrc_config`] of `pose`, trained ([`training_config`]) on
/// `materials` with the scanner model `scanner` and `seed`, or loaded from
/// `cache` when that file holds the model of the same inputs
/// ([`sensor::Lrc::load_or_train`]). The text says how it was obtained:
/// trained (and why the cache was not used) or loaded.
pub fn train_lrc(
    materials: &[scene::Material],
    scanner: &sensor::ScannerConfig,
    pose: &plan::PoseConfig,
    seed: u64,
    cache: Option<&Path>,
) -> Result<(sensor::Lrc, String), ExploreError> {
    let config = lrc_config(pose);
    let training = training_config();
    let classifier = |e: sensor::LrcError| ExploreError::Classifier(e.to_string());
    Ok(match cache {
        Some(path) => {
            let (lrc, outcome) =
                sensor::Lrc::load_or_train(path, config, &training, materials, scanner, seed)
                    .map_err(classifier)?;
            let obtained = match outcome {
                sensor::classifier::LrcCacheOutcome::Loaded => "loaded from cache".to_owned(),
                sensor::classifier::LrcCacheOutcome::Trained(why) => format!("trained ({why})"),
            };
            (lrc, obtained)
        }
        None => (
            sensor::Lrc::train(config, &training, materials, scanner, seed).map_err(classifier)?,
            "trained (no cache file)".to_owned(),
        ),
    })
}

/// The points of a sweep indexed for patch look-ups: the returns within a
/// radius of a target, as an LRC observation.
pub struct PatchIndex<'a> {
    points: &'a [SweepPoint],
    /// Per point, its return (`None` for a point at its ray's origin): made
    /// once here, not once per patch that holds the point (a point of a
    /// predicted sweep is in about ten of the patches Stage Two looks at).
    returns: Vec<Option<ObservedReturn>>,
    tree: kiddo::ImmutableKdTree<Real, 3>,
}

impl std::fmt::Debug for PatchIndex<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PatchIndex")
            .field("points", &self.points.len())
            .finish_non_exhaustive()
    }
}

impl<'a> PatchIndex<'a> {
    /// The index of `points`.
    pub fn new(points: &'a [SweepPoint]) -> Self {
        let coords: Vec<[Real; 3]> = points
            .iter()
            .map(|p| [p.point.x, p.point.y, p.point.z])
            .collect();
        let returns = points
            .iter()
            .map(|p| {
                let (direction, range_m) = UnitVector3::try_new_and_get(p.point - p.origin, 1e-12)?;
                Some(ObservedReturn {
                    origin: p.origin,
                    direction,
                    range_m,
                    intensity: p.intensity,
                })
            })
            .collect();
        Self {
            points,
            returns,
            tree: kiddo::ImmutableKdTree::new_from_slice(&coords),
        }
    }

    /// The points indexed.
    pub fn points(&self) -> &'a [SweepPoint] {
        self.points
    }

    /// The distance from `target` to the nearest point, metres (infinite
    /// without points): a patch of a smaller radius around it is empty.
    pub fn nearest_m(&self, target: &Point3) -> Real {
        if self.points.is_empty() {
            return Real::INFINITY;
        }
        self.tree
            .nearest_one::<kiddo::SquaredEuclidean>(&[target.x, target.y, target.z])
            .distance
            .sqrt()
    }

    /// The returns within `radius_m` of `target`, in point order, as an
    /// observation of `target` (what `sensor::Observation::from_sweep`
    /// gives); with `seen_side`, only those whose ray origin lies on that
    /// side of `target` (`(origin − target) · seen_side > 0`): a patch on
    /// one face of a thin wall also holds the returns of its other face, a
    /// few millimetres away.
    pub fn observation(
        &self,
        target: &Point3,
        radius_m: Real,
        seen_side: Option<&UnitVector3>,
    ) -> sensor::Observation {
        let mut obs = sensor::Observation::default();
        self.observe_into(target, radius_m, seen_side, true, &mut obs);
        obs
    }

    /// [`PatchIndex::observation`] into `obs`, reusing its storage; with
    /// `in_point_order` false, the returns in the index's own order (the
    /// same set, found faster; sums over them may differ in the last bits).
    pub fn observe_into(
        &self,
        target: &Point3,
        radius_m: Real,
        seen_side: Option<&UnitVector3>,
        in_point_order: bool,
        obs: &mut sensor::Observation,
    ) {
        let near = self.tree.within_unsorted::<kiddo::SquaredEuclidean>(
            &[target.x, target.y, target.z],
            radius_m * radius_m,
        );
        let on_side =
            |r: &ObservedReturn| seen_side.is_none_or(|n| (r.origin - target).dot(n) > 0.0);
        obs.returns.clear();
        if in_point_order {
            // Point indices sort faster as `u32` than the neighbours do (2³²
            // sweep points, at least 56 bytes each, would take 240 GB).
            let mut idx: Vec<u32> = near.iter().map(|n| n.item as u32).collect();
            idx.sort_unstable();
            obs.returns.extend(
                idx.iter()
                    .filter_map(|&k| self.returns[k as usize])
                    .filter(on_side),
            );
        } else {
            obs.returns.extend(
                near.iter()
                    .filter_map(|n| self.returns[n.item as usize])
                    .filter(on_side),
            );
        }
        obs.target = Some(*target);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom::Vector3;

    fn point(x: Real, y: Real, z: Real, origin_z: Real) -> SweepPoint {
        SweepPoint {
            point: Point3::new(x, y, z),
            origin: Point3::new(x, y, origin_z),
            intensity: 0.5,
            material: None,
            cell: None,
        }
    }

    /// The config and training are the run's: Table 6.1's constraints
    /// from `[explore.pose]`, 60 observations per material, the 0.18 m
    /// patch.
    #[test]
    fn the_config_follows_the_pose_constraints() {
        let pose = plan::PoseConfig {
            phi_max_deg: 30.0,
            d_min_m: 0.3,
            d_max_m: 0.7,
            ..plan::PoseConfig::default()
        };
        let c = lrc_config(&pose);
        assert_eq!(
            (c.min_range_m, c.max_range_m, c.max_incidence_deg),
            (0.3, 0.7, 30.0)
        );
        assert_eq!(c.fit_window_deg, LrcConfig::default().fit_window_deg);
        assert_eq!(training_config().observations_per_material, 60);
        assert_eq!(patch_radius_m(), 0.18);
    }

    /// A patch holds exactly the points within the radius (brute force),
    /// and with a seen side only those whose origin lies on it.
    #[test]
    fn patches_hold_the_points_within_the_radius_on_the_seen_side() {
        // A wall at z = 0 seen from above, and its back at z = −0.004 seen
        // from below.
        let mut points = Vec::new();
        for i in 0..20 {
            for j in 0..20 {
                let (x, y) = (0.02 * Real::from(i), 0.02 * Real::from(j));
                points.push(point(x, y, 0.0, 0.5));
                points.push(point(x, y, -0.004, -0.5));
            }
        }
        let index = PatchIndex::new(&points);
        let target = Point3::new(0.2, 0.2, 0.0);
        let all = index.observation(&target, 0.05, None);
        let brute: Vec<Point3> = points
            .iter()
            .filter(|p| (p.point - target).norm() <= 0.05)
            .map(|p| p.point)
            .collect();
        let got: Vec<Point3> = all.returns.iter().map(ObservedReturn::point).collect();
        assert_eq!(got.len(), brute.len());
        for (a, b) in got.iter().zip(&brute) {
            assert!((a - b).norm() < 1e-12);
        }
        assert!(index.nearest_m(&target) < 1e-12);
        assert!((index.nearest_m(&Point3::new(0.2, 0.2, 0.1)) - 0.1).abs() < 1e-12);
        assert_eq!(PatchIndex::new(&[]).nearest_m(&target), Real::INFINITY);
        let up = UnitVector3::new_normalize(Vector3::z());
        let seen = index.observation(&target, 0.05, Some(&up));
        assert_eq!(2 * seen.returns.len(), all.returns.len());
        assert!(seen.returns.iter().all(|r| r.origin.z > 0.0));
        assert_eq!(seen.target, Some(target));
    }
}
