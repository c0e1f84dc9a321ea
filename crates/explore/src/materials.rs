//! Material identification with the LRC (A§3.3, App. B): the classifier
//! trained on the run's materials, the belief per disc voxel (A§4.4), and the
//! patches of a sweep around a disc that form an observation.

use crate::ExploreError;
use crate::discs::DiscMap;
use geom::{Real, TriMesh};
use sensor::SweepPoint;

/// Material identification with the LRC (A§3.3, App. B): every disc is
/// targeted in every sweep whose scanner passed within the LRC's range of it;
/// the returns within the training patch radius of its centre form an
/// observation, and each one the LRC accepts (range, incidence, enough
/// points) updates the belief of the disc's voxels (eq. 4.15). The LRC is
/// trained on the scene's materials with the simulator's scanner model. Stage
/// One's sweeps identify some materials this way ("some surfaces also had
/// their material-types identified", A§3.3); Stage Two aims at the discs
/// with the most information left.
pub(crate) struct Materials {
    pub(crate) lrc: sensor::Lrc,
    pub(crate) belief: map::MaterialBelief,
    /// Per disc: whether the mapped surface within the LRC's patch radius of
    /// its centre is flat enough for the LRC (see [`flat_patches`]).
    pub(crate) flat: Vec<bool>,
    pub(crate) patch_m: Real,
    reach_m: Real,
    /// Per disc, its belief voxels (`MaterialBelief::disc_voxels`, in its
    /// order): the discs do not change during a run.
    voxels: Vec<Vec<map::VoxelKey>>,
    /// How the LRC was obtained: trained (and why the cache was not used)
    /// or loaded from its cache.
    pub(crate) obtained: String,
}

impl Materials {
    /// `None` without materials or without discs. The LRC is trained on
    /// `materials` with the scanner model `scanner`, or loaded from
    /// `cache` when that file holds the model of the same inputs
    /// ([`sensor::Lrc::load_or_train`]).
    pub(crate) fn new(
        d: &mut DiscMap,
        mesh: &TriMesh,
        pose: &plan::PoseConfig,
        materials: &[scene::Material],
        scanner: &sensor::ScannerConfig,
        seed: u64,
        cache: Option<&std::path::Path>,
    ) -> Result<Option<Self>, ExploreError> {
        use sensor::classifier::{LrcConfig, TrainingConfig};
        d.observations = vec![0; d.discs.len()];
        if materials.is_empty() || d.discs.is_empty() {
            return Ok(None);
        }
        // The LRC's validity domain is Stage Two's constraints (Table 6.1:
        // φ_max, d_min, d_max), read from one place, `[explore.pose]`.
        let config = LrcConfig {
            min_range_m: pose.d_min_m,
            max_range_m: pose.d_max_m,
            max_incidence_deg: pose.phi_max_deg,
            ..LrcConfig::default()
        };
        let training = TrainingConfig {
            observations_per_material: LRC_TRAINING_OBSERVATIONS,
            ..TrainingConfig::default()
        };
        let classifier = |e: sensor::LrcError| ExploreError::Classifier(e.to_string());
        let (lrc, obtained) = match cache {
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
                sensor::Lrc::train(config, &training, materials, scanner, seed)
                    .map_err(classifier)?,
                "trained (no cache file)".to_owned(),
            ),
        };
        let mut belief = map::MaterialBelief::new(map::MaterialConfig {
            n_materials: materials.len(),
            ..map::MaterialConfig::default()
        })?;
        // Each disc's voxels (in parallel), then the belief's voxels in
        // disc order, as `insert_disc` would insert them.
        let voxels: Vec<Vec<map::VoxelKey>> = {
            use rayon::prelude::*;
            d.discs
                .par_iter()
                .map(|disc| belief.disc_voxels(disc))
                .collect()
        };
        for key in voxels.iter().flatten() {
            belief.insert_surface(*key);
        }
        let patch_m = training.patch_radius_m;
        let flat = flat_patches(
            &d.discs,
            &mesh.vertices,
            patch_m,
            lrc.plane_rms_limit_m * config.max_plane_rms_ratio,
        );
        Ok(Some(Self {
            lrc,
            belief,
            flat,
            patch_m,
            reach_m: config.max_range_m + patch_m,
            voxels,
            obtained,
        }))
    }

    /// Classify every disc in reach of `sweep` and update the beliefs.
    pub(crate) fn observe(
        &mut self,
        d: &mut DiscMap,
        sweep: &sensor::Sweep,
    ) -> Result<(), ExploreError> {
        use rayon::prelude::*;
        let pts = sweep.points();
        if pts.is_empty() {
            return Ok(());
        }
        let coords: Vec<[Real; 3]> = pts
            .iter()
            .map(|p| [p.point.x, p.point.y, p.point.z])
            .collect();
        let tree: kiddo::ImmutableKdTree<Real, 3> = kiddo::ImmutableKdTree::new_from_slice(&coords);
        let origin = pts[pts.len() / 2].origin;
        let (lrc, patch, reach) = (&self.lrc, self.patch_m, self.reach_m);
        let facing = &d.facing;
        let results: Vec<(usize, Vec<Real>)> = d
            .discs
            .par_iter()
            .enumerate()
            .filter(|(_, disc)| (disc.centre - origin).norm() <= reach)
            .filter_map(|(i, disc)| {
                let mut obs = patch_observation(pts, &tree, &disc.centre, patch);
                // Only returns from the seen side of the disc's surface: a
                // patch around a disc on one face of a thin wall (the right
                // web seen from under the beam) also holds the returns of
                // the other face (its containment sheet seen from the
                // channel), a few millimetres away.
                if let Some(f) = facing.get(i) {
                    obs.returns
                        .retain(|r| (r.origin - disc.centre).dot(f) > 0.0);
                }
                lrc.classify(&obs).ok().map(|r| (i, r.posterior))
            })
            .collect();
        for (i, posterior) in results {
            for &key in &self.voxels[i] {
                self.belief.update(key, &posterior)?;
            }
            d.observations[i] += 1;
        }
        Ok(())
    }

    /// The material information remaining on disc `i` (eq. 4.16 over its
    /// voxels).
    pub(crate) fn h3(&self, i: usize) -> Real {
        // `MaterialBelief::h3_disc` over the remembered voxels, summed in
        // the same order.
        self.voxels[i]
            .iter()
            .filter_map(|k| self.belief.h3_voxel(*k))
            .sum()
    }

    /// The belief voxels of disc `i`.
    pub(crate) fn disc_voxels(&self, i: usize) -> &[map::VoxelKey] {
        &self.voxels[i]
    }

    /// `H3` over every disc voxel (eq. 4.17).
    pub(crate) fn h3_total(&self) -> Real {
        self.belief.h3_total()
    }

    /// Write the posteriors and `H3` into the disc map.
    pub(crate) fn finish(&self, d: &mut DiscMap) {
        use rayon::prelude::*;
        (d.posterior, d.h3) = d
            .discs
            .par_iter()
            .map(|disc| {
                (
                    self.belief.disc_probabilities(disc).unwrap_or_default(),
                    self.belief.h3_disc(disc),
                )
            })
            .unzip();
        d.h3_total = Some(self.h3_total());
    }
}

/// Per disc: whether the vertices of the mapped surface `vertices` within
/// `radius_m` of its centre lie within `limit_m` RMS of their plane of best
/// fit. The LRC refuses an observation of a patch that is not flat (an edge,
/// a corner, a second surface or a curve within its patch), so a disc whose
/// mapped surroundings are not flat is not worth a Stage Two viewpoint: it
/// cannot be identified within the LRC's constraints.
fn flat_patches(
    discs: &[map::Disc],
    vertices: &[geom::Point3],
    radius_m: Real,
    limit_m: Real,
) -> Vec<bool> {
    use rayon::prelude::*;
    if vertices.is_empty() {
        return vec![false; discs.len()];
    }
    let coords: Vec<[Real; 3]> = vertices.iter().map(|p| [p.x, p.y, p.z]).collect();
    let tree: kiddo::ImmutableKdTree<Real, 3> = kiddo::ImmutableKdTree::new_from_slice(&coords);
    discs
        .par_iter()
        .map(|disc| {
            let c = disc.centre;
            let near = tree
                .within_unsorted::<kiddo::SquaredEuclidean>(&[c.x, c.y, c.z], radius_m * radius_m);
            let offsets: Vec<geom::Vector3> =
                near.iter().map(|n| vertices[n.item as usize] - c).collect();
            offsets.len() >= 3
                && geom::Pca::of_offsets(&offsets)
                    .is_some_and(|p| p.eigenvalues[0].max(0.0).sqrt() <= limit_m)
        })
        .collect()
}

/// The returns of `points` within `radius_m` of `target`, as an LRC
/// observation ([`patch_observation`] with its own kd-tree).
pub(crate) fn sweep_patch(
    points: &[SweepPoint],
    target: &geom::Point3,
    radius_m: Real,
) -> sensor::Observation {
    let coords: Vec<[Real; 3]> = points
        .iter()
        .map(|p| [p.point.x, p.point.y, p.point.z])
        .collect();
    let tree: kiddo::ImmutableKdTree<Real, 3> = kiddo::ImmutableKdTree::new_from_slice(&coords);
    patch_observation(points, &tree, target, radius_m)
}

/// The returns of `points` (indexed by `tree`) within `radius_m` of
/// `target`, in point order: `sensor::Observation::from_sweep` through a
/// kd-tree.
fn patch_observation(
    points: &[SweepPoint],
    tree: &kiddo::ImmutableKdTree<Real, 3>,
    target: &geom::Point3,
    radius_m: Real,
) -> sensor::Observation {
    let near = tree.within_unsorted::<kiddo::SquaredEuclidean>(
        &[target.x, target.y, target.z],
        radius_m * radius_m,
    );
    let mut idx: Vec<usize> = near.iter().map(|n| n.item as usize).collect();
    idx.sort_unstable();
    let returns = idx
        .iter()
        .filter_map(|&k| {
            let p = &points[k];
            let (direction, range_m) =
                geom::UnitVector3::try_new_and_get(p.point - p.origin, 1e-12)?;
            Some(sensor::classifier::ObservedReturn {
                origin: p.origin,
                direction,
                range_m,
                intensity: p.intensity,
            })
        })
        .collect();
    sensor::Observation {
        returns,
        target: Some(*target),
    }
}

/// Simulated observations per material the LRC is trained on.
const LRC_TRAINING_OBSERVATIONS: usize = 60;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::probe::MapProbe;
    use hw::LineScanner;

    #[test]
    fn patch_observation_equals_from_sweep() {
        // A 10° sweep of bridge1 from the start pose; patches around some points.
        let world = std::sync::Arc::new(
            scene::builtin::scene("bridge1")
                .unwrap()
                .build(std::path::Path::new("."))
                .unwrap(),
        );
        let robot = robot::builtin("denso-vm6083").unwrap();
        let q: Vec<Real> = [0.0, -55.0, 165.0, 0.0, -110.0, 0.0]
            .iter()
            .map(|d: &Real| d.to_radians())
            .collect();
        let scanner = sensor::Scanner::new(sensor::ScannerConfig::default()).unwrap();
        let base = geom::Isometry3::identity();
        let mut probe = MapProbe::new(robot.clone(), world, base, &q, scanner).unwrap();
        probe.seed_noise(1);
        let sweep = hw::tilt_sweep(
            &mut probe,
            &robot,
            &base,
            &sensor::SweepConfig {
                tilt_deg: 10.0,
                ..sensor::SweepConfig::default()
            },
            &mut |_, _| {},
        )
        .unwrap();
        let pts = sweep.points();
        assert!(pts.len() > 1000, "{}", pts.len());
        let coords: Vec<[Real; 3]> = pts
            .iter()
            .map(|p| [p.point.x, p.point.y, p.point.z])
            .collect();
        let tree = kiddo::ImmutableKdTree::new_from_slice(&coords);
        for k in (0..pts.len()).step_by(pts.len() / 7) {
            let target = pts[k].point + geom::Vector3::new(0.01, -0.02, 0.0);
            let a = patch_observation(pts, &tree, &target, 0.18);
            let b = sensor::Observation::from_sweep(&sweep, &target, 0.18);
            assert!(!a.returns.is_empty());
            assert_eq!(a, b);
        }
    }
}
