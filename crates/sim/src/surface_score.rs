//! Ground-truth scoring of a surface model (SPEC §6; Pudney's acceptance: every
//! reachable face modelled, shared edges where faces meet, corner vertices
//! where three meet, no stray polygons).
//!
//! The truth is a [`Scene`]'s triangles grouped into [`TrueFace`]s: maximal
//! sets of coplanar triangles connected through shared edges
//! ([`true_faces`], of `scene::faces`). The caller says which faces count (e.g. not the faces
//! resting on the table, [`not_resting_on`]); [`score_surface_model`] then
//! reports, against a [`SurfaceModel`]:
//!
//! * per counted face, the area fraction of uniform samples (at least one per
//!   `sample_spacing_m²`) within λ of a model polygon *on that face*;
//! * per true edge between two counted faces whose normals differ by more than
//!   μ, the fraction of its length along which the model has a shared edge
//!   (within λ) between a polygon on one face and a polygon on the other;
//! * per true corner of counted faces (a vertex where three faces with
//!   pairwise normal angles above μ meet), whether a model corner vertex of a
//!   polygon on one of them lies within λ;
//! * stray polygons (on no true face) and the share of the points they hold;
//! * accuracy: distances of the model's polygon vertices to the scene.
//!
//! A polygon is *on* a face when its normal is within μ of the face's, its
//! centroid is within λ of the face's plane, and its centroid or a vertex is
//! within λ of the face's triangles.

use crate::SimError;
use crate::metrics::DistanceStats;
use geom::polygon2;
use geom::{Aabb, PlaneFrame, Point2, Point3, Real, Segment3, UnitVector3};
use rayon::prelude::*;
use scene::Scene;
pub use scene::faces::{TrueFace, not_resting_on, true_faces};
use scene::faces::{VertexKey, group_faces, mesh_topology, triangle_samples};
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet, HashMap};
use surface::{SegmentId, SurfaceModel};

/// Most samples one scoring may take (faces and edges together); a finer
/// spacing over a larger area is refused.
pub const MAX_SCORE_SAMPLES: usize = 50_000_000;

/// Settings of [`score_surface_model`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SurfaceScoreConfig {
    /// Distance within which a sample, edge point or corner is matched, metres
    /// (Pudney's λ, default 0.05).
    pub lambda_m: Real,
    /// Angle tolerance, degrees (Pudney's μ, default 10): polygon normal
    /// against face normal, and the least dihedral angle of a true edge.
    pub mu_deg: Real,
    /// Sample spacing, metres: at least one face sample per `spacing²` and one
    /// edge sample per `spacing` of length (default 0.005, SPEC §6).
    pub sample_spacing_m: Real,
}

impl Default for SurfaceScoreConfig {
    fn default() -> Self {
        Self {
            lambda_m: 0.05,
            mu_deg: 10.0,
            sample_spacing_m: 0.005,
        }
    }
}

impl SurfaceScoreConfig {
    /// `lambda_m` and `sample_spacing_m` finite > 0, `mu_deg` in `(0, 90)`.
    /// Errors name the field.
    pub fn validate(&self) -> Result<(), SimError> {
        let bad = |what: &str, message: String| {
            Err(SimError::InvalidArgument {
                what: format!("surface_score.{what}"),
                message,
            })
        };
        if !(self.lambda_m.is_finite() && self.lambda_m > 0.0) {
            return bad(
                "lambda_m",
                format!(
                    "expected a finite distance > 0 (metres), got {}",
                    self.lambda_m
                ),
            );
        }
        if !(self.mu_deg.is_finite() && self.mu_deg > 0.0 && self.mu_deg < 90.0) {
            return bad(
                "mu_deg",
                format!("expected an angle in (0, 90) degrees, got {}", self.mu_deg),
            );
        }
        if !(self.sample_spacing_m.is_finite() && self.sample_spacing_m > 0.0) {
            return bad(
                "sample_spacing_m",
                format!(
                    "expected a finite distance > 0 (metres), got {}",
                    self.sample_spacing_m
                ),
            );
        }
        Ok(())
    }
}

/// Coverage of one counted face.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FaceScore {
    /// The face ([`TrueFace::id`]).
    pub face: usize,
    /// Name of its scene object.
    pub object: String,
    /// Outward normal.
    pub normal: [Real; 3],
    /// Area, m².
    pub area_m2: Real,
    /// Samples taken.
    pub samples: usize,
    /// Area fraction of the samples within λ of a polygon on the face, `[0, 1]`.
    pub covered_fraction: Real,
    /// Area fraction of the samples within λ of any model polygon, whatever
    /// its normal, `[0, 1]` (initial segments excluded). On a curved surface
    /// the true mesh's facets are narrower than μ, and a polygon spanning
    /// several of them is "on" only those within μ of its normal; this is
    /// "within λ of the model" alone (issue 9, acceptance 4).
    pub within_lambda_fraction: Real,
    /// Model polygons on the face.
    pub polygons: usize,
    /// Angle between the face normal and the normal of the largest polygon on
    /// it, degrees (`None` without a polygon).
    pub normal_error_deg: Option<Real>,
}

/// Shared-edge coverage of one true edge.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EdgeScore {
    /// The two faces, lower id first.
    pub faces: [usize; 2],
    /// Angle between their normals, degrees.
    pub dihedral_deg: Real,
    /// Length of the edge, metres.
    pub length_m: Real,
    /// Length fraction along which the model has a shared edge between
    /// polygons on the two faces within λ, `[0, 1]`.
    pub covered_fraction: Real,
}

/// One true corner.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CornerScore {
    /// Where it is.
    pub position: [Real; 3],
    /// The faces meeting there.
    pub faces: Vec<usize>,
    /// `true` when a model corner vertex of a polygon on one of them is within λ.
    pub found: bool,
}

/// Model polygons on no true face.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StrayScore {
    /// How many (initial segments excluded).
    pub polygons: usize,
    /// Share of all points fed to the model that they represent, `[0, 1]`.
    pub points_share: Real,
    /// The largest share one of them holds, `[0, 1]`.
    pub max_points_share: Real,
    /// Share of the points held by point segments, `[0, 1]`.
    pub point_segments_share: Real,
}

/// The score of a surface model against the ground truth (for `run.json`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SurfaceScore {
    /// The settings used.
    pub config: SurfaceScoreConfig,
    /// Per counted face.
    pub faces: Vec<FaceScore>,
    /// Area-weighted coverage of all counted faces, `[0, 1]`.
    pub coverage: Real,
    /// Area-weighted [`FaceScore::within_lambda_fraction`] of all counted
    /// faces, `[0, 1]`.
    pub within_lambda: Real,
    /// The counted faces' area within λ of a model polygon, m².
    pub modelled_m2: Real,
    /// Per true edge between counted faces.
    pub edges: Vec<EdgeScore>,
    /// Length-weighted shared-edge coverage of all those edges, `[0, 1]`
    /// (1 when there are none).
    pub edge_coverage: Real,
    /// Per true corner of counted faces.
    pub corners: Vec<CornerScore>,
    /// Corners with a model corner vertex.
    pub corners_found: usize,
    /// Polygons on no true face.
    pub stray: StrayScore,
    /// Distances of the model's polygon vertices (initial segments excluded)
    /// to the scene; `None` without such vertices.
    pub vertex_accuracy: Option<DistanceStats>,
}

/// A model polygon prepared for distance queries.
struct PolyCache {
    id: SegmentId,
    frame: PlaneFrame,
    pts: Vec<Point2>,
    bounds: Aabb,
}

impl PolyCache {
    fn distance(&self, p: &Point3) -> Real {
        let q = self.frame.to_2d(p);
        let h = self.frame.height(p);
        if polygon2::contains_point(&self.pts, &q, 0.0) {
            return h.abs();
        }
        let n = self.pts.len();
        let d = (0..n)
            .map(|i| polygon2::distance_point_segment(&q, &self.pts[i], &self.pts[(i + 1) % n]))
            .fold(Real::INFINITY, Real::min);
        d.hypot(h)
    }
}

fn face_distance(scene: &Scene, face: &TrueFace, p: &Point3) -> Real {
    face.triangles
        .iter()
        .map(|&t| scene.mesh().triangle(t as usize).distance_to_point(p))
        .fold(Real::INFINITY, Real::min)
}

/// Whether polygon (normal, centroid, vertices) is on `face`.
fn is_on(
    scene: &Scene,
    face: &TrueFace,
    cfg: &SurfaceScoreConfig,
    normal: &UnitVector3,
    centroid: &Point3,
    vertices: &[Point3],
) -> bool {
    let lambda = cfg.lambda_m;
    if normal.dot(&face.normal) < cfg.mu_deg.to_radians().cos()
        || (face.normal.dot(&centroid.coords) - face.offset).abs() >= lambda
    {
        return false;
    }
    let near = |p: &Point3| {
        face.bounds.distance_squared_to_point(p) < lambda * lambda
            && face_distance(scene, face, p) < lambda
    };
    near(centroid) || vertices.iter().any(near)
}

/// The weighted mean of `(value, weight)` pairs; `empty` when the weights sum
/// to zero (area- or length-weighted fractions of faces, edges, polygons).
pub(crate) fn weighted_mean(
    pairs: impl Iterator<Item = (Real, Real)> + Clone,
    empty: Real,
) -> Real {
    let total: Real = pairs.clone().map(|(_, w)| w).sum();
    if total > 0.0 {
        pairs.map(|(v, w)| v * w).sum::<Real>() / total
    } else {
        empty
    }
}

fn estimated_samples(area: Real, spacing: Real) -> Real {
    area / (spacing * spacing)
}

/// Score `model` against `scene` (see the [module documentation](self)).
/// `counted` picks the faces to score (e.g. [`not_resting_on`]`(0.0)`); edges
/// and corners are scored when all their faces count. Deterministic: the same
/// inputs give the same report.
///
/// Errors: a config failing [`SurfaceScoreConfig::validate`], or more than
/// [`MAX_SCORE_SAMPLES`] samples needed.
#[allow(
    clippy::too_many_lines,
    reason = "SPEC §6's scoring in its sections (the model's polygons on the true faces, faces, edges, corners, strays, vertex accuracy), each a few lines over the same face and polygon tables"
)]
pub fn score_surface_model(
    scene: &Scene,
    model: &SurfaceModel,
    cfg: &SurfaceScoreConfig,
    counted: &dyn Fn(&TrueFace) -> bool,
) -> Result<SurfaceScore, SimError> {
    cfg.validate()?;
    let lambda = cfg.lambda_m;
    let cos_mu = cfg.mu_deg.to_radians().cos();
    let topo = mesh_topology(scene);
    let (faces, tri_face) = group_faces(scene, &topo);
    let counts: Vec<bool> = faces.iter().map(counted).collect();

    // Budget before sampling.
    let area: Real = faces
        .iter()
        .zip(&counts)
        .filter(|(_, c)| **c)
        .map(|(f, _)| f.area_m2)
        .sum();
    let estimate = estimated_samples(area, cfg.sample_spacing_m);
    if estimate.is_nan() || estimate >= MAX_SCORE_SAMPLES as Real {
        return Err(SimError::InvalidArgument {
            what: "surface_score.sample_spacing_m".into(),
            message: format!(
                "{} m over {area:.3} m² of counted faces needs about {estimate:.3e} samples (at most {MAX_SCORE_SAMPLES})",
                cfg.sample_spacing_m
            ),
        });
    }

    // Model polygons (initial segments included: they can model true faces and
    // share edges) and which faces each is on.
    let mut polys: Vec<PolyCache> = Vec::new();
    let mut on_faces: Vec<Vec<usize>> = Vec::new();
    let mut initial: Vec<bool> = Vec::new();
    for s in model.segments() {
        let Some(p) = s.as_polygon() else { continue };
        let frame = p.frame();
        let vertices: Vec<Point3> = p.vertices().collect();
        let normal = p.normal();
        let centroid = p.centroid();
        let bounds = Aabb::from_points(vertices.iter());
        let on: Vec<usize> = faces
            .iter()
            .filter(|f| {
                f.bounds.loosened(lambda).intersects(&bounds)
                    && is_on(scene, f, cfg, &normal, &centroid, &vertices)
            })
            .map(|f| f.id)
            .collect();
        polys.push(PolyCache {
            id: s.id(),
            pts: p.points_2d(&frame),
            frame,
            bounds,
        });
        on_faces.push(on);
        initial.push(s.is_initial());
    }
    let index_of: HashMap<SegmentId, usize> =
        polys.iter().enumerate().map(|(i, p)| (p.id, i)).collect();
    let mut polys_on_face: Vec<Vec<usize>> = vec![Vec::new(); faces.len()];
    for (i, on) in on_faces.iter().enumerate() {
        for &f in on {
            polys_on_face[f].push(i);
        }
    }

    // Faces.
    let face_scores: Vec<FaceScore> = faces
        .par_iter()
        .filter(|f| counts[f.id])
        .map(|f| {
            let mut samples = Vec::new();
            for &t in &f.triangles {
                triangle_samples(
                    &scene.mesh().triangle(t as usize),
                    cfg.sample_spacing_m,
                    &mut samples,
                );
            }
            let near = &polys_on_face[f.id];
            let within = |i: usize, p: &Point3| {
                polys[i].bounds.distance_squared_to_point(p) < lambda * lambda
                    && polys[i].distance(p) < lambda
            };
            let (mut covered, mut any, mut total) = (0.0, 0.0, 0.0);
            for (p, w) in &samples {
                total += w;
                if near.iter().any(|&i| within(i, p)) {
                    covered += w;
                    any += w;
                } else if (0..polys.len()).any(|i| !initial[i] && within(i, p)) {
                    any += w;
                }
            }
            let largest = near.iter().copied().max_by(|&a, &b| {
                let area = |i: usize| {
                    model
                        .polygon(polys[i].id)
                        .map_or(0.0, surface::Polygon::area)
                };
                area(a).total_cmp(&area(b)).then(b.cmp(&a))
            });
            FaceScore {
                face: f.id,
                object: scene
                    .objects()
                    .get(f.object.index())
                    .map_or_else(String::new, |o| o.name.clone()),
                normal: [f.normal.x, f.normal.y, f.normal.z],
                area_m2: f.area_m2,
                samples: samples.len(),
                covered_fraction: if total > 0.0 {
                    (covered / total).min(1.0)
                } else {
                    0.0
                },
                within_lambda_fraction: if total > 0.0 {
                    (any / total).min(1.0)
                } else {
                    0.0
                },
                polygons: near.len(),
                normal_error_deg: largest.and_then(|i| model.polygon(polys[i].id)).map(|p| {
                    p.normal()
                        .dot(&f.normal)
                        .clamp(-1.0, 1.0)
                        .acos()
                        .to_degrees()
                }),
            }
        })
        .collect();
    let coverage = weighted_mean(
        face_scores.iter().map(|f| (f.covered_fraction, f.area_m2)),
        0.0,
    );
    let within_lambda = weighted_mean(
        face_scores
            .iter()
            .map(|f| (f.within_lambda_fraction, f.area_m2)),
        0.0,
    );

    // True edges between counted faces with a dihedral angle above μ.
    let mut true_edges: BTreeMap<(usize, usize), Vec<Segment3>> = BTreeMap::new();
    let mut vertex_faces: BTreeMap<VertexKey, (Point3, BTreeSet<usize>)> = BTreeMap::new();
    for (t, keys) in topo.triangle_keys.iter().enumerate() {
        let Some(f) = tri_face[t] else { continue };
        let tri = scene.mesh().triangle(t);
        for (k, p) in keys.iter().zip([tri.a, tri.b, tri.c]) {
            vertex_faces
                .entry(*k)
                .or_insert_with(|| (p, BTreeSet::new()))
                .1
                .insert(f);
        }
    }
    for ((ka, kb), tris) in &topo.edges {
        let fs: BTreeSet<usize> = tris.iter().filter_map(|&t| tri_face[t as usize]).collect();
        let fs: Vec<usize> = fs.into_iter().collect();
        for (i, &a) in fs.iter().enumerate() {
            for &b in &fs[i + 1..] {
                if !(counts[a] && counts[b]) || faces[a].normal.dot(&faces[b].normal) >= cos_mu {
                    continue;
                }
                if let (Some(pa), Some(pb)) = (vertex_faces.get(ka), vertex_faces.get(kb)) {
                    true_edges
                        .entry((a, b))
                        .or_default()
                        .push(Segment3::new(pa.0, pb.0));
                }
            }
        }
    }
    // Model shared edges by the face pairs they join.
    let mut model_edges: BTreeMap<(usize, usize), Vec<Segment3>> = BTreeMap::new();
    for (i, pc) in polys.iter().enumerate() {
        let Some(p) = model.polygon(pc.id) else {
            continue;
        };
        for e in 0..p.len() {
            let (Some(edge), Some((a, b))) = (p.edge(e), p.edge_points(e)) else {
                continue;
            };
            let Some(share) = edge.share else { continue };
            let Some(&j) = index_of.get(&share.neighbour) else {
                continue;
            };
            for &fa in &on_faces[i] {
                for &fb in &on_faces[j] {
                    if fa < fb {
                        model_edges
                            .entry((fa, fb))
                            .or_default()
                            .push(Segment3::new(a, b));
                    }
                }
            }
        }
    }
    let edge_scores: Vec<EdgeScore> = true_edges
        .iter()
        .map(|(&(a, b), segs)| {
            let found = model_edges.get(&(a, b)).map_or(&[][..], Vec::as_slice);
            let (mut length, mut covered) = (0.0, 0.0);
            for s in segs {
                let len = s.length();
                #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
                let k = ((len / cfg.sample_spacing_m).ceil() as usize).max(1);
                let w = len / k as Real;
                for i in 0..k {
                    let x = s.a + (s.b - s.a) * ((i as Real + 0.5) / k as Real);
                    if found.iter().any(|m| m.distance_to_point(&x) < lambda) {
                        covered += w;
                    }
                }
                length += len;
            }
            EdgeScore {
                faces: [a, b],
                dihedral_deg: faces[a]
                    .normal
                    .dot(&faces[b].normal)
                    .clamp(-1.0, 1.0)
                    .acos()
                    .to_degrees(),
                length_m: length,
                covered_fraction: if length > 0.0 {
                    (covered / length).min(1.0)
                } else {
                    0.0
                },
            }
        })
        .collect();
    let edge_coverage = weighted_mean(
        edge_scores.iter().map(|e| (e.covered_fraction, e.length_m)),
        1.0,
    );

    // Corners: vertices where three faces with pairwise angles above μ meet.
    let corner_vertices: Vec<Point3> = polys
        .iter()
        .filter_map(|pc| model.polygon(pc.id))
        .flat_map(|p| p.nodes().iter().filter(|n| n.corner.is_some()))
        .map(|n| n.position)
        .collect();
    let mut corners = Vec::new();
    for (p, fs) in vertex_faces.values() {
        if fs.len() < 3 || !fs.iter().all(|&f| counts[f]) {
            continue;
        }
        let v: Vec<usize> = fs.iter().copied().collect();
        let apart = |a: usize, b: usize| faces[a].normal.dot(&faces[b].normal) < cos_mu;
        let mut is_corner = false;
        'search: for i in 0..v.len() {
            for j in i + 1..v.len() {
                for k in j + 1..v.len() {
                    let (a, b, c) = (v[i], v[j], v[k]);
                    if apart(a, b)
                        && apart(a, c)
                        && apart(b, c)
                        && faces[a]
                            .normal
                            .dot(&faces[b].normal.cross(&faces[c].normal))
                            .abs()
                            > 1e-6
                    {
                        is_corner = true;
                        break 'search;
                    }
                }
            }
        }
        if is_corner {
            corners.push(CornerScore {
                position: [p.x, p.y, p.z],
                found: corner_vertices.iter().any(|c| (c - p).norm() < lambda),
                faces: v,
            });
        }
    }
    let corners_found = corners.iter().filter(|c| c.found).count();

    // Stray polygons and point segments.
    let fed = model.points_fed().max(1) as Real;
    let mut stray = StrayScore {
        polygons: 0,
        points_share: 0.0,
        max_points_share: 0.0,
        point_segments_share: 0.0,
    };
    for (i, pc) in polys.iter().enumerate() {
        if initial[i] || !on_faces[i].is_empty() {
            continue;
        }
        let share = model.segment(pc.id).map_or(0, surface::Segment::points) as Real / fed;
        stray.polygons += 1;
        stray.points_share += share;
        stray.max_points_share = stray.max_points_share.max(share);
    }
    stray.point_segments_share = model
        .segments()
        .filter(|s| s.as_point().is_some())
        .map(surface::Segment::points)
        .sum::<u64>() as Real
        / fed;

    // Accuracy of the polygon vertices.
    let vertices: Vec<Point3> = model
        .segments()
        .filter(|s| !s.is_initial())
        .filter_map(surface::Segment::as_polygon)
        .flat_map(surface::Polygon::vertices)
        .collect();
    let search = scene.bounding_box().extents().norm().max(1.0) + 1.0;
    let vertex_accuracy = crate::metrics::accuracy(scene, &vertices, search).distances;

    let modelled_m2 = face_scores
        .iter()
        .map(|f| f.within_lambda_fraction * f.area_m2)
        .sum();
    Ok(SurfaceScore {
        config: *cfg,
        faces: face_scores,
        coverage,
        within_lambda,
        modelled_m2,
        edges: edge_scores,
        edge_coverage,
        corners,
        corners_found,
        stray,
        vertex_accuracy,
    })
}
