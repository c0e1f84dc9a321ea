//! Reading triangle meshes and point clouds from files, and writing PLY and OBJ.
//!
//! # Entry points
//!
//! | function | reads / writes |
//! |---|---|
//! | [`load_mesh`] | `.obj` (via `tobj`), `.stl` binary or ASCII (via `stl_io`), `.ply` → [`TriMesh`] |
//! | [`load_cloud`] | `.ply`, `.pcd`, `.txt` / `.xyz` / `.csv` / `.pts` → [`PointCloud`] |
//! | [`load_cloud_or_mesh_vertices`] | any of the above; a mesh gives its vertices |
//! | [`read_ply_vertices`] | every scalar property of a PLY `vertex` element → [`PlyTable`] |
//! | [`read_pcd_header`] | a PCD header → [`PcdHeader`] (viewpoint, organized size, fields) |
//! | [`write_ply_vertices`], [`write_ply_vertices_file`] | `f32` columns → binary little-endian PLY |
//! | [`write_mesh_ply`], [`write_mesh_obj`] | [`TriMesh`] → binary PLY / text OBJ |
//! | [`rays::read_rays`], [`rays::write_rays`] | rays files (24-byte `f32` records) of `surveyor raycast` |
//!
//! The format is chosen by the file extension, case-insensitively; any other
//! extension is [`SceneError::Unsupported`].
//!
//! ```
//! use scene::io;
//! use std::path::Path;
//!
//! // Paths relative to the crate (doctests run there).
//! let block = io::load_mesh(Path::new("../../data/meshes/cinder_block_meters.obj"), 1.0)?;
//! assert_eq!(block.triangles.len(), 84);
//!
//! let milk = io::load_cloud(Path::new("../../data/pointclouds/pcl_milk.pcd"))?;
//! assert_eq!(milk.points.len(), 13_704);
//!
//! // Points out as a binary PLY with one float column per coordinate.
//! let [x, y, z] = [0, 1, 2].map(|k| milk.points.iter().map(|p| p[k] as f32).collect::<Vec<_>>());
//! let mut ply = Vec::new();
//! io::write_ply_vertices(&mut ply, &["x", "y", "z"], &[&x, &y, &z])?;
//! assert!(ply.starts_with(b"ply\nformat binary_little_endian 1.0\n"));
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! # Conventions
//!
//! * **Units and frames.** Coordinates are taken as they are in the file, in the
//!   file's own frame, and are expected to be metres (SPEC §2). [`load_mesh`]
//!   multiplies them by its `scale` argument (e.g. `0.001` for a CAD file in
//!   millimetres, `0.0254` for inches). Nothing is rotated: a PCD file's
//!   `VIEWPOINT` is reported by [`read_pcd_header`] but not applied, and a PCL
//!   camera cloud stays in the camera frame (x right, y down, z forward).
//! * **Non-finite values.** A PCD file marks invalid pixels of organized clouds
//!   with NaN coordinates: such points are dropped and every other attribute
//!   stays aligned with the kept points (a PCD cloud whose kept points include a
//!   non-finite normal loses its normals, `normals: None`, rather than carrying
//!   NaN). No other format has that convention, so a NaN or infinite coordinate
//!   (or normal) in a text cloud, PLY, OBJ or STL file is an error naming the
//!   line, vertex or point.
//! * **Errors.** Every failure is a [`SceneError`] naming the file, and the line
//!   (text formats, headers) or element, row and property (binary data) at
//!   fault, with what was expected and what was found. Nothing panics on bad
//!   input: truncated data, lying size fields, corrupt LZF streams and garbage
//!   are all reported. Size fields must match the data exactly: a PLY element
//!   count, PCD `POINTS` (or `WIDTH × HEIGHT`), compressed-block size or binary
//!   STL triangle count that is *smaller* than the data is an error too, never
//!   a silent truncation (only zero padding may follow a PCD compressed block,
//!   as PCL writes it), and a count far larger than the file could hold is
//!   refused before anything is allocated for it. A file that parses but holds
//!   no points or no triangles is an error too.
//! * **Meshes** are built with [`TriMesh::new`], so every returned mesh has
//!   finite vertices and in-range indices. Polygons are fan-triangulated. Winding
//!   is kept as in the file. PLY and STL meshes keep every vertex of the file (STL
//!   vertices are the distinct corner positions); OBJ meshes keep the vertices
//!   referenced by faces, numbered in order of first use. OBJ and STL
//!   coordinates pass through `f32` (the readers' precision).
//! * **Attributes.** Normals are reported as stored (not renormalised). Labels
//!   must be integers. Intensities are stored as `f32`.
//!
//! # Formats
//!
//! * **PLY**: `ascii`, `binary_little_endian`, `binary_big_endian`; scalar types
//!   `char uchar short ushort int uint float double` and their `int8 … float64`
//!   names; list properties of any count and item type; `comment` and
//!   `obj_info` lines. ASCII rows are one per line. Meshes use the `vertex`
//!   element's `x y z` and the `face` element's `vertex_indices` (or
//!   `vertex_index`) list; every other element and property is skipped (but still
//!   checked for completeness). Clouds use `x y z`, optional `nx ny nz` (or
//!   `normal_x …`), `intensity` (or `scalar_intensity`) and `label` (or
//!   `instance`, `scalar_label`).
//! * **PCD** (PCL, `VERSION` 0.5–0.7): `FIELDS SIZE TYPE COUNT WIDTH HEIGHT
//!   VIEWPOINT POINTS DATA`, `DATA ascii | binary | binary_compressed`. Compressed
//!   data is a little-endian `u32` compressed size and `u32` uncompressed size,
//!   then an LZF stream that decompresses to each field's values for all points,
//!   field after field (structure of arrays). `x y z` (`F` 4 or 8) are required;
//!   `normal_x normal_y normal_z` give normals, `label` labels, `intensity`
//!   intensities; `rgb`, `rgba`, `_` padding and all other fields are skipped.
//! * **Text clouds** (`.txt .xyz .csv .pts`): one point per line, values
//!   separated by whitespace or by commas; `#` starts a comment; blank lines are
//!   skipped. Columns are `x y z`, `x y z nx ny nz` or `x y z nx ny nz label`, the
//!   same count on every line (so that colours are not mistaken for normals, a
//!   normal component beyond ±1 is an error). A first line of names (e.g.
//!   `x,y,z,nx,ny,nz,label`, or CloudCompare's `//X,Y,Z,Nx,Ny,Nz`) instead maps
//!   columns by name, case-insensitively (`x y z`, `nx ny nz` or `normal_x …`,
//!   `label`/`instance`/`class`, `intensity`; others ignored). A `.pts` file
//!   follows the Leica layout: an optional first line with the point count, then
//!   `x y z`, `x y z intensity` or `x y z intensity r g b`.
//! * **OBJ**: `v` (with optional `w`, or colours, which are ignored) and `f`
//!   (positive or negative indices, `v/vt/vn` forms) lines; texture coordinates,
//!   normals, groups, materials (`mtllib` files need not exist), lines and points
//!   are ignored.
//! * **STL**: binary (recognised by its size, `84 + 50 × triangles` bytes, even
//!   when its header starts with `solid`) or ASCII.

mod obj;
mod pcd;
mod ply;
pub mod rays;
mod stl;
mod text;

pub use obj::write_mesh_obj;
pub use pcd::{PcdData, PcdField, PcdHeader, PcdType, read_pcd_header};
pub use ply::{
    PlyTable, read_ply_vertices, write_mesh_ply, write_ply_vertices, write_ply_vertices_file,
};

/// Most vertices of one polygon face in an OBJ or PLY file: a 200 000-vertex
/// OBJ face took minutes to triangulate, and a PLY face's fan of slivers
/// defeats the scene's BVH (40 000 vertices: 23 s to score one scan).
pub const MAX_FACE_VERTICES: usize = 4096;

use crate::{PointCloud, SceneError, TriMesh};
use geom::{Point3, Real, Vector3};
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;

/// What [`load_mesh`] accepts, for [`SceneError::Unsupported`].
const MESH_EXTENSIONS: &str = "a mesh file: .obj, .stl or .ply";
/// What [`load_cloud`] accepts, for [`SceneError::Unsupported`].
const CLOUD_EXTENSIONS: &str = "a point-cloud file: .ply, .pcd, .txt, .xyz, .csv or .pts";
/// What [`load_cloud_or_mesh_vertices`] accepts.
const ANY_EXTENSIONS: &str =
    "a point-cloud or mesh file: .ply, .pcd, .txt, .xyz, .csv, .pts, .obj or .stl";

/// Load a triangle mesh, choosing the format by extension (`.obj`, `.stl`,
/// `.ply`), and multiply every coordinate by `scale` (`1.0` for files in
/// metres).
///
/// `scale` must be finite and positive (a negative factor would mirror the mesh
/// and turn it inside out). A file without triangles is an error.
pub fn load_mesh(path: &Path, scale: Real) -> Result<TriMesh, SceneError> {
    if !(scale.is_finite() && scale > 0.0) {
        return Err(SceneError::invalid(
            format!("{}: scale", path.display()),
            format!("the scale factor must be finite and positive, got {scale}"),
        ));
    }
    let ext = extension(path);
    match ext.as_deref() {
        Some("obj") => obj::load_mesh(path, &read_file(path)?, scale),
        Some("stl") => stl::load_mesh(path, &read_file(path)?, scale),
        Some("ply") => ply::load_mesh(path, &read_file(path)?, scale),
        _ => Err(SceneError::Unsupported {
            path: path.to_owned(),
            expected: MESH_EXTENSIONS,
        }),
    }
}

/// Load a point cloud, choosing the format by extension (`.ply`, `.pcd`, or
/// text: `.txt`, `.xyz`, `.csv`, `.pts`). A file without (valid) points is an
/// error. See the [module docs](self) for the fields each format provides.
pub fn load_cloud(path: &Path) -> Result<PointCloud, SceneError> {
    let ext = extension(path);
    match ext.as_deref() {
        Some("ply") => ply::load_cloud(path, &read_file(path)?),
        Some("pcd") => pcd::load_cloud(path, &read_file(path)?),
        Some(kind @ ("txt" | "xyz" | "csv" | "pts")) => {
            let layout = if kind == "pts" {
                text::Layout::LeicaPts
            } else {
                text::Layout::Plain
            };
            text::load_cloud(path, &read_file(path)?, layout)
        }
        _ => Err(SceneError::Unsupported {
            path: path.to_owned(),
            expected: CLOUD_EXTENSIONS,
        }),
    }
}

/// Every `stride`-th point of the cloud file at `path`, `stride` being
/// `stride_of(number of points)` (at least 1), and the number of points:
/// [`load_cloud`]'s points `.step_by(stride)`. A binary PLY cloud is read
/// only at those points (a report draws thousands of a run's millions).
pub fn sample_cloud_points(
    path: &Path,
    stride_of: impl FnOnce(usize) -> usize,
) -> Result<(usize, Vec<Point3>), SceneError> {
    if extension(path).as_deref() == Some("ply") {
        return ply::sample_cloud_points(path, stride_of);
    }
    let points = load_cloud(path)?.points;
    let stride = stride_of(points.len()).max(1);
    Ok((points.len(), points.into_iter().step_by(stride).collect()))
}

/// Load points from a cloud file, or the vertices of a mesh file (`.obj`,
/// `.stl`), as a cloud. A `.ply` file is read as a cloud (its vertex element,
/// with normals, labels and intensities when present), whether or not it has
/// faces. Mesh vertices without normals in the file get the area-weighted
/// normals of their faces ([`geom::TriMesh::vertex_normals`]), which point to
/// the side the faces' winding makes "out".
pub fn load_cloud_or_mesh_vertices(path: &Path) -> Result<PointCloud, SceneError> {
    let ext = extension(path);
    match ext.as_deref() {
        Some("obj" | "stl") => {
            let mesh = load_mesh(path, 1.0)?;
            let normals = mesh.vertex_normals();
            let mut cloud = PointCloud::from_points(mesh.vertices);
            cloud.normals = Some(normals);
            Ok(cloud)
        }
        Some("ply") => ply::load_cloud_with_face_normals(path, &read_file(path)?),
        Some("pcd" | "txt" | "xyz" | "csv" | "pts") => load_cloud(path),
        _ => Err(SceneError::Unsupported {
            path: path.to_owned(),
            expected: ANY_EXTENSIONS,
        }),
    }
}

/// The lower-case extension of `path`.
fn extension(path: &Path) -> Option<String> {
    path.extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
}

/// The whole file.
fn read_file(path: &Path) -> Result<Vec<u8>, SceneError> {
    std::fs::read(path).map_err(|source| SceneError::Io {
        path: path.to_owned(),
        source,
    })
}

/// Create (or truncate) `path` and write it through a buffer.
fn write_file(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<File>) -> io::Result<()>,
) -> Result<(), SceneError> {
    let io_err = |source| SceneError::Write {
        path: path.to_owned(),
        source,
    };
    let mut w = BufWriter::new(File::create(path).map_err(io_err)?);
    write(&mut w).map_err(io_err)?;
    w.flush().map_err(io_err)
}

/// Precision a writer stores coordinates in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Precision {
    F32,
    F64,
}

/// Check a mesh before writing it: finite coordinates (that fit `f32` when
/// written as `f32`) and in-range indices.
fn check_mesh_for_writing(
    path: &Path,
    mesh: &TriMesh,
    precision: Precision,
) -> Result<(), SceneError> {
    let what = || format!("{}: mesh to write", path.display());
    for (i, v) in mesh.vertices.iter().enumerate() {
        let bad = v.iter().any(|c| {
            !c.is_finite() || (precision == Precision::F32 && c.abs() > Real::from(f32::MAX))
        });
        if bad {
            return Err(SceneError::invalid(
                what(),
                format!(
                    "vertex {i} ({}, {}, {}) is not finite{}",
                    v.x,
                    v.y,
                    v.z,
                    if precision == Precision::F32 {
                        " or does not fit a 32-bit float"
                    } else {
                        ""
                    }
                ),
            ));
        }
    }
    let n = mesh.vertices.len();
    if let Some(t) = mesh
        .triangles
        .iter()
        .position(|t| t.iter().any(|&i| i as usize >= n))
    {
        return Err(SceneError::invalid(
            what(),
            format!("triangle {t} refers to a vertex beyond the {n} given"),
        ));
    }
    Ok(())
}

/// The mesh read from `path`, checked; no triangles is an error.
fn finish_mesh(
    path: &Path,
    vertices: Vec<Point3>,
    triangles: Vec<[u32; 3]>,
) -> Result<TriMesh, SceneError> {
    if triangles.is_empty() {
        return Err(SceneError::invalid(
            path.display().to_string(),
            format!(
                "the file has no triangles ({} vertices, no faces)",
                vertices.len()
            ),
        ));
    }
    let mesh = TriMesh::new(vertices, triangles, &path.display().to_string())?;
    if let Some((i, v)) = mesh
        .vertices
        .iter()
        .enumerate()
        .find(|(_, v)| v.iter().any(|c| c.abs() > crate::spec::MAX_COORDINATE_M))
    {
        return Err(SceneError::invalid(
            path.display().to_string(),
            format!(
                "vertex {i} at ({:.3e}, {:.3e}, {:.3e}) m (after scaling) is beyond ±{:e} m",
                v.x,
                v.y,
                v.z,
                crate::spec::MAX_COORDINATE_M
            ),
        ));
    }
    Ok(mesh)
}

/// Per-point columns decoded from a file, all of one length.
struct Fields<'a> {
    xyz: [&'a [f64]; 3],
    normals: Option<[&'a [f64]; 3]>,
    label: Option<&'a [f64]>,
    intensity: Option<&'a [f64]>,
}

/// What a non-finite coordinate means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum NonFinite {
    /// An invalid point (PCD): drop it.
    Drop,
    /// Bad input: an error.
    Reject,
}

/// Assemble a cloud from decoded columns. `name` names point `i` in errors.
fn build_cloud(
    path: &Path,
    fields: &Fields<'_>,
    non_finite: NonFinite,
    name: impl Fn(usize) -> String,
) -> Result<PointCloud, SceneError> {
    let [x, y, z] = fields.xyz;
    let n = x.len();
    let err = |i: usize, msg: String| SceneError::parse(path, None, format!("{}: {msg}", name(i)));
    let mut points = Vec::with_capacity(n);
    let mut normals = fields.normals.map(|_| Vec::with_capacity(n));
    let mut labels = fields.label.map(|_| Vec::with_capacity(n));
    let mut intensities = fields.intensity.map(|_| Vec::with_capacity(n));
    let mut normals_finite = true;
    for i in 0..n {
        let p = Point3::new(x[i], y[i], z[i]);
        if !geom::math::is_finite_point(&p) {
            match non_finite {
                NonFinite::Drop => continue,
                NonFinite::Reject => {
                    return Err(err(
                        i,
                        format!("coordinates ({}, {}, {}) are not finite", p.x, p.y, p.z),
                    ));
                }
            }
        }
        if p.iter().any(|c| c.abs() > crate::spec::MAX_COORDINATE_M) {
            return Err(err(
                i,
                format!(
                    "coordinates ({:.3e}, {:.3e}, {:.3e}) are beyond ±{:e} m",
                    p.x,
                    p.y,
                    p.z,
                    crate::spec::MAX_COORDINATE_M
                ),
            ));
        }
        points.push(p);
        if let (Some(out), Some([a, b, c])) = (normals.as_mut(), fields.normals) {
            let v = Vector3::new(a[i], b[i], c[i]);
            if !v.iter().all(|c| c.is_finite()) {
                if non_finite == NonFinite::Reject {
                    return Err(err(
                        i,
                        format!("normal ({}, {}, {}) is not finite", v.x, v.y, v.z),
                    ));
                }
                normals_finite = false;
            }
            out.push(v);
        }
        if let (Some(out), Some(l)) = (labels.as_mut(), fields.label) {
            out.push(to_label(l[i]).map_err(|m| err(i, m))?);
        }
        if let (Some(out), Some(v)) = (intensities.as_mut(), fields.intensity) {
            out.push(v[i] as f32);
        }
    }
    if points.is_empty() {
        return Err(SceneError::invalid(
            path.display().to_string(),
            if n == 0 {
                "the file has no points".to_owned()
            } else {
                format!("none of the file's {n} points has finite coordinates")
            },
        ));
    }
    Ok(PointCloud {
        points,
        normals: normals.filter(|_| normals_finite),
        labels,
        intensities,
    })
}

/// A label value as an integer.
fn to_label(v: f64) -> Result<i64, String> {
    // 2^63: the first f64 beyond i64.
    const LIMIT: f64 = 9_223_372_036_854_775_808.0;
    if v.fract() == 0.0 && (-LIMIT..LIMIT).contains(&v) {
        Ok(v as i64)
    } else {
        Err(format!("label {v} is not an integer"))
    }
}
