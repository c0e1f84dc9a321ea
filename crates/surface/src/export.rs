//! Output: the `surface_model.json` layout, a triangulated OBJ, and statistics.

use crate::model::SurfaceModel;
use crate::segment::{Polygon, SegmentKind};
use geom::Real;
use serde::{Deserialize, Serialize};
use std::fmt::Write as _;

/// `surface_model.json`: `{"segments": [...], "surfaces": [[id, ...], ...]}`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelJson {
    /// Every segment, in id order.
    pub segments: Vec<SegmentJson>,
    /// The surfaces (connected components of the neighbour relation).
    pub surfaces: Vec<Vec<u32>>,
}

/// One segment of [`ModelJson`], tagged by `"kind"`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum SegmentJson {
    /// A planar polygon segment.
    Polygon {
        /// Segment id.
        id: u32,
        /// Sensor points represented (`m`).
        points: u64,
        /// `true` for an initial segment.
        initial: bool,
        /// A point of the plane (centroid of the points).
        centroid: [Real; 3],
        /// Outward unit normal.
        normal: [Real; 3],
        /// Vertices, anticlockwise about the normal.
        vertices: Vec<[Real; 3]>,
        /// `edges[i]` joins `vertices[i]` to `vertices[(i + 1) % n]`.
        edges: Vec<EdgeJson>,
    },
    /// A point segment.
    Point {
        /// Segment id.
        id: u32,
        /// Sensor points represented (`m`).
        points: u64,
        /// The point.
        centroid: [Real; 3],
        /// Unit sensing axis (into the surface).
        sensing_axis: [Real; 3],
    },
}

/// One edge of a polygon in [`ModelJson`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct EdgeJson {
    /// The neighbour this edge is shared with, if shared.
    pub shared_with: Option<u32>,
    /// Index of the corresponding edge in that neighbour.
    pub corresponding_edge: Option<usize>,
    /// `true` when the edge's start vertex is a corner vertex.
    pub corner_start: bool,
}

/// Counts of the model.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ModelStats {
    /// Updates performed.
    pub updates: u64,
    /// Segments.
    pub segments: usize,
    /// Planar polygon segments (initial ones included).
    pub polygons: usize,
    /// Point segments.
    pub points: usize,
    /// Pairs of corresponding shared edges.
    pub shared_edge_pairs: usize,
    /// Corner vertices (counted per segment: a cube corner modelled by three
    /// segments has three).
    pub corner_vertices: usize,
}

/// Median, 95th percentile and maximum of per-update times, microseconds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct UpdateTimes {
    /// Median.
    pub median: Real,
    /// 95th percentile (nearest rank).
    pub p95: Real,
    /// Maximum.
    pub max: Real,
}

impl UpdateTimes {
    /// Summarise samples (microseconds); zeros for no samples.
    ///
    /// ```
    /// let t = surface::UpdateTimes::from_micros(&[3.0, 1.0, 2.0, 10.0]);
    /// assert_eq!((t.median, t.p95, t.max), (2.5, 10.0, 10.0));
    /// ```
    pub fn from_micros(samples: &[Real]) -> Self {
        let mut v: Vec<Real> = samples.iter().copied().filter(|x| x.is_finite()).collect();
        if v.is_empty() {
            return Self::default();
        }
        v.sort_by(Real::total_cmp);
        let n = v.len();
        let median = if n % 2 == 1 {
            v[n / 2]
        } else {
            0.5 * (v[n / 2 - 1] + v[n / 2])
        };
        let rank = ((0.95 * n as Real).ceil() as usize).clamp(1, n);
        Self {
            median,
            p95: v[rank - 1],
            max: v[n - 1],
        }
    }
}

/// `stats.json`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StatsJson {
    /// Updates performed.
    pub updates: u64,
    /// Per-update times, microseconds (measured by the caller).
    pub update_us: UpdateTimes,
    /// Segments.
    pub segments: usize,
    /// Planar polygon segments.
    pub polygons: usize,
    /// Point segments.
    pub points: usize,
    /// Pairs of corresponding shared edges.
    pub shared_edge_pairs: usize,
    /// Corner vertices.
    pub corner_vertices: usize,
}

impl ModelStats {
    /// The `stats.json` record with the caller's timings.
    pub fn to_json(&self, update_us: UpdateTimes) -> StatsJson {
        StatsJson {
            updates: self.updates,
            update_us,
            segments: self.segments,
            polygons: self.polygons,
            points: self.points,
            shared_edge_pairs: self.shared_edge_pairs,
            corner_vertices: self.corner_vertices,
        }
    }
}

fn arr(v: &impl std::ops::Index<usize, Output = Real>) -> [Real; 3] {
    [v[0], v[1], v[2]]
}

impl SurfaceModel {
    /// The model in the `surface_model.json` layout.
    pub fn to_model_json(&self) -> ModelJson {
        let segments = self
            .segments
            .values()
            .map(|s| match &s.kind {
                SegmentKind::Point(p) => SegmentJson::Point {
                    id: s.id.0,
                    points: s.moments.m,
                    centroid: arr(&p.centroid.coords),
                    sensing_axis: arr(&p.sensing_axis().into_inner()),
                },
                SegmentKind::Polygon(p) => SegmentJson::Polygon {
                    id: s.id.0,
                    points: s.moments.m,
                    initial: p.initial,
                    centroid: arr(&p.centroid.coords),
                    normal: arr(&p.normal.into_inner()),
                    vertices: p.nodes.iter().map(|n| arr(&n.position.coords)).collect(),
                    edges: p
                        .nodes
                        .iter()
                        .map(|n| EdgeJson {
                            shared_with: n.edge.share.map(|sh| sh.neighbour.0),
                            corresponding_edge: n
                                .edge
                                .share
                                .and_then(|sh| self.pair_edge(sh.neighbour, sh.pair)),
                            corner_start: n.corner.is_some(),
                        })
                        .collect(),
                },
            })
            .collect();
        let surfaces = self
            .surfaces()
            .into_iter()
            .map(|c| c.into_iter().map(|id| id.0).collect())
            .collect();
        ModelJson { segments, surfaces }
    }

    /// Wavefront OBJ: polygons triangulated (ear clipping), one `g` group per
    /// segment (`g segment_<id>`); point segments as `p` elements.
    pub fn to_obj(&self) -> String {
        let mut out = String::new();
        let _ = writeln!(
            out,
            "# surveyor surface model: {} segments",
            self.segments.len()
        );
        let mut next = 1usize;
        for s in self.segments.values() {
            match &s.kind {
                SegmentKind::Point(p) => {
                    let c = p.centroid;
                    let _ = writeln!(
                        out,
                        "g point_{}\nv {} {} {}\np {}",
                        s.id.0, c.x, c.y, c.z, next
                    );
                    next += 1;
                }
                SegmentKind::Polygon(p) => {
                    let _ = writeln!(out, "g segment_{}", s.id.0);
                    for n in &p.nodes {
                        let v = n.position;
                        let _ = writeln!(out, "v {} {} {}", v.x, v.y, v.z);
                    }
                    for [a, b, c] in triangulate(p) {
                        let _ = writeln!(out, "f {} {} {}", next + a, next + b, next + c);
                    }
                    next += p.nodes.len();
                }
            }
        }
        out
    }

    /// Counts of the model.
    pub fn stats(&self) -> ModelStats {
        let mut st = ModelStats {
            updates: self.updates,
            segments: self.segments.len(),
            ..ModelStats::default()
        };
        let mut shared = 0usize;
        for s in self.segments.values() {
            match &s.kind {
                SegmentKind::Point(_) => st.points += 1,
                SegmentKind::Polygon(p) => {
                    st.polygons += 1;
                    shared += p.shared_edge_count();
                    st.corner_vertices += p.corner_count();
                }
            }
        }
        st.shared_edge_pairs = shared / 2;
        st
    }
}

/// Triangles of a polygon (vertex indices, anticlockwise in the polygon's
/// frame): `geom`'s ear clipping on its 2-D points.
fn triangulate(p: &Polygon) -> Vec<[usize; 3]> {
    let pts = p.points_2d(&p.frame());
    geom::primitives::triangulate(&pts)
        .into_iter()
        .map(|t| t.map(|k| k as usize))
        .collect()
}
