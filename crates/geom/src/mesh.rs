//! Indexed triangle meshes: the one mesh type of the workspace (scene objects,
//! robot link shapes, reconstructed surfaces).

use crate::aabb::Aabb;
use crate::math::{Isometry3, Point3, Real, Vector3, is_finite_point};
use crate::triangle::Triangle;
use serde::{Deserialize, Serialize};

/// Geometry that cannot make a valid mesh (or a primitive with invalid
/// dimensions). `what` names the source: a file, an object, a shape.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("{what}: {message}")]
pub struct MeshError {
    /// The file, object or shape at fault.
    pub what: String,
    /// What is wrong.
    pub message: String,
}

impl MeshError {
    /// An error about `what`.
    pub fn new(what: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            what: what.into(),
            message: message.into(),
        }
    }
}

/// An indexed triangle mesh in metres. Triangles wind anticlockwise seen from
/// outside (right-hand normals point out) for the closed primitives; imported
/// meshes keep whatever winding their file has.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct TriMesh {
    /// Vertex positions.
    pub vertices: Vec<Point3>,
    /// Vertex indices of each triangle.
    pub triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    /// A mesh from vertices and triangles, checked: every coordinate finite,
    /// every index in range. `what` names the source in errors (a file path, an
    /// object name).
    pub fn new(
        vertices: Vec<Point3>,
        triangles: Vec<[u32; 3]>,
        what: &str,
    ) -> Result<Self, MeshError> {
        if let Some(i) = vertices.iter().position(|p| !is_finite_point(p)) {
            return Err(MeshError::new(
                what,
                format!("vertex {i} has a non-finite coordinate"),
            ));
        }
        let n = vertices.len();
        if let Some((t, _)) = triangles
            .iter()
            .enumerate()
            .find(|(_, tri)| tri.iter().any(|&v| v as usize >= n))
        {
            return Err(MeshError::new(
                what,
                format!("triangle {t} refers to a vertex beyond the {n} given"),
            ));
        }
        Ok(Self {
            vertices,
            triangles,
        })
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// `true` when there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Triangle `i` as geometry.
    #[inline]
    pub fn triangle(&self, i: usize) -> Triangle {
        let [a, b, c] = self.triangles[i];
        Triangle::new(
            self.vertices[a as usize],
            self.vertices[b as usize],
            self.vertices[c as usize],
        )
    }

    /// All triangles as geometry.
    pub fn iter_triangles(&self) -> impl Iterator<Item = Triangle> + '_ {
        (0..self.triangles.len()).map(|i| self.triangle(i))
    }

    /// Bounding box of the vertices.
    pub fn bounding_box(&self) -> Aabb {
        Aabb::from_points(&self.vertices)
    }

    /// Total area.
    pub fn area(&self) -> Real {
        self.iter_triangles().map(|t| t.area()).sum()
    }

    /// Apply a rigid transform to every vertex.
    pub fn transform(&mut self, frame_from_mesh: &Isometry3) {
        for v in &mut self.vertices {
            *v = frame_from_mesh * *v;
        }
    }

    /// The mesh moved by a rigid transform.
    pub fn transformed(&self, frame_from_mesh: &Isometry3) -> Self {
        let mut m = self.clone();
        m.transform(frame_from_mesh);
        m
    }

    /// Scale every vertex about the origin, per axis.
    pub fn scale(&mut self, factor: Vector3) {
        for v in &mut self.vertices {
            v.coords.component_mul_assign(&factor);
        }
    }

    /// Append another mesh.
    pub fn append(&mut self, other: &Self) {
        let base = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.triangles.extend(
            other
                .triangles
                .iter()
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
    }

    /// Reverse the winding of every triangle (flip the normals).
    pub fn flip(&mut self) {
        for t in &mut self.triangles {
            t.swap(1, 2);
        }
    }

    /// Area-weighted vertex normals: each vertex gets the unit sum of the
    /// right-hand normals (`(b − a) × (c − a)`, twice the area) of the triangles
    /// using it, so the winding decides the side. A vertex used by no triangle,
    /// or whose triangles cancel, gets the zero vector.
    pub fn vertex_normals(&self) -> Vec<Vector3> {
        let mut sums = vec![Vector3::zeros(); self.vertices.len()];
        for t in &self.triangles {
            let [a, b, c] = t.map(|i| self.vertices[i as usize]);
            let n = (b - a).cross(&(c - a));
            for &i in t {
                sums[i as usize] += n;
            }
        }
        for n in &mut sums {
            let len = n.norm();
            *n = if len > 0.0 {
                *n / len
            } else {
                Vector3::zeros()
            };
        }
        sums
    }

    /// Number of edges used by exactly one triangle (0 for a closed mesh).
    pub fn boundary_edge_count(&self) -> usize {
        let mut edges = std::collections::HashMap::<(u32, u32), u32>::new();
        for t in &self.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                *edges.entry((a.min(b), a.max(b))).or_default() += 1;
            }
        }
        edges.values().filter(|&&c| c == 1).count()
    }

    /// Signed volume by the divergence theorem: positive for a closed mesh with
    /// outward normals.
    pub fn signed_volume(&self) -> Real {
        self.iter_triangles()
            .map(|t| t.a.coords.dot(&t.b.coords.cross(&t.c.coords)) / 6.0)
            .sum()
    }
}
