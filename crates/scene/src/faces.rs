//! A mesh scene's true planar faces: its triangles grouped into maximal
//! sets of coplanar triangles connected through shared edges
//! ([`true_faces`], over the welded [`mesh_topology`]), their outlines
//! ([`face_outline`]) and stratified samples of their triangles
//! ([`triangle_samples`]). What a surface model is scored against, and what
//! a surface-following run gives a priori when its robot cannot reach a
//! face.

use crate::{FaceId, ObjectId, Scene};
use geom::{Aabb, Point3, Real, UnitVector3, Vector3, unit};
use serde::Serialize;
use std::collections::{BTreeMap, HashMap};

/// Triangles whose normals differ by less than this are coplanar when they share
/// an edge (radians; 0.01°).
const COPLANAR_RAD: Real = 1.745e-4;

/// Vertices closer than this are welded when grouping triangles (metres).
const WELD_M: Real = 1e-7;

/// A true planar face: a maximal set of coplanar scene triangles connected
/// through shared edges.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TrueFace {
    /// Index in the list [`true_faces`] returns.
    pub id: usize,
    /// Outward unit normal (area-weighted mean of its triangles').
    pub normal: UnitVector3,
    /// Plane offset: `normal · x = offset` on the face.
    pub offset: Real,
    /// Scene triangle indices.
    pub triangles: Vec<u32>,
    /// Area, m².
    pub area_m2: Real,
    /// The scene object of its first triangle.
    pub object: ObjectId,
    /// Bounding box.
    pub bounds: Aabb,
}

/// A vertex welded within 10⁻⁷ m: its coordinates in units of 10⁻⁷ m.
pub type VertexKey = [i64; 3];

/// The welded key of `p`.
pub fn vertex_key(p: &Point3) -> VertexKey {
    // Coordinates are within scene::MAX_COORDINATE_M (1e7 m): / 1e-7 fits i64.
    #[allow(clippy::cast_possible_truncation)]
    let k = |c: Real| (c / WELD_M).round() as i64;
    [k(p.x), k(p.y), k(p.z)]
}

/// A mesh scene's welded topology: per triangle its vertex keys and
/// normal; per undirected edge the triangles using it.
#[derive(Clone, Debug)]
pub struct MeshTopology {
    /// Per triangle, its vertices' keys.
    pub triangle_keys: Vec<[VertexKey; 3]>,
    /// Per undirected edge (its keys in order), the non-degenerate
    /// triangles using it.
    pub edges: BTreeMap<(VertexKey, VertexKey), Vec<u32>>,
    /// Per triangle, its unit normal (`None` when degenerate).
    pub normals: Vec<Option<UnitVector3>>,
}

/// The welded topology of `scene`'s triangles.
pub fn mesh_topology(scene: &Scene) -> MeshTopology {
    let mesh = scene.mesh();
    let mut tri_keys = Vec::with_capacity(mesh.len());
    let mut edges: BTreeMap<(VertexKey, VertexKey), Vec<u32>> = BTreeMap::new();
    let mut normals = Vec::with_capacity(mesh.len());
    for (t, tri) in mesh.iter_triangles().enumerate() {
        let keys = [vertex_key(&tri.a), vertex_key(&tri.b), vertex_key(&tri.c)];
        let n = tri.normal();
        normals.push(n);
        if n.is_some() {
            for (a, b) in [(0, 1), (1, 2), (2, 0)] {
                let (ka, kb) = (keys[a], keys[b]);
                let e = if ka <= kb { (ka, kb) } else { (kb, ka) };
                #[allow(clippy::cast_possible_truncation)]
                edges.entry(e).or_default().push(t as u32);
            }
        }
        tri_keys.push(keys);
    }
    MeshTopology {
        triangle_keys: tri_keys,
        edges,
        normals,
    }
}

fn find(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// Group `scene`'s triangles into its true faces (see [`true_faces`]) by
/// its topology `topo`; returns the faces and each triangle's face (`None`
/// for a degenerate triangle).
pub fn group_faces(scene: &Scene, topo: &MeshTopology) -> (Vec<TrueFace>, Vec<Option<usize>>) {
    let mesh = scene.mesh();
    let n = mesh.len();
    let mut parent: Vec<usize> = (0..n).collect();
    let cos_tol = COPLANAR_RAD.cos();
    for tris in topo.edges.values() {
        for (i, &a) in tris.iter().enumerate() {
            for &b in &tris[i + 1..] {
                let (Some(na), Some(nb)) = (topo.normals[a as usize], topo.normals[b as usize])
                else {
                    continue;
                };
                if na.dot(&nb) >= cos_tol {
                    let (ra, rb) = (find(&mut parent, a as usize), find(&mut parent, b as usize));
                    if ra != rb {
                        parent[ra.max(rb)] = ra.min(rb);
                    }
                }
            }
        }
    }
    let mut root_face: HashMap<usize, usize> = HashMap::new();
    let mut members: Vec<Vec<u32>> = Vec::new();
    let mut tri_face = vec![None; n];
    for (t, slot) in tri_face.iter_mut().enumerate() {
        if topo.normals[t].is_none() {
            continue;
        }
        let r = find(&mut parent, t);
        let f = *root_face.entry(r).or_insert_with(|| {
            members.push(Vec::new());
            members.len() - 1
        });
        #[allow(clippy::cast_possible_truncation)]
        members[f].push(t as u32);
        *slot = Some(f);
    }
    let faces = members
        .into_iter()
        .enumerate()
        .map(|(id, triangles)| {
            let mut nsum = Vector3::zeros();
            let mut csum = Vector3::zeros();
            let mut area = 0.0;
            let mut bounds = Aabb::empty();
            for &t in &triangles {
                let tri = mesh.triangle(t as usize);
                let a = tri.area();
                nsum += tri
                    .normal()
                    .map_or(Vector3::zeros(), |n| n.into_inner() * a);
                csum += tri.centroid().coords * a;
                area += a;
                for p in [tri.a, tri.b, tri.c] {
                    bounds.grow(&p);
                }
            }
            let normal = unit(nsum).unwrap_or_else(|| {
                topo.normals[triangles[0] as usize].unwrap_or_else(Vector3::z_axis)
            });
            let centroid = csum / area.max(Real::MIN_POSITIVE);
            TrueFace {
                id,
                normal,
                offset: normal.dot(&centroid),
                object: scene.triangle_object(FaceId(triangles[0])),
                triangles,
                area_m2: area,
                bounds,
            }
        })
        .collect();
    (faces, tri_face)
}

/// The scene's true planar faces: maximal sets of coplanar triangles (normals
/// within 0.01°) connected through shared edges (vertices welded within
/// 10⁻⁷ m), in order of their first triangle. Degenerate triangles belong to
/// no face.
pub fn true_faces(scene: &Scene) -> Vec<TrueFace> {
    group_faces(scene, &mesh_topology(scene)).0
}

/// A face predicate (of a surface model's score, say) that drops the faces resting on
/// a horizontal support at height `z`: those facing down (normal within 1° of
/// −z) whose highest point is within 1 mm of `z` (the bottom of an object
/// standing on the table). Every other face counts.
pub fn not_resting_on(z: Real) -> impl Fn(&TrueFace) -> bool {
    move |f: &TrueFace| !(f.normal.z < -(1f64.to_radians().cos()) && f.bounds.max.z <= z + 1e-3)
}

/// Stratified uniform samples of a triangle: the centroids of its `k²`
/// congruent sub-triangles, `k = ⌈√(area / spacing²)⌉`; each stands for
/// `area / k²`.
pub fn triangle_samples(tri: &geom::Triangle, spacing: Real, out: &mut Vec<(Point3, Real)>) {
    let area = tri.area();
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    let k = ((area / (spacing * spacing)).sqrt().ceil() as usize).max(1);
    let kf = k as Real;
    let w = area / (kf * kf);
    let (ab, ac) = (tri.b - tri.a, tri.c - tri.a);
    for i in 0..k {
        for j in 0..k - i {
            let (u, v) = ((i as Real + 1.0 / 3.0) / kf, (j as Real + 1.0 / 3.0) / kf);
            out.push((tri.a + ab * u + ac * v, w));
            if i + j + 2 <= k {
                let (u, v) = ((i as Real + 2.0 / 3.0) / kf, (j as Real + 2.0 / 3.0) / kf);
                out.push((tri.a + ab * u + ac * v, w));
            }
        }
    }
}

/// The outline of a true face: its boundary loop (the edges of its
/// triangles that no other of its triangles shares, vertices welded within
/// 10⁻⁷ m), anticlockwise about its outward normal when the scene's
/// triangles are, with collinear vertices dropped. `None` when the boundary
/// is not one loop (a face with a hole, or faces touching at a vertex).
pub fn face_outline(scene: &Scene, face: &TrueFace) -> Option<Vec<Point3>> {
    type Key = [i64; 3];
    #[allow(clippy::cast_possible_truncation)]
    let key = |p: &Point3| -> Key { [p.x, p.y, p.z].map(|v| (v * 1e7).round() as i64) };
    let mut edges: HashMap<(Key, Key), Point3> = HashMap::new();
    for &t in &face.triangles {
        let tri = scene.mesh().triangle(t as usize);
        for (a, b) in [(tri.a, tri.b), (tri.b, tri.c), (tri.c, tri.a)] {
            let (ka, kb) = (key(&a), key(&b));
            if edges.remove(&(kb, ka)).is_none() {
                edges.insert((ka, kb), a);
            }
        }
    }
    let mut next: HashMap<Key, (Key, Point3)> = HashMap::new();
    for (&(ka, kb), &a) in &edges {
        if next.insert(ka, (kb, a)).is_some() {
            return None;
        }
    }
    let start = *next.keys().min()?;
    let mut loop_points = Vec::with_capacity(next.len());
    let mut at = start;
    for _ in 0..next.len() {
        let (to, p) = next.get(&at)?;
        loop_points.push(*p);
        at = *to;
        if at == start {
            break;
        }
    }
    if at != start || loop_points.len() != next.len() {
        return None;
    }
    let n = loop_points.len();
    let outline: Vec<Point3> = (0..n)
        .filter(|&i| {
            let (prev, p, nxt) = (
                loop_points[(i + n - 1) % n],
                loop_points[i],
                loop_points[(i + 1) % n],
            );
            (p - prev).cross(&(nxt - p)).norm() > 1e-9
        })
        .map(|i| loop_points[i])
        .collect();
    (outline.len() >= 3).then_some(outline)
}
