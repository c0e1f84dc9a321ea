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

/// Points (the true-surface samples) indexed for "which lie within `r` of
/// this point" queries: a dense grid of cubes of side at least `2r` over
/// their bounding box, so a query looks in at most 8 cells (per axis the
/// cell holding the point and the nearer neighbour). Far faster than a k-d
/// tree for the 10 mm queries of the coverage metric, with the same
/// answers (`d² ≤ r²`).
#[derive(Clone, Debug)]
pub struct SampleGrid {
    origin: [Real; 3],
    cell: Real,
    dims: [usize; 3],
    /// Per cell, where its samples start in `items` and `points` (one more
    /// entry than cells).
    starts: Vec<u32>,
    /// Sample indices, by cell.
    items: Vec<u32>,
    /// Per sample, its cell.
    cell_of_item: Vec<u32>,
    /// The samples, by cell.
    points: Vec<[Real; 3]>,
    r2: Real,
}

/// Most cells a [`SampleGrid`] allocates; a sparser set of samples gets
/// larger cells.
const MAX_GRID_CELLS: usize = 1 << 25;

impl SampleGrid {
    /// Index `points` for queries of radius `r` (> 0). Fails on more than
    /// `u32::MAX` points.
    pub fn new(points: &[[Real; 3]], r: Real) -> Result<Self, SimError> {
        if points.len() >= u32::MAX as usize {
            return Err(SimError::InvalidArgument {
                what: "coverage samples".into(),
                message: format!(
                    "{} samples: at most {} can be indexed",
                    points.len(),
                    u32::MAX
                ),
            });
        }
        let (mut lo, mut hi) = ([Real::INFINITY; 3], [Real::NEG_INFINITY; 3]);
        for p in points {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        if points.is_empty() {
            (lo, hi) = ([0.0; 3], [0.0; 3]);
        }
        let extent = [0, 1, 2].map(|k| hi[k] - lo[k]);
        let mut cell = 2.0 * r.max(1e-9);
        let cells_of = |cell: Real| -> usize {
            extent
                .iter()
                .map(|e| (e / cell).floor() as usize + 1)
                .product()
        };
        while cells_of(cell) > MAX_GRID_CELLS {
            cell *= 1.5;
        }
        let dims = extent.map(|e| (e / cell).floor() as usize + 1);
        let index = |p: &[Real; 3]| -> usize {
            let c = [0, 1, 2].map(|k| (((p[k] - lo[k]) / cell) as usize).min(dims[k] - 1));
            (c[2] * dims[1] + c[1]) * dims[0] + c[0]
        };
        let mut counts = vec![0u32; dims.iter().product::<usize>() + 1];
        for p in points {
            counts[index(p) + 1] += 1;
        }
        for i in 1..counts.len() {
            counts[i] += counts[i - 1];
        }
        let mut fill = counts.clone();
        let mut items = vec![0u32; points.len()];
        let mut sorted = vec![[0.0; 3]; points.len()];
        for (i, p) in points.iter().enumerate() {
            let c = index(p);
            let at = fill[c] as usize;
            items[at] = i as u32;
            sorted[at] = *p;
            fill[c] += 1;
        }
        let mut cell_of_item = vec![0u32; points.len()];
        for c in 0..counts.len() - 1 {
            for &i in &items[counts[c] as usize..counts[c + 1] as usize] {
                cell_of_item[i as usize] = c as u32;
            }
        }
        Ok(Self {
            origin: lo,
            cell,
            dims,
            starts: counts,
            cell_of_item,
            items,
            points: sorted,
            r2: r * r,
        })
    }

    /// The cell a point falls in, in the order the cells are stored (`None`
    /// outside the grid): sorting query points by it makes their lookups
    /// walk memory in order.
    pub fn cell_of(&self, p: &[Real; 3]) -> Option<usize> {
        let mut c = [0usize; 3];
        for k in 0..3 {
            let x = ((p[k] - self.origin[k]) / self.cell).floor();
            if !(x >= 0.0 && x < self.dims[k] as Real) {
                return None;
            }
            c[k] = x as usize;
        }
        Some((c[2] * self.dims[1] + c[1]) * self.dims[0] + c[0])
    }

    /// Call `f` with the index of every sample within `r` of `p`.
    pub fn within(&self, p: &[Real; 3], f: impl FnMut(usize)) {
        self.within_cells(p, |_| true, f);
    }

    /// [`SampleGrid::cell_range`] packed: the lowest cell a sphere of
    /// radius `r` about `p` can reach (as [`SampleGrid::cell_of`]), and per
    /// axis `k` (bit `k`) whether it reaches the next cell along it too.
    fn reach_of(&self, p: &[Real; 3]) -> Option<(usize, u8)> {
        let range = self.cell_range(p)?;
        let corner = (range[2].0 * self.dims[1] + range[1].0) * self.dims[0] + range[0].0;
        let upper = (0..3).fold(0u8, |m, k| m | (u8::from(range[k].1 > range[k].0) << k));
        Some((corner, upper))
    }

    /// Set the bit (in `bits`, by position in the grid's storage order) of
    /// every sample within `r` of `p` in the cells of
    /// [`SampleGrid::reach_of`]'s `(corner, upper)`. A cell's samples are
    /// one run of bits: a cell whose bits are all set is skipped, and so is
    /// each sample already set.
    fn mark_within(&self, corner: usize, upper: u8, p: &[Real; 3], bits: &mut [u64]) {
        let (sy, sz) = (self.dims[0], self.dims[0] * self.dims[1]);
        let up = |k: u8| usize::from(upper >> k & 1);
        for z in 0..=up(2) {
            for y in 0..=up(1) {
                for x in 0..=up(0) {
                    let cell = corner + z * sz + y * sy + x;
                    let (s, e) = (self.starts[cell] as usize, self.starts[cell + 1] as usize);
                    if all_set(bits, s, e) {
                        continue;
                    }
                    for (k, q) in self.points[s..e].iter().enumerate() {
                        let at = s + k;
                        let (word, bit) = (at / 64, 1u64 << (at % 64));
                        if bits[word] & bit != 0 {
                            continue;
                        }
                        let d2 =
                            (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2);
                        if d2 <= self.r2 {
                            bits[word] |= bit;
                        }
                    }
                }
            }
        }
    }

    /// The cells a sphere of radius `r ≤ cell/2` about `p` can reach: per
    /// axis, the nearer neighbour cell only (`None`: none).
    fn cell_range(&self, p: &[Real; 3]) -> Option<[(usize, usize); 3]> {
        let mut range = [(0usize, 0usize); 3];
        for k in 0..3 {
            let x = (p[k] - self.origin[k]) / self.cell;
            let c = x.floor();
            if !(c >= -1.0 && c <= self.dims[k] as Real) {
                return None;
            }
            let (a, b) = if x - c < 0.5 {
                (c - 1.0, c)
            } else {
                (c, c + 1.0)
            };
            let a = a.max(0.0) as usize;
            let b = (b.min(self.dims[k] as Real - 1.0)).max(-1.0);
            if b < 0.0 || a > b as usize {
                return None;
            }
            range[k] = (a, b as usize);
        }
        Some(range)
    }

    /// Call `f` with the index of every sample within `r` of `p` in the
    /// cells within reach of `p` (cell indices as [`SampleGrid::cell_of`])
    /// that `open` accepts.
    pub fn within_cells(
        &self,
        p: &[Real; 3],
        open: impl Fn(usize) -> bool,
        mut f: impl FnMut(usize),
    ) {
        let Some(range) = self.cell_range(p) else {
            return;
        };
        for z in range[2].0..=range[2].1 {
            for y in range[1].0..=range[1].1 {
                let row = (z * self.dims[1] + y) * self.dims[0];
                for cell in row + range[0].0..=row + range[0].1 {
                    if !open(cell) {
                        continue;
                    }
                    let (s, e) = (self.starts[cell] as usize, self.starts[cell + 1] as usize);
                    for (q, &i) in self.points[s..e].iter().zip(&self.items[s..e]) {
                        let d2 =
                            (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2);
                        if d2 <= self.r2 {
                            f(i as usize);
                        }
                    }
                }
            }
        }
    }
}

/// Whether bits `s..e` of `bits` are all set.
fn all_set(bits: &[u64], s: usize, e: usize) -> bool {
    let mut at = s;
    while at < e {
        let (word, from) = (at / 64, at % 64);
        let to = (e - word * 64).min(64);
        let mask = if to - from == 64 {
            u64::MAX
        } else {
            ((1u64 << (to - from)) - 1) << from
        };
        if bits[word] & mask != mask {
            return false;
        }
        at = word * 64 + to;
    }
    true
}

/// Coverage kept up to date as points arrive: the true-surface samples of
/// [`coverage`] (same sampler, same samples) indexed once, each batch of
/// points marking the samples within the threshold. After any batches the
/// report equals [`coverage`] of all points so far.
#[derive(Debug)]
pub struct CoverageTracker {
    grid: SampleGrid,
    /// The samples' bounding box grown by the threshold: a point outside it
    /// is within the threshold of no sample.
    reach: Option<Aabb>,
    points: Vec<[Real; 3]>,
    normals: Vec<[Real; 3]>,
    observable: Option<Vec<bool>>,
    material: Vec<u16>,
    covered: Vec<bool>,
    /// Per grid cell, how many of its samples are not covered yet: a point
    /// looks only in cells with some (a covered sample stays covered).
    uncovered_in_cell: Vec<u32>,
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
        let grid = SampleGrid::new(&points, cfg.covered_within_m)?;
        let uncovered_in_cell = grid.starts.windows(2).map(|w| w[1] - w[0]).collect();
        Ok(Self {
            grid,
            uncovered_in_cell,
            reach,
            points,
            normals,
            observable: None,
            material,
            covered,
            covered_within_m: cfg.covered_within_m,
            region: cfg.sampling.region,
            samples_per_m2,
            density_capped,
            names: scene.materials().iter().map(|m| m.name.clone()).collect(),
        })
    }

    /// Mark the samples within the threshold of any of `points`.
    pub fn add_points(&mut self, points: &[Point3]) {
        let Some(reach) = &self.reach else {
            return;
        };
        let grid = &self.grid;
        let open = &self.uncovered_in_cell;
        let hits: Vec<usize> = points
            .par_iter()
            .filter(|p| reach.contains_point(p))
            .fold(Vec::new, |mut out, p| {
                grid.within_cells(&[p.x, p.y, p.z], |c| open[c] > 0, |i| out.push(i));
                out
            })
            .flatten()
            .collect();
        for i in hits {
            if let Some(c) = self.covered.get_mut(i)
                && !*c
            {
                *c = true;
                self.uncovered_in_cell[grid.cell_of_item[i] as usize] -= 1;
            }
        }
    }

    /// The samples within the threshold of any of `points`, one bit per
    /// sample (`⌈samples / 64⌉` words), whatever is covered so far.
    pub fn bits_of(&self, points: &[Point3]) -> Vec<u64> {
        let stored = self.stored_bits_of(points);
        let mut bits = vec![0u64; stored.len()];
        for (w, &word) in stored.iter().enumerate() {
            let mut rest = word;
            while rest != 0 {
                let i = self.grid.items[w * 64 + rest.trailing_zeros() as usize] as usize;
                bits[i / 64] |= 1u64 << (i % 64);
                rest &= rest - 1;
            }
        }
        bits
    }

    /// [`CoverageTracker::bits_of`] in the tracker's storage order (the
    /// same for every call, not the samples' own): for counting, comparing
    /// and uniting such sets, as the oracle does, without the reordering.
    pub fn stored_bits_of(&self, points: &[Point3]) -> Vec<u64> {
        let mut bits = vec![0u64; self.points.len().div_ceil(64)];
        let Some(reach) = &self.reach else {
            return bits;
        };
        let grid = &self.grid;
        // Each point's cells, by their lowest corner, so the lookups walk
        // memory in order.
        let mut inside: Vec<(usize, u8, [Real; 3])> = points
            .iter()
            .filter(|p| reach.contains_point(p))
            .filter_map(|p| {
                let q = [p.x, p.y, p.z];
                grid.reach_of(&q).map(|(corner, upper)| (corner, upper, q))
            })
            .collect();
        inside.sort_unstable_by_key(|(c, _, _)| *c);
        for (corner, upper, q) in &inside {
            grid.mark_within(*corner, *upper, q, &mut bits);
        }
        bits
    }

    /// Samples.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// No samples.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
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

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// `bits_of` (and the storage-order bits it is made from) marks
    /// exactly the samples a brute-force scan finds within the threshold of
    /// some point: points near the cube's faces, batch by batch.
    #[test]
    fn bits_of_matches_brute_force() {
        let world = scene::builtin::scene("cube")
            .unwrap()
            .build(std::path::Path::new("."))
            .unwrap();
        let scene = world.as_scene().unwrap();
        let mut cfg = MetricsConfig {
            covered_within_m: 0.02,
            ..MetricsConfig::default()
        };
        cfg.sampling.samples_per_m2 = 2000.0;
        let tracker = CoverageTracker::new(scene, &cfg).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
        for n in [0, 1, 300, 3000] {
            // Points on and near random samples, and some far off.
            let points: Vec<Point3> = (0..n)
                .map(|_| {
                    let s = tracker.points[rng.random_range(0..tracker.points.len())];
                    let j = if rng.random_range(0.0..1.0) < 0.1 {
                        0.5
                    } else {
                        0.03
                    };
                    Point3::new(
                        s[0] + rng.random_range(-j..j),
                        s[1] + rng.random_range(-j..j),
                        s[2] + rng.random_range(-j..j),
                    )
                })
                .collect();
            let r2 = tracker.grid.r2;
            let want: Vec<bool> = tracker
                .points
                .iter()
                .map(|q| {
                    points.iter().any(|p| {
                        (q[0] - p.x).powi(2) + (q[1] - p.y).powi(2) + (q[2] - p.z).powi(2) <= r2
                    })
                })
                .collect();
            let bits = tracker.bits_of(&points);
            let got: Vec<bool> = (0..want.len())
                .map(|i| bits[i / 64] >> (i % 64) & 1 == 1)
                .collect();
            assert_eq!(got, want, "{n} points");
            let stored: u32 = tracker
                .stored_bits_of(&points)
                .iter()
                .map(|w| w.count_ones())
                .sum();
            assert_eq!(stored as usize, want.iter().filter(|c| **c).count());
            if n >= 300 {
                assert!(want.iter().any(|c| *c) && !want.iter().all(|c| *c));
            }
        }
    }

    /// The grid finds exactly the samples a brute-force scan finds, for
    /// queries inside, at the edge of and outside the samples' box.
    #[test]
    fn sample_grid_matches_brute_force() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let samples: Vec<[Real; 3]> = (0..5000)
            .map(|_| {
                [
                    rng.random_range(-0.3..0.3),
                    rng.random_range(0.0..0.2),
                    rng.random_range(-0.05..0.05),
                ]
            })
            .collect();
        for r in [0.01, 0.03] {
            let grid = SampleGrid::new(&samples, r).unwrap();
            for _ in 0..2000 {
                let p = [
                    rng.random_range(-0.35..0.35),
                    rng.random_range(-0.05..0.25),
                    rng.random_range(-0.1..0.1),
                ];
                let mut got = Vec::new();
                grid.within(&p, |i| got.push(i));
                got.sort_unstable();
                let want: Vec<usize> = (0..samples.len())
                    .filter(|&i| {
                        let q = samples[i];
                        (q[0] - p[0]).powi(2) + (q[1] - p[1]).powi(2) + (q[2] - p[2]).powi(2)
                            <= r * r
                    })
                    .collect();
                assert_eq!(got, want, "r {r}, query {p:?}");
            }
        }
        let empty = SampleGrid::new(&[], 0.01).unwrap();
        empty.within(&[0.0; 3], |_| panic!("no samples"));
    }
}
