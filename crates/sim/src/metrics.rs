//! Ground-truth metrics of a measured point cloud (SPEC §6): coverage of the
//! true surfaces (per material and overall) and accuracy of the points.

use crate::scenario::MetricsConfig;
use geom::{Aabb, Point3, Real};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use scene::{Scene, sample_surfaces};
use serde::Serialize;
use std::num::NonZero;

/// Coverage of one material.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MaterialCoverage {
    /// Material name.
    pub material: String,
    /// True-surface samples of this material.
    pub samples: usize,
    /// Of which covered.
    pub covered: usize,
}

/// Coverage of the true surfaces.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CoverageReport {
    /// Samples of the true surfaces considered.
    pub samples: usize,
    /// Samples with a measured point within the threshold.
    pub covered: usize,
    /// The threshold, metres.
    pub covered_within_m: Real,
    /// The region the samples were restricted to.
    pub region: Option<Aabb>,
    /// Per material, in the scene's table order (materials with no samples omitted).
    pub per_material: Vec<MaterialCoverage>,
}

impl CoverageReport {
    /// Covered fraction in `[0, 1]` (0 when there are no samples).
    pub fn fraction(&self) -> Real {
        if self.samples == 0 {
            0.0
        } else {
            self.covered as Real / self.samples as Real
        }
    }
}

/// Distances from measured points to the true surface.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AccuracyReport {
    /// Points evaluated.
    pub points: usize,
    /// Mean distance, metres.
    pub mean_m: Real,
    /// 95th percentile, metres.
    pub p95_m: Real,
    /// Largest, metres.
    pub max_m: Real,
}

/// Coverage of `scene` by `points` under `cfg` (SPEC §6).
pub fn coverage(scene: &Scene, points: &[Point3], cfg: &MetricsConfig) -> CoverageReport {
    let samples = sample_surfaces(scene, &cfg.sampling);
    let covered_flags: Vec<bool> = if points.is_empty() {
        vec![false; samples.len()]
    } else {
        let arr: Vec<[Real; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
        let tree: ImmutableKdTree<Real, 3> = ImmutableKdTree::new_from_slice(&arr);
        let r2 = cfg.covered_within_m * cfg.covered_within_m;
        let one = NonZero::<usize>::MIN;
        // A bounded search: most samples have no point near them, and an
        // unbounded nearest-neighbour search would wander the whole tree.
        samples
            .par_iter()
            .map(|s| {
                let q = [s.point.x, s.point.y, s.point.z];
                !tree
                    .nearest_n_within::<SquaredEuclidean>(&q, r2, one, false)
                    .is_empty()
            })
            .collect()
    };
    let mut per = vec![(0usize, 0usize); scene.materials().len()];
    for (s, c) in samples.iter().zip(&covered_flags) {
        let e = &mut per[usize::from(s.material.0)];
        e.0 += 1;
        e.1 += usize::from(*c);
    }
    CoverageReport {
        samples: samples.len(),
        covered: covered_flags.iter().filter(|c| **c).count(),
        covered_within_m: cfg.covered_within_m,
        region: cfg.sampling.region,
        per_material: scene
            .materials()
            .iter()
            .zip(per)
            .filter(|(_, (n, _))| *n > 0)
            .map(|(m, (n, c))| MaterialCoverage {
                material: m.name.clone(),
                samples: n,
                covered: c,
            })
            .collect(),
    }
}

/// Accuracy of `points` against the true surface: each point's distance to the
/// nearest triangle (points farther than `search_m` count as `search_m`).
pub fn accuracy(scene: &Scene, points: &[Point3], search_m: Real) -> AccuracyReport {
    let mut d: Vec<Real> = points
        .par_iter()
        .map(|p| {
            scene
                .closest_point(p, search_m)
                .map_or(search_m, |(d, _, _)| d)
        })
        .collect();
    if d.is_empty() {
        return AccuracyReport {
            points: 0,
            mean_m: 0.0,
            p95_m: 0.0,
            max_m: 0.0,
        };
    }
    d.sort_by(Real::total_cmp);
    let n = d.len();
    AccuracyReport {
        points: n,
        mean_m: d.iter().sum::<Real>() / n as Real,
        p95_m: d[((0.95 * n as Real).ceil() as usize).clamp(1, n) - 1],
        max_m: d[n - 1],
    }
}
