//! The input of integration: a sweep kept on its (scan, ray) grid, or a plain
//! list of points with the origin of the ray that measured each.
//!
//! A tilt sweep of the 2-D scanner is a matrix of ranges `R_{θ,α}` (A eq.
//! 4.12): row `j` is the scan taken at tilt `α_j` from the pose
//! `world_from_scanner_j`, column `i` the ray at bearing `θ_i`. The point of a
//! return is `world_from_scanner_j · [0, −r sin θ_i, r cos θ_i]` (A eq. 4.7 /
//! 5.1). [`SweepGrid`] keeps that grid, which the occlusion weighting of
//! A§4.2.1 needs (range jumps between adjacent rays). [`PointSweep`] is what a
//! scan file holds: points and per-point ray origins, no grid.

use crate::MapError;
use geom::math::is_finite_point;
use geom::{Isometry3, Point3, Real, Vector3};
use std::path::Path;

/// One sweep on its (scan, ray) grid. Checked on construction: every pose and
/// bearing finite, every range finite and non-negative, the grid complete.
#[derive(Clone, Debug, PartialEq)]
pub struct SweepGrid {
    bearings_rad: Vec<Real>,
    /// `(sin θ_i, cos θ_i)`.
    sin_cos: Vec<(Real, Real)>,
    scanner_poses: Vec<Isometry3>,
    ranges_m: Vec<Option<Real>>,
}

impl SweepGrid {
    /// A sweep from its bearings `θ_i`, the `world_from_scanner` pose of each
    /// scan, and the range grid in scan-major order (`ranges_m[j·n + i]` is ray
    /// `i` of scan `j`; `None` = no return).
    pub fn new(
        bearings_rad: Vec<Real>,
        scanner_poses: Vec<Isometry3>,
        ranges_m: Vec<Option<Real>>,
    ) -> Result<Self, MapError> {
        let n = bearings_rad.len();
        if n == 0 || scanner_poses.is_empty() {
            return Err(MapError::input(
                "sweep",
                format!(
                    "empty sweep ({} scans of {n} rays); a sweep needs at least one scan and one ray",
                    scanner_poses.len()
                ),
            ));
        }
        if ranges_m.len() != n * scanner_poses.len() {
            return Err(MapError::input(
                "sweep",
                format!(
                    "{} ranges given for {} scans of {n} rays (expected {})",
                    ranges_m.len(),
                    scanner_poses.len(),
                    n * scanner_poses.len()
                ),
            ));
        }
        if let Some(i) = bearings_rad.iter().position(|b| !b.is_finite()) {
            return Err(MapError::input(
                "sweep",
                format!("bearing {i} is not finite"),
            ));
        }
        if let Some(j) = scanner_poses.iter().position(|p| !is_finite_pose(p)) {
            return Err(MapError::input(
                "sweep",
                format!("scanner pose of scan {j} is not finite"),
            ));
        }
        if let Some(k) = ranges_m
            .iter()
            .position(|r| r.is_some_and(|r| !(r.is_finite() && r >= 0.0)))
        {
            return Err(MapError::input(
                "sweep",
                format!(
                    "range of scan {}, ray {} is {:?}: expected a finite, non-negative distance",
                    k / n,
                    k % n,
                    ranges_m[k]
                ),
            ));
        }
        let sin_cos = bearings_rad.iter().map(|t| t.sin_cos()).collect();
        Ok(Self {
            bearings_rad,
            sin_cos,
            scanner_poses,
            ranges_m,
        })
    }

    /// A sweep from the scans of a [`sensor::Scanner`] (`bearings_rad` =
    /// [`sensor::Scanner::bearings_rad`]), one per tilt step, in order.
    pub fn from_scans(bearings_rad: &[Real], scans: &[sensor::Scan]) -> Result<Self, MapError> {
        let n = bearings_rad.len();
        let mut ranges = Vec::with_capacity(n * scans.len());
        for (j, scan) in scans.iter().enumerate() {
            if scan.returns.len() != n {
                return Err(MapError::input(
                    "sweep",
                    format!(
                        "scan {j} has {} returns for {n} bearings",
                        scan.returns.len()
                    ),
                ));
            }
            ranges.extend(scan.returns.iter().map(|r| r.map(|r| r.range_m)));
        }
        Self::new(
            bearings_rad.to_vec(),
            scans.iter().map(|s| s.world_from_scanner).collect(),
            ranges,
        )
    }

    /// Number of scans (rows, tilt steps `j`).
    pub fn scan_count(&self) -> usize {
        self.scanner_poses.len()
    }

    /// Rays per scan (columns, bearings `i`).
    pub fn rays_per_scan(&self) -> usize {
        self.bearings_rad.len()
    }

    /// The bearings `θ_i`, radians.
    pub fn bearings_rad(&self) -> &[Real] {
        &self.bearings_rad
    }

    /// `world_from_scanner` of each scan.
    pub fn scanner_poses(&self) -> &[Isometry3] {
        &self.scanner_poses
    }

    /// The range grid, scan-major.
    pub fn ranges_m(&self) -> &[Option<Real>] {
        &self.ranges_m
    }

    /// Range of ray `ray` in scan `scan` (`None`: no return or out of bounds).
    #[inline]
    pub fn range_m(&self, scan: usize, ray: usize) -> Option<Real> {
        if ray >= self.rays_per_scan() {
            return None;
        }
        self.ranges_m
            .get(scan * self.rays_per_scan() + ray)
            .copied()
            .flatten()
    }

    /// The scanner position (origin of every ray) of scan `scan`.
    #[inline]
    pub fn origin(&self, scan: usize) -> Option<Point3> {
        self.scanner_poses
            .get(scan)
            .map(|p| Point3::from(p.translation.vector))
    }

    /// The measured point of ray `ray` in scan `scan` (A eq. 4.7).
    #[inline]
    pub fn point(&self, scan: usize, ray: usize) -> Option<Point3> {
        let r = self.range_m(scan, ray)?;
        let (s, c) = self.sin_cos[ray];
        Some(self.scanner_poses[scan] * Point3::new(0.0, -r * s, r * c))
    }

    /// Number of returns.
    pub fn point_count(&self) -> usize {
        self.ranges_m.iter().filter(|r| r.is_some()).count()
    }

    /// Every return as `(origin, point)`, scan-major.
    pub fn rays(&self) -> Vec<(Point3, Point3)> {
        let n = self.rays_per_scan();
        let mut out = Vec::with_capacity(self.point_count());
        for j in 0..self.scan_count() {
            let o = Point3::from(self.scanner_poses[j].translation.vector);
            for i in 0..n {
                if let Some(p) = self.point(j, i) {
                    out.push((o, p));
                }
            }
        }
        out
    }

    /// Pairs of grid-adjacent returns whose ranges differ by more than
    /// `range_jump_m` (A§4.2.1: `|r_{i,j} − r_{i+1,j}|` along a scan and
    /// `|r_{i,j} − r_{i,j+1}|` across scans), as point pairs.
    pub fn range_jumps(&self, range_jump_m: Real) -> Vec<(Point3, Point3)> {
        let n = self.rays_per_scan();
        let m = self.scan_count();
        let mut out = Vec::new();
        for j in 0..m {
            for i in 0..n {
                let Some(r) = self.range_m(j, i) else {
                    continue;
                };
                for (jj, ii) in [(j, i + 1), (j + 1, i)] {
                    if let Some(r2) = self.range_m(jj, ii)
                        && (r - r2).abs() > range_jump_m
                        && let (Some(p), Some(q)) = (self.point(j, i), self.point(jj, ii))
                    {
                        out.push((p, q));
                    }
                }
            }
        }
        out
    }
}

fn is_finite_pose(p: &Isometry3) -> bool {
    p.translation.vector.iter().all(|v| v.is_finite())
        && p.rotation.coords.iter().all(|v| v.is_finite())
}

/// Check a point list with per-point ray origins: same length, not empty,
/// every coordinate finite. `what` names the input in errors.
pub(crate) fn check_point_list(
    what: &str,
    origins: &[Point3],
    points: &[Point3],
) -> Result<(), MapError> {
    if points.is_empty() {
        return Err(MapError::input(what, "no points"));
    }
    if origins.len() != points.len() {
        return Err(MapError::input(
            what,
            format!(
                "{} origins for {} points: every point needs the origin of its ray",
                origins.len(),
                points.len()
            ),
        ));
    }
    if let Some(i) = points.iter().position(|p| !is_finite_point(p)) {
        return Err(MapError::input(
            what,
            format!("point {i} has a non-finite coordinate"),
        ));
    }
    if let Some(i) = origins.iter().position(|p| !is_finite_point(p)) {
        return Err(MapError::input(
            what,
            format!("origin {i} has a non-finite coordinate"),
        ));
    }
    Ok(())
}

/// Pairs of consecutive points of a plain list that look like neighbouring
/// rays of one scan and whose ranges differ by more than `range_jump_m`.
///
/// A point list has no grid, so the grid is recovered where it safely can be:
/// points `k` and `k + 1` count as neighbours along a scan when they share the
/// same origin exactly (one scan: one scanner position) and their ray
/// directions are at most `max_angle_rad` apart (adjacent bearings; a gap of
/// missing returns or a jump to the next scan row is wider). Neighbours across
/// scans cannot be recovered from a list and are skipped.
pub(crate) fn list_range_jumps(
    origins: &[Point3],
    points: &[Point3],
    range_jump_m: Real,
    max_angle_rad: Real,
) -> Vec<(Point3, Point3)> {
    let cos_max = max_angle_rad.cos();
    let mut out = Vec::new();
    for k in 1..points.len() {
        if origins[k] != origins[k - 1] {
            continue;
        }
        let a: Vector3 = points[k - 1] - origins[k - 1];
        let b: Vector3 = points[k] - origins[k];
        let (ra, rb) = (a.norm(), b.norm());
        if ra == 0.0 || rb == 0.0 || (ra - rb).abs() <= range_jump_m {
            continue;
        }
        if a.dot(&b) >= cos_max * ra * rb {
            out.push((points[k - 1], points[k]));
        }
    }
    out
}

/// A plain sweep: points with the origin of the ray that measured each, as a
/// scan file holds them. Checked on construction (not empty, same lengths,
/// finite). `source` names it in messages (a file path).
#[derive(Clone, Debug, PartialEq)]
pub struct PointSweep {
    source: String,
    origins: Vec<Point3>,
    points: Vec<Point3>,
}

impl PointSweep {
    /// A checked point sweep.
    pub fn new(
        source: impl Into<String>,
        origins: Vec<Point3>,
        points: Vec<Point3>,
    ) -> Result<Self, MapError> {
        let source = source.into();
        check_point_list(&source, &origins, &points)?;
        Ok(Self {
            source,
            origins,
            points,
        })
    }

    /// Read a scan file written by `surveyor scan`: a PLY whose vertices carry
    /// float properties `x y z` (the point) and `ox oy oz` (the ray origin),
    /// world frame. Other properties (`intensity`) are ignored.
    pub fn read_ply(path: &Path) -> Result<Self, MapError> {
        let table = scene::io::read_ply_vertices(path)?;
        let what = path.display().to_string();
        let column = |name: &str| {
            table.column(name).ok_or_else(|| {
                MapError::input(
                    &what,
                    format!(
                        "no vertex property `{name}` (scan files carry x y z and the ray origin ox oy oz)"
                    ),
                )
            })
        };
        let cols = [
            column("x")?,
            column("y")?,
            column("z")?,
            column("ox")?,
            column("oy")?,
            column("oz")?,
        ];
        for (c, name) in cols.iter().zip(["x", "y", "z", "ox", "oy", "oz"]) {
            if let Some(row) = c.iter().position(|v| !v.is_finite()) {
                return Err(MapError::input(
                    &what,
                    format!("vertex {row}: `{name}` is not finite ({})", c[row]),
                ));
            }
        }
        let n = table.len();
        let points = (0..n)
            .map(|i| Point3::new(cols[0][i], cols[1][i], cols[2][i]))
            .collect();
        let origins = (0..n)
            .map(|i| Point3::new(cols[3][i], cols[4][i], cols[5][i]))
            .collect();
        Self::new(what, origins, points)
    }

    /// Where the points came from.
    pub fn source(&self) -> &str {
        &self.source
    }

    /// Ray origins, one per point.
    pub fn origins(&self) -> &[Point3] {
        &self.origins
    }

    /// The measured points.
    pub fn points(&self) -> &[Point3] {
        &self.points
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Always `false`: a point sweep is never empty.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}
