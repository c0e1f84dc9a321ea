//! The links as the follower sees them (eq. 4's link distances and the
//! safety guard), placed at one pose, and their closest points to known
//! surface: a capsule (its axis and radius) or a link's collision mesh,
//! triangle by triangle.
//!
//! A URDF arm's links are meshes. Any capsule around one stands off it
//! somewhere: the bounding ellipsoid's long axis put the UR5's upper arm 37 mm
//! into the table it stands on (the mesh is 30 mm above it), and a link the
//! guard sees within the margin may not come closer, so the arm held still in
//! 509 of 629 steps. Meshes are therefore measured exactly: two planar
//! regions (a triangle, a polygon) that do not meet are closest at a vertex of
//! one over the other's face or between two edges, so the distance is the
//! least of each triangle vertex to the region's face, each region edge to
//! the triangle, and zero where a triangle edge crosses the region.

use crate::query::closest_segment_polygon;
use geom::line::closest_segment_segment;
use geom::{Aabb, Isometry3, Plane, Point3, Real, Segment3, TriMesh, Triangle, Vector3, polygon2};
use robot::{CollisionShape, LinkId, Robot};
use std::sync::Arc;
use surface::Polygon;

/// One collision shape of a link, in the link frame.
#[derive(Clone, Debug, PartialEq)]
pub enum LinkShape {
    /// A capsule: distances are measured from its axis, less its radius.
    Capsule {
        /// The axis.
        axis: Segment3,
        /// The radius about it.
        radius: Real,
    },
    /// A collision mesh (a URDF link's): distances are measured from its
    /// triangles.
    Mesh(Arc<LinkMesh>),
}

/// A collision mesh in its link's frame, with each triangle's box: the
/// distance queries run in the link frame (the query is moved, not the
/// mesh), so placing a link costs nothing.
#[derive(Clone, Debug)]
pub struct LinkMesh {
    mesh: Arc<TriMesh>,
    tris: Vec<Triangle>,
    boxes: Vec<Aabb>,
    bounds: Aabb,
    /// The centre of `bounds`, and the farthest vertex from it.
    centre: Point3,
    reach: Real,
}

impl PartialEq for LinkMesh {
    fn eq(&self, other: &Self) -> bool {
        self.mesh == other.mesh
    }
}

impl LinkMesh {
    /// The triangles of `mesh` and their boxes.
    pub fn new(mesh: Arc<TriMesh>) -> Self {
        let tris: Vec<Triangle> = mesh
            .triangles
            .iter()
            .map(|t| {
                Triangle::new(
                    mesh.vertices[t[0] as usize],
                    mesh.vertices[t[1] as usize],
                    mesh.vertices[t[2] as usize],
                )
            })
            .collect();
        let boxes: Vec<Aabb> = tris
            .iter()
            .map(|t| Aabb::from_points([&t.a, &t.b, &t.c]))
            .collect();
        let bounds = boxes.iter().fold(Aabb::empty(), |a, b| a.merged(b));
        let centre = bounds.center();
        let reach = mesh
            .vertices
            .iter()
            .map(|v| (v - centre).norm())
            .fold(0.0, Real::max);
        Self {
            mesh,
            tris,
            boxes,
            bounds,
            centre,
            reach,
        }
    }

    /// The mesh, link frame.
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }
}

/// One collision shape of one moving link (several per link are treated as
/// one link, its closest point winning).
#[derive(Clone, Debug, PartialEq)]
pub struct LinkBody {
    /// The link.
    pub link: LinkId,
    /// Its shape.
    pub shape: LinkShape,
}

/// The shapes of every moving link (the links after
/// [`Robot::mounted_links`]; link 0 is always left out): each capsule and
/// each collision mesh as it is.
pub fn link_bodies(robot: &Robot) -> Vec<LinkBody> {
    let mut out = Vec::new();
    for (i, link) in robot
        .links
        .iter()
        .enumerate()
        .skip(robot.mounted_links().max(1))
    {
        for shape in &link.collision {
            let shape = match shape {
                CollisionShape::Capsule(c) => LinkShape::Capsule {
                    axis: c.segment,
                    radius: c.radius,
                },
                // A mesh without triangles has no surface to keep off.
                CollisionShape::Mesh(m) if m.triangles.is_empty() => continue,
                CollisionShape::Mesh(m) => LinkShape::Mesh(Arc::new(LinkMesh::new(Arc::clone(m)))),
            };
            out.push(LinkBody {
                link: LinkId(i),
                shape,
            });
        }
    }
    out
}

/// A link shape at one pose, world frame.
#[derive(Clone, Debug)]
pub(crate) enum Placed {
    /// A capsule's axis and radius.
    Capsule { axis: Segment3, radius: Real },
    /// A mesh at `pose` (world from link), with the triangles left out of
    /// queries (`false`), if any.
    Mesh {
        mesh: Arc<LinkMesh>,
        pose: Isometry3,
        keep: Option<Vec<bool>>,
    },
}

/// Distance between two boxes (0 when they overlap).
fn box_distance(a: &Aabb, b: &Aabb) -> Real {
    let gap = (a.min - b.max).sup(&(b.min - a.max)).sup(&Vector3::zeros());
    gap.norm()
}

/// Closest points between triangle `t` and segment `s`: `(distance, point
/// on t, point on s)`.
fn closest_triangle_segment(t: &Triangle, s: &Segment3) -> (Real, Point3, Point3) {
    if let Some(u) = t.segment_hit(s) {
        let x = s.point_at(u);
        return (0.0, x, x);
    }
    let mut best = (Real::INFINITY, t.a, s.a);
    for e in [s.a, s.b] {
        let c = t.closest_point(&e);
        let d = (c - e).norm();
        if d < best.0 {
            best = (d, c, e);
        }
    }
    for edge in t.edges() {
        let (ts, te, d) = closest_segment_segment(s, &edge);
        if d < best.0 {
            best = (d, edge.point_at(te), s.point_at(ts));
        }
    }
    best
}

/// A planar region of known surface: a polygon, or a quadrilateral strip.
struct Region<'a> {
    plane: Plane,
    inside: &'a dyn Fn(&Point3) -> bool,
    edges: Vec<(Segment3, Aabb)>,
    bounds: Aabb,
    /// How far the vertices stand off the plane, at most (a model
    /// polygon's vertices need not lie exactly on its fitted plane).
    off_plane: Real,
}

impl Region<'_> {
    fn new<'a>(
        plane: Plane,
        inside: &'a dyn Fn(&Point3) -> bool,
        vertices: &[Point3],
    ) -> Region<'a> {
        let n = vertices.len();
        let edges = (0..n)
            .map(|i| {
                let (a, b) = (vertices[i], vertices[(i + 1) % n]);
                (Segment3::new(a, b), Aabb::new(a, b))
            })
            .collect();
        // Points projected into the region stand off the vertices' box by
        // at most how far the vertices stand off the plane.
        let off_plane = vertices
            .iter()
            .map(|v| plane.signed_distance(v).abs())
            .fold(0.0, Real::max);
        let bounds = Aabb::from_points(vertices).loosened(off_plane + 1e-9);
        Region {
            plane,
            inside,
            edges,
            bounds,
            off_plane,
        }
    }
}

/// Closest points between the triangles and `region`, looking no farther
/// than `limit`: `(distance, on a triangle, on the region)`, or `limit`
/// (with meaningless points) when nothing is closer.
fn triangles_to_region(
    mesh: &LinkMesh,
    keep: Option<&[bool]>,
    region: &Region<'_>,
    limit: Real,
) -> (Real, Point3, Point3) {
    let origin = Point3::origin();
    let mut best = (limit, origin, origin);
    // A triangle is looked at when its box is within `best` of the
    // region's and its vertices are not all `best` (and the vertices'
    // standoff) or more to one side of the region's plane (the region's box
    // is loose in a link frame turned against the region).
    let plane_gap = |t: &Triangle| {
        let h = [t.a, t.b, t.c].map(|v| region.plane.signed_distance(&v));
        if h.iter().all(|x| *x > 0.0) {
            h[0].min(h[1]).min(h[2])
        } else if h.iter().all(|x| *x < 0.0) {
            -(h[0].max(h[1]).max(h[2]))
        } else {
            0.0
        }
    };
    let near = |k: usize, t: &Triangle, b: &Aabb, best: Real| {
        keep.is_none_or(|m| m[k])
            && box_distance(b, &region.bounds) < best
            && plane_gap(t) < best + region.off_plane
    };
    // The cheap cases first (a triangle edge through the region, a vertex
    // over it), so that the edge-to-triangle tests below run only on the
    // triangles still within the distance they found.
    for (k, (t, b)) in mesh.tris.iter().zip(&mesh.boxes).enumerate() {
        if !near(k, t, b, best.0) {
            continue;
        }
        let p = [t.a, t.b, t.c];
        let h = p.map(|v| region.plane.signed_distance(&v));
        for (i, j) in [(0, 1), (1, 2), (2, 0)] {
            if h[i] * h[j] <= 0.0 && (h[i] - h[j]).abs() > 0.0 {
                let x = p[i] + (p[j] - p[i]) * (h[i] / (h[i] - h[j]));
                if (region.inside)(&x) {
                    return (0.0, x, x);
                }
            }
        }
        for i in 0..3 {
            if h[i].abs() < best.0 {
                let q = region.plane.project(&p[i]);
                if (region.inside)(&q) {
                    best = (h[i].abs(), p[i], q);
                }
            }
        }
    }
    for (k, (t, b)) in mesh.tris.iter().zip(&mesh.boxes).enumerate() {
        if !near(k, t, b, best.0) {
            continue;
        }
        for (e, eb) in &region.edges {
            if box_distance(b, eb) >= best.0 {
                continue;
            }
            let (d, on_t, on_e) = closest_triangle_segment(t, e);
            if d < best.0 {
                best = (d, on_t, on_e);
            }
        }
    }
    best
}

impl Placed {
    /// `shape` in the world frame of a link at `world_from_link`.
    pub(crate) fn new(shape: &LinkShape, world_from_link: &Isometry3) -> Self {
        match shape {
            LinkShape::Capsule { axis, radius } => Self::Capsule {
                axis: Segment3::new(world_from_link * axis.a, world_from_link * axis.b),
                radius: *radius,
            },
            LinkShape::Mesh(mesh) => Self::Mesh {
                mesh: Arc::clone(mesh),
                pose: *world_from_link,
                keep: None,
            },
        }
    }

    /// Leaves out a mesh's triangles that lie wholly within `radius` of `c`
    /// (the control point's own zone on the tool link, P§3.3); a capsule is
    /// left as it is.
    pub(crate) fn drop_triangles_within(&mut self, c: &Point3, radius: Real) {
        if let Self::Mesh { mesh, pose, keep } = self {
            let local = pose.inverse_transform_point(c);
            *keep = Some(
                mesh.tris
                    .iter()
                    .map(|t| [t.a, t.b, t.c].iter().any(|v| (v - local).norm() >= radius))
                    .collect(),
            );
        }
    }

    /// The radius distances are measured beyond (0 for a mesh).
    pub(crate) fn radius(&self) -> Real {
        match self {
            Self::Capsule { radius, .. } => *radius,
            Self::Mesh { .. } => 0.0,
        }
    }

    /// A centre and a half size: every point of the shape (less its radius)
    /// lies within the half size of the centre.
    pub(crate) fn centre_reach(&self) -> (Point3, Real) {
        match self {
            Self::Capsule { axis, .. } => (
                Point3::from((axis.a.coords + axis.b.coords) * 0.5),
                axis.length() * 0.5,
            ),
            Self::Mesh { mesh, pose, .. } => (pose * mesh.centre, mesh.reach),
        }
    }

    /// The most any point of the shape moved from `self` to `other` (the
    /// same shape at another pose), or more: a point's travel under a rigid
    /// motion is convex in the point, so over a segment it is greatest at an
    /// end, and over a mesh at most its greatest at a corner of the mesh's
    /// box (link frame).
    pub(crate) fn travel_to(&self, other: &Self) -> Real {
        match (self, other) {
            (Self::Capsule { axis: a, .. }, Self::Capsule { axis: b, .. }) => {
                (b.a - a.a).norm().max((b.b - a.b).norm())
            }
            (Self::Mesh { mesh, pose: a, .. }, Self::Mesh { pose: b, .. }) => {
                let (lo, hi) = (mesh.bounds.min, mesh.bounds.max);
                (0..8)
                    .map(|k| {
                        let c = Point3::new(
                            if k & 1 == 0 { lo.x } else { hi.x },
                            if k & 2 == 0 { lo.y } else { hi.y },
                            if k & 4 == 0 { lo.z } else { hi.z },
                        );
                        (b * c - a * c).norm()
                    })
                    .fold(0.0, Real::max)
            }
            _ => Real::INFINITY,
        }
    }

    /// A lower bound of the distance from the shape (less its radius) to `p`.
    pub(crate) fn lower_bound_to_point(&self, p: &Point3) -> Real {
        match self {
            Self::Capsule { axis, .. } => axis.distance_to_point(p),
            Self::Mesh { mesh, pose, .. } => mesh
                .bounds
                .distance_squared_to_point(&pose.inverse_transform_point(p))
                .sqrt(),
        }
    }

    /// Distance from the shape (less its radius) to `p` and the closest
    /// point on it; `limit` (and `p`) when nothing is closer than `limit`
    /// (a capsule is measured whatever the limit).
    pub(crate) fn to_point(&self, p: &Point3, limit: Real) -> (Real, Point3) {
        match self {
            Self::Capsule { axis, .. } => {
                let c = axis.closest_point(p);
                ((c - p).norm(), c)
            }
            Self::Mesh { mesh, pose, keep } => {
                let local = pose.inverse_transform_point(p);
                if mesh.bounds.distance_squared_to_point(&local) >= limit * limit {
                    return (limit, *p);
                }
                let mut best = (limit, local);
                for (k, (t, b)) in mesh.tris.iter().zip(&mesh.boxes).enumerate() {
                    if keep.as_ref().is_some_and(|m| !m[k])
                        || b.distance_squared_to_point(&local) >= best.0 * best.0
                    {
                        continue;
                    }
                    let c = t.closest_point(&local);
                    let d = (c - local).norm();
                    if d < best.0 {
                        best = (d, c);
                    }
                }
                (best.0, pose * best.1)
            }
        }
    }

    /// Closest points between the shape (less its radius) and polygon `g`:
    /// `(distance, on the shape, on g)`, as [`Self::to_point`] for `limit`.
    pub(crate) fn to_polygon(&self, g: &Polygon, limit: Real) -> (Real, Point3, Point3) {
        match self {
            Self::Capsule { axis, .. } => closest_segment_polygon(axis, g),
            Self::Mesh { mesh, pose, keep } => {
                let world_plane = g.plane();
                let local: Vec<Point3> = g
                    .vertices()
                    .map(|v| pose.inverse_transform_point(&v))
                    .collect();
                let off_plane = g
                    .vertices()
                    .map(|v| world_plane.signed_distance(&v).abs())
                    .fold(0.0, Real::max);
                let near = Aabb::from_points(&local).loosened(off_plane + 1e-9);
                if box_distance(&mesh.bounds, &near) >= limit {
                    return (limit, Point3::origin(), Point3::origin());
                }
                let frame = g.frame();
                let pts = g.points_2d(&frame);
                let inside =
                    |p: &Point3| polygon2::contains_point(&pts, &frame.to_2d(&(pose * p)), 0.0);
                let Some(n) =
                    geom::unit(pose.inverse_transform_vector(&world_plane.normal.into_inner()))
                else {
                    return (limit, Point3::origin(), Point3::origin());
                };
                let plane = Plane::from_point_normal(
                    &pose.inverse_transform_point(&world_plane.point()),
                    n,
                );
                let region = Region::new(plane, &inside, &local);
                let (d, on_t, on_g) = triangles_to_region(mesh, keep.as_deref(), &region, limit);
                (d, pose * on_t, pose * on_g)
            }
        }
    }

    /// A lower bound of the distance between the shape (less its radius)
    /// and segment `s`, at most `limit` for a mesh: a capsule's exact
    /// distance, a mesh's nearest triangle box (a test whether to look
    /// closer, so it is cheap).
    pub(crate) fn lower_bound_to_segment(&self, s: &Segment3, limit: Real) -> Real {
        match self {
            Self::Capsule { axis, .. } => closest_segment_segment(axis, s).2,
            Self::Mesh { mesh, pose, .. } => {
                let sb = Aabb::new(
                    pose.inverse_transform_point(&s.a),
                    pose.inverse_transform_point(&s.b),
                );
                if box_distance(&mesh.bounds, &sb) >= limit {
                    return limit;
                }
                mesh.boxes
                    .iter()
                    .map(|b| box_distance(b, &sb))
                    .fold(limit, Real::min)
            }
        }
    }

    /// Closest points between the shape (less its radius) and segment `s`:
    /// `(distance, on the shape, on s)`, as [`Self::to_point`] for `limit`.
    pub(crate) fn to_segment(&self, s: &Segment3, limit: Real) -> (Real, Point3, Point3) {
        match self {
            Self::Capsule { axis, .. } => {
                let (ta, ts, d) = closest_segment_segment(axis, s);
                (d, axis.point_at(ta), s.point_at(ts))
            }
            Self::Mesh { mesh, pose, keep } => {
                let local = Segment3::new(
                    pose.inverse_transform_point(&s.a),
                    pose.inverse_transform_point(&s.b),
                );
                let sb = Aabb::new(local.a, local.b);
                let mut best = (limit, s.a, s.a);
                for (k, (t, b)) in mesh.tris.iter().zip(&mesh.boxes).enumerate() {
                    if keep.as_ref().is_some_and(|m| !m[k]) || box_distance(b, &sb) >= best.0 {
                        continue;
                    }
                    let (d, on_t, on_s) = closest_triangle_segment(t, &local);
                    if d < best.0 {
                        best = (d, pose * on_t, pose * on_s);
                    }
                }
                best
            }
        }
    }

    /// Closest points between the shape (less its radius) and the planar
    /// convex quadrilateral `q` (normal `n`), as [`Self::to_polygon`].
    pub(crate) fn to_quad(
        &self,
        q: &[Point3; 4],
        n: &Vector3,
        limit: Real,
    ) -> (Real, Point3, Point3) {
        match self {
            Self::Capsule { axis, .. } => closest_segment_quad(axis, q, n),
            Self::Mesh { mesh, pose, keep } => {
                let local = q.map(|v| pose.inverse_transform_point(&v));
                let ln = pose.inverse_transform_vector(n);
                let inside = |p: &Point3| inside_quad(&local, &ln, p);
                let Some(unit) = geom::unit(ln) else {
                    return (limit, Point3::origin(), Point3::origin());
                };
                let region =
                    Region::new(Plane::from_point_normal(&local[0], unit), &inside, &local);
                let (d, on_t, on_q) = triangles_to_region(mesh, keep.as_deref(), &region, limit);
                (d, pose * on_t, pose * on_q)
            }
        }
    }
}

/// Whether `p` (on the plane of `q`) lies in the planar convex
/// quadrilateral `q` with normal `n`.
fn inside_quad(q: &[Point3; 4], n: &Vector3, p: &Point3) -> bool {
    let side = |i: usize| (q[(i + 1) % 4] - q[i]).cross(&(p - q[i])).dot(n);
    let sides = [side(0), side(1), side(2), side(3)];
    sides.iter().all(|v| *v >= -1e-12) || sides.iter().all(|v| *v <= 1e-12)
}

/// Closest points between segment `s` and the planar convex quadrilateral
/// `q` (normal `n`): `(distance, point on s, point on q)`.
pub(crate) fn closest_segment_quad(
    s: &Segment3,
    q: &[Point3; 4],
    n: &Vector3,
) -> (Real, Point3, Point3) {
    let inside = |p: &Point3| inside_quad(q, n, p);
    let h = |p: &Point3| (p - q[0]).dot(n);
    let (ha, hb) = (h(&s.a), h(&s.b));
    if ha * hb <= 0.0 && (ha - hb).abs() > 0.0 {
        let x = s.point_at(ha / (ha - hb));
        if inside(&x) {
            return (0.0, x, x);
        }
    }
    let mut best = (Real::INFINITY, s.a, s.a);
    for (e, he) in [(s.a, ha), (s.b, hb)] {
        let p = e - n * he;
        if inside(&p) && he.abs() < best.0 {
            best = (he.abs(), e, p);
        }
    }
    for i in 0..4 {
        let edge = Segment3::new(q[i], q[(i + 1) % 4]);
        let (ts, te, d) = closest_segment_segment(s, &edge);
        if d < best.0 {
            best = (d, s.point_at(ts), edge.point_at(te));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A unit cube mesh `[0, 1]³` (12 triangles).
    fn unit_cube() -> Arc<TriMesh> {
        let v: Vec<Point3> = (0..8)
            .map(|i| {
                Point3::new(
                    Real::from(i & 1),
                    Real::from((i >> 1) & 1),
                    Real::from((i >> 2) & 1),
                )
            })
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let mut t = Vec::new();
        for q in quads {
            t.push([q[0], q[1], q[2]]);
            t.push([q[0], q[2], q[3]]);
        }
        Arc::new(TriMesh::new(v, t, "unit cube").unwrap())
    }

    /// The distance between the unit cube `[0, 1]³` and a point, by hand.
    fn cube_distance(p: &Point3) -> Real {
        let gap = |x: Real| (-x).max(x - 1.0).max(0.0);
        Vector3::new(gap(p.x), gap(p.y), gap(p.z)).norm()
    }

    fn square(c: Point3, half: Real, n: Vector3) -> [Point3; 4] {
        let u = if n.x.abs() < 0.9 {
            geom::unit(Vector3::x().cross(&n)).unwrap().into_inner()
        } else {
            geom::unit(Vector3::y().cross(&n)).unwrap().into_inner()
        };
        let v = n.cross(&u);
        [
            c - u * half - v * half,
            c + u * half - v * half,
            c + u * half + v * half,
            c - u * half + v * half,
        ]
    }

    #[test]
    fn a_mesh_is_measured_to_its_faces_edges_and_corners() {
        let placed = Placed::new(
            &LinkShape::Mesh(Arc::new(LinkMesh::new(unit_cube()))),
            &Isometry3::identity(),
        );
        // A square 0.3 above the top face, centred: a vertex-face case
        // from the square's side, face-face in fact.
        let n = Vector3::z();
        let q = square(Point3::new(0.5, 0.5, 1.3), 0.2, n);
        let (d, on_mesh, on_q) = placed.to_quad(&q, &n, 10.0);
        assert!((d - 0.3).abs() < 1e-12, "{d}");
        assert!((on_mesh.z - 1.0).abs() < 1e-12 && (on_q.z - 1.3).abs() < 1e-12);
        // A square beside the +x face tilted 45° about y whose corner
        // points at the face: its edge, not a mesh vertex, is closest
        // (the square's nearest edge runs 0.2 from the face).
        let n45 = geom::unit(Vector3::new(1.0, 0.0, 1.0))
            .unwrap()
            .into_inner();
        let half = 0.1;
        let c = Point3::new(1.2 + half * n45.z, 0.5, 0.5 - half * n45.x);
        let q = square(c, half, n45);
        let lowest = q.iter().map(|p| p.x).fold(Real::INFINITY, Real::min);
        let (d, ..) = placed.to_quad(&q, &n45, 10.0);
        assert!((d - (lowest - 1.0)).abs() < 1e-9, "{d} {lowest}");
        // A point off a corner.
        let p = Point3::new(1.3, 1.4, -0.2);
        let (d, c) = placed.to_point(&p, 10.0);
        assert!((d - cube_distance(&p)).abs() < 1e-12);
        assert!((c - Point3::new(1.0, 1.0, 0.0)).norm() < 1e-12);
        // Nothing within the limit: the limit.
        assert_eq!(placed.to_point(&p, 0.1).0, 0.1);
        // A segment through the cube: 0; one 0.5 off its +x face: at most that.
        let s = Segment3::new(Point3::new(-1.0, 0.5, 0.5), Point3::new(2.0, 0.5, 0.5));
        assert_eq!(placed.lower_bound_to_segment(&s, 10.0), 0.0);
        let s = Segment3::new(Point3::new(1.5, -1.0, 0.5), Point3::new(1.5, 2.0, 0.5));
        assert_eq!(placed.lower_bound_to_segment(&s, 10.0), 0.5);
        assert_eq!(placed.lower_bound_to_segment(&s, 0.2), 0.2);
    }

    proptest! {
        /// A square's distance from the cube mesh, against the least of a
        /// fine sampling of the square (an upper bound within the sampling
        /// step) and a lower bound from that less the step.
        #[test]
        fn a_mesh_to_a_square_agrees_with_sampling(
            cx in -1.0..2.0f64, cy in -1.0..2.0f64, cz in -1.0..2.0f64,
            nx in -1.0..1.0f64, ny in -1.0..1.0f64, nz in -1.0..1.0f64,
            half in 0.05..0.6f64,
            rx in -3.0..3.0f64, ry in -3.0..3.0f64, rz in -3.0..3.0f64,
            tx in -2.0..2.0f64,
        ) {
            let n = Vector3::new(nx, ny, nz);
            prop_assume!(n.norm() > 0.2);
            let n = geom::unit(n).unwrap().into_inner();
            let c = Point3::new(cx, cy, cz);
            let q = square(c, half, n);
            let placed = Placed::new(&LinkShape::Mesh(Arc::new(LinkMesh::new(unit_cube()))), &Isometry3::identity());
            let (d, on_mesh, on_q) = placed.to_quad(&q, &n, 100.0);
            let k = 60;
            let mut sampled = Real::INFINITY;
            for i in 0..=k {
                for j in 0..=k {
                    let (s, t) = (Real::from(i) / Real::from(k), Real::from(j) / Real::from(k));
                    let p = q[0] + (q[1] - q[0]) * s + (q[3] - q[0]) * t;
                    sampled = sampled.min(cube_distance(&p));
                }
            }
            let step = 2.0 * half / Real::from(k) * std::f64::consts::SQRT_2;
            // Inside the cube the mesh distance is to its surface, the
            // sampled one 0: only compare squares that stay outside.
            prop_assume!(sampled > 0.0 || d == 0.0);
            prop_assert!(d <= sampled + 1e-9, "{d} > sampled {sampled}");
            prop_assert!(d >= sampled - step - 1e-9, "{d} < sampled {sampled} - {step}");
            prop_assert!(((on_mesh - on_q).norm() - d).abs() < 1e-9);
            // The same with the cube and the square moved together: the
            // queries run in the link frame and answer in the world's.
            let pose = Isometry3::new(Vector3::new(tx, -tx, 0.5 * tx), Vector3::new(rx, ry, rz));
            let moved = Placed::new(&LinkShape::Mesh(Arc::new(LinkMesh::new(unit_cube()))), &pose);
            let mq = q.map(|v| pose * v);
            let (dm, on_mesh_m, on_q_m) = moved.to_quad(&mq, &(pose * n), 100.0);
            prop_assert!((dm - d).abs() < 1e-9, "{dm} against {d}");
            prop_assert!(((on_mesh_m - on_q_m).norm() - dm).abs() < 1e-9);
            let p = Point3::new(cz, cx, cy);
            if cube_distance(&p) > 0.0 {
                let (dp, on_p) = moved.to_point(&(pose * p), 100.0);
                prop_assert!((dp - cube_distance(&p)).abs() < 1e-9);
                prop_assert!(((on_p - pose * p).norm() - dp).abs() < 1e-9);
            }
        }
    }
}
