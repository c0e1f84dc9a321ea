//! Rays files: the workload format of `surveyor raycast` and
//! `surveyor raycast-fixture`.
//!
//! A rays file is a flat sequence of 24-byte records, one per ray, and nothing
//! else: six little-endian `f32`, the origin `x y z` then the unit direction
//! `dx dy dz` (the layout of [`Scene::cast_rays_f32`](crate::Scene::cast_rays_f32)).
//! A file whose length is not a whole number of records, a non-finite value or
//! a direction whose squared length is more than [`DIRECTION_TOLERANCE`] from 1
//! is an error naming the file and the ray.
//!
//! ```
//! use scene::io::rays;
//! let dir = tempfile::tempdir()?;
//! let path = dir.path().join("rays.bin");
//! let workload = [[0.0, 0.0, 1.0, 0.0, 0.0, -1.0], [1.0, 2.0, 3.0, 0.6, 0.8, 0.0]];
//! rays::write_rays(&path, &workload)?;
//! assert_eq!(std::fs::metadata(&path)?.len(), 48);
//! assert_eq!(rays::read_rays(&path)?, workload);
//! // A direction that is not unit is refused before the file is touched.
//! let err = rays::write_rays(&path, &[[0.0, 0.0, 0.0, 0.0, 0.0, 2.0]]).unwrap_err();
//! assert!(err.to_string().ends_with("ray 0: direction (0, 0, 2) has length 2, expected a unit vector"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use super::read_file;
use crate::SceneError;
use std::io::Write as _;
use std::path::Path;

/// One ray: origin `x y z`, then unit direction `dx dy dz`.
pub type RayRecord = [f32; 6];

/// Bytes per ray record.
pub const RAY_BYTES: usize = 24;

/// Largest accepted `|‖d‖² − 1|` of a ray direction `d` (`f32` data
/// normalised in `f32` is within a few ulps).
pub const DIRECTION_TOLERANCE: f32 = 1e-3;

/// Read a rays file (format in the [module docs](self)).
pub fn read_rays(path: &Path) -> Result<Vec<RayRecord>, SceneError> {
    parse_rays(path, &read_file(path)?)
}

/// Decode the bytes of a rays file; `path` names it in errors.
pub fn parse_rays(path: &Path, bytes: &[u8]) -> Result<Vec<RayRecord>, SceneError> {
    if !bytes.len().is_multiple_of(RAY_BYTES) {
        let whole = bytes.len() / RAY_BYTES;
        return Err(SceneError::parse(
            path,
            None,
            format!(
                "{} bytes is not a whole number of rays ({RAY_BYTES} bytes each: six \
                 little-endian f32): {whole} whole rays and {} bytes left over from byte {} \
                 (file truncated?)",
                bytes.len(),
                bytes.len() % RAY_BYTES,
                whole * RAY_BYTES
            ),
        ));
    }
    let mut rays = Vec::with_capacity(bytes.len() / RAY_BYTES);
    for (index, chunk) in bytes.chunks_exact(RAY_BYTES).enumerate() {
        let mut ray = [0f32; 6];
        for (v, b) in ray.iter_mut().zip(chunk.chunks_exact(4)) {
            *v = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
        }
        check_ray(&ray).map_err(|message| SceneError::Ray {
            path: path.to_owned(),
            index,
            message,
        })?;
        rays.push(ray);
    }
    Ok(rays)
}

/// Write `rays` to a new rays file at `path` (created or truncated). Every ray
/// is checked first; nothing is written when one fails.
pub fn write_rays(path: &Path, rays: &[RayRecord]) -> Result<(), SceneError> {
    for (index, ray) in rays.iter().enumerate() {
        check_ray(ray).map_err(|message| SceneError::Ray {
            path: path.to_owned(),
            index,
            message,
        })?;
    }
    super::write_file(path, |w| {
        for ray in rays {
            for v in ray {
                w.write_all(&v.to_le_bytes())?;
            }
        }
        Ok(())
    })
}

/// A finite origin and a unit direction.
fn check_ray(ray: &RayRecord) -> Result<(), String> {
    const NAMES: [&str; 6] = ["x", "y", "z", "dx", "dy", "dz"];
    if let Some(k) = ray.iter().position(|v| !v.is_finite()) {
        return Err(format!(
            "{} is {} (expected a finite number)",
            NAMES[k], ray[k]
        ));
    }
    let [dx, dy, dz] = [ray[3], ray[4], ray[5]];
    let n2 = dx * dx + dy * dy + dz * dz;
    // Finite components: n2 is finite or +inf (overflow), never NaN.
    if (n2 - 1.0).abs() > DIRECTION_TOLERANCE {
        return Err(format!(
            "direction ({dx}, {dy}, {dz}) has length {}, expected a unit vector",
            n2.sqrt()
        ));
    }
    Ok(())
}
