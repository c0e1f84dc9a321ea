//! Link meshes: closed meshes of the URDF primitives, the embedded VM-6083
//! meshes, and the [`MeshLoader`] through which URDF mesh files are read.
//!
//! This crate reads no mesh file format itself: file formats are the `scene`
//! crate's business (its importers report file, line and field on bad input). A
//! caller that wants URDF collision meshes passes a loader — `sim` passes one
//! backed by `scene::io::load_mesh` — and [`NoMeshLoader`] skips them with a
//! warning, which is all forward kinematics needs.

use crate::error::RobotError;
use geom::primitives::cylinder;
use geom::{Point3, Real, TriMesh};
use std::path::Path;

/// Number of segments around the cylinder meshes built for URDF `<cylinder>`.
pub const CYLINDER_SEGMENTS: u32 = 24;

/// What a [`MeshLoader`] made of a mesh file.
#[derive(Clone, Debug, PartialEq)]
pub enum LoadedMesh {
    /// The triangles, in the file's own frame and units.
    Mesh(TriMesh),
    /// The loader does not read this file (format or policy): the geometry is
    /// skipped and the reason goes to [`crate::Robot::warnings`].
    Skipped(String),
}

/// Reads the mesh files a URDF refers to.
pub trait MeshLoader {
    /// Load `path`. `Err` (a missing or corrupt file) fails the URDF load with an
    /// error naming the URDF line and the mesh.
    fn load(&self, path: &Path) -> Result<LoadedMesh, String>;
}

/// A loader that reads nothing: URDF mesh geometry is skipped with a warning
/// (links without other shapes then get automatic capsules).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoMeshLoader;

impl MeshLoader for NoMeshLoader {
    fn load(&self, _path: &Path) -> Result<LoadedMesh, String> {
        Ok(LoadedMesh::Skipped(
            "mesh files are not read without a mesh loader".to_owned(),
        ))
    }
}

impl<F> MeshLoader for F
where
    F: Fn(&Path) -> Result<LoadedMesh, String>,
{
    fn load(&self, path: &Path) -> Result<LoadedMesh, String> {
        self(path)
    }
}

/// The closed cylinder of `radius` and `length` centred on the origin along z
/// (URDF `<cylinder>`), with [`CYLINDER_SEGMENTS`] sides.
pub fn urdf_cylinder(radius: Real, length: Real, what: &str) -> Result<TriMesh, RobotError> {
    let h = 0.5 * length;
    cylinder(
        &Point3::new(0.0, 0.0, -h),
        &Point3::new(0.0, 0.0, h),
        radius,
        CYLINDER_SEGMENTS,
    )
    .map_err(|e| RobotError::MeshData {
        what: what.to_owned(),
        message: e.message,
    })
}

/// Parse the `v`/`f` lines of an embedded OBJ asset (the built-in VM-6083 link
/// meshes, written by a known converter with triangles only). Not for user files.
pub(crate) fn parse_embedded_obj(text: &str, what: &str) -> Result<TriMesh, RobotError> {
    let bad = |line: usize, message: &str| RobotError::MeshData {
        what: what.to_owned(),
        message: format!("line {}: {message}", line + 1),
    };
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => {
                let c: Vec<Real> = words.filter_map(|w| w.parse().ok()).collect();
                let [x, y, z] = c[..] else {
                    return Err(bad(k, "expected `v x y z`"));
                };
                vertices.push(Point3::new(x, y, z));
            }
            Some("f") => {
                let idx: Vec<u32> = words
                    .filter_map(|w| w.split('/').next()?.parse::<u32>().ok()?.checked_sub(1))
                    .collect();
                let [a, b, c] = idx[..] else {
                    return Err(bad(k, "expected a triangle `f a b c`"));
                };
                triangles.push([a, b, c]);
            }
            _ => {}
        }
    }
    TriMesh::new(vertices, triangles, what).map_err(|e| RobotError::MeshData {
        what: e.what,
        message: e.message,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cylinder_is_centred_closed_and_outward() {
        let c = urdf_cylinder(0.5, 2.0, "c").unwrap();
        let n = Real::from(CYLINDER_SEGMENTS);
        let polygon_area = 0.5 * n * 0.25 * (std::f64::consts::TAU / n).sin();
        assert!((c.signed_volume() - polygon_area * 2.0).abs() < 1e-12);
        assert_eq!(c.boundary_edge_count(), 0);
        let bb = c.bounding_box();
        assert!((bb.min.z + 1.0).abs() < 1e-12 && (bb.max.z - 1.0).abs() < 1e-12);
        assert!(urdf_cylinder(0.0, 1.0, "c").is_err());
    }

    #[test]
    fn embedded_obj_parses_and_rejects_garbage() {
        let m = parse_embedded_obj("# c\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "tri").unwrap();
        assert_eq!((m.vertices.len(), m.triangles.len()), (3, 1));
        assert!(parse_embedded_obj("v 0 0 0\nf 1 2 3\n", "broken").is_err());
        assert!(parse_embedded_obj("v 0 0\n", "short").is_err());
        assert!(parse_embedded_obj("v 0 0 0\nf 0 1 1\n", "zero index").is_err());
    }

    #[test]
    fn no_loader_skips() {
        assert!(matches!(
            NoMeshLoader.load(Path::new("x.stl")),
            Ok(LoadedMesh::Skipped(_))
        ));
    }
}
