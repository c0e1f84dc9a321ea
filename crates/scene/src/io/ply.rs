//! PLY (Stanford polygon file format): header, the three encodings, vertex
//! tables, meshes, clouds and the binary writers.

use super::{Fields, MAX_FACE_VERTICES, NonFinite, build_cloud, read_file};
use crate::{PointCloud, SceneError, TriMesh};
use geom::{Point3, Real};
use std::io::{self, Write};
use std::path::Path;

/// Every scalar (non-list) property of a PLY file's `vertex` element, as `f64`
/// columns in the order the header declares them.
///
/// Values are converted exactly: every PLY scalar type (`char` … `double`) is
/// representable in `f64`; `float` properties written as ASCII are rounded to
/// `f32` first, so ASCII and binary files holding the same `float`s give
/// identical tables. List properties of the vertex element are skipped.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlyTable {
    /// Property names, in header order.
    pub names: Vec<String>,
    /// One column per name, each with one value per vertex.
    pub columns: Vec<Vec<f64>>,
}

impl PlyTable {
    /// The column of property `name`, if the vertex element has it.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        self.names
            .iter()
            .position(|n| n == name)
            .and_then(|i| self.columns.get(i))
            .map(Vec::as_slice)
    }

    /// Number of vertices (rows).
    pub fn len(&self) -> usize {
        self.columns.first().map_or(0, Vec::len)
    }

    /// `true` when the table has no rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Read every scalar property of the `vertex` element of a PLY file (any of the
/// three encodings). The whole file is checked: a truncated or malformed face
/// section is an error too. A file with zero vertices gives an empty table; a
/// file with no `vertex` element is an error. Coordinates are not checked for
/// finiteness here (it is a generic table); [`load_cloud`](super::load_cloud)
/// and [`load_mesh`](super::load_mesh) do check them.
pub fn read_ply_vertices(path: &Path) -> Result<PlyTable, SceneError> {
    let bytes = read_file(path)?;
    Ok(parse_ply(&bytes, path, Want::Table)?.vertex)
}

/// Write a point table as a binary little-endian PLY with one `vertex` element
/// and one `float` property per column.
///
/// `names[i]` names `columns[i]`. Fails with [`io::ErrorKind::InvalidInput`],
/// before writing anything, when there are no columns, the counts of names and
/// columns differ, the columns differ in length, or a name is empty, repeated
/// or contains whitespace.
pub fn write_ply_vertices(
    writer: &mut impl Write,
    names: &[&str],
    columns: &[&[f32]],
) -> io::Result<()> {
    check_vertex_columns(names, columns)
        .map_err(|m| io::Error::new(io::ErrorKind::InvalidInput, m))?;
    let rows = columns.first().map_or(0, |c| c.len());
    let mut header = format!(
        "ply\nformat binary_little_endian 1.0\ncomment written by surveyor\nelement vertex {rows}\n"
    );
    for name in names {
        header.push_str("property float ");
        header.push_str(name);
        header.push('\n');
    }
    header.push_str("end_header\n");
    writer.write_all(header.as_bytes())?;
    let mut buf = Vec::with_capacity(CHUNK_BYTES + 4 * columns.len());
    for row in 0..rows {
        for column in columns {
            buf.extend_from_slice(&column[row].to_le_bytes());
        }
        if buf.len() >= CHUNK_BYTES {
            writer.write_all(&buf)?;
            buf.clear();
        }
    }
    writer.write_all(&buf)
}

/// [`write_ply_vertices`] into a new file at `path` (created or truncated). The
/// columns are checked before the file is touched.
pub fn write_ply_vertices_file(
    path: &Path,
    names: &[&str],
    columns: &[&[f32]],
) -> Result<(), SceneError> {
    check_vertex_columns(names, columns)
        .map_err(|m| SceneError::invalid(format!("{}: PLY vertex columns", path.display()), m))?;
    super::write_file(path, |w| write_ply_vertices(w, names, columns))
}

/// Write a mesh as a binary little-endian PLY: `float` x, y, z per vertex and a
/// `list uchar uint vertex_indices` per triangle. The mesh is checked first
/// (finite coordinates that fit an `f32`, indices in range); nothing is written
/// when it fails.
pub fn write_mesh_ply(path: &Path, mesh: &TriMesh) -> Result<(), SceneError> {
    super::check_mesh_for_writing(path, mesh, super::Precision::F32)?;
    super::write_file(path, |w| {
        let header = format!(
            "ply\nformat binary_little_endian 1.0\ncomment written by surveyor (metres)\n\
             element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
             element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
            mesh.vertices.len(),
            mesh.triangles.len()
        );
        w.write_all(header.as_bytes())?;
        let mut buf = Vec::with_capacity(CHUNK_BYTES + 16);
        for v in &mesh.vertices {
            for c in [v.x, v.y, v.z] {
                buf.extend_from_slice(&(c as f32).to_le_bytes());
            }
            if buf.len() >= CHUNK_BYTES {
                w.write_all(&buf)?;
                buf.clear();
            }
        }
        for t in &mesh.triangles {
            buf.push(3);
            for i in t {
                buf.extend_from_slice(&i.to_le_bytes());
            }
            if buf.len() >= CHUNK_BYTES {
                w.write_all(&buf)?;
                buf.clear();
            }
        }
        w.write_all(&buf)
    })
}

/// Size of the write buffer flushed to the writer.
const CHUNK_BYTES: usize = 1 << 16;

fn check_vertex_columns(names: &[&str], columns: &[&[f32]]) -> Result<(), String> {
    if names.is_empty() {
        return Err("no columns to write: a PLY vertex element needs at least one property".into());
    }
    if names.len() != columns.len() {
        return Err(format!(
            "{} property names but {} columns",
            names.len(),
            columns.len()
        ));
    }
    let rows = columns[0].len();
    for (name, column) in names.iter().zip(columns) {
        if column.len() != rows {
            return Err(format!(
                "column '{name}' has {} values but column '{}' has {rows}",
                column.len(),
                names[0]
            ));
        }
    }
    for (i, name) in names.iter().enumerate() {
        if name.is_empty() || name.chars().any(|c| c.is_whitespace() || c.is_control()) {
            return Err(format!(
                "property name {name:?} is not a PLY word (non-empty, no whitespace)"
            ));
        }
        if names[..i].contains(name) {
            return Err(format!("property name '{name}' appears twice"));
        }
    }
    Ok(())
}

/// Load a PLY mesh: `vertex` x, y, z and the `face` element's `vertex_indices`
/// (or `vertex_index`) lists, fan-triangulated.
pub(super) fn load_mesh(path: &Path, bytes: &[u8], scale: Real) -> Result<TriMesh, SceneError> {
    let ply = parse_ply(bytes, path, Want::Mesh)?;
    if !ply.has_faces {
        // `Invalid`, like a mesh without triangles: the file is a fine point
        // cloud (callers may fall back to `load_cloud` on this variant).
        return Err(SceneError::invalid(
            path.display().to_string(),
            "the PLY file has no 'face' element with a 'vertex_indices' list: it is a point \
             cloud (load it with load_cloud)",
        ));
    }
    let table = &ply.vertex;
    let (x, y, z) = xyz_columns(table, path)?;
    let vertices: Vec<Point3> = (0..table.len())
        .map(|i| Point3::new(x[i] * scale, y[i] * scale, z[i] * scale))
        .collect();
    super::finish_mesh(path, vertices, ply.triangles)
}

/// Load a PLY point cloud from the `vertex` element.
pub(super) fn load_cloud(path: &Path, bytes: &[u8]) -> Result<PointCloud, SceneError> {
    cloud_of(path, &parse_ply(bytes, path, Want::Cloud)?)
}

/// Load a PLY point cloud from the `vertex` element; when the file gives no
/// normals but has faces (a mesh, e.g. the TSDF mesh of `surveyor map`), each
/// vertex gets the area-weighted normal of its faces
/// ([`geom::TriMesh::vertex_normals`]: the faces' winding sets the side).
pub(super) fn load_cloud_with_face_normals(
    path: &Path,
    bytes: &[u8],
) -> Result<PointCloud, SceneError> {
    let mut ply = parse_ply(bytes, path, Want::CloudAndFaces)?;
    let mut cloud = cloud_of(path, &ply)?;
    if cloud.normals.is_none() && !ply.triangles.is_empty() {
        let mesh = TriMesh {
            vertices: std::mem::take(&mut cloud.points),
            triangles: std::mem::take(&mut ply.triangles),
        };
        cloud.normals = Some(mesh.vertex_normals());
        cloud.points = mesh.vertices;
    }
    Ok(cloud)
}

/// Every `stride`-th vertex position of the PLY cloud at `path` (the first,
/// then each `stride` on; `stride` is `stride_of(vertex count)`, at least 1)
/// and the vertex count: `load_cloud`'s points `.step_by(stride)`, reading
/// only those rows when the file is binary with the vertex element first
/// and of fixed-size rows (as `surveyor explore` writes `cloud.ply`: a
/// cloud of millions of points is not read whole to draw thousands). Any
/// other file is loaded whole. Every position read must be finite.
pub(super) fn sample_cloud_points(
    path: &Path,
    stride_of: impl FnOnce(usize) -> usize,
) -> Result<(usize, Vec<Point3>), SceneError> {
    use std::io::{BufRead, BufReader, Read};
    let io_err = |source| SceneError::Io {
        path: path.to_owned(),
        source,
    };
    let file = std::fs::File::open(path).map_err(io_err)?;
    let mut reader = BufReader::with_capacity(1 << 20, file);
    let mut head = Vec::new();
    while !(head.ends_with(b"\nend_header\n") || head.ends_with(b"\nend_header\r\n"))
        && head.len() < SAMPLED_HEADER_MAX
    {
        if reader.read_until(b'\n', &mut head).map_err(io_err)? == 0 {
            break;
        }
    }
    // Only the layout read row by row here; anything else (or a header
    // this loop misread) is loaded whole, with the full checks.
    let layout = parse_header(&head, path).ok().and_then(|h| {
        let Encoding::Binary(order) = h.encoding else {
            return None;
        };
        let vertex = h.elements.first().filter(|e| e.name == "vertex")?;
        let row = vertex.fixed_row_size()?;
        let at = |name: &str| {
            let mut offset = 0;
            for p in &vertex.props {
                let Kind::Scalar(kind) = p.kind else {
                    return None;
                };
                if p.name == name {
                    return Some((offset, kind));
                }
                offset += kind.size();
            }
            None
        };
        Some((order, vertex.count, row, [at("x")?, at("y")?, at("z")?]))
    });
    let Some((order, count, row, xyz)) = layout else {
        let cloud = load_cloud(path, &read_file(path)?)?;
        let stride = stride_of(cloud.points.len()).max(1);
        return Ok((
            cloud.points.len(),
            cloud.points.into_iter().step_by(stride).collect(),
        ));
    };
    let stride = stride_of(count).max(1);
    let mut points = Vec::with_capacity(count.div_ceil(stride));
    let mut bytes = vec![0u8; row];
    let skip = i64::try_from((stride - 1).saturating_mul(row)).unwrap_or(i64::MAX);
    for i in (0..count).step_by(stride) {
        if i > 0 {
            reader.seek_relative(skip).map_err(io_err)?;
        }
        reader.read_exact(&mut bytes).map_err(|e| {
            SceneError::parse(
                path,
                None,
                format!("vertex {i} of {count}: the file ends inside it ({e}; truncated?)"),
            )
        })?;
        let [x, y, z] = xyz.map(|(offset, kind)| kind.decode(&bytes[offset..], order));
        if !(x.is_finite() && y.is_finite() && z.is_finite()) {
            return Err(SceneError::parse(
                path,
                None,
                format!("vertex {i}: non-finite position ({x}, {y}, {z})"),
            ));
        }
        points.push(Point3::new(x, y, z));
    }
    Ok((count, points))
}

/// The longest header [`sample_cloud_points`] reads, bytes (a PLY header is
/// a few lines; a longer one goes to the full reader, which says what is
/// wrong with it).
const SAMPLED_HEADER_MAX: usize = 1 << 16;

fn cloud_of(path: &Path, ply: &Parsed) -> Result<PointCloud, SceneError> {
    let table = &ply.vertex;
    let (x, y, z) = xyz_columns(table, path)?;
    let normals = match (
        find_column(table, &["nx", "normal_x"]),
        find_column(table, &["ny", "normal_y"]),
        find_column(table, &["nz", "normal_z"]),
    ) {
        (Some(a), Some(b), Some(c)) => Some([a, b, c]),
        (None, None, None) => None,
        _ => {
            return Err(SceneError::parse(
                path,
                None,
                format!(
                    "vertex element has only some of the normal properties nx, ny, nz \
                     (found: {})",
                    table.names.join(" ")
                ),
            ));
        }
    };
    let fields = Fields {
        xyz: [x, y, z],
        normals,
        label: find_column(table, &["label", "instance", "scalar_label"]),
        intensity: find_column(table, &["intensity", "scalar_intensity"]),
    };
    build_cloud(path, &fields, NonFinite::Reject, |i| format!("vertex {i}"))
}

fn find_column<'t>(table: &'t PlyTable, names: &[&str]) -> Option<&'t [f64]> {
    names.iter().find_map(|n| table.column(n))
}

/// The x, y and z columns of a vertex table.
type Xyz<'t> = (&'t [f64], &'t [f64], &'t [f64]);

fn xyz_columns<'t>(table: &'t PlyTable, path: &Path) -> Result<Xyz<'t>, SceneError> {
    let get = |name: &str| {
        table.column(name).ok_or_else(|| {
            SceneError::parse(
                path,
                None,
                format!(
                    "vertex element has no property '{name}' (found: {})",
                    if table.names.is_empty() {
                        "none".to_owned()
                    } else {
                        table.names.join(" ")
                    }
                ),
            )
        })
    };
    Ok((get("x")?, get("y")?, get("z")?))
}

// ---------------------------------------------------------------------------
// Reading

/// What the caller needs from the file; every mode validates the whole file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Want {
    /// The vertex table only, values unchecked.
    Table,
    /// The vertex table; x y z and normals must be finite.
    Cloud,
    /// The vertex table and the triangulated faces; x y z must be finite.
    Mesh,
    /// [`Want::Cloud`] plus the triangulated faces when the file has them.
    CloudAndFaces,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Self> {
        Some(match name {
            "char" | "int8" => Self::I8,
            "uchar" | "uint8" => Self::U8,
            "short" | "int16" => Self::I16,
            "ushort" | "uint16" => Self::U16,
            "int" | "int32" => Self::I32,
            "uint" | "uint32" => Self::U32,
            "float" | "float32" => Self::F32,
            "double" | "float64" => Self::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Self::I8 | Self::U8 => 1,
            Self::I16 | Self::U16 => 2,
            Self::I32 | Self::U32 | Self::F32 => 4,
            Self::F64 => 8,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Self::I8 => "char",
            Self::U8 => "uchar",
            Self::I16 => "short",
            Self::U16 => "ushort",
            Self::I32 => "int",
            Self::U32 => "uint",
            Self::F32 => "float",
            Self::F64 => "double",
        }
    }

    /// Inclusive value range of the integer types.
    fn int_range(self) -> Option<(i64, i64)> {
        match self {
            Self::I8 => Some((i8::MIN.into(), i8::MAX.into())),
            Self::U8 => Some((0, u8::MAX.into())),
            Self::I16 => Some((i16::MIN.into(), i16::MAX.into())),
            Self::U16 => Some((0, u16::MAX.into())),
            Self::I32 => Some((i32::MIN.into(), i32::MAX.into())),
            Self::U32 => Some((0, u32::MAX.into())),
            Self::F32 | Self::F64 => None,
        }
    }

    /// Decode one value; `b` holds at least `self.size()` bytes.
    #[inline]
    fn decode(self, b: &[u8], order: Order) -> f64 {
        match order {
            Order::Little => match self {
                Self::I8 => f64::from(b[0] as i8),
                Self::U8 => f64::from(b[0]),
                Self::I16 => f64::from(i16::from_le_bytes(bytes_of(b))),
                Self::U16 => f64::from(u16::from_le_bytes(bytes_of(b))),
                Self::I32 => f64::from(i32::from_le_bytes(bytes_of(b))),
                Self::U32 => f64::from(u32::from_le_bytes(bytes_of(b))),
                Self::F32 => f64::from(f32::from_le_bytes(bytes_of(b))),
                Self::F64 => f64::from_le_bytes(bytes_of(b)),
            },
            Order::Big => match self {
                Self::I8 => f64::from(b[0] as i8),
                Self::U8 => f64::from(b[0]),
                Self::I16 => f64::from(i16::from_be_bytes(bytes_of(b))),
                Self::U16 => f64::from(u16::from_be_bytes(bytes_of(b))),
                Self::I32 => f64::from(i32::from_be_bytes(bytes_of(b))),
                Self::U32 => f64::from(u32::from_be_bytes(bytes_of(b))),
                Self::F32 => f64::from(f32::from_be_bytes(bytes_of(b))),
                Self::F64 => f64::from_be_bytes(bytes_of(b)),
            },
        }
    }

    /// Parse one ASCII token as a value of this type.
    fn parse_token(self, token: &str) -> Result<f64, String> {
        match self {
            Self::F32 => token
                .parse::<f32>()
                .map(f64::from)
                .map_err(|_| format!("'{token}' is not a number")),
            Self::F64 => token
                .parse::<f64>()
                .map_err(|_| format!("'{token}' is not a number")),
            _ => {
                let (lo, hi) = self.int_range().unwrap_or((i64::MIN, i64::MAX));
                let v = if let Ok(v) = token.parse::<i64>() {
                    v
                } else {
                    // Tolerate integers written as "3.0", but nothing else.
                    let f = token
                        .parse::<f64>()
                        .map_err(|_| format!("'{token}' is not a number"))?;
                    if f.fract() != 0.0 || !f.is_finite() || f.abs() > 9.0e15 {
                        return Err(format!("'{token}' is not an integer ({})", self.name()));
                    }
                    f as i64
                };
                if v < lo || v > hi {
                    return Err(format!("{v} is out of range for {}", self.name()));
                }
                Ok(v as f64)
            }
        }
    }
}

#[inline]
fn bytes_of<const N: usize>(b: &[u8]) -> [u8; N] {
    let mut a = [0u8; N];
    a.copy_from_slice(&b[..N]);
    a
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Order {
    Little,
    Big,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Encoding {
    Ascii,
    Binary(Order),
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Clone, Debug)]
struct Property {
    name: String,
    kind: Kind,
}

#[derive(Clone, Debug)]
struct Element {
    name: String,
    count: usize,
    props: Vec<Property>,
}

impl Element {
    /// Bytes per row when every property is a scalar.
    fn fixed_row_size(&self) -> Option<usize> {
        self.props.iter().try_fold(0, |acc, p| match p.kind {
            Kind::Scalar(s) => Some(acc + s.size()),
            Kind::List { .. } => None,
        })
    }

    /// Smallest possible bytes per row (lists of length zero).
    fn min_row_size(&self) -> usize {
        self.props
            .iter()
            .map(|p| match p.kind {
                Kind::Scalar(s) => s.size(),
                Kind::List { count, .. } => count.size(),
            })
            .sum()
    }
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset of the first body byte.
    body: usize,
    /// Number of header lines (the body starts on the next line).
    lines: usize,
}

#[allow(
    clippy::too_many_lines,
    reason = "the PLY header line by line (format, comments, elements and their properties), each error naming its line"
)]
fn parse_header(bytes: &[u8], path: &Path) -> Result<Header, SceneError> {
    let err = |line: usize, msg: String| SceneError::parse(path, Some(line), msg);
    if bytes.is_empty() {
        return Err(SceneError::parse(
            path,
            None,
            "empty file (expected a PLY header)",
        ));
    }
    let mut pos = 0;
    let mut line_no = 0;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        let Some(nl) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(err(
                line_no + 1,
                "header ends without an 'end_header' line (file truncated?)".into(),
            ));
        };
        let raw = &bytes[pos..pos + nl];
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        pos += nl + 1;
        line_no += 1;
        let Ok(text) = std::str::from_utf8(raw) else {
            return Err(err(line_no, "header line is not text".into()));
        };
        if line_no == 1 {
            if text.trim_end() != "ply" {
                return Err(err(
                    1,
                    format!(
                        "not a PLY file: the first line must be 'ply', found '{}'",
                        shorten(text)
                    ),
                ));
            }
            continue;
        }
        let words: Vec<&str> = text.split_whitespace().collect();
        match words.as_slice() {
            [] | ["comment" | "obj_info", ..] => {}
            ["format", kind, version] => {
                if encoding.is_some() {
                    return Err(err(line_no, "a second 'format' line".into()));
                }
                // PLY has one version (issue 48: `format ascii 7.5` was read).
                if version.parse::<f64>() != Ok(1.0) {
                    return Err(err(
                        line_no,
                        format!(
                            "PLY format version '{}', expected 1.0 (the only one)",
                            shorten(version)
                        ),
                    ));
                }
                encoding = Some(match *kind {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::Binary(Order::Little),
                    "binary_big_endian" => Encoding::Binary(Order::Big),
                    other => {
                        return Err(err(
                            line_no,
                            format!(
                                "unknown PLY format '{other}' (expected ascii, \
                                 binary_little_endian or binary_big_endian)"
                            ),
                        ));
                    }
                });
            }
            ["format", ..] => {
                return Err(err(
                    line_no,
                    format!(
                        "malformed format line '{}' (expected 'format <encoding> 1.0')",
                        shorten(text)
                    ),
                ));
            }
            ["element", name, count] => {
                let count = count.parse::<usize>().map_err(|_| {
                    err(
                        line_no,
                        format!("element '{name}': count '{count}' is not a non-negative integer"),
                    )
                })?;
                elements.push(Element {
                    name: (*name).to_owned(),
                    count,
                    props: Vec::new(),
                });
            }
            ["element", ..] => {
                return Err(err(
                    line_no,
                    format!(
                        "malformed element line '{}' (expected 'element <name> <count>')",
                        shorten(text)
                    ),
                ));
            }
            ["property", rest @ ..] => {
                let Some(element) = elements.last_mut() else {
                    return Err(err(
                        line_no,
                        "'property' line before any 'element' line".into(),
                    ));
                };
                let scalar = |name: &str| {
                    Scalar::parse(name).ok_or_else(|| {
                        err(
                            line_no,
                            format!(
                                "unknown property type '{name}' (expected char, uchar, short, \
                                 ushort, int, uint, float, double or int8 … float64)"
                            ),
                        )
                    })
                };
                let (name, kind) = match rest {
                    ["list", count, item, name] => {
                        let count = scalar(count)?;
                        if count.int_range().is_none() {
                            return Err(err(
                                line_no,
                                format!(
                                    "list '{name}': the count type must be an integer type, \
                                     not {}",
                                    count.name()
                                ),
                            ));
                        }
                        (
                            *name,
                            Kind::List {
                                count,
                                item: scalar(item)?,
                            },
                        )
                    }
                    [ty, name] if *ty != "list" => (*name, Kind::Scalar(scalar(ty)?)),
                    _ => {
                        return Err(err(
                            line_no,
                            format!(
                                "malformed property line '{}' (expected 'property <type> \
                                 <name>' or 'property list <count type> <item type> <name>')",
                                shorten(text)
                            ),
                        ));
                    }
                };
                element.props.push(Property {
                    name: name.to_owned(),
                    kind,
                });
            }
            ["end_header"] => break,
            [word, ..] => {
                return Err(err(
                    line_no,
                    format!(
                        "unexpected header line starting with '{}' (expected format, element, \
                         property, comment, obj_info or end_header)",
                        shorten(word)
                    ),
                ));
            }
        }
    }
    let Some(encoding) = encoding else {
        return Err(err(line_no, "the header has no 'format' line".into()));
    };
    Ok(Header {
        encoding,
        elements,
        body: pos,
        lines: line_no,
    })
}

/// At most 60 characters of `s`, for quoting input in messages.
fn shorten(s: &str) -> String {
    if s.chars().count() <= 60 {
        s.to_owned()
    } else {
        let mut t: String = s.chars().take(57).collect();
        t.push_str("...");
        t
    }
}

struct Parsed {
    vertex: PlyTable,
    triangles: Vec<[u32; 3]>,
    has_faces: bool,
}

/// What to do with each element while walking the body.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    Vertex,
    /// A face element; the payload is the index of its index-list property.
    Face(usize),
    Skip,
}

/// Per-element state while reading.
struct Plan {
    role: Role,
    /// For the vertex element: which properties must hold finite values.
    finite: Vec<bool>,
}

fn parse_ply(bytes: &[u8], path: &Path, want: Want) -> Result<Parsed, SceneError> {
    let header = parse_header(bytes, path)?;
    let Some(vertex_index) = header.elements.iter().position(|e| e.name == "vertex") else {
        return Err(SceneError::parse(
            path,
            None,
            "PLY header declares no 'vertex' element",
        ));
    };
    let vertex_count = header.elements[vertex_index].count;
    let mut face_seen = false;
    let plans: Vec<Plan> = header
        .elements
        .iter()
        .enumerate()
        .map(|(i, e)| {
            let role = if i == vertex_index {
                Role::Vertex
            } else if e.name == "face"
                && matches!(want, Want::Mesh | Want::CloudAndFaces)
                && !face_seen
            {
                match e.props.iter().position(|p| {
                    matches!(p.kind, Kind::List { .. })
                        && (p.name == "vertex_indices" || p.name == "vertex_index")
                }) {
                    Some(k) => {
                        face_seen = true;
                        Role::Face(k)
                    }
                    None => Role::Skip,
                }
            } else {
                Role::Skip
            };
            let finite = e
                .props
                .iter()
                .map(|p| {
                    let coordinate = matches!(p.name.as_str(), "x" | "y" | "z");
                    let normal = matches!(
                        p.name.as_str(),
                        "nx" | "ny" | "nz" | "normal_x" | "normal_y" | "normal_z"
                    );
                    role == Role::Vertex
                        && match want {
                            Want::Table => false,
                            Want::Cloud | Want::CloudAndFaces => coordinate || normal,
                            Want::Mesh => coordinate,
                        }
                })
                .collect();
            Plan { role, finite }
        })
        .collect();

    let mut out = Parsed {
        vertex: PlyTable::default(),
        triangles: Vec::new(),
        has_faces: face_seen,
    };
    let body = &bytes[header.body..];
    let mut reader = Reader {
        path,
        vertex_count,
        out: &mut out,
    };
    match header.encoding {
        Encoding::Binary(order) => {
            reader.read_binary(&header.elements, &plans, body, header.body, order)?;
        }
        Encoding::Ascii => reader.read_ascii(&header.elements, &plans, body, header.lines)?,
    }
    Ok(out)
}

struct Reader<'a> {
    path: &'a Path,
    vertex_count: usize,
    out: &'a mut Parsed,
}

/// What is wrong with face `row` of `n` vertices (fewer than 3, or more than
/// [`MAX_FACE_VERTICES`]: its fan's slivers defeat the scene's BVH).
fn face_size(row: usize, n: usize) -> String {
    if n < 3 {
        format!("face {row} has {n} vertices; a face needs at least 3")
    } else {
        format!("face {row} has {n} vertices, more than {MAX_FACE_VERTICES}; split the face")
    }
}

impl Reader<'_> {
    fn start_vertex_table(&mut self, element: &Element, capacity: usize) {
        let scalars: Vec<&Property> = element
            .props
            .iter()
            .filter(|p| matches!(p.kind, Kind::Scalar(_)))
            .collect();
        self.out.vertex.names = scalars.iter().map(|p| p.name.clone()).collect();
        self.out.vertex.columns = vec![Vec::with_capacity(capacity); scalars.len()];
    }

    /// Fan-triangulate one face's index list (already range-checked).
    fn push_face(&mut self, indices: &[u32]) {
        if let Some((&first, rest)) = indices.split_first() {
            for pair in rest.windows(2) {
                self.out.triangles.push([first, pair[0], pair[1]]);
            }
        }
    }

    /// Check one face index value read from the file.
    fn face_index(&self, value: f64, face: usize) -> Result<u32, String> {
        if value.fract() != 0.0
            || value < 0.0
            || value >= self.vertex_count as f64
            || value > f64::from(u32::MAX)
        {
            return Err(format!(
                "face {face}: vertex index {value} is out of range (the file has {} vertices)",
                self.vertex_count
            ));
        }
        Ok(value as u32)
    }

    /// Read a binary body; `body_offset` is its position in the file (for
    /// messages).
    fn read_binary(
        &mut self,
        elements: &[Element],
        plans: &[Plan],
        body: &[u8],
        body_offset: usize,
        order: Order,
    ) -> Result<(), SceneError> {
        let path = self.path;
        // E.g. "… element 'vertex' row 12 (of 40), property 'z': needs 4 bytes, only 2 left".
        let fail = |element: &Element, row: usize, what: &str, detail: String| {
            SceneError::parse(
                path,
                None,
                format!(
                    "binary data truncated or corrupt: element '{}' row {row} (of {}), {what}: \
                     {detail}",
                    element.name, element.count
                ),
            )
        };
        let short = |need: usize, left: usize| format!("needs {need} bytes, only {left} left");
        let mut pos = 0usize;
        let mut face_buf: Vec<u32> = Vec::new();
        for (element, plan) in elements.iter().zip(plans) {
            let left = body.len() - pos;
            // Fail early, and without allocating, when fixed-size rows cannot
            // all fit. (Rows with lists are checked one by one below, which
            // names the exact list that does not fit.)
            let min_row = element.min_row_size();
            if let Some(size) = element.fixed_row_size()
                && size > 0
                && element.count > left / size
            {
                let row = left / size;
                let (what, need, have) = first_prop_past(element, left - row * size);
                return Err(fail(element, row, &what, short(need, have)));
            }
            if plan.role == Role::Skip
                && let Some(size) = element.fixed_row_size()
            {
                pos += size * element.count;
                continue;
            }
            if plan.role == Role::Vertex {
                self.start_vertex_table(element, element.count.min(left / min_row.max(1)));
            }
            if element.props.is_empty() {
                // Rows of nothing: whatever the count, there is nothing to read.
                continue;
            }
            for row in 0..element.count {
                let mut column = 0;
                for (j, (p, &finite)) in element.props.iter().zip(&plan.finite).enumerate() {
                    let prop = || format!("property '{}'", p.name);
                    match (plan.role, p.kind) {
                        (Role::Vertex, Kind::Scalar(s)) => {
                            let Some(b) = body.get(pos..pos + s.size()) else {
                                return Err(fail(
                                    element,
                                    row,
                                    &prop(),
                                    short(s.size(), body.len() - pos),
                                ));
                            };
                            pos += s.size();
                            let v = s.decode(b, order);
                            if finite && !v.is_finite() {
                                return Err(SceneError::parse(
                                    path,
                                    None,
                                    format!(
                                        "vertex {row}: property '{}' is {v} (expected a finite \
                                         number)",
                                        p.name
                                    ),
                                ));
                            }
                            self.out.vertex.columns[column].push(v);
                            column += 1;
                        }
                        (Role::Face(k), Kind::List { count, item }) if k == j => {
                            let Some(b) = body.get(pos..pos + count.size()) else {
                                return Err(fail(
                                    element,
                                    row,
                                    &format!("count of list '{}'", p.name),
                                    short(count.size(), body.len() - pos),
                                ));
                            };
                            pos += count.size();
                            let n = list_len(count.decode(b, order))
                                .map_err(|m| fail(element, row, &prop(), m))?;
                            let need = n.saturating_mul(item.size());
                            let Some(items) = body.get(pos..pos.saturating_add(need)) else {
                                return Err(fail(
                                    element,
                                    row,
                                    &format!("list '{}' of {n} indices", p.name),
                                    short(need, body.len() - pos),
                                ));
                            };
                            pos += need;
                            if !(3..=MAX_FACE_VERTICES).contains(&n) {
                                return Err(SceneError::parse(path, None, face_size(row, n)));
                            }
                            face_buf.clear();
                            for c in items.chunks_exact(item.size()) {
                                let index = self
                                    .face_index(item.decode(c, order), row)
                                    .map_err(|m| SceneError::parse(path, None, m))?;
                                face_buf.push(index);
                            }
                            self.push_face(&face_buf);
                        }
                        _ => {
                            pos = skip_binary(body, pos, p, order)
                                .map_err(|m| fail(element, row, &prop(), m))?;
                        }
                    }
                }
            }
        }
        if pos < body.len() {
            // The data goes on past what the header declares: a count that is
            // too small must not silently drop the rest of the file.
            let extra = body.len() - pos;
            let rows = elements
                .last()
                .and_then(Element::fixed_row_size)
                .filter(|&size| size > 0 && extra.is_multiple_of(size))
                .map(|size| {
                    format!(
                        " (= {} more '{}' rows of {size} bytes)",
                        extra / size,
                        elements.last().map_or("", |e| e.name.as_str())
                    )
                })
                .unwrap_or_default();
            return Err(SceneError::parse(
                path,
                None,
                format!(
                    "{extra} bytes of data after the declared elements{rows}: the header \
                     declares {}, which end at byte {} of {}; a header count smaller than the \
                     data?",
                    declared(elements),
                    body_offset + pos,
                    body_offset + body.len()
                ),
            ));
        }
        Ok(())
    }

    fn read_ascii(
        &mut self,
        elements: &[Element],
        plans: &[Plan],
        body: &[u8],
        header_lines: usize,
    ) -> Result<(), SceneError> {
        let path = self.path;
        let mut lines = body
            .split(|&b| b == b'\n')
            .enumerate()
            .map(|(i, l)| (header_lines + 1 + i, l.strip_suffix(b"\r").unwrap_or(l)));
        let mut face_buf: Vec<u32> = Vec::new();
        let mut tokens: Vec<&str> = Vec::new();
        for (element, plan) in elements.iter().zip(plans) {
            if plan.role == Role::Vertex {
                // ASCII rows take at least two bytes per value.
                let capacity = element
                    .count
                    .min(body.len() / (2 * element.props.len().max(1)));
                self.start_vertex_table(element, capacity);
            }
            for row in 0..element.count {
                // Rows are one per line; blank lines are skipped.
                let (line_no, text) = loop {
                    let Some((line_no, raw)) = lines.next() else {
                        return Err(SceneError::parse(
                            path,
                            None,
                            format!(
                                "file ends in element '{}' after {row} of {} rows (file \
                                 truncated?)",
                                element.name, element.count
                            ),
                        ));
                    };
                    let Ok(text) = std::str::from_utf8(raw) else {
                        return Err(SceneError::parse(path, Some(line_no), "line is not text"));
                    };
                    if !text.trim().is_empty() {
                        break (line_no, text);
                    }
                };
                let err = |m: String| {
                    SceneError::parse(
                        path,
                        Some(line_no),
                        format!("element '{}' row {row}: {m}", element.name),
                    )
                };
                tokens.clear();
                tokens.extend(text.split_whitespace());
                let mut t = 0usize;
                let mut column = 0usize;
                for (j, (p, &finite)) in element.props.iter().zip(&plan.finite).enumerate() {
                    match p.kind {
                        Kind::Scalar(s) => {
                            let Some(token) = tokens.get(t) else {
                                return Err(err(format!(
                                    "too few values: property '{}' is missing (the line has {} \
                                     values)",
                                    p.name,
                                    tokens.len()
                                )));
                            };
                            t += 1;
                            if plan.role != Role::Vertex {
                                // Validate, but keep nothing.
                                s.parse_token(token)
                                    .map_err(|m| err(format!("property '{}': {m}", p.name)))?;
                                continue;
                            }
                            let v = s
                                .parse_token(token)
                                .map_err(|m| err(format!("property '{}': {m}", p.name)))?;
                            if finite && !v.is_finite() {
                                return Err(err(format!(
                                    "property '{}' is {v} (expected a finite number)",
                                    p.name
                                )));
                            }
                            self.out.vertex.columns[column].push(v);
                            column += 1;
                        }
                        Kind::List { count, item } => {
                            let Some(token) = tokens.get(t) else {
                                return Err(err(format!(
                                    "too few values: the count of list '{}' is missing",
                                    p.name
                                )));
                            };
                            t += 1;
                            let n = count
                                .parse_token(token)
                                .and_then(list_len)
                                .map_err(|m| err(format!("list '{}': {m}", p.name)))?;
                            let Some(items) = tokens.get(t..t + n) else {
                                return Err(err(format!(
                                    "too few values: list '{}' declares {n} items but the line \
                                     has only {} more values",
                                    p.name,
                                    tokens.len() - t
                                )));
                            };
                            t += n;
                            let is_faces = plan.role == Role::Face(j);
                            if is_faces && !(3..=MAX_FACE_VERTICES).contains(&n) {
                                return Err(err(face_size(row, n)));
                            }
                            face_buf.clear();
                            for token in items {
                                let v = item
                                    .parse_token(token)
                                    .map_err(|m| err(format!("list '{}': {m}", p.name)))?;
                                if is_faces {
                                    face_buf.push(self.face_index(v, row).map_err(&err)?);
                                }
                            }
                            if is_faces {
                                self.push_face(&face_buf);
                            }
                        }
                    }
                }
                if t != tokens.len() {
                    return Err(err(format!(
                        "too many values: expected {t}, the line has {}",
                        tokens.len()
                    )));
                }
            }
        }
        // Rows past the declared counts: a count that is too small must not
        // silently drop the rest of the file.
        let mut extra = lines.filter(|(_, raw)| !raw.trim_ascii().is_empty());
        if let Some((line_no, _)) = extra.next() {
            let more = 1 + extra.count();
            return Err(SceneError::parse(
                path,
                Some(line_no),
                format!(
                    "{more} more non-blank line{} after the declared elements: the header \
                     declares {}; a header count smaller than the data?",
                    if more == 1 { "" } else { "s" },
                    declared(elements)
                ),
            ));
        }
        Ok(())
    }
}

/// The element counts a header declares, e.g. `100 'vertex' rows, 0 'face'
/// rows`.
fn declared(elements: &[Element]) -> String {
    if elements.is_empty() {
        return "no elements".to_owned();
    }
    elements
        .iter()
        .map(|e| format!("{} '{}' rows", e.count, e.name))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The first property of a fixed-layout row that does not fit in `left`
/// bytes: its description, its size and the bytes left for it.
fn first_prop_past(element: &Element, left: usize) -> (String, usize, usize) {
    let mut offset = 0;
    for p in &element.props {
        let size = match p.kind {
            Kind::Scalar(s) => s.size(),
            Kind::List { count, .. } => count.size(),
        };
        if offset + size > left {
            return (format!("property '{}'", p.name), size, left - offset);
        }
        offset += size;
    }
    ("row".to_owned(), element.min_row_size(), left)
}

/// A list count as a length.
fn list_len(v: f64) -> Result<usize, String> {
    if v < 0.0 {
        Err(format!("negative list length {v}"))
    } else {
        Ok(v as usize)
    }
}

/// Skip one property of one binary row: the position after it, or what went
/// wrong ("needs N bytes, only M left").
fn skip_binary(body: &[u8], pos: usize, p: &Property, order: Order) -> Result<usize, String> {
    let left = body.len() - pos;
    let short = |need: usize| format!("needs {need} bytes, only {left} left");
    match p.kind {
        Kind::Scalar(s) => {
            if s.size() > left {
                return Err(short(s.size()));
            }
            Ok(pos + s.size())
        }
        Kind::List { count, item } => {
            let Some(b) = body.get(pos..pos + count.size()) else {
                return Err(short(count.size()));
            };
            let n = list_len(count.decode(b, order))?;
            let need = n.saturating_mul(item.size()).saturating_add(count.size());
            if need > left {
                return Err(short(need));
            }
            Ok(pos + need)
        }
    }
}
