//! Link meshes: loading OBJ and STL collision meshes, and closed meshes of the URDF
//! primitives (boxes, cylinders).

use crate::error::RobotError;
use crate::model::LinkMesh;
use geom::{Aabb, Isometry3, Point3, Real, Triangle, Vector3};
use std::collections::HashMap;
use std::io::{BufRead, Cursor};
use std::path::Path;

/// Number of segments around the cylinder meshes built for URDF `<cylinder>`.
pub const CYLINDER_SEGMENTS: usize = 24;

impl LinkMesh {
    /// A mesh from vertices and triangles, checked: finite vertices, indices in range.
    pub fn new(
        vertices: Vec<Point3>,
        triangles: Vec<[u32; 3]>,
        what: &str,
    ) -> Result<Self, RobotError> {
        let mesh = Self {
            vertices,
            triangles,
        };
        mesh.validate(what)?;
        Ok(mesh)
    }

    /// `Ok` when every vertex is finite and every index is in range.
    pub fn validate(&self, what: &str) -> Result<(), RobotError> {
        if let Some(i) = self
            .vertices
            .iter()
            .position(|p| !geom::math::is_finite_point(p))
        {
            return Err(RobotError::MeshData {
                what: what.to_owned(),
                message: format!("vertex {i} is not finite"),
            });
        }
        if u32::try_from(self.vertices.len()).is_err() {
            return Err(RobotError::MeshData {
                what: what.to_owned(),
                message: format!(
                    "{} vertices is more than a link mesh can index",
                    self.vertices.len()
                ),
            });
        }
        let n = self.vertices.len() as u32;
        if let Some(t) = self
            .triangles
            .iter()
            .position(|t| t.iter().any(|&i| i >= n))
        {
            return Err(RobotError::MeshData {
                what: what.to_owned(),
                message: format!("triangle {t} indexes past the {n} vertices"),
            });
        }
        Ok(())
    }

    /// `true` when the mesh has no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Triangle `i` as a [`Triangle`]; `None` when out of range.
    pub fn triangle(&self, i: usize) -> Option<Triangle> {
        let [a, b, c] = *self.triangles.get(i)?;
        Some(Triangle::new(
            *self.vertices.get(a as usize)?,
            *self.vertices.get(b as usize)?,
            *self.vertices.get(c as usize)?,
        ))
    }

    /// All triangles (those with out-of-range indices are skipped).
    pub fn iter_triangles(&self) -> impl Iterator<Item = Triangle> + '_ {
        (0..self.triangles.len()).filter_map(|i| self.triangle(i))
    }

    /// The bounding box of the vertices.
    pub fn bounding_box(&self) -> Aabb {
        Aabb::from_points(&self.vertices)
    }

    /// The mesh with every vertex mapped by `frame_from_mesh`.
    pub fn transformed(&self, frame_from_mesh: &Isometry3) -> Self {
        Self {
            vertices: self.vertices.iter().map(|p| frame_from_mesh * p).collect(),
            triangles: self.triangles.clone(),
        }
    }

    /// Append `other`'s vertices and triangles.
    pub fn append(&mut self, other: &Self) {
        let offset = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.triangles.extend(
            other
                .triangles
                .iter()
                .map(|t| [t[0] + offset, t[1] + offset, t[2] + offset]),
        );
    }

    /// The closed box `[min, max]` (12 triangles, outward normals).
    pub fn cuboid(min: Point3, max: Point3) -> Self {
        let corner = |i: usize| {
            Point3::new(
                if i & 1 == 0 { min.x } else { max.x },
                if i & 2 == 0 { min.y } else { max.y },
                if i & 4 == 0 { min.z } else { max.z },
            )
        };
        let vertices = (0..8).map(corner).collect();
        // Each face as two triangles, anticlockwise seen from outside.
        let triangles = vec![
            [0, 2, 3],
            [0, 3, 1], // z = min
            [4, 5, 7],
            [4, 7, 6], // z = max
            [0, 1, 5],
            [0, 5, 4], // y = min
            [2, 6, 7],
            [2, 7, 3], // y = max
            [0, 4, 6],
            [0, 6, 2], // x = min
            [1, 3, 7],
            [1, 7, 5], // x = max
        ];
        Self {
            vertices,
            triangles,
        }
    }

    /// The closed cylinder of `radius` and `length` centred on the origin along z,
    /// with `segments` sides (URDF `<cylinder>`).
    pub fn cylinder(radius: Real, length: Real, segments: usize) -> Self {
        let segments = segments.max(3);
        let h = 0.5 * length;
        let mut vertices = Vec::with_capacity(2 * segments + 2);
        for k in 0..segments {
            let a = std::f64::consts::TAU * k as Real / segments as Real;
            let (s, c) = a.sin_cos();
            vertices.push(Point3::new(radius * c, radius * s, -h));
            vertices.push(Point3::new(radius * c, radius * s, h));
        }
        let bottom = vertices.len() as u32;
        vertices.push(Point3::new(0.0, 0.0, -h));
        vertices.push(Point3::new(0.0, 0.0, h));
        let top = bottom + 1;
        let mut triangles = Vec::with_capacity(4 * segments);
        let n = segments as u32;
        for k in 0..n {
            let (b0, t0) = (2 * k, 2 * k + 1);
            let (b1, t1) = (2 * ((k + 1) % n), 2 * ((k + 1) % n) + 1);
            triangles.push([b0, b1, t1]);
            triangles.push([b0, t1, t0]);
            triangles.push([bottom, b1, b0]);
            triangles.push([top, t0, t1]);
        }
        Self {
            vertices,
            triangles,
        }
    }

    /// Parse Wavefront OBJ text (all objects merged; polygons triangulated;
    /// materials ignored). `what` names the source in errors.
    pub fn from_obj_str(text: &str, what: &str) -> Result<Self, RobotError> {
        Self::from_obj_reader(&mut Cursor::new(text.as_bytes()), what)
    }

    /// Parse Wavefront OBJ from a reader; see [`LinkMesh::from_obj_str`].
    pub fn from_obj_reader(reader: &mut impl BufRead, what: &str) -> Result<Self, RobotError> {
        let options = tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ..Default::default()
        };
        let (models, _materials) =
            tobj::load_obj_buf(reader, &options, |_| Ok((Vec::new(), HashMap::new()))).map_err(
                |e| RobotError::MeshData {
                    what: what.to_owned(),
                    message: format!("cannot parse OBJ: {e}"),
                },
            )?;
        let mut mesh = Self::default();
        for model in models {
            let m = model.mesh;
            let offset = mesh.vertices.len() as u32;
            mesh.vertices.extend(
                m.positions
                    .chunks_exact(3)
                    .map(|c| Point3::new(Real::from(c[0]), Real::from(c[1]), Real::from(c[2]))),
            );
            mesh.triangles.extend(
                m.indices
                    .chunks_exact(3)
                    .map(|t| [t[0] + offset, t[1] + offset, t[2] + offset]),
            );
        }
        mesh.validate(what)?;
        Ok(mesh)
    }

    /// Parse an STL file's bytes (binary or ASCII). `what` names the source in errors.
    pub fn from_stl_bytes(bytes: &[u8], what: &str) -> Result<Self, RobotError> {
        let indexed =
            stl_io::read_stl(&mut Cursor::new(bytes)).map_err(|e| RobotError::MeshData {
                what: what.to_owned(),
                message: format!("cannot parse STL: {e}"),
            })?;
        let vertices = indexed
            .vertices
            .iter()
            .map(|v| Point3::new(Real::from(v.0[0]), Real::from(v.0[1]), Real::from(v.0[2])))
            .collect();
        let triangles = indexed
            .faces
            .iter()
            .map(|f| f.vertices.map(|i| u32::try_from(i).unwrap_or(u32::MAX)))
            .collect();
        Self::new(vertices, triangles, what)
    }

    /// Load an STL or OBJ file, chosen by extension.
    pub fn from_file(path: &Path) -> Result<Self, RobotError> {
        let what = path.display().to_string();
        let bytes = std::fs::read(path).map_err(|e| RobotError::Io {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        match extension(path).as_deref() {
            Some("stl") => Self::from_stl_bytes(&bytes, &what),
            Some("obj") => Self::from_obj_reader(&mut Cursor::new(bytes), &what),
            other => Err(RobotError::MeshData {
                what,
                message: format!(
                    "unsupported mesh format {}: expected .stl or .obj",
                    other.map_or_else(|| "(no extension)".to_owned(), |e| format!(".{e}"))
                ),
            }),
        }
    }

    /// Vertices scaled per axis (URDF `<mesh scale>`).
    pub fn scaled(&self, scale: &Vector3) -> Self {
        Self {
            vertices: self
                .vertices
                .iter()
                .map(|p| Point3::from(p.coords.component_mul(scale)))
                .collect(),
            triangles: self.triangles.clone(),
        }
    }
}

/// The lower-case extension of `path`, if any.
pub(crate) fn extension(path: &Path) -> Option<String> {
    path.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Signed volume by the divergence theorem: positive for outward orientation.
    fn volume(m: &LinkMesh) -> Real {
        m.iter_triangles()
            .map(|t| t.a.coords.dot(&t.b.coords.cross(&t.c.coords)) / 6.0)
            .sum()
    }

    #[test]
    fn primitives_are_closed_and_outward() {
        let b = LinkMesh::cuboid(Point3::new(-1.0, -2.0, 0.0), Point3::new(1.0, 2.0, 3.0));
        assert!((volume(&b) - 24.0).abs() < 1e-12);
        let c = LinkMesh::cylinder(0.5, 2.0, CYLINDER_SEGMENTS);
        let n = CYLINDER_SEGMENTS as Real;
        let polygon_area = 0.5 * n * 0.25 * (std::f64::consts::TAU / n).sin();
        assert!((volume(&c) - polygon_area * 2.0).abs() < 1e-12);
        assert_eq!(c.triangles.len(), 4 * CYLINDER_SEGMENTS);
    }

    #[test]
    fn obj_and_stl_parse() {
        let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
        let m = LinkMesh::from_obj_str(obj, "quad").unwrap();
        assert_eq!(m.triangles.len(), 2);
        let stl = b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n";
        let s = LinkMesh::from_stl_bytes(stl, "tri").unwrap();
        assert_eq!((s.vertices.len(), s.triangles.len()), (3, 1));
        let bad = LinkMesh::from_obj_str("v 0 0 0\nf 1 2 3\n", "broken");
        assert!(bad.is_err());
    }
}
