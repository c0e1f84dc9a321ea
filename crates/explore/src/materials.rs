//! Material identification with the LRC (A§3.3, App. B): the classifier
//! trained on the run's materials, the belief per disc voxel (A§4.4), and the
//! patches of a sweep around a disc that form an observation.

use crate::ExploreError;
use crate::discs::DiscMap;
use crate::lrc::{IDENTIFIED_P, PatchIndex};
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
    /// Per disc, the belief's slots of its voxels, in the same order (every
    /// disc voxel has a belief from the start, and keeps its slot).
    slots: Vec<Vec<usize>>,
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
        d.observations = vec![0; d.discs.len()];
        d.identified_at = vec![None; d.discs.len()];
        if materials.is_empty() || d.discs.is_empty() {
            return Ok(None);
        }
        let config = crate::lrc::lrc_config(pose);
        let (lrc, obtained) = crate::lrc::train_lrc(materials, scanner, pose, seed, cache)?;
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
        let slots = voxels
            .iter()
            .map(|v| v.iter().filter_map(|k| belief.slot(*k)).collect())
            .collect();
        let patch_m = crate::lrc::patch_radius_m();
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
            slots,
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
        let index = PatchIndex::new(pts);
        // The scanner's positions: a standing sweep's lie on a short arc, a
        // motion's along its path.
        let origins = geom::Aabb::from_points(pts.iter().map(|p| &p.origin));
        let (lrc, patch, reach) = (&self.lrc, self.patch_m, self.reach_m);
        let facing = &d.facing;
        let results: Vec<(usize, Vec<Real>)> = d
            .discs
            .par_iter()
            .enumerate()
            .filter(|(_, disc)| origins.distance_squared_to_point(&disc.centre) <= reach * reach)
            .filter_map(|(i, disc)| {
                let obs = index.observation(&disc.centre, patch, seen_side(facing.get(i)).as_ref());
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

    /// Of the discs `candidates`, those a sweep of `points` (a prediction on
    /// the mapped surface) would give the LRC an observation of that passes
    /// its geometric checks (range, incidence, returns and span in the fit
    /// window, flatness), as [`Materials::observe`] forms it; `None`, with
    /// no other disc checked, when disc `first` (checked first) fails those
    /// checks. `first` is in the list only if it is among `candidates`.
    pub(crate) fn usable(
        &self,
        d: &DiscMap,
        points: &[SweepPoint],
        candidates: &[usize],
        first: usize,
    ) -> Option<Vec<usize>> {
        if points.is_empty() {
            return None;
        }
        let index = PatchIndex::new(points);
        let origins = geom::Aabb::from_points(points.iter().map(|p| &p.origin));
        let lrc = &self.lrc;
        // Cheap refusals first (each one the LRC's checks would make): out
        // of reach of every origin, every origin nearer than the shortest
        // range (with room for the target's projection onto the patch's
        // plane), or no origin on the disc's seen side (no returns left).
        let near_m = (lrc.config.min_range_m - 0.15).max(0.0);
        let plausible = |i: usize| {
            let c = &d.discs[i].centre;
            if origins.distance_squared_to_point(c) > self.reach_m * self.reach_m {
                return false;
            }
            // The farthest corner of the origins' box, and the farthest
            // any origin reaches along the disc's facing normal.
            let far = (0..3)
                .map(|a| {
                    (c[a] - origins.min[a])
                        .abs()
                        .max((c[a] - origins.max[a]).abs())
                })
                .map(|v| v * v)
                .sum::<Real>();
            if far < near_m * near_m {
                return false;
            }
            d.facing.get(i).is_none_or(|f| {
                (0..3)
                    .map(|a| (f[a] * origins.min[a]).max(f[a] * origins.max[a]))
                    .sum::<Real>()
                    > c.coords.dot(f)
            })
        };
        let mut obs = sensor::Observation::default();
        let mut passes = |i: usize| {
            plausible(i) && {
                index.observe_into(
                    &d.discs[i].centre,
                    self.patch_m,
                    seen_side(d.facing.get(i)).as_ref(),
                    false,
                    &mut obs,
                );
                lrc.geometry_passes(&obs, &lrc.config).is_ok()
            }
        };
        if !passes(first) {
            return None;
        }
        Some(
            candidates
                .iter()
                .copied()
                .filter(|&i| i == first || passes(i))
                .collect(),
        )
    }

    /// The material information remaining on disc `i` (eq. 4.16 over its
    /// voxels).
    pub(crate) fn h3(&self, i: usize) -> Real {
        // `MaterialBelief::h3_disc` over the remembered voxels, summed in
        // the same order.
        self.slots[i].iter().map(|&s| self.belief.h3_in(s)).sum()
    }

    /// The most probable material of disc `i` and its probability (the
    /// mean over its belief voxels, as `MaterialBelief::disc_probabilities`).
    fn best(&self, i: usize) -> Option<(usize, Real)> {
        let n = self.belief.config().n_materials;
        let mut sum = vec![0.0; n];
        let mut count = 0usize;
        for &slot in &self.slots[i] {
            for (s, v) in sum.iter_mut().zip(self.belief.probabilities_in(slot)) {
                *s += v;
            }
            count += 1;
        }
        if count == 0 {
            return None;
        }
        sum.iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1).then(b.0.cmp(&a.0)))
            .map(|(m, &s)| (m, s / count as Real))
    }

    /// Whether disc `i` is identified: its most probable material at
    /// `p >= IDENTIFIED_P`.
    pub(crate) fn identified(&self, i: usize) -> bool {
        self.best(i).is_some_and(|(_, p)| p >= IDENTIFIED_P)
    }

    /// Mark the discs identified after viewpoint `k` in `d.identified_at`
    /// (a disc identified before keeps its viewpoint, one no longer
    /// identified loses it) and return how many are.
    pub(crate) fn mark_identified(&self, d: &mut DiscMap, k: usize) -> usize {
        use rayon::prelude::*;
        let now: Vec<bool> = (0..d.discs.len())
            .into_par_iter()
            .map(|i| self.identified(i))
            .collect();
        for (at, now) in d.identified_at.iter_mut().zip(now) {
            *at = if now { Some(at.unwrap_or(k)) } else { None };
        }
        d.identified_at.iter().filter(|a| a.is_some()).count()
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

/// The seen side of a disc whose normal turned toward the scanner is
/// `facing`, as [`PatchIndex::observation`] takes it.
fn seen_side(facing: Option<&geom::Vector3>) -> Option<geom::UnitVector3> {
    facing.and_then(|f| geom::UnitVector3::try_new(*f, 1e-12))
}

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
        let index = PatchIndex::new(pts);
        for k in (0..pts.len()).step_by(pts.len() / 7) {
            let target = pts[k].point + geom::Vector3::new(0.01, -0.02, 0.0);
            let a = index.observation(&target, 0.18, None);
            let b = sensor::Observation::from_sweep(&sweep, &target, 0.18);
            assert!(!a.returns.is_empty());
            assert_eq!(a, b);
        }
    }
}
