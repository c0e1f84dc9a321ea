//! Shared test support: a URDF mesh loader backed by `scene`'s importer, as
//! `sim` provides in production.

use robot::LoadedMesh;
use std::path::Path;

/// Read STL/OBJ/PLY with `scene::io::load_mesh`; skip other formats.
pub fn scene_meshes(path: &Path) -> Result<LoadedMesh, String> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("stl" | "obj" | "ply") => scene::io::load_mesh(path, 1.0)
            .map(LoadedMesh::Mesh)
            .map_err(|e| e.to_string()),
        other => Ok(LoadedMesh::Skipped(format!(
            "{} files are not read",
            other.unwrap_or("extension-less")
        ))),
    }
}
