//! Shared test support: the URDF mesh loader `sim` provides in production,
//! backed by `scene`'s importer.

use robot::LoadedMesh;
use scene::SceneError;
use std::path::Path;

/// Read meshes with `scene::io::load_mesh`; skip formats it does not read.
pub fn scene_meshes(path: &Path) -> Result<LoadedMesh, String> {
    match scene::io::load_mesh(path, 1.0) {
        Ok(mesh) => Ok(LoadedMesh::Mesh(mesh)),
        Err(SceneError::Unsupported { expected, .. }) => {
            Ok(LoadedMesh::Skipped(format!("not read ({expected})")))
        }
        Err(e) => Err(e.to_string()),
    }
}
