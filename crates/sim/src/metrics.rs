//! Ground-truth metrics of a measured point cloud (SPEC §6): coverage of the
//! true surfaces (per material and overall) and accuracy of the points.

use crate::SimError;
use geom::{Aabb, Point3, Real};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use scenario::MetricsConfig;
use scene::{DEFAULT_SAMPLE_CHUNK, RayCast, Scene, SurfaceSampler};
use serde::Serialize;
use std::num::NonZero;

pub use record::{CoverageReport, MaterialCoverage};

/// Distances from measured points to the true surface.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct AccuracyReport {
    /// Points evaluated.
    pub points: usize,
    /// Their distance statistics; `None` when there were no points (a scan that
    /// hit nothing has no accuracy, not a perfect one).
    pub distances: Option<DistanceStats>,
}

/// Statistics of point-to-surface distances.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct DistanceStats {
    /// Mean distance, metres.
    pub mean_m: Real,
    /// 95th percentile, metres.
    pub p95_m: Real,
    /// Largest, metres.
    pub max_m: Real,
}

impl std::fmt::Display for AccuracyReport {
    /// `mean 1.2 mm, 95th percentile 3.4 mm, max 9.9 mm over 123 points`, or
    /// `no points`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.distances {
            None => write!(f, "no points"),
            Some(d) => write!(
                f,
                "mean {:.1} mm, 95th percentile {:.1} mm, max {:.1} mm over {} points",
                1000.0 * d.mean_m,
                1000.0 * d.p95_m,
                1000.0 * d.max_m,
                self.points
            ),
        }
    }
}

/// Coverage of `scene` by `points` under `cfg` (SPEC §6). The true-surface
/// samples are streamed in chunks of [`scene::DEFAULT_SAMPLE_CHUNK`], so memory
/// stays bounded whatever the scene, and their number is capped by
/// `cfg.sampling.max_samples` (the report gives the density used). Refuses a
/// configuration that fails [`MetricsConfig::validate`].
pub fn coverage(
    scene: &Scene,
    points: &[Point3],
    cfg: &MetricsConfig,
) -> Result<CoverageReport, SimError> {
    coverage_in_chunks(scene, points, cfg, DEFAULT_SAMPLE_CHUNK)
}

/// [`coverage`] with a given chunk size (the result does not depend on it).
pub fn coverage_in_chunks(
    scene: &Scene,
    points: &[Point3],
    cfg: &MetricsConfig,
    chunk: usize,
) -> Result<CoverageReport, SimError> {
    cfg.validate()?;
    let sampler = SurfaceSampler::new(scene, &cfg.sampling)
        .map_err(|e| SimError::Scenario {
            source_name: "metrics".into(),
            message: e.to_string(),
        })?
        .with_chunk(chunk);
    let samples_per_m2 = sampler.samples_per_m2();
    let density_capped = sampler.is_capped();
    let tree: Option<ImmutableKdTree<Real, 3>> = (!points.is_empty()).then(|| {
        let arr: Vec<[Real; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
        ImmutableKdTree::new_from_slice(&arr)
    });
    let r2 = cfg.covered_within_m * cfg.covered_within_m;
    let one = NonZero::<usize>::MIN;
    // (samples, covered) per material.
    let mut per = vec![(0usize, 0usize); scene.materials().len()];
    for samples in sampler {
        let covered_flags: Vec<bool> = match &tree {
            None => vec![false; samples.len()],
            // A bounded search: most samples have no point near them, and an
            // unbounded nearest-neighbour search would wander the whole tree.
            Some(tree) => samples
                .par_iter()
                .map(|s| {
                    let q = [s.point.x, s.point.y, s.point.z];
                    !tree
                        .nearest_n_within::<SquaredEuclidean>(&q, r2, one, false)
                        .is_empty()
                })
                .collect(),
        };
        for (s, c) in samples.iter().zip(&covered_flags) {
            if let Some(e) = per.get_mut(usize::from(s.material.0)) {
                e.0 += 1;
                e.1 += usize::from(*c);
            }
        }
    }
    Ok(CoverageReport {
        samples: per.iter().map(|e| e.0).sum(),
        covered: per.iter().map(|e| e.1).sum(),
        covered_within_m: cfg.covered_within_m,
        region: cfg.sampling.region,
        samples_per_m2,
        density_capped,
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
    })
}

/// Coverage kept up to date as points arrive: the true-surface samples of
/// [`coverage`] (same sampler, same samples) indexed once, each batch of
/// points marking the samples within the threshold. After any batches the
/// report equals [`coverage`] of all points so far.
#[derive(Debug)]
pub struct CoverageTracker {
    tree: Option<ImmutableKdTree<Real, 3>>,
    /// The samples' bounding box grown by the threshold: a point outside it
    /// is within the threshold of no sample.
    reach: Option<Aabb>,
    points: Vec<[Real; 3]>,
    normals: Vec<[Real; 3]>,
    observable: Option<Vec<bool>>,
    material: Vec<u16>,
    covered: Vec<bool>,
    r2: Real,
    covered_within_m: Real,
    region: Option<Aabb>,
    samples_per_m2: Real,
    density_capped: bool,
    names: Vec<String>,
}

impl CoverageTracker {
    /// Draw the samples of `scene` under `cfg` (all kept in memory: mind
    /// `cfg.sampling.max_samples`).
    pub fn new(scene: &Scene, cfg: &MetricsConfig) -> Result<Self, SimError> {
        cfg.validate()?;
        let sampler =
            SurfaceSampler::new(scene, &cfg.sampling).map_err(|e| SimError::Scenario {
                source_name: "metrics".into(),
                message: e.to_string(),
            })?;
        let samples_per_m2 = sampler.samples_per_m2();
        let density_capped = sampler.is_capped();
        let mut points: Vec<[Real; 3]> = Vec::new();
        let mut normals: Vec<[Real; 3]> = Vec::new();
        let mut material = Vec::new();
        for chunk in sampler {
            for s in chunk {
                points.push([s.point.x, s.point.y, s.point.z]);
                normals.push([s.normal.x, s.normal.y, s.normal.z]);
                material.push(s.material.0);
            }
        }
        let covered = vec![false; points.len()];
        // Grown a little more than the threshold: no rounding of the box can
        // shut out a point the tree would find.
        let r = cfg.covered_within_m + 1e-9;
        let reach = points.first().map(|p| {
            let (lo, hi) = points.iter().fold((*p, *p), |(lo, hi), q| {
                (
                    [0, 1, 2].map(|k| lo[k].min(q[k])),
                    [0, 1, 2].map(|k| hi[k].max(q[k])),
                )
            });
            Aabb::new(
                Point3::from(lo.map(|v| v - r)),
                Point3::from(hi.map(|v| v + r)),
            )
        });
        Ok(Self {
            tree: (!points.is_empty()).then(|| ImmutableKdTree::new_from_slice(&points)),
            reach,
            points,
            normals,
            observable: None,
            material,
            covered,
            r2: cfg.covered_within_m * cfg.covered_within_m,
            covered_within_m: cfg.covered_within_m,
            region: cfg.sampling.region,
            samples_per_m2,
            density_capped,
            names: scene.materials().iter().map(|m| m.name.clone()).collect(),
        })
    }

    /// Mark the samples within the threshold of any of `points`.
    pub fn add_points(&mut self, points: &[Point3]) {
        let (Some(tree), Some(reach)) = (&self.tree, &self.reach) else {
            return;
        };
        let r2 = self.r2;
        let hits: Vec<u64> = points
            .par_iter()
            .filter(|p| reach.contains_point(p))
            .flat_map_iter(|p| {
                tree.within_unsorted::<SquaredEuclidean>(&[p.x, p.y, p.z], r2)
                    .into_iter()
                    .map(|n| n.item)
            })
            .collect();
        for i in hits {
            if let Some(c) = self.covered.get_mut(i as usize) {
                *c = true;
            }
        }
    }

    /// Covered fraction so far.
    pub fn fraction(&self) -> Real {
        if self.covered.is_empty() {
            0.0
        } else {
            self.covered.iter().filter(|c| **c).count() as Real / self.covered.len() as Real
        }
    }

    /// Mark which samples are observable at all: a sample is observable when
    /// one of `viewpoints` lies within `max_range_m` in front of its face
    /// (at more than 1° from grazing) with nothing of `scene` between them.
    /// An upper bound on what any sensing from those points can cover (the
    /// scanner's field and the arm's paths are ignored). Samples are taken
    /// per cell of `cell_m`: the first sample of each cell stands for it.
    pub fn set_observable_from(
        &mut self,
        scene: &Scene,
        viewpoints: &[Point3],
        max_range_m: Real,
        cell_m: Real,
    ) {
        let mut cells: std::collections::HashMap<[i64; 3], usize> =
            std::collections::HashMap::new();
        let mut rep = Vec::with_capacity(self.points.len());
        for p in &self.points {
            let key = p.map(|v| (v / cell_m).floor() as i64);
            let next = cells.len();
            rep.push(*cells.entry(key).or_insert(next));
        }
        let mut reps = vec![usize::MAX; cells.len()];
        for (i, r) in rep.iter().enumerate() {
            if reps[*r] == usize::MAX {
                reps[*r] = i;
            }
        }
        let grazing = 1f64.to_radians().sin();
        let seen: Vec<bool> = reps
            .par_iter()
            .map(|&i| {
                let p = Point3::from(self.points[i]);
                let n = geom::Vector3::from(self.normals[i]);
                let start = p + n * 1e-4;
                viewpoints.iter().any(|v| {
                    let d = v - start;
                    let len = d.norm();
                    if !(len > 1e-9 && len <= max_range_m) || n.dot(&d) <= grazing * len {
                        return false;
                    }
                    let ray = geom::Ray::new(start, geom::UnitVector3::new_unchecked(d / len));
                    scene.cast_ray(&ray, len).is_none()
                })
            })
            .collect();
        self.observable = Some(rep.iter().map(|r| seen[*r]).collect());
    }

    /// `(observable samples, of which covered)`, once
    /// [`CoverageTracker::set_observable_from`] has run.
    pub fn observable_counts(&self) -> Option<(usize, usize)> {
        let mask = self.observable.as_ref()?;
        let n = mask.iter().filter(|m| **m).count();
        let c = mask
            .iter()
            .zip(&self.covered)
            .filter(|(m, c)| **m && **c)
            .count();
        Some((n, c))
    }

    /// The report, as [`coverage`] gives it.
    pub fn report(&self) -> CoverageReport {
        let mut per = vec![(0usize, 0usize); self.names.len()];
        for (m, c) in self.material.iter().zip(&self.covered) {
            if let Some(e) = per.get_mut(usize::from(*m)) {
                e.0 += 1;
                e.1 += usize::from(*c);
            }
        }
        CoverageReport {
            samples: per.iter().map(|e| e.0).sum(),
            covered: per.iter().map(|e| e.1).sum(),
            covered_within_m: self.covered_within_m,
            region: self.region,
            samples_per_m2: self.samples_per_m2,
            density_capped: self.density_capped,
            per_material: self
                .names
                .iter()
                .zip(per)
                .filter(|(_, (n, _))| *n > 0)
                .map(|(name, (n, c))| MaterialCoverage {
                    material: name.clone(),
                    samples: n,
                    covered: c,
                })
                .collect(),
        }
    }
}

/// Accuracy of `points` against the true surface: each point's distance to the
/// nearest triangle (points farther than `search_m` count as `search_m`).
/// No points gives [`AccuracyReport::distances`] `None`.
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
            distances: None,
        };
    }
    d.sort_by(Real::total_cmp);
    let n = d.len();
    AccuracyReport {
        points: n,
        distances: Some(DistanceStats {
            mean_m: d.iter().sum::<Real>() / n as Real,
            p95_m: d[((0.95 * n as Real).ceil() as usize).clamp(1, n) - 1],
            max_m: d[n - 1],
        }),
    }
}
