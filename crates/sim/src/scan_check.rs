//! Checks of a run against a real scan (issue 9, acceptance 5): when the world
//! is a point cloud there is no solid truth to collide with or to score faces
//! against, but two things can still be measured against the scan points:
//!
//! * **clearance**: the smallest distance from the robot's link capsules to any
//!   scan point ([`ScanIndex::capsule_distance`], [`scan_clearance`]), taken
//!   at every pose of a run by [`crate::follow_job::FollowJudge`];
//! * **model accuracy**: for every non-initial polygon of a surface model, the
//!   largest distance from the polygon (sampled densely over its interior and
//!   perimeter, plus its vertices) to the nearest scan point, and the share of
//!   its area within λ of the scan ([`model_to_scan`]).
//!
//! Both use a kd-tree over the points ([`ScanIndex`]), so a query costs about
//! a logarithm of the cloud's size rather than a pass over it.

use crate::SimError;
use geom::polygon2;
use geom::{Capsule, Isometry3, PlaneFrame, Point2, Point3, Real, polygon3::newell_normal, unit};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use rayon::prelude::*;
use robot::{PosedShape, Robot};
use serde::{Deserialize, Serialize};
use surface::{SegmentId, SurfaceModel};

/// Longest piece of a capsule axis answered by one kd-tree query in
/// [`ScanIndex::capsule_distance`], metres (longer axes are split).
const AXIS_PIECE_M: Real = 0.02;

/// Most pieces one capsule axis is split into (a longer axis gets longer pieces).
const MAX_AXIS_PIECES: usize = 1024;

/// Most samples one [`model_to_scan`] may take; a finer spacing over a larger
/// model is refused.
pub const MAX_MODEL_SCAN_SAMPLES: usize = 50_000_000;

/// The points of a scan (world frame) in a kd-tree, for nearest-point queries.
#[derive(Debug)]
pub struct ScanIndex {
    tree: ImmutableKdTree<Real, 3>,
    points: Vec<[Real; 3]>,
}

impl ScanIndex {
    /// An index over `points`. Errors: no points, or a non-finite coordinate.
    pub fn new(points: &[Point3]) -> Result<Self, SimError> {
        if points.is_empty() {
            return Err(SimError::InvalidArgument {
                what: "scan points".into(),
                message: "expected at least one point".into(),
            });
        }
        if let Some(i) = points.iter().position(|p| !geom::math::is_finite_point(p)) {
            return Err(SimError::InvalidArgument {
                what: "scan points".into(),
                message: format!("point {i} has a non-finite coordinate"),
            });
        }
        let points: Vec<[Real; 3]> = points.iter().map(|p| [p.x, p.y, p.z]).collect();
        Ok(Self {
            tree: ImmutableKdTree::new_from_slice(&points),
            points,
        })
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// `true` when there are no points (never: [`ScanIndex::new`] refuses that).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Distance from `p` to the nearest scan point.
    pub fn nearest_distance(&self, p: &Point3) -> Real {
        self.tree
            .nearest_one::<SquaredEuclidean>(&[p.x, p.y, p.z])
            .distance
            .sqrt()
    }

    /// Distance from the surface of `capsule` to the nearest scan point (0 when
    /// a point is inside it). Exact: the axis is split into pieces of at most
    /// `AXIS_PIECE_M` (0.02 m); the nearest point to each piece's midpoint bounds the
    /// axis distance from above, and every piece that could still hold a
    /// closer point is searched with a ball query around its midpoint that
    /// covers all points within that bound of the piece.
    pub fn capsule_distance(&self, capsule: &Capsule) -> Real {
        let seg = &capsule.segment;
        let len = seg.length();
        let pieces = ((len / AXIS_PIECE_M).ceil() as usize).clamp(1, MAX_AXIS_PIECES);
        let half = 0.5 * len / pieces as Real;
        let mids: Vec<Point3> = (0..pieces)
            .map(|i| seg.a + (seg.b - seg.a) * ((i as Real + 0.5) / pieces as Real))
            .collect();
        let near: Vec<Real> = mids.iter().map(|m| self.nearest_distance(m)).collect();
        // Every midpoint is on the axis: the nearest point to it bounds the
        // axis distance.
        let mut best = near.iter().copied().fold(Real::INFINITY, Real::min);
        // A piece's points are at least (distance to its midpoint − half) away.
        let mut order: Vec<usize> = (0..pieces).collect();
        order.sort_by(|&a, &b| near[a].total_cmp(&near[b]));
        for i in order {
            if near[i] - half >= best {
                continue;
            }
            let r = best + half;
            let m = mids[i];
            for n in self
                .tree
                .within_unsorted::<SquaredEuclidean>(&[m.x, m.y, m.z], r * r)
            {
                let q = self.points[n.item as usize];
                best = best.min(seg.distance_to_point(&Point3::new(q[0], q[1], q[2])));
            }
        }
        (best - capsule.radius).max(0.0)
    }
}

/// Smallest distance from the robot's link capsules (links ≥ 1; the base is
/// mounted on the scene) to the scan, at the given link frames
/// (`base_from_link`, from forward kinematics); `None` when no such link has a
/// capsule (mesh-shaped links are not measured here, unlike in
/// [`plan::contact::min_clearance`], which measures them against a scene's
/// triangles).
pub fn scan_clearance(
    robot: &Robot,
    base_from_link: &[Isometry3],
    world_from_base: &Isometry3,
    scan: &ScanIndex,
) -> Option<Real> {
    robot
        .posed_collision_shapes(base_from_link)
        .into_iter()
        .filter_map(|s| match s {
            PosedShape::Capsule { link, capsule } if link.index() >= robot.mounted_links() => {
                Some(scan.capsule_distance(&capsule.transformed(world_from_base)))
            }
            _ => None,
        })
        .min_by(Real::total_cmp)
}

/// Settings of [`model_to_scan`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ModelScanConfig {
    /// A sample is within tolerance when a scan point is within this distance,
    /// metres (Pudney's λ, default 0.05).
    pub lambda_m: Real,
    /// Spacing of the samples, metres: a square grid over each polygon's
    /// interior and points along its perimeter (default 0.005 = λ/10).
    pub sample_spacing_m: Real,
}

impl Default for ModelScanConfig {
    fn default() -> Self {
        Self {
            lambda_m: 0.05,
            sample_spacing_m: 0.005,
        }
    }
}

impl ModelScanConfig {
    /// Both distances finite > 0. Errors name the field.
    pub fn validate(&self) -> Result<(), SimError> {
        for (what, v) in [
            ("lambda_m", self.lambda_m),
            ("sample_spacing_m", self.sample_spacing_m),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(SimError::InvalidArgument {
                    what: format!("model_to_scan.{what}"),
                    message: format!("expected a finite distance > 0 (metres), got {v}"),
                });
            }
        }
        Ok(())
    }
}

/// One polygon against the scan.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PolygonScanScore {
    /// The model segment (`None` for a polygon given by its vertices alone).
    pub segment: Option<SegmentId>,
    /// Vertices.
    pub vertices: usize,
    /// Vertices within λ of a scan point.
    pub vertices_within_lambda: usize,
    /// Area, m².
    pub area_m2: Real,
    /// Outward unit normal.
    pub normal: [Real; 3],
    /// Centroid (of the represented points, for a model polygon).
    pub centroid: [Real; 3],
    /// Samples taken (interior grid, perimeter, vertices).
    pub samples: usize,
    /// The largest distance of a sample to the nearest scan point, metres.
    pub max_m: Real,
    /// Where that sample is.
    pub max_at: [Real; 3],
    /// Area fraction of the interior samples within λ of a scan point, `[0, 1]`
    /// (the perimeter samples' fraction for a polygon too thin to hold any).
    pub within_lambda_fraction: Real,
    /// `true` when every sample is within λ ([`PolygonScanScore::max_m`] ≤ λ).
    pub within_lambda: bool,
}

/// A surface model against a scan (for `run.json`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ModelScanScore {
    /// The settings used.
    pub config: ModelScanConfig,
    /// Per non-initial polygon, in segment order.
    pub polygons: Vec<PolygonScanScore>,
    /// The largest [`PolygonScanScore::max_m`]; `None` without polygons.
    pub max_m: Option<Real>,
    /// Area-weighted [`PolygonScanScore::within_lambda_fraction`] over the
    /// polygons, `[0, 1]` (1 without polygons).
    pub within_lambda_fraction: Real,
    /// Polygons with a sample farther than λ from the scan.
    pub polygons_beyond_lambda: usize,
    /// Share of the polygons' vertices within λ of a scan point, `[0, 1]` (1
    /// without polygons).
    pub vertices_within_lambda_fraction: Real,
}

/// Samples of a polygon: vertices, perimeter points at most `spacing` apart,
/// and the centres of the `spacing` grid cells (in `frame`'s 2-D coordinates)
/// inside it. Returns (interior samples, boundary samples).
fn polygon_samples(
    frame: &PlaneFrame,
    vertices: &[Point3],
    spacing: Real,
) -> (Vec<Point3>, Vec<Point3>) {
    let n = vertices.len();
    let mut boundary = Vec::new();
    for i in 0..n {
        let (a, b) = (vertices[i], vertices[(i + 1) % n]);
        let k = (((b - a).norm() / spacing).ceil() as usize).max(1);
        for j in 0..k {
            boundary.push(a + (b - a) * (j as Real / k as Real));
        }
    }
    let pts: Vec<Point2> = vertices.iter().map(|v| frame.to_2d(v)).collect();
    let (mut lo, mut hi) = (
        Point2::new(Real::INFINITY, Real::INFINITY),
        Point2::new(Real::NEG_INFINITY, Real::NEG_INFINITY),
    );
    for p in &pts {
        lo = Point2::new(lo.x.min(p.x), lo.y.min(p.y));
        hi = Point2::new(hi.x.max(p.x), hi.y.max(p.y));
    }
    let mut interior = Vec::new();
    if n >= 3 {
        let nx = ((hi.x - lo.x) / spacing).ceil() as usize;
        let ny = ((hi.y - lo.y) / spacing).ceil() as usize;
        for i in 0..nx {
            for j in 0..ny {
                let q = Point2::new(
                    lo.x + (i as Real + 0.5) * spacing,
                    lo.y + (j as Real + 0.5) * spacing,
                );
                if polygon2::contains_point(&pts, &q, 0.0) {
                    interior.push(frame.to_3d(&q));
                }
            }
        }
    }
    (interior, boundary)
}

/// Samples [`polygon_samples`] would take, estimated from the polygon's extent.
fn estimated_samples(frame: &PlaneFrame, vertices: &[Point3], spacing: Real) -> Real {
    let pts: Vec<Point2> = vertices.iter().map(|v| frame.to_2d(v)).collect();
    let span = |f: fn(&Point2) -> Real| {
        let (lo, hi) = pts
            .iter()
            .map(f)
            .fold((Real::INFINITY, Real::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
        (hi - lo).max(0.0)
    };
    let perimeter: Real = (0..vertices.len())
        .map(|i| (vertices[(i + 1) % vertices.len()] - vertices[i]).norm())
        .sum();
    (span(|p| p.x) / spacing + 1.0) * (span(|p| p.y) / spacing + 1.0)
        + perimeter / spacing
        + vertices.len() as Real
}

fn score_polygon(
    segment: Option<SegmentId>,
    frame: &PlaneFrame,
    vertices: &[Point3],
    area_m2: Real,
    scan: &ScanIndex,
    cfg: &ModelScanConfig,
) -> PolygonScanScore {
    let (interior, boundary) = polygon_samples(frame, vertices, cfg.sample_spacing_m);
    let lambda = cfg.lambda_m;
    let dist = |pts: &[Point3]| -> Vec<Real> {
        pts.par_iter().map(|p| scan.nearest_distance(p)).collect()
    };
    let (di, db) = (dist(&interior), dist(&boundary));
    let (mut max_m, mut max_at) = (0.0, frame.origin);
    for (p, d) in interior.iter().zip(&di).chain(boundary.iter().zip(&db)) {
        if *d > max_m {
            (max_m, max_at) = (*d, *p);
        }
    }
    let fraction =
        |d: &[Real]| d.iter().filter(|d| **d <= lambda).count() as Real / d.len() as Real;
    let within_lambda_fraction = if di.is_empty() {
        if db.is_empty() { 1.0 } else { fraction(&db) }
    } else {
        fraction(&di)
    };
    let c = frame.origin;
    PolygonScanScore {
        segment,
        vertices: vertices.len(),
        vertices_within_lambda: vertices
            .iter()
            .filter(|v| scan.nearest_distance(v) <= lambda)
            .count(),
        area_m2,
        normal: [frame.normal.x, frame.normal.y, frame.normal.z],
        centroid: [c.x, c.y, c.z],
        samples: interior.len() + boundary.len(),
        max_m,
        max_at: [max_at.x, max_at.y, max_at.z],
        within_lambda_fraction,
        within_lambda: max_m <= lambda,
    }
}

/// One planar polygon, given by its vertices (anticlockwise about its normal,
/// as Newell's normal orients them), against the scan: see [`model_to_scan`].
///
/// Errors: a config failing [`ModelScanConfig::validate`], fewer than three
/// vertices, non-finite vertices, no area, or more than
/// [`MAX_MODEL_SCAN_SAMPLES`] samples needed.
pub fn polygon_to_scan(
    vertices: &[Point3],
    scan: &ScanIndex,
    cfg: &ModelScanConfig,
) -> Result<PolygonScanScore, SimError> {
    cfg.validate()?;
    let bad = |message: &str| SimError::InvalidArgument {
        what: "polygon".into(),
        message: message.into(),
    };
    if vertices.len() < 3 {
        return Err(bad("expected at least three vertices"));
    }
    if !vertices.iter().all(geom::math::is_finite_point) {
        return Err(bad("a vertex has a non-finite coordinate"));
    }
    let newell = newell_normal(vertices);
    let normal = unit(newell).ok_or_else(|| bad("the vertices enclose no area"))?;
    let centroid = Point3::from(
        vertices.iter().map(|v| v.coords).sum::<geom::Vector3>() / vertices.len() as Real,
    );
    let frame = PlaneFrame::new(centroid, normal);
    check_budget(
        estimated_samples(&frame, vertices, cfg.sample_spacing_m),
        cfg,
    )?;
    Ok(score_polygon(
        None,
        &frame,
        vertices,
        0.5 * newell.norm(),
        scan,
        cfg,
    ))
}

fn check_budget(estimate: Real, cfg: &ModelScanConfig) -> Result<(), SimError> {
    if estimate.is_nan() || estimate >= MAX_MODEL_SCAN_SAMPLES as Real {
        return Err(SimError::InvalidArgument {
            what: "model_to_scan.sample_spacing_m".into(),
            message: format!(
                "{} m needs about {estimate:.3e} samples (at most {MAX_MODEL_SCAN_SAMPLES})",
                cfg.sample_spacing_m
            ),
        });
    }
    Ok(())
}

/// Every non-initial polygon of `model` against the scan: the largest distance
/// from the polygon to the nearest scan point, over samples at its vertices,
/// along its perimeter (at most `sample_spacing_m` apart) and at the centres
/// of a `sample_spacing_m` square grid (in the polygon's plane) inside it —
/// so the true largest distance over the polygon exceeds the reported one by
/// at most `sample_spacing_m / √2` — and the area fraction of the interior
/// samples within λ. Point segments and initial (a-priori) segments are not
/// scored. Deterministic: the same inputs give the same report.
///
/// Errors: a config failing [`ModelScanConfig::validate`], or more than
/// [`MAX_MODEL_SCAN_SAMPLES`] samples needed.
pub fn model_to_scan(
    model: &SurfaceModel,
    scan: &ScanIndex,
    cfg: &ModelScanConfig,
) -> Result<ModelScanScore, SimError> {
    cfg.validate()?;
    let polys: Vec<(SegmentId, PlaneFrame, Vec<Point3>, Real)> = model
        .segments()
        .filter(|s| !s.is_initial())
        .filter_map(|s| {
            s.as_polygon()
                .map(|p| (s.id(), p.frame(), p.vertices().collect(), p.area()))
        })
        .collect();
    let estimate: Real = polys
        .iter()
        .map(|(_, f, v, _)| estimated_samples(f, v, cfg.sample_spacing_m))
        .sum();
    check_budget(estimate, cfg)?;
    let polygons: Vec<PolygonScanScore> = polys
        .iter()
        .map(|(id, frame, v, area)| score_polygon(Some(*id), frame, v, *area, scan, cfg))
        .collect();
    let max_m = polygons.iter().map(|p| p.max_m).reduce(Real::max);
    let within_lambda_fraction = crate::surface_score::weighted_mean(
        polygons
            .iter()
            .map(|p| (p.within_lambda_fraction, p.area_m2)),
        1.0,
    );
    let vertices: usize = polygons.iter().map(|p| p.vertices).sum();
    let vertices_within: usize = polygons.iter().map(|p| p.vertices_within_lambda).sum();
    Ok(ModelScanScore {
        config: *cfg,
        vertices_within_lambda_fraction: if vertices == 0 {
            1.0
        } else {
            vertices_within as Real / vertices as Real
        },
        polygons_beyond_lambda: polygons.iter().filter(|p| !p.within_lambda).count(),
        polygons,
        max_m,
        within_lambda_fraction,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points on z = 0, `step` apart, over [−half, half]².
    fn grid(step: Real, half: Real) -> Vec<Point3> {
        let n = (half / step).round() as i64;
        let mut v = Vec::new();
        for i in -n..=n {
            for j in -n..=n {
                v.push(Point3::new(i as Real * step, j as Real * step, 0.0));
            }
        }
        v
    }

    #[test]
    fn rejects_empty_and_non_finite_scans() {
        assert!(ScanIndex::new(&[]).is_err());
        let e = ScanIndex::new(&[Point3::origin(), Point3::new(0.0, Real::NAN, 0.0)])
            .unwrap_err()
            .to_string();
        assert!(e.contains("point 1"), "{e}");
    }

    #[test]
    fn capsule_distance_matches_brute_force() {
        use rand::{RngExt, SeedableRng};
        let pts = grid(0.01, 0.3);
        let scan = ScanIndex::new(&pts).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for _ in 0..200 {
            let mut p = || {
                Point3::new(
                    rng.random_range(-0.4..0.4),
                    rng.random_range(-0.4..0.4),
                    rng.random_range(-0.2..0.4),
                )
            };
            let (a, b) = (p(), p());
            let c = Capsule::new(a, b, 0.02);
            let brute = pts
                .iter()
                .map(|q| c.distance_to_point(q))
                .fold(Real::INFINITY, Real::min)
                .max(0.0);
            assert!((scan.capsule_distance(&c) - brute).abs() < 1e-12, "{c:?}");
        }
    }

    #[test]
    fn model_config_is_checked() {
        let bad = ModelScanConfig {
            sample_spacing_m: 0.0,
            ..ModelScanConfig::default()
        };
        assert!(
            bad.validate()
                .unwrap_err()
                .to_string()
                .contains("sample_spacing_m")
        );
        let scan = ScanIndex::new(&grid(0.1, 0.1)).unwrap();
        let tiny = ModelScanConfig {
            sample_spacing_m: 1e-6,
            ..ModelScanConfig::default()
        };
        let sq = [
            Point3::new(-10.0, -10.0, 0.0),
            Point3::new(10.0, -10.0, 0.0),
            Point3::new(10.0, 10.0, 0.0),
        ];
        assert!(polygon_to_scan(&sq, &scan, &tiny).is_err());
        assert!(polygon_to_scan(&sq[..2], &scan, &ModelScanConfig::default()).is_err());
    }
}
