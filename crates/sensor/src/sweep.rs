//! Tilt sweeps: one joint (joint 5 of the VM-6083 by default) nods the 2-D
//! scanner through α while scans are taken at a fixed tilt step (A§5.1.1,
//! Fig. 5.2; α = 60° in A Table 6.1). [`SweepConfig`] gives the tilt angles;
//! [`Sweep`] holds the returns on their (scan, ray) grid; [`SweepBuilder`]
//! makes one scan by scan from what a scanner reports.

use crate::{ScannerConfig, SensorError};
use geom::math::is_finite_point;
use geom::{Isometry3, Point3, Real, Vector3};
use scene::MaterialId;
use serde::{Deserialize, Serialize};

/// Most scans one sweep may have ([`SweepConfig::scan_count`]), checked by
/// [`SweepConfig::validate`]: a 0.0036° step over the full 360°. The default
/// sweep has 151.
pub const MAX_SCANS_PER_SWEEP: usize = 100_000;

/// Most rays (scans × rays per scan) one sweep may cast, checked by
/// [`SweepConfig::validate_with`]. A sweep keeps every return, about 100 bytes
/// each, so this is ~400 MB; the default sweep casts 151 × 342 = 51 642.
pub const MAX_RAYS_PER_SWEEP: usize = 4_000_000;

/// How to sweep.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SweepConfig {
    /// Total tilt α, degrees.
    pub tilt_deg: Real,
    /// Tilt between consecutive scans, degrees.
    pub step_deg: Real,
    /// The tilting joint, 1-based (5 = the VM-6083's fifth joint).
    pub joint: usize,
}

impl Default for SweepConfig {
    fn default() -> Self {
        Self {
            tilt_deg: 60.0,
            step_deg: 0.4,
            joint: 5,
        }
    }
}

impl SweepConfig {
    /// Check the fields.
    pub fn validate(&self) -> Result<(), SensorError> {
        if !(self.tilt_deg.is_finite() && self.tilt_deg >= 0.0 && self.tilt_deg <= 360.0) {
            return Err(SensorError::Config {
                field: "tilt_deg",
                expected: "a value in [0, 360]",
                got: self.tilt_deg.to_string(),
            });
        }
        if !(self.step_deg.is_finite() && self.step_deg > 0.0) {
            return Err(SensorError::Config {
                field: "step_deg",
                expected: "a positive angle",
                got: self.step_deg.to_string(),
            });
        }
        // A step past the whole tilt leaves a sweep of one scan (issue 48:
        // `step_deg = 1e308` did so without a word).
        if self.tilt_deg > 0.0 && self.step_deg > self.tilt_deg {
            return Err(SensorError::Config {
                field: "step_deg",
                expected: "a positive angle at most tilt_deg (a larger step sweeps one scan)",
                got: self.step_deg.to_string(),
            });
        }
        if self.joint == 0 {
            return Err(SensorError::Config {
                field: "joint",
                expected: "a 1-based joint number",
                got: "0".into(),
            });
        }
        let scans = self.scan_count();
        if scans > MAX_SCANS_PER_SWEEP {
            return Err(SensorError::Budget {
                field: "step_deg",
                value: self.step_deg.to_string(),
                count: scans,
                what: "scans per sweep",
                limit: MAX_SCANS_PER_SWEEP,
            });
        }
        Ok(())
    }

    /// [`Self::validate`] and [`ScannerConfig::validate`], then the sweep's total
    /// ray count against [`MAX_RAYS_PER_SWEEP`].
    pub fn validate_with(&self, scanner: &ScannerConfig) -> Result<(), SensorError> {
        self.validate()?;
        scanner.validate()?;
        let rays = self.scan_count().saturating_mul(scanner.ray_count());
        if rays > MAX_RAYS_PER_SWEEP {
            return Err(SensorError::Budget {
                field: "step_deg",
                value: self.step_deg.to_string(),
                count: rays,
                what: "rays per sweep (scans × rays per scan)",
                limit: MAX_RAYS_PER_SWEEP,
            });
        }
        Ok(())
    }

    /// Number of scans in a sweep: `⌊α / step⌋ + 1` (saturating at `usize::MAX`
    /// for a step too small to count).
    pub fn scan_count(&self) -> usize {
        let steps = (self.tilt_deg / self.step_deg + 1e-9).floor();
        if steps.is_finite() && steps >= 0.0 {
            (steps as usize).saturating_add(1)
        } else {
            usize::MAX
        }
    }

    /// The tilt joint's values, radians, centred on `centre_rad` and shifted as
    /// little as needed to stay inside `limits` (when the window fits).
    pub fn tilt_values(&self, centre_rad: Real, limits: Option<(Real, Real)>) -> Vec<Real> {
        let alpha = self.tilt_deg.to_radians();
        let step = self.step_deg.to_radians();
        let mut start = centre_rad - 0.5 * alpha;
        if let Some((lo, hi)) = limits
            && hi - lo >= alpha
        {
            start = start.clamp(lo, hi - alpha);
        }
        // Clamped: `start + step·k` can pass the upper limit by rounding.
        (0..self.scan_count())
            .map(|k| {
                let t = start + step * k as Real;
                limits.map_or(t, |(lo, hi)| t.clamp(lo, hi))
            })
            .collect()
    }
}

/// A cell of the range grid `R_{θ,α}` (A eq. 4.12): scan `j` (the tilt step,
/// a row) and ray `i` (the bearing, a column).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct GridCell {
    /// Scan index `j` (row).
    pub scan: u32,
    /// Ray index `i` (column).
    pub ray: u32,
}

/// One return of a sweep.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SweepPoint {
    /// The measured point, world frame.
    pub point: Point3,
    /// Origin of the ray that measured it (the scanner), world frame.
    pub origin: Point3,
    /// Return intensity (0 when the source did not report one).
    pub intensity: Real,
    /// Ground-truth material of the surface hit, where known (simulation).
    pub material: Option<MaterialId>,
    /// Where the return sits on the (scan, ray) grid, where known.
    pub cell: Option<GridCell>,
}

impl SweepPoint {
    /// Measured range: the distance from the ray's origin to the point.
    #[inline]
    pub fn range_m(&self) -> Real {
        (self.point - self.origin).norm()
    }
}

/// A tilt sweep: every return with the origin of its ray, its intensity, its
/// ground-truth material where known, and (for sweeps taken by a scanner or
/// read from a file that keeps it) its cell of the (scan, ray) grid of A eq.
/// 5.1 / 4.12. This is the one sweep type of the workspace: the simulator and
/// drivers produce it, scan files hold it, maps and the classifier consume it.
///
/// A sweep may be empty (a scan that hit nothing). Invariants, checked by
/// every constructor: every coordinate finite; either every point has a grid cell or none has, and
/// cells are strictly increasing in scan-major order (so each cell holds at
/// most one return and grid neighbours can be found by search).
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    points: Vec<SweepPoint>,
    shape: Option<GridShape>,
    scanner_poses: Vec<Isometry3>,
    bearings_rad: Vec<Real>,
    misses: Vec<(Point3, Vector3)>,
}

/// The size of a sweep's grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GridShape {
    /// Scans (rows).
    pub scans: u32,
    /// Rays per scan (columns).
    pub rays_per_scan: u32,
}

/// The unit direction, in the scanner frame, of the ray at bearing `θ`:
/// `(0, −sin θ, cos θ)` (A eq. 4.7; `z` is the centre ray, `y` the +90° side,
/// `x` the normal of the scan plane). The one place this formula lives.
#[inline]
pub fn beam_direction(bearing_rad: Real) -> Vector3 {
    let (s, c) = bearing_rad.sin_cos();
    Vector3::new(0.0, -s, c)
}

fn sweep_error(message: impl Into<String>) -> SensorError {
    SensorError::Sweep {
        message: message.into(),
    }
}

impl Sweep {
    /// A sweep from its points. Fails when a coordinate or intensity is not
    /// finite, or grid cells are given for some points but not
    /// others, or not strictly increasing in scan-major order.
    pub fn from_points(points: Vec<SweepPoint>) -> Result<Self, SensorError> {
        for (k, p) in points.iter().enumerate() {
            if !is_finite_point(&p.point) {
                return Err(sweep_error(format!(
                    "point {k} has a non-finite coordinate"
                )));
            }
            if !is_finite_point(&p.origin) {
                return Err(sweep_error(format!(
                    "the ray origin of point {k} has a non-finite coordinate"
                )));
            }
            if !p.intensity.is_finite() {
                return Err(sweep_error(format!(
                    "point {k}: intensity {} is not finite",
                    p.intensity
                )));
            }
        }
        let with_cells = points.iter().filter(|p| p.cell.is_some()).count();
        let shape = if with_cells == 0 {
            None
        } else if with_cells < points.len() {
            return Err(sweep_error(format!(
                "{with_cells} of {} points have a (scan, ray) cell: give a cell for every point or for none",
                points.len()
            )));
        } else {
            let mut rays = 0;
            let mut prev: Option<GridCell> = None;
            for (k, p) in points.iter().enumerate() {
                let Some(c) = p.cell else { continue };
                if let Some(q) = prev
                    && c <= q
                {
                    return Err(sweep_error(format!(
                        "point {k}: cell (scan {}, ray {}) follows (scan {}, ray {}); cells must be strictly increasing, scan-major",
                        c.scan, c.ray, q.scan, q.ray
                    )));
                }
                rays = rays.max(c.ray + 1);
                prev = Some(c);
            }
            let scans = prev.map_or(0, |c| c.scan + 1);
            Some(GridShape {
                scans,
                rays_per_scan: rays,
            })
        };
        Ok(Self {
            points,
            shape,
            scanner_poses: Vec::new(),
            bearings_rad: Vec::new(),
            misses: Vec::new(),
        })
    }

    /// A sweep from a range grid: bearings `θ_i`, the `world_from_scanner`
    /// pose of each scan, and the ranges in scan-major order
    /// (`ranges_m[j·n + i]` is ray `i` of scan `j`; `None` = no return). The
    /// point of a return is `world_from_scanner_j · r·`[`beam_direction`]`(θ_i)`
    /// (A eq. 4.7); intensities are 0 and materials unknown.
    pub fn from_range_grid(
        bearings_rad: &[Real],
        scanner_poses: &[Isometry3],
        ranges_m: &[Option<Real>],
    ) -> Result<Self, SensorError> {
        let n = bearings_rad.len();
        if ranges_m.len() != n * scanner_poses.len() {
            return Err(sweep_error(format!(
                "{} ranges given for {} scans of {n} rays (expected {})",
                ranges_m.len(),
                scanner_poses.len(),
                n * scanner_poses.len()
            )));
        }
        let mut b = SweepBuilder::new(bearings_rad)?;
        let zeros = vec![0.0; n];
        for (pose, row) in scanner_poses.iter().zip(ranges_m.chunks(n.max(1))) {
            b.push_scan(pose, row, &zeros, None)?;
        }
        b.finish()
    }

    /// The returns, scan-major when the sweep has a grid, else in source order.
    pub fn points(&self) -> &[SweepPoint] {
        &self.points
    }

    /// Number of returns.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// `true` when no ray returned.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The grid's size, when the sweep keeps its grid.
    pub fn grid_shape(&self) -> Option<GridShape> {
        self.shape
    }

    /// `world_from_scanner` of every scan, where the sweep was taken by a
    /// scanner in this process (empty for sweeps read from files).
    pub fn scanner_poses(&self) -> &[Isometry3] {
        &self.scanner_poses
    }

    /// The ray bearings `θ_i`, where known (empty for sweeps read from files).
    pub fn bearings_rad(&self) -> &[Real] {
        &self.bearings_rad
    }

    /// Every beam of a scanner's sweep that returned nothing, as its origin
    /// and unit direction in the world, in (scan, ray) order (empty for
    /// sweeps read from files). A scan taken while the arm moved measured
    /// each beam from a pose of its own ([`SweepBuilder::push_scan_posed`]).
    pub fn misses(&self) -> &[(Point3, Vector3)] {
        &self.misses
    }

    /// The same returns as a plain list: no grid cells, scanner poses or
    /// bearings (what a foreign cloud with ray origins gives).
    pub fn without_grid(&self) -> Self {
        Self {
            points: self
                .points
                .iter()
                .map(|p| SweepPoint { cell: None, ..*p })
                .collect(),
            shape: None,
            scanner_poses: Vec::new(),
            bearings_rad: Vec::new(),
            misses: Vec::new(),
        }
    }

    /// The measured points alone.
    pub fn positions(&self) -> Vec<Point3> {
        self.points.iter().map(|p| p.point).collect()
    }

    /// The ray origins alone.
    pub fn origins(&self) -> Vec<Point3> {
        self.points.iter().map(|p| p.origin).collect()
    }

    /// Index of the return in `cell`, if any (binary search on the grid).
    pub fn find(&self, cell: GridCell) -> Option<usize> {
        self.shape?;
        self.points
            .binary_search_by(|p| p.cell.cmp(&Some(cell)))
            .ok()
    }

    /// Pairs `(k, l)` of returns that are neighbours on the grid: the next
    /// ray of the same scan (`|r_{i,j} − r_{i+1,j}|` of A§4.2.1) and the same
    /// ray of the next scan (`|r_{i,j} − r_{i,j+1}|`). Empty without a grid.
    pub fn grid_neighbours(&self) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        if self.shape.is_none() {
            return out;
        }
        // The points are in cell order, so the cells one scan on are too:
        // one pointer walks them beside `k` (what `find` would give each).
        let mut next = 0;
        for (k, p) in self.points.iter().enumerate() {
            let Some(c) = p.cell else { continue };
            if let Some(q) = self.points.get(k + 1).and_then(|q| q.cell)
                && q.scan == c.scan
                && q.ray == c.ray + 1
            {
                out.push((k, k + 1));
            }
            let below = Some(GridCell {
                scan: c.scan + 1,
                ray: c.ray,
            });
            while self.points.get(next).is_some_and(|q| q.cell < below) {
                next += 1;
            }
            if self.points.get(next).is_some_and(|q| q.cell == below) {
                out.push((k, next));
            }
        }
        out
    }
}

/// Builds a [`Sweep`] scan by scan from what a scanner reports (ranges per
/// bearing and the pose the scan was taken from), so simulated and real
/// scanners make sweeps the same way.
#[derive(Clone, Debug)]
pub struct SweepBuilder {
    bearings_rad: Vec<Real>,
    dirs: Vec<Vector3>,
    points: Vec<SweepPoint>,
    poses: Vec<Isometry3>,
    misses: Vec<(Point3, Vector3)>,
}

impl SweepBuilder {
    /// A builder for scans with these bearings `θ_i` (radians, finite, at
    /// least one).
    pub fn new(bearings_rad: &[Real]) -> Result<Self, SensorError> {
        if bearings_rad.is_empty() {
            return Err(sweep_error("no bearings: a scan needs at least one ray"));
        }
        if let Some(i) = bearings_rad.iter().position(|b| !b.is_finite()) {
            return Err(sweep_error(format!("bearing {i} is not finite")));
        }
        Ok(Self {
            bearings_rad: bearings_rad.to_vec(),
            dirs: bearings_rad.iter().map(|b| beam_direction(*b)).collect(),
            points: Vec::new(),
            poses: Vec::new(),
            misses: Vec::new(),
        })
    }

    /// Add the next scan: one range per bearing (`None`: no return), the
    /// intensities (one per bearing), and ground-truth materials where known.
    /// Fails, adding nothing, on a length mismatch, a non-finite pose, or a
    /// range that is not a finite non-negative distance.
    pub fn push_scan(
        &mut self,
        world_from_scanner: &Isometry3,
        ranges_m: &[Option<Real>],
        intensities: &[Real],
        materials: Option<&[Option<MaterialId>]>,
    ) -> Result<(), SensorError> {
        self.push(
            std::slice::from_ref(world_from_scanner),
            ranges_m,
            intensities,
            materials,
        )
    }

    /// Add the next scan, taken while the scanner moved: beam `i` measured
    /// from `world_from_scanner[i]` (one pose per bearing; the scan's pose
    /// in [`Sweep::scanner_poses`] is its first beam's). Otherwise as
    /// [`SweepBuilder::push_scan`].
    pub fn push_scan_posed(
        &mut self,
        world_from_scanner: &[Isometry3],
        ranges_m: &[Option<Real>],
        intensities: &[Real],
        materials: Option<&[Option<MaterialId>]>,
    ) -> Result<(), SensorError> {
        let n = self.bearings_rad.len();
        if world_from_scanner.len() != n {
            return Err(sweep_error(format!(
                "scan {}: {} beam poses for {n} bearings",
                self.poses.len(),
                world_from_scanner.len()
            )));
        }
        self.push(world_from_scanner, ranges_m, intensities, materials)
    }

    /// [`SweepBuilder::push_scan`] with one pose for the whole scan, or
    /// one per beam.
    fn push(
        &mut self,
        poses: &[Isometry3],
        ranges_m: &[Option<Real>],
        intensities: &[Real],
        materials: Option<&[Option<MaterialId>]>,
    ) -> Result<(), SensorError> {
        let n = self.bearings_rad.len();
        let j = self.poses.len();
        if ranges_m.len() != n || intensities.len() != n || materials.is_some_and(|m| m.len() != n)
        {
            return Err(sweep_error(format!(
                "scan {j}: {} ranges, {} intensities{} for {n} bearings",
                ranges_m.len(),
                intensities.len(),
                materials.map_or(String::new(), |m| format!(", {} materials", m.len()))
            )));
        }
        if let Some(k) = poses.iter().position(|p| !is_finite_pose(p)) {
            return Err(sweep_error(if poses.len() == 1 {
                format!("scanner pose of scan {j} is not finite")
            } else {
                format!("scanner pose of scan {j}, ray {k} is not finite")
            }));
        }
        if let Some(i) = ranges_m
            .iter()
            .position(|r| r.is_some_and(|r| !(r.is_finite() && r >= 0.0)))
        {
            return Err(sweep_error(format!(
                "range of scan {j}, ray {i} is {:?}: expected a finite, non-negative distance",
                ranges_m[i]
            )));
        }
        let Some(&first) = poses.first() else {
            return Err(sweep_error(format!("scan {j}: no scanner pose")));
        };
        for (i, r) in ranges_m.iter().enumerate() {
            let pose = poses.get(i).unwrap_or(&first);
            let origin = Point3::from(pose.translation.vector);
            let Some(r) = r else {
                self.misses.push((origin, pose.rotation * self.dirs[i]));
                continue;
            };
            self.points.push(SweepPoint {
                point: origin + pose.rotation * (self.dirs[i] * *r),
                origin,
                intensity: intensities[i],
                material: materials.and_then(|m| m[i]),
                cell: Some(GridCell {
                    scan: j as u32,
                    ray: i as u32,
                }),
            });
        }
        self.poses.push(first);
        Ok(())
    }

    /// Scans added so far.
    pub fn scan_count(&self) -> usize {
        self.poses.len()
    }

    /// The points of the scans added so far, in the order they came.
    pub fn points(&self) -> &[SweepPoint] {
        &self.points
    }

    /// The sweep (empty when no ray returned).
    pub fn finish(self) -> Result<Sweep, SensorError> {
        let mut sweep = Sweep::from_points(self.points)?;
        sweep.shape = Some(GridShape {
            scans: self.poses.len() as u32,
            rays_per_scan: self.bearings_rad.len() as u32,
        });
        sweep.scanner_poses = self.poses;
        sweep.bearings_rad = self.bearings_rad;
        sweep.misses = self.misses;
        Ok(sweep)
    }
}

fn is_finite_pose(p: &Isometry3) -> bool {
    p.translation.vector.iter().all(|v| v.is_finite())
        && p.rotation.coords.iter().all(|v| v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The neighbour pairs against the definition (each return's next ray
    /// on its scan, and its ray on the next scan found by `find`), on grids
    /// with returns missing at random, whole scans missing, and none.
    #[test]
    fn grid_neighbours_are_the_next_ray_and_the_next_scan() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(4);
        for keep in [1.0, 0.9, 0.5, 0.1] {
            let mut points = Vec::new();
            for scan in 0..25u32 {
                if scan % 7 == 3 {
                    continue;
                }
                for ray in 0..40u32 {
                    if rng.random_range(0.0..1.0) < keep {
                        let v = Real::from(scan) + 0.01 * Real::from(ray);
                        points.push(SweepPoint {
                            point: Point3::new(v, 1.0, 0.0),
                            origin: Point3::origin(),
                            intensity: 0.0,
                            material: None,
                            cell: Some(GridCell { scan, ray }),
                        });
                    }
                }
            }
            let sweep = Sweep::from_points(points).unwrap();
            let mut expected = Vec::new();
            for (k, p) in sweep.points().iter().enumerate() {
                let c = p.cell.unwrap();
                if let Some(l) = sweep.find(GridCell {
                    scan: c.scan,
                    ray: c.ray + 1,
                }) {
                    expected.push((k, l));
                }
                if let Some(l) = sweep.find(GridCell {
                    scan: c.scan + 1,
                    ray: c.ray,
                }) {
                    expected.push((k, l));
                }
            }
            assert_eq!(sweep.grid_neighbours(), expected, "keep {keep}");
        }
    }

    #[test]
    fn default_sweep_has_151_scans_over_60_degrees() {
        let s = SweepConfig::default();
        assert_eq!(s.scan_count(), 151);
        let t = s.tilt_values(0.0, None);
        assert!((t[0] + 30f64.to_radians()).abs() < 1e-12);
        assert!((t[150] - 30f64.to_radians()).abs() < 1e-9);
        // Near a limit the window slides inside it.
        let lim = (-120f64.to_radians(), 120f64.to_radians());
        let t = s.tilt_values(-110f64.to_radians(), Some(lim));
        assert!((t[0] - lim.0).abs() < 1e-12);
        assert!(t.iter().all(|v| *v >= lim.0 - 1e-12 && *v <= lim.1 + 1e-12));
        // At the upper limit every value stays inside it exactly (a robot
        // refuses a joint an ulp past its limit).
        for centre in [120.0f64, 119.9, 95.0] {
            let t = s.tilt_values(centre.to_radians(), Some(lim));
            assert!(t.iter().all(|v| *v >= lim.0 && *v <= lim.1), "{centre}");
            assert_eq!(*t.last().unwrap(), lim.1.min(t[0] + 60f64.to_radians()));
        }
        assert!(SweepConfig { step_deg: 0.0, ..s }.validate().is_err());
    }

    /// Issue 48: a step past the whole tilt swept one scan without a word.
    #[test]
    fn a_step_past_the_tilt_is_refused() {
        for step_deg in [1e308, 60.5] {
            let e = SweepConfig {
                step_deg,
                ..SweepConfig::default()
            }
            .validate()
            .unwrap_err()
            .to_string();
            assert!(
                e.contains("step_deg") && e.contains("at most tilt_deg"),
                "{e}"
            );
        }
        let whole = SweepConfig {
            step_deg: 60.0,
            ..SweepConfig::default()
        };
        assert_eq!(whole.validate().map(|()| whole.scan_count()).unwrap(), 2);
        let still = SweepConfig {
            tilt_deg: 0.0,
            step_deg: 5.0,
            ..SweepConfig::default()
        };
        assert!(still.validate().is_ok());
    }

    #[test]
    fn sweeps_over_budget_are_refused_before_allocating() {
        // Issue 8: step_deg = 1e-7 asked for 6·10⁸ scans and aborted the process.
        let tiny = SweepConfig {
            step_deg: 1e-7,
            ..SweepConfig::default()
        };
        assert_eq!(tiny.scan_count(), 600_000_001);
        let err = tiny.validate().unwrap_err().to_string();
        assert_eq!(
            err,
            "sensor config `step_deg` = 0.0000001 gives 600000001 scans per sweep, more than the limit of 100000"
        );
        // The limit itself: 360° at 0.0036° is 100 001 scans, 0.00360002° fits.
        let at = |step_deg| SweepConfig {
            tilt_deg: 360.0,
            step_deg,
            joint: 5,
        };
        assert_eq!(at(0.0036).scan_count(), 100_001);
        assert!(at(0.0036).validate().is_err());
        assert_eq!(at(0.003_600_02).scan_count(), 100_000);
        assert!(at(0.003_600_02).validate().is_ok());
        // Scans × rays: the default scanner (342 rays) over 20 000 scans is 6.8 M rays.
        let scanner = ScannerConfig::default();
        assert_eq!(scanner.ray_count(), 342);
        assert!(SweepConfig::default().validate_with(&scanner).is_ok());
        let long = SweepConfig {
            step_deg: 60.0 / 20_000.0,
            ..SweepConfig::default()
        };
        assert!(long.validate().is_ok());
        let err = long.validate_with(&scanner).unwrap_err().to_string();
        assert!(err.contains("6840342 rays per sweep"), "{err}");
        assert!(err.contains("limit of 4000000"), "{err}");
    }
}
