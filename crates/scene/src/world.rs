//! Compiled scenes: a triangle soup with materials and a BVH, answering ray,
//! nearest-point and collision queries.

use crate::bvh::{Aabb32, BuildParams, Bvh, RayF32};
use crate::error::SceneError;
use crate::material::{Material, MaterialId, validate_materials};
use crate::mesh::TriMesh;
use crate::wide::{Bvh4, LeafTest, Stack, prefetch};
use geom::{Aabb, Capsule, InvariantViolation, Point3, Ray, Real, Triangle, UnitVector3, Vector3};
use rayon::prelude::*;
use std::cell::RefCell;
use std::ops::{ControlFlow, Range};
use wide::{CmpGe, CmpLe, f32x4};

/// Index of a triangle of a [`Scene`]'s mesh (its face).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
#[serde(transparent)]
pub struct FaceId(pub u32);

/// Index of an object of a [`Scene`] ([`Scene::objects`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, PartialOrd, Ord, Hash, serde::Serialize)]
#[serde(transparent)]
pub struct ObjectId(pub u32);

impl ObjectId {
    /// The index into [`Scene::objects`].
    #[inline]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// What a ray met.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the ray, metres.
    pub distance: Real,
    /// The surface point.
    pub point: Point3,
    /// Unit surface normal, turned to face the ray's origin.
    pub normal: UnitVector3,
    /// Material of the surface, when known.
    pub material: Option<MaterialId>,
    /// Index of the scene object, when the world is made of objects.
    pub object: Option<ObjectId>,
    /// Index of the triangle (mesh worlds) or point (point-cloud worlds).
    pub element: u32,
}

/// Fewest rays [`RayCast::cast_rays`] gives one task (a ray takes a few
/// microseconds; a task costs rayon about one).
pub const CAST_PIECE: usize = 48;

/// Anything a simulated range sensor can measure: one required method, batches
/// provided (in parallel).
pub trait RayCast: Sync {
    /// The first surface along `ray` within `max_range_m`, if any.
    fn cast_ray(&self, ray: &Ray, max_range_m: Real) -> Option<Hit>;

    /// The material behind a [`Hit::material`] id, when the world has a table.
    fn material(&self, _id: MaterialId) -> Option<&Material> {
        None
    }

    /// [`RayCast::cast_ray`] for many rays, in parallel, results in input order.
    /// Pieces of [`CAST_PIECE`] rays at least: one scan line of a few hundred
    /// rays is shared among the threads (a piece of 256 left a 342-ray line
    /// to the calling thread alone).
    fn cast_rays(&self, rays: &[Ray], max_range_m: Real) -> Vec<Option<Hit>> {
        rays.par_iter()
            .with_min_len(CAST_PIECE)
            .map(|r| self.cast_ray(r, max_range_m))
            .collect()
    }
}

/// One named object of a scene.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneObject {
    /// Name (unique within the scene).
    pub name: String,
    /// Material of all its faces.
    pub material: MaterialId,
    /// Its triangles in [`Scene::mesh`].
    pub triangles: Range<usize>,
    /// `true` when its mesh is closed (every edge shared by two triangles), so
    /// "inside" is meaningful.
    pub closed: bool,
}

/// A triangle prepared for the ray test: first vertex and two edges, in f32.
#[derive(Clone, Copy, Debug)]
struct TriF32 {
    v0: [f32; 3],
    e1: [f32; 3],
    e2: [f32; 3],
}

impl TriF32 {
    fn new(t: &Triangle) -> Self {
        let f = |p: &Point3| [p.x as f32, p.y as f32, p.z as f32];
        let a = f(&t.a);
        let b = f(&t.b);
        let c = f(&t.c);
        Self {
            v0: a,
            e1: [b[0] - a[0], b[1] - a[1], b[2] - a[2]],
            e2: [c[0] - a[0], c[1] - a[1], c[2] - a[2]],
        }
    }

    /// Möller–Trumbore, both sides, under the convention of
    /// [`geom::Triangle::ray_hit`]: hits at `t ∈ [0, t_max]`, edges and vertices
    /// included (`u ≥ 0`, `v ≥ 0`, `u + v ≤ 1`), a ray in the triangle's plane
    /// misses. The same operations in the same order as [`Tri4::hit`], so the two
    /// agree to the bit.
    #[inline]
    fn hit(&self, o: &[f32; 3], d: &[f32; 3], t_max: f32) -> Option<f32> {
        let (e1, e2) = (&self.e1, &self.e2);
        let p = cross(d, e2);
        let det = dot(e1, &p);
        if det.abs() < DET_MIN {
            return None;
        }
        let inv = 1.0 / det;
        let s = [o[0] - self.v0[0], o[1] - self.v0[1], o[2] - self.v0[2]];
        let u = dot(&s, &p) * inv;
        let q = cross(&s, e1);
        let v = dot(d, &q) * inv;
        let t = dot(e2, &q) * inv;
        (u >= 0.0 && v >= 0.0 && u + v <= 1.0 && t >= 0.0 && t <= t_max).then_some(t)
    }
}

/// Below this |determinant| a ray counts as lying in the triangle's plane.
const DET_MIN: f32 = 1e-20;

/// Four triangles side by side (structure of arrays) for one four-lane
/// Möller–Trumbore test; lanes beyond a leaf's triangles are all zero
/// (determinant 0: never hit).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Tri4 {
    v0: [f32x4; 3],
    e1: [f32x4; 3],
    e2: [f32x4; 3],
}

impl Tri4 {
    fn new(tris: &[TriF32]) -> Self {
        let lanes = |f: &dyn Fn(&TriF32) -> [f32; 3]| -> [f32x4; 3] {
            let mut a = [[0.0f32; 4]; 3];
            for (lane, t) in tris.iter().take(4).enumerate() {
                let v = f(t);
                for axis in 0..3 {
                    a[axis][lane] = v[axis];
                }
            }
            a.map(f32x4::from)
        };
        Self {
            v0: lanes(&|t| t.v0),
            e1: lanes(&|t| t.e1),
            e2: lanes(&|t| t.e2),
        }
    }

    /// [`TriF32::hit`] on four triangles at once: the lane and distance of the
    /// closest hit in `[0, t_max]` (the lowest lane on ties).
    #[inline]
    fn hit(&self, r: &RayLanes, t_max: f32) -> Option<(usize, f32)> {
        let [dx, dy, dz] = r.dir;
        let [e1x, e1y, e1z] = self.e1;
        let [e2x, e2y, e2z] = self.e2;
        let px = dy * e2z - dz * e2y;
        let py = dz * e2x - dx * e2z;
        let pz = dx * e2y - dy * e2x;
        let det = e1x * px + e1y * py + e1z * pz;
        let inv = f32x4::ONE / det;
        let sx = r.origin[0] - self.v0[0];
        let sy = r.origin[1] - self.v0[1];
        let sz = r.origin[2] - self.v0[2];
        let u = (sx * px + sy * py + sz * pz) * inv;
        let qx = sy * e1z - sz * e1y;
        let qy = sz * e1x - sx * e1z;
        let qz = sx * e1y - sy * e1x;
        let v = (dx * qx + dy * qy + dz * qz) * inv;
        let t = (e2x * qx + e2y * qy + e2z * qz) * inv;
        let zero = f32x4::ZERO;
        let ok = det.abs().cmp_ge(f32x4::splat(DET_MIN))
            & u.cmp_ge(zero)
            & v.cmp_ge(zero)
            & (u + v).cmp_le(f32x4::ONE)
            & t.cmp_ge(zero)
            & t.cmp_le(f32x4::splat(t_max));
        let mut mask = ok.move_mask();
        if mask == 0 {
            return None;
        }
        let ts = t.to_array();
        let mut best: Option<(usize, f32)> = None;
        while mask != 0 {
            let k = mask.trailing_zeros() as usize & 3;
            mask &= mask - 1;
            if best.is_none_or(|(_, b)| ts[k] < b) {
                best = Some((k, ts[k]));
            }
        }
        best
    }
}

/// A ray's origin and direction, each coordinate in all four lanes.
#[derive(Clone, Copy, Debug)]
struct RayLanes {
    origin: [f32x4; 3],
    dir: [f32x4; 3],
}

/// The leaves of the wide tree: packets of four triangles, tested against one ray.
struct PacketLeaves<'a> {
    packets: &'a [Tri4],
}

impl PacketLeaves<'_> {
    #[inline]
    fn range(payload: u32) -> Range<usize> {
        let start = (payload >> PACKET_BITS) as usize;
        start..start + (payload & ((1 << PACKET_BITS) - 1)) as usize
    }
}

impl LeafTest for PacketLeaves<'_> {
    /// The closest hit among the leaf's packets: `(packet · 4 + lane, t)`.
    #[inline]
    fn test(&mut self, ray: &RayF32, payload: u32, t_best: f32) -> Option<(u32, f32)> {
        let ray = RayLanes {
            origin: ray.origin.map(f32x4::splat),
            dir: ray.dir.map(f32x4::splat),
        };
        let range = Self::range(payload);
        let start = range.start;
        let packets = self.packets.get(range)?;
        let mut found: Option<(u32, f32)> = None;
        let mut best = t_best;
        for (k, packet) in packets.iter().enumerate() {
            if let Some((lane, t)) = packet.hit(&ray, best)
                && found.is_none_or(|(_, b)| t < b)
            {
                best = t;
                found = Some(((start + k) as u32 * 4 + lane as u32, t));
            }
        }
        found
    }

    #[inline]
    fn prefetch(&self, payload: u32) {
        if let Some(p) = self.packets.get(Self::range(payload).start) {
            prefetch(p);
            prefetch(&p.e1[1]);
            prefetch(&p.e2[2]);
        }
    }
}

/// Packets per leaf are stored in the low bits of a wide-tree leaf payload.
const PACKET_BITS: u32 = 4;
/// The SAH build of the triangle tree: leaves of at most four triangles (one
/// four-lane packet).
const TRIANGLE_BUILD: BuildParams = BuildParams {
    bins: 16,
    max_leaf: 4,
    traversal_cost: 1.0,
    block: 4,
};

thread_local! {
    /// Traversal stack reused by single-ray queries on this thread.
    static STACK: RefCell<Stack> = RefCell::new(Vec::with_capacity(64));
}

#[inline]
fn cross(a: &[f32; 3], b: &[f32; 3]) -> [f32; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline]
fn dot(a: &[f32; 3], b: &[f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// A scene of triangle-mesh objects with materials, ready for queries.
#[derive(Clone, Debug)]
pub struct Scene {
    materials: Vec<Material>,
    objects: Vec<SceneObject>,
    mesh: TriMesh,
    tri_object: Vec<u32>,
    bvh: Bvh,
    /// Triangles in BVH slot order.
    tris: Vec<TriF32>,
    /// The four-wide collapse of `bvh`, for bulk ray casting; its leaf payloads
    /// are `first packet << PACKET_BITS | packet count`.
    bvh4: Bvh4,
    /// Each closed object's index and bounding box: a point outside every
    /// box (but its own object's) is inside no closed object.
    closed_bounds: Vec<(u32, Aabb)>,
    /// Each leaf's triangles in packets of four.
    packets: Vec<Tri4>,
    /// The triangle (face index) of each packet lane; `u32::MAX` for padding.
    packet_faces: Vec<[u32; 4]>,
}

impl Scene {
    /// A scene from named meshes (world frame) and a material table.
    pub fn from_objects(
        materials: Vec<Material>,
        objects: Vec<(String, MaterialId, TriMesh)>,
    ) -> Result<Self, SceneError> {
        validate_materials(&materials)?;
        let mut mesh = TriMesh::default();
        let mut list = Vec::with_capacity(objects.len());
        let mut tri_object = Vec::new();
        for (k, (name, material, m)) in objects.into_iter().enumerate() {
            if usize::from(material.0) >= materials.len() {
                return Err(SceneError::invalid(
                    format!("object `{name}`"),
                    format!(
                        "material id {} is not in the table of {}",
                        material.0,
                        materials.len()
                    ),
                ));
            }
            if list.iter().any(|o: &SceneObject| o.name == name) {
                return Err(SceneError::invalid(
                    format!("object `{name}`"),
                    "object names must be unique",
                ));
            }
            if m.is_empty() {
                return Err(SceneError::invalid(
                    format!("object `{name}`"),
                    "has no triangles",
                ));
            }
            let area = m.area();
            if area.is_nan() || area <= 0.0 {
                return Err(SceneError::invalid(
                    format!("object `{name}`"),
                    format!(
                        "has no area: all {} triangles are degenerate",
                        m.triangles.len()
                    ),
                ));
            }
            let start = mesh.triangles.len();
            let closed = m.boundary_edge_count() == 0;
            mesh.append(&m);
            tri_object.extend(std::iter::repeat_n(k as u32, m.len()));
            list.push(SceneObject {
                name,
                material,
                triangles: start..mesh.triangles.len(),
                closed,
            });
        }
        // Packet indices must fit the wide tree's 31-bit leaf payloads.
        if mesh.triangles.len() >= 1 << (31 - PACKET_BITS) {
            return Err(SceneError::invalid("scene", "more than 2²⁷ triangles"));
        }
        let (bounds, centroids): (Vec<Aabb32>, Vec<[f32; 3]>) = mesh
            .iter_triangles()
            .map(|t| {
                let b = Aabb32::from_f64(&Aabb::from_points([&t.a, &t.b, &t.c]));
                let c = t.centroid();
                (b, [c.x as f32, c.y as f32, c.z as f32])
            })
            .unzip();
        let bvh = Bvh::build_with(&bounds, &centroids, &TRIANGLE_BUILD);
        let tris: Vec<TriF32> = bvh
            .prim_indices
            .iter()
            .map(|&i| TriF32::new(&mesh.triangle(i as usize)))
            .collect();
        let mut packets = Vec::new();
        let mut packet_faces = Vec::new();
        let bvh4 = Bvh4::from_binary(&bvh, |first, count| {
            let start = packets.len() as u32;
            let slots = first as usize..(first + count) as usize;
            for (tri, slot) in tris[slots.clone()].chunks(4).zip(slots.step_by(4)) {
                packets.push(Tri4::new(tri));
                let mut faces = [u32::MAX; 4];
                for (lane, f) in faces.iter_mut().take(tri.len()).enumerate() {
                    *f = bvh.prim_indices[slot + lane];
                }
                packet_faces.push(faces);
            }
            (start << PACKET_BITS) | (packets.len() as u32 - start)
        })
        .ok_or_else(|| SceneError::invalid("scene", "too many triangles for the wide BVH"))?;
        let closed_bounds = list
            .iter()
            .enumerate()
            .filter(|(_, o)| o.closed)
            .map(|(k, o)| {
                let corners = mesh.triangles[o.triangles.clone()]
                    .iter()
                    .flat_map(|t| t.iter().map(|&v| &mesh.vertices[v as usize]));
                (k as u32, Aabb::from_points(corners))
            })
            .collect();
        Ok(Self {
            materials,
            objects: list,
            mesh,
            tri_object,
            bvh,
            tris,
            closed_bounds,
            bvh4,
            packets,
            packet_faces,
        })
    }

    /// A scene of one mesh with one material.
    pub fn from_mesh(
        name: &str,
        mesh: TriMesh,
        materials: Vec<Material>,
        material: MaterialId,
    ) -> Result<Self, SceneError> {
        Self::from_objects(materials, vec![(name.to_owned(), material, mesh)])
    }

    /// The material table.
    pub fn materials(&self) -> &[Material] {
        &self.materials
    }

    /// A material by id.
    pub fn material(&self, id: MaterialId) -> Option<&Material> {
        self.materials.get(usize::from(id.0))
    }

    /// The objects.
    pub fn objects(&self) -> &[SceneObject] {
        &self.objects
    }

    /// All triangles, in world coordinates.
    pub fn mesh(&self) -> &TriMesh {
        &self.mesh
    }

    /// The object a triangle belongs to.
    pub fn triangle_object(&self, face: FaceId) -> ObjectId {
        ObjectId(self.tri_object[face.0 as usize])
    }

    /// The object called `id`, if it exists.
    pub fn object(&self, id: ObjectId) -> Option<&SceneObject> {
        self.objects.get(id.index())
    }

    /// The material of a triangle.
    pub fn triangle_material(&self, face: FaceId) -> MaterialId {
        self.objects[self.tri_object[face.0 as usize] as usize].material
    }

    /// Bounding box of the whole scene.
    pub fn bounding_box(&self) -> Aabb {
        self.mesh.bounding_box()
    }

    /// The acceleration structure (for checks and statistics).
    pub fn bvh(&self) -> &Bvh {
        &self.bvh
    }

    /// Check both BVHs against the triangles.
    pub fn check_invariants(&self) -> Result<(), InvariantViolation> {
        self.invariant_detail()
            .map_err(|d| InvariantViolation::new("scene", d))
    }

    /// [`Scene::check_invariants`], the failure as text.
    fn invariant_detail(&self) -> Result<(), String> {
        let bounds: Vec<Aabb32> = self
            .mesh
            .iter_triangles()
            .map(|t| Aabb32::from_f64(&Aabb::from_points([&t.a, &t.b, &t.c])))
            .collect();
        self.bvh.invariant_detail(&bounds)?;
        // The wide tree: each face in exactly one leaf packet lane, inside the
        // leaf's box, and the packets equal to the faces they name.
        let mut seen = vec![false; bounds.len()];
        self.bvh4.invariant_detail(|payload, leaf_box| {
            let start = (payload >> PACKET_BITS) as usize;
            let count = (payload & ((1 << PACKET_BITS) - 1)) as usize;
            if count == 0 {
                return Err(format!("leaf {payload:#x} has no packets"));
            }
            for k in start..start + count {
                let faces = self
                    .packet_faces
                    .get(k)
                    .ok_or(format!("packet {k} missing"))?;
                let packet = self.packets.get(k).ok_or(format!("packet {k} missing"))?;
                for (lane, &f) in faces.iter().enumerate() {
                    if f == u32::MAX {
                        continue;
                    }
                    let b = bounds
                        .get(f as usize)
                        .ok_or(format!("packet {k} names face {f}"))?;
                    if std::mem::replace(&mut seen[f as usize], true) {
                        return Err(format!("face {f} in two packet lanes"));
                    }
                    if !leaf_box.contains(b) {
                        return Err(format!("leaf box does not contain face {f}"));
                    }
                    let want = TriF32::new(&self.mesh.triangle(f as usize));
                    let lane_of = |v: &[f32x4; 3]| v.map(|x| x.to_array()[lane]);
                    if lane_of(&packet.v0) != want.v0
                        || lane_of(&packet.e1) != want.e1
                        || lane_of(&packet.e2) != want.e2
                    {
                        return Err(format!("packet {k} lane {lane} is not face {f}"));
                    }
                }
            }
            Ok(())
        })?;
        match seen.iter().position(|s| !s) {
            Some(f) => Err(format!("face {f} in no packet")),
            None => Ok(()),
        }
    }

    /// The raw fast path: distance to the first triangle along a unit direction
    /// and its index, in single precision. Used by bulk ray casting.
    ///
    /// Hits follow the convention of [`geom::Triangle::ray_hit`]: `t ∈ [0, t_max]`,
    /// edges and vertices included.
    #[inline]
    pub fn first_hit_f32(&self, origin: [f32; 3], dir: [f32; 3], t_max: f32) -> Option<(f32, u32)> {
        STACK.with(|s| match s.try_borrow_mut() {
            Ok(mut stack) => self.first_hit_with(origin, dir, t_max, &mut stack),
            Err(_) => self.first_hit_with(origin, dir, t_max, &mut Vec::new()),
        })
    }

    /// [`Scene::first_hit_f32`] with a caller-owned traversal stack.
    #[inline]
    fn first_hit_with(
        &self,
        origin: [f32; 3],
        dir: [f32; 3],
        t_max: f32,
        stack: &mut Stack,
    ) -> Option<(f32, u32)> {
        let ray = RayF32::new(origin, dir);
        let mut leaves = PacketLeaves {
            packets: &self.packets,
        };
        self.bvh4
            .closest_hit(&ray, t_max, stack, &mut leaves)
            .and_then(|hit| self.lane_face(hit))
    }

    /// `(t, face)` of a packet-lane hit.
    #[inline]
    fn lane_face(&self, (lane_id, t): (u32, f32)) -> Option<(f32, u32)> {
        let faces = self.packet_faces.get((lane_id / 4) as usize)?;
        Some((t, faces[(lane_id % 4) as usize]))
    }

    /// Bulk ray casting: `rays` holds six floats per ray (origin, unit direction);
    /// `out` receives one distance per ray, `+inf` on a miss. Runs on the rayon
    /// pool of the caller, in chunks of 1024 rays, each walked several rays at a
    /// time ([`Bvh4::closest_hits`]).
    pub fn cast_rays_f32(&self, rays: &[[f32; 6]], t_max: f32, out: &mut [f32]) {
        const CHUNK: usize = 1024;
        out.par_chunks_mut(CHUNK)
            .zip(rays.par_chunks(CHUNK))
            .for_each(|(out, rays)| {
                let prepared: Vec<RayF32> = rays
                    .iter()
                    .map(|r| RayF32::new([r[0], r[1], r[2]], [r[3], r[4], r[5]]))
                    .collect();
                let mut hits = vec![None; prepared.len()];
                let mut leaves = PacketLeaves {
                    packets: &self.packets,
                };
                self.bvh4
                    .closest_hits(&prepared, t_max, &mut leaves, &mut hits);
                for (o, h) in out.iter_mut().zip(hits) {
                    *o = h.map_or(f32::INFINITY, |(_, t)| t);
                }
            });
    }

    /// The first hit `(face, t)` of each of `rays` within `t_max`, `None` on a
    /// miss, into `hits` (one slot per ray): the walk of one chunk of
    /// [`Scene::cast_rays_f32`], on the calling thread, several rays at a
    /// time, so the same hits, with their faces, for a caller that spreads
    /// rays over threads itself (the Python package's `Scene.raycast`).
    pub fn first_hits(&self, rays: &[RayF32], t_max: f32, hits: &mut [Option<(u32, f32)>]) {
        let mut leaves = PacketLeaves {
            packets: &self.packets,
        };
        self.bvh4.closest_hits(rays, t_max, &mut leaves, hits);
        for h in hits {
            *h = h
                .and_then(|hit| self.lane_face(hit))
                .map(|(t, face)| (face, t));
        }
    }

    /// The closest point of the scene's surface to `p` within `max_distance`:
    /// `(distance, triangle, point)`.
    pub fn closest_point(&self, p: &Point3, max_distance: Real) -> Option<(Real, FaceId, Point3)> {
        let mut best_d = max_distance;
        let mut best: Option<(u32, Point3)> = None;
        // Grow the query box as the best distance shrinks: visit leaves within
        // the current radius, closest-first is not needed for correctness.
        let mut stack = vec![0usize];
        let nodes = &self.bvh.nodes;
        if self.bvh.is_empty() {
            return None;
        }
        while let Some(i) = stack.pop() {
            let n = &nodes[i];
            let b = Aabb32 {
                min: n.min,
                max: n.max,
            }
            .to_f64();
            if b.distance_squared_to_point(p) > best_d * best_d {
                continue;
            }
            if n.count > 0 {
                for slot in n.first..n.first + n.count {
                    let face = self.bvh.prim_indices[slot as usize];
                    let q = self.mesh.triangle(face as usize).closest_point(p);
                    let d = (q - p).norm();
                    if d < best_d {
                        best_d = d;
                        best = Some((face, q));
                    }
                }
            } else {
                // Push the farther child first so the nearer is visited first.
                let c0 = n.first as usize;
                let d0 = Aabb32 {
                    min: nodes[c0].min,
                    max: nodes[c0].max,
                }
                .to_f64()
                .distance_squared_to_point(p);
                let d1 = Aabb32 {
                    min: nodes[c0 + 1].min,
                    max: nodes[c0 + 1].max,
                }
                .to_f64()
                .distance_squared_to_point(p);
                if d0 <= d1 {
                    stack.push(c0 + 1);
                    stack.push(c0);
                } else {
                    stack.push(c0);
                    stack.push(c0 + 1);
                }
            }
        }
        best.map(|(f, q)| (best_d, FaceId(f), q))
    }

    /// Triangles whose boxes overlap `query` (candidates for exact tests).
    pub fn triangles_near(&self, query: &Aabb) -> Vec<u32> {
        let q = Aabb32::from_f64(query);
        let mut out = Vec::new();
        let _: Option<()> = self.bvh.query_aabb(&q, |slot| {
            out.push(self.bvh.prim_indices[slot as usize]);
            ControlFlow::Continue(())
        });
        out
    }

    /// The first triangle found within `clearance` of the capsule's surface
    /// (i.e. closer than `radius + clearance` to its axis), with its distance.
    pub fn capsule_contact(&self, capsule: &Capsule, clearance: Real) -> Option<(FaceId, Real)> {
        let q = Aabb32::from_f64(&capsule.bounding_box().loosened(clearance));
        self.bvh.query_aabb(&q, |slot| {
            let face = self.bvh.prim_indices[slot as usize];
            let d = capsule.distance_to_triangle(&self.mesh.triangle(face as usize));
            if d <= clearance {
                ControlFlow::Break((FaceId(face), d))
            } else {
                ControlFlow::Continue(())
            }
        })
    }

    /// The first pair (scene triangle, given triangle index) that intersect,
    /// testing the given triangles (world frame) against the scene.
    pub fn triangles_contact(&self, triangles: &[Triangle]) -> Option<(FaceId, usize)> {
        for (k, t) in triangles.iter().enumerate() {
            let q = Aabb32::from_f64(&Aabb::from_points([&t.a, &t.b, &t.c]));
            let found = self.bvh.query_aabb(&q, |slot| {
                let face = self.bvh.prim_indices[slot as usize];
                if self.mesh.triangle(face as usize).intersects_triangle(t) {
                    ControlFlow::Break(face)
                } else {
                    ControlFlow::Continue(())
                }
            });
            if let Some(face) = found {
                return Some((FaceId(face), k));
            }
        }
        None
    }

    /// `true` when `p` lies inside a closed object (other than `except`): the
    /// first surface of a closed object met along a fixed direction is seen from
    /// its back. Triangles of `except` and of open objects are ignored, so a
    /// face flush against another object's face resolves to the other object.
    pub fn is_inside_closed_object(&self, p: &Point3, except: Option<ObjectId>) -> bool {
        // Outside every closed object's box no ray needs casting.
        if !self
            .closed_bounds
            .iter()
            .any(|(k, b)| Some(ObjectId(*k)) != except && b.contains_point(p))
        {
            return false;
        }
        self.ray_exits_closed_object(p, except)
    }

    /// The ray test of [`Scene::is_inside_closed_object`], without its box
    /// test.
    fn ray_exits_closed_object(&self, p: &Point3, except: Option<ObjectId>) -> bool {
        // A direction off every axis avoids grazing axis-aligned edges.
        let dir = Vector3::new(0.267_261_241_9, 0.534_522_483_8, 0.801_783_725_7);
        let ray = RayF32::new(
            [p.x as f32, p.y as f32, p.z as f32],
            [dir.x as f32, dir.y as f32, dir.z as f32],
        );
        let hit = self.bvh.closest_hit(&ray, f32::INFINITY, |slot, best| {
            let face = self.bvh.prim_indices[slot as usize];
            let obj = self.tri_object[face as usize];
            if Some(ObjectId(obj)) == except || !self.objects[obj as usize].closed {
                return None;
            }
            self.tris[slot as usize].hit(&ray.origin, &ray.dir, best)
        });
        hit.is_some_and(|(slot, _)| {
            let face = self.bvh.prim_indices[slot as usize];
            self.mesh
                .triangle(face as usize)
                .normal()
                .is_some_and(|n| n.dot(&dir) > 0.0)
        })
    }
}

impl RayCast for Scene {
    fn material(&self, id: MaterialId) -> Option<&Material> {
        Scene::material(self, id)
    }

    fn cast_ray(&self, ray: &Ray, max_range_m: Real) -> Option<Hit> {
        let o = [
            ray.origin.x as f32,
            ray.origin.y as f32,
            ray.origin.z as f32,
        ];
        let d = [ray.dir.x as f32, ray.dir.y as f32, ray.dir.z as f32];
        let (t32, face) = self.first_hit_f32(o, d, max_range_m as f32)?;
        let tri = self.mesh.triangle(face as usize);
        // Refine the distance in double precision on the hit triangle.
        let t = tri
            .ray_hit(ray, max_range_m * (1.0 + 1e-6))
            .unwrap_or(Real::from(t32));
        if t > max_range_m {
            return None;
        }
        let n = tri.normal().unwrap_or(-ray.dir);
        let normal = if n.dot(&ray.dir) > 0.0 { -n } else { n };
        let object = self.tri_object[face as usize];
        Some(Hit {
            distance: t,
            point: ray.point_at(t),
            normal,
            material: Some(self.objects[object as usize].material),
            object: Some(ObjectId(object)),
            element: face,
        })
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]
    use super::*;
    use crate::sampling::{SamplingConfig, SurfaceSampler};
    use rand::{RngExt, SeedableRng};

    /// The box test only skips rays that would find no closed object from
    /// behind: on the built-in scenes, the probes of every surface sample
    /// (as the exposure test places them) and random points in the scene's
    /// box get the ray test's answer.
    #[test]
    fn the_box_test_keeps_the_ray_tests_answer() {
        for name in ["bridge3", "cube", "block1", "block2", "cylinder"] {
            let world = crate::builtin::scene(name)
                .unwrap()
                .build(std::path::Path::new("."))
                .unwrap();
            let scene = world.as_scene().unwrap();
            let cfg = SamplingConfig {
                samples_per_m2: 2000.0,
                exposed_only: false,
                ..SamplingConfig::default()
            };
            let mut checked = 0;
            for s in SurfaceSampler::new(scene, &cfg).unwrap().flatten() {
                for side in [1e-4, -1e-4, 1e-2] {
                    let p = s.point + s.normal.into_inner() * side;
                    for except in [Some(s.object), None] {
                        assert_eq!(
                            scene.is_inside_closed_object(&p, except),
                            scene.ray_exits_closed_object(&p, except),
                            "{name}: {p:?} except {except:?}"
                        );
                        checked += 1;
                    }
                }
            }
            let b = scene.bounding_box();
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
            for _ in 0..20_000 {
                let p = Point3::new(
                    rng.random_range(b.min.x - 0.1..b.max.x + 0.1),
                    rng.random_range(b.min.y - 0.1..b.max.y + 0.1),
                    rng.random_range(b.min.z - 0.1..b.max.z + 0.1),
                );
                assert_eq!(
                    scene.is_inside_closed_object(&p, None),
                    scene.ray_exits_closed_object(&p, None),
                    "{name}: {p:?}"
                );
            }
            assert!(checked > 1000, "{name}: {checked} probes");
        }
    }
}
