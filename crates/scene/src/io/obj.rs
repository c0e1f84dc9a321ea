//! Wavefront OBJ meshes, read through `tobj` and written as text.
//!
//! `tobj` reports errors without line numbers and can overflow an index (a
//! panic in debug builds) on texture or normal references such as `f 1/0/1`.
//! So a first pass checks every `v` and `f` line here, with line numbers, and
//! hands `tobj` only positions and position indices: no `vt`/`vn` data, no
//! materials, no groups. `tobj` then parses and triangulates.

use super::{MAX_FACE_VERTICES, Precision, check_mesh_for_writing, finish_mesh, write_file};
use crate::{SceneError, TriMesh};
use geom::{Point3, Real};
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

pub(super) fn load_mesh(path: &Path, bytes: &[u8], scale: Real) -> Result<TriMesh, SceneError> {
    let clean = sanitize(path, bytes)?;
    // `..Default::default()` keeps this compiling if another crate turns on
    // tobj's optional `merging`/`reordering` fields (features unify).
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    // No material is ever needed (and `mtllib` lines were dropped); a missing
    // .mtl file must not stop the geometry from loading.
    let (models, _materials) = tobj::load_obj_buf(&mut clean.as_bytes(), &options, |_| {
        Ok((Vec::new(), std::collections::HashMap::new()))
    })
    .map_err(|e| SceneError::parse(path, None, format!("OBJ: {e}")))?;
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for model in &models {
        let base = vertices.len() as u32;
        vertices.extend(model.mesh.positions.chunks_exact(3).map(|p| {
            Point3::new(
                Real::from(p[0]) * scale,
                Real::from(p[1]) * scale,
                Real::from(p[2]) * scale,
            )
        }));
        triangles.extend(
            model
                .mesh
                .indices
                .chunks_exact(3)
                .map(|t| [t[0] + base, t[1] + base, t[2] + base]),
        );
    }
    finish_mesh(path, vertices, triangles)
}

/// Check every `v` and `f` line (with line numbers) and return an OBJ text of
/// `v x y z` and `f i j k …` lines only, with absolute 1-based indices.
fn sanitize(path: &Path, bytes: &[u8]) -> Result<String, SceneError> {
    let err = |line: usize, msg: String| SceneError::parse(path, Some(line), msg);
    let mut out = String::with_capacity(bytes.len() / 2);
    let mut vertex_count = 0usize;
    // Highest positive index and where it was used (forward references are
    // checked once all vertices are known).
    let mut highest: Option<(usize, usize)> = None;
    let mut faces = 0usize;
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line_no = i + 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let trimmed = raw.trim_ascii_start();
        let keyword = trimmed
            .split(u8::is_ascii_whitespace)
            .next()
            .unwrap_or_default();
        if keyword != b"v" && keyword != b"f" {
            // Comments, vt, vn, groups, materials, lines, points, free-form
            // data: not geometry we use. (May be any encoding.)
            continue;
        }
        let Ok(text) = std::str::from_utf8(trimmed) else {
            return Err(err(line_no, "line is not text".into()));
        };
        let mut words = text.split_whitespace();
        words.next();
        let words: Vec<&str> = words.collect();
        if keyword == b"v" {
            let mut numbers = Vec::with_capacity(words.len());
            for w in &words {
                let v = w
                    .parse::<f32>()
                    .map_err(|_| err(line_no, format!("vertex: '{w}' is not a number")))?;
                numbers.push(v);
            }
            let (x, y, z) = match numbers.as_slice() {
                // x y z, x y z r g b (colour ignored), x y z r g b a.
                [x, y, z] | [x, y, z, _, _, _] | [x, y, z, _, _, _, _] => (*x, *y, *z),
                [x, y, z, w] => {
                    if *w == 0.0 || !w.is_finite() {
                        return Err(err(
                            line_no,
                            format!("vertex weight w = {w} (expected a finite non-zero number)"),
                        ));
                    }
                    (x / w, y / w, z / w)
                }
                _ => {
                    return Err(err(
                        line_no,
                        format!(
                            "vertex has {} values, expected x y z (optionally w, or r g b)",
                            numbers.len()
                        ),
                    ));
                }
            };
            if !(x.is_finite() && y.is_finite() && z.is_finite()) {
                return Err(err(
                    line_no,
                    format!("vertex ({x}, {y}, {z}) is not finite (or too large for f32)"),
                ));
            }
            vertex_count += 1;
            // `{}` of an f32 prints the shortest text that parses back to it.
            let _ = writeln!(out, "v {x} {y} {z}");
        } else {
            if words.len() < 3 {
                return Err(err(
                    line_no,
                    format!("face has {} vertices; a face needs at least 3", words.len()),
                ));
            }
            if words.len() > MAX_FACE_VERTICES {
                return Err(err(
                    line_no,
                    format!(
                        "face has {} vertices, more than {MAX_FACE_VERTICES} (the triangulation \
                         grows faster than linearly with them; split the face)",
                        words.len()
                    ),
                ));
            }
            out.push('f');
            for w in &words {
                let v = w.split('/').next().unwrap_or_default();
                let index = v.parse::<i64>().map_err(|_| {
                    err(
                        line_no,
                        format!("face: '{w}' does not start with a vertex index"),
                    )
                })?;
                let absolute = match index {
                    0 => {
                        return Err(err(
                            line_no,
                            "face: vertex index 0 (OBJ indices start at 1)".into(),
                        ));
                    }
                    i if i < 0 => {
                        let back = i.unsigned_abs() as usize;
                        if back > vertex_count {
                            return Err(err(
                                line_no,
                                format!(
                                    "face: relative index {i} points before the first vertex \
                                     ({vertex_count} defined so far)"
                                ),
                            ));
                        }
                        vertex_count - back + 1
                    }
                    i => {
                        let i = i as usize;
                        if highest.is_none_or(|(h, _)| i > h) {
                            highest = Some((i, line_no));
                        }
                        i
                    }
                };
                let _ = write!(out, " {absolute}");
            }
            out.push('\n');
            faces += 1;
        }
    }
    if let Some((index, line)) = highest
        && index > vertex_count
    {
        return Err(err(
            line,
            format!("face refers to vertex {index} but the file has {vertex_count} vertices"),
        ));
    }
    if faces == 0 {
        return Err(SceneError::invalid(
            path.display().to_string(),
            format!("the file has no faces ({vertex_count} vertices)"),
        ));
    }
    Ok(out)
}

/// Write a mesh as a Wavefront OBJ text file: a comment, `v x y z` lines
/// (shortest text that reads back to the same `f64`) and `f a b c` lines
/// (1-based). The mesh is checked first (finite vertices, indices in range);
/// nothing is written when it fails.
pub fn write_mesh_obj(path: &Path, mesh: &TriMesh) -> Result<(), SceneError> {
    check_mesh_for_writing(path, mesh, Precision::F64)?;
    write_file(path, |w| {
        writeln!(
            w,
            "# written by surveyor: {} vertices, {} triangles, metres",
            mesh.vertices.len(),
            mesh.triangles.len()
        )?;
        for v in &mesh.vertices {
            writeln!(w, "v {} {} {}", v.x, v.y, v.z)?;
        }
        for [a, b, c] in &mesh.triangles {
            writeln!(w, "f {} {} {}", a + 1, b + 1, c + 1)?;
        }
        Ok(())
    })
}
