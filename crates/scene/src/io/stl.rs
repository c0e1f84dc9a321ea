//! STL meshes (binary and ASCII) through `stl_io`.
//!
//! `stl_io` decides "ASCII" whenever the file starts with `solid `, which some
//! binary exporters also write into their 80-byte header, and does not accept
//! an ASCII file whose first line is a bare `solid`. So the kind is decided
//! here: a file whose length is exactly what its triangle count promises
//! (`84 + 50 n` bytes) is binary; otherwise a file starting with `solid` is
//! ASCII. A binary file is checked against that length before `stl_io` reads
//! it, so truncation gives a clear error, and so does a count smaller than the
//! data (the triangles past it are not silently dropped).

use super::finish_mesh;
use crate::{SceneError, TriMesh};
use geom::{Point3, Real};
use std::io::Cursor;
use std::path::Path;

/// Bytes of a binary STL before the triangles: header and triangle count.
const HEADER: usize = 84;
/// Bytes per binary STL triangle.
const TRIANGLE: usize = 50;

pub(super) fn load_mesh(path: &Path, bytes: &[u8], scale: Real) -> Result<TriMesh, SceneError> {
    let perr = |msg: String| SceneError::parse(path, None, msg);
    if bytes.is_empty() {
        return Err(perr("empty file (expected a binary or ASCII STL)".into()));
    }
    let looks_ascii = bytes.trim_ascii_start().starts_with(b"solid");
    let indexed = if bytes.len() >= HEADER {
        let count = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        let expected = HEADER + TRIANGLE * count;
        if bytes.len() == expected {
            read_binary(bytes).map_err(|e| perr(format!("binary STL: {e}")))?
        } else if bytes.len() > expected && !looks_ascii {
            // A count smaller than the data must not silently drop triangles.
            let extra = bytes.len() - expected;
            return Err(perr(format!(
                "binary STL longer than declared: the header declares {count} triangles = \
                 {expected} bytes, the file has {} ({extra} bytes after the last declared \
                 triangle{}); a triangle count smaller than the data?",
                bytes.len(),
                if extra.is_multiple_of(TRIANGLE) {
                    format!(", = {} more triangles", extra / TRIANGLE)
                } else {
                    String::new()
                }
            )));
        } else if looks_ascii {
            read_ascii(bytes).map_err(|e| {
                perr(format!(
                    "not a valid ASCII STL ({e}), nor a complete binary STL (its header would \
                     declare {count} triangles = {expected} bytes, the file has {})",
                    bytes.len()
                ))
            })?
        } else {
            return Err(perr(format!(
                "binary STL truncated: the header declares {count} triangles = {expected} \
                 bytes, the file has {}",
                bytes.len()
            )));
        }
    } else if looks_ascii {
        read_ascii(bytes).map_err(|e| perr(format!("ASCII STL: {e}")))?
    } else {
        return Err(perr(format!(
            "too short for a binary STL ({} bytes, the header alone is {HEADER}) and not an \
             ASCII STL (no leading 'solid')",
            bytes.len()
        )));
    };
    let vertices = indexed
        .vertices
        .iter()
        .map(|v| {
            Point3::new(
                Real::from(v[0]) * scale,
                Real::from(v[1]) * scale,
                Real::from(v[2]) * scale,
            )
        })
        .collect();
    let triangles = indexed
        .faces
        .iter()
        .map(|f| f.vertices.map(|i| i as u32))
        .collect();
    finish_mesh(path, vertices, triangles)
}

/// A binary STL of exactly `84 + 50 count` bytes.
fn read_binary(bytes: &[u8]) -> std::io::Result<stl_io::IndexedMesh> {
    if bytes.trim_ascii_start().starts_with(b"solid") {
        // Blank the header so that stl_io does not take it for ASCII.
        let mut copy = bytes.to_vec();
        copy[..80].fill(0);
        stl_io::read_stl(&mut Cursor::new(copy))
    } else {
        stl_io::read_stl(&mut Cursor::new(bytes))
    }
}

/// An ASCII STL; the first line is replaced by `solid surveyor`, which stl_io
/// recognises whatever the file's own first line (`solid`, `  solid name`).
fn read_ascii(bytes: &[u8]) -> std::io::Result<stl_io::IndexedMesh> {
    let rest = bytes
        .iter()
        .position(|&b| b == b'\n')
        .map_or(&[][..], |nl| &bytes[nl + 1..]);
    let mut copy = Vec::with_capacity(rest.len() + 16);
    copy.extend_from_slice(b"solid surveyor\n");
    copy.extend_from_slice(rest);
    stl_io::read_stl(&mut Cursor::new(copy))
}
