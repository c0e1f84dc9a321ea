//! PCD (Point Cloud Library) point clouds: header, `ascii`, `binary` and
//! `binary_compressed` (LZF, structure-of-arrays) data.

use super::{Fields, NonFinite, build_cloud, read_file};
use crate::{PointCloud, SceneError};
use geom::{Isometry3, Translation3, UnitQuaternion};
use std::path::Path;

/// The header of a PCD file, as declared (nothing about the data is checked
/// beyond the header's own consistency).
#[derive(Clone, Debug, PartialEq)]
pub struct PcdHeader {
    /// The `VERSION` value (`0.7`, `.7`, `0.6` …), when the header has one.
    pub version: Option<String>,
    /// The fields of every point, in file order.
    pub fields: Vec<PcdField>,
    /// `WIDTH`: points per row of an organized cloud, or the point count.
    pub width: usize,
    /// `HEIGHT`: rows of an organized cloud, 1 for an unorganized one.
    pub height: usize,
    /// `POINTS`: number of points stored (`width × height`), including the
    /// invalid (NaN) pixels of organized clouds.
    pub points: usize,
    /// `VIEWPOINT`: the sensor pose in the cloud's frame (PCL's
    /// `sensor_origin_` and `sensor_orientation_`); identity when absent.
    /// [`load_cloud`](super::load_cloud) does not apply it.
    pub cloud_from_sensor: Isometry3,
    /// `DATA`: how the points are stored.
    pub data: PcdData,
}

/// One field (column group) of a PCD point.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct PcdField {
    /// Name, e.g. `x`, `normal_x`, `label`, `rgba`, `_` (padding).
    pub name: String,
    /// Bytes per element: 1, 2, 4 or 8.
    pub size: usize,
    /// Element type.
    pub kind: PcdType,
    /// Elements per point (`COUNT`), usually 1.
    pub count: usize,
}

/// Element type of a PCD field (`TYPE I`, `U` or `F`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PcdType {
    /// `I`: signed integer.
    Signed,
    /// `U`: unsigned integer.
    Unsigned,
    /// `F`: IEEE float (`SIZE` 4 or 8).
    Float,
}

impl PcdType {
    /// The header letter: `I`, `U` or `F`.
    pub fn letter(self) -> char {
        match self {
            Self::Signed => 'I',
            Self::Unsigned => 'U',
            Self::Float => 'F',
        }
    }
}

/// Storage of a PCD file's points (`DATA` line).
///
/// The data must fill the file exactly: bytes or lines beyond `POINTS` points
/// are an error, except zero bytes after a compressed block (PCL pads its
/// compressed files).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PcdData {
    /// One text line per point.
    Ascii,
    /// Packed little-endian records, point after point.
    Binary,
    /// `u32` compressed size, `u32` uncompressed size, then an LZF stream that
    /// decompresses to the fields one after another (structure of arrays).
    BinaryCompressed,
}

/// Read and check the header of a PCD file (for its viewpoint, size of an
/// organized cloud, or fields).
pub fn read_pcd_header(path: &Path) -> Result<PcdHeader, SceneError> {
    let bytes = read_file(path)?;
    Ok(parse_header(&bytes, path)?.header)
}

struct Parsed {
    header: PcdHeader,
    /// Byte offset of the first data byte.
    body: usize,
    /// Number of header lines (ASCII data starts on the next line).
    lines: usize,
}

/// The field at `i` as a reader of one value type.
#[derive(Clone, Copy, Debug)]
enum Value {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl Value {
    fn of(field: &PcdField) -> Option<Self> {
        Some(match (field.kind, field.size) {
            (PcdType::Signed, 1) => Self::I8,
            (PcdType::Unsigned, 1) => Self::U8,
            (PcdType::Signed, 2) => Self::I16,
            (PcdType::Unsigned, 2) => Self::U16,
            (PcdType::Signed, 4) => Self::I32,
            (PcdType::Unsigned, 4) => Self::U32,
            (PcdType::Signed, 8) => Self::I64,
            (PcdType::Unsigned, 8) => Self::U64,
            (PcdType::Float, 4) => Self::F32,
            (PcdType::Float, 8) => Self::F64,
            _ => return None,
        })
    }

    /// Decode a little-endian value; `b` holds at least its size.
    #[inline]
    fn decode(self, b: &[u8]) -> f64 {
        match self {
            Self::I8 => f64::from(b[0] as i8),
            Self::U8 => f64::from(b[0]),
            Self::I16 => f64::from(i16::from_le_bytes(le(b))),
            Self::U16 => f64::from(u16::from_le_bytes(le(b))),
            Self::I32 => f64::from(i32::from_le_bytes(le(b))),
            Self::U32 => f64::from(u32::from_le_bytes(le(b))),
            Self::I64 => i64::from_le_bytes(le(b)) as f64,
            Self::U64 => u64::from_le_bytes(le(b)) as f64,
            Self::F32 => f64::from(f32::from_le_bytes(le(b))),
            Self::F64 => f64::from_le_bytes(le(b)),
        }
    }
}

#[inline]
fn le<const N: usize>(b: &[u8]) -> [u8; N] {
    let mut a = [0u8; N];
    a.copy_from_slice(&b[..N]);
    a
}

#[allow(
    clippy::too_many_lines,
    reason = "the PCD header line by line in the order the format fixes (VERSION, FIELDS, SIZE, TYPE, COUNT, WIDTH, HEIGHT, VIEWPOINT, POINTS, DATA), each error naming its line"
)]
fn parse_header(bytes: &[u8], path: &Path) -> Result<Parsed, SceneError> {
    let err = |line: usize, msg: String| SceneError::parse(path, Some(line), msg);
    if bytes.is_empty() {
        return Err(SceneError::parse(
            path,
            None,
            "empty file (expected a PCD header)",
        ));
    }
    let mut version = None;
    let mut names: Option<(usize, Vec<String>)> = None;
    let mut sizes: Option<(usize, Vec<usize>)> = None;
    let mut types: Option<(usize, Vec<PcdType>)> = None;
    let mut counts: Option<(usize, Vec<usize>)> = None;
    let mut width: Option<(usize, usize)> = None;
    let mut height: Option<(usize, usize)> = None;
    let mut points: Option<(usize, usize)> = None;
    let mut viewpoint = None;
    let mut pos = 0;
    let mut line_no = 0;
    let data = loop {
        let Some(nl) = bytes[pos..].iter().position(|&b| b == b'\n') else {
            return Err(err(
                line_no + 1,
                "header ends without a 'DATA' line (file truncated?)".into(),
            ));
        };
        let raw = &bytes[pos..pos + nl];
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        pos += nl + 1;
        line_no += 1;
        let Ok(text) = std::str::from_utf8(raw) else {
            return Err(err(line_no, "header line is not text".into()));
        };
        let words: Vec<&str> = text.split_whitespace().collect();
        let Some((&key, values)) = words.split_first() else {
            continue;
        };
        if key.starts_with('#') {
            continue;
        }
        let once = |seen: bool| {
            if seen {
                Err(err(line_no, format!("a second {key} line")))
            } else {
                Ok(())
            }
        };
        let numbers = |what: &str| -> Result<Vec<usize>, SceneError> {
            values
                .iter()
                .map(|v| {
                    v.parse::<usize>().map_err(|_| {
                        err(
                            line_no,
                            format!("{key}: '{v}' is not a non-negative integer ({what})"),
                        )
                    })
                })
                .collect()
        };
        let single = |what: &str| -> Result<usize, SceneError> {
            match numbers(what)?.as_slice() {
                [n] => Ok(*n),
                _ => Err(err(
                    line_no,
                    format!("{key} takes one value ({what}), found {}", values.len()),
                )),
            }
        };
        match key {
            "VERSION" => {
                once(version.is_some())?;
                let v = values.first().copied().unwrap_or("");
                if !matches!(v, "0.5" | ".5" | "0.6" | ".6" | "0.7" | ".7") || values.len() != 1 {
                    return Err(err(
                        line_no,
                        format!(
                            "unsupported PCD version '{}' (expected 0.5 to 0.7)",
                            values.join(" ")
                        ),
                    ));
                }
                version = Some(v.to_owned());
            }
            "FIELDS" | "COLUMNS" => {
                once(names.is_some())?;
                if values.is_empty() {
                    return Err(err(line_no, "FIELDS lists no fields".into()));
                }
                names = Some((line_no, values.iter().map(|s| (*s).to_owned()).collect()));
            }
            "SIZE" => {
                once(sizes.is_some())?;
                sizes = Some((line_no, numbers("bytes per element")?));
            }
            "TYPE" => {
                once(types.is_some())?;
                let t = values
                    .iter()
                    .map(|v| match *v {
                        "I" => Ok(PcdType::Signed),
                        "U" => Ok(PcdType::Unsigned),
                        "F" => Ok(PcdType::Float),
                        other => Err(err(
                            line_no,
                            format!("TYPE: '{other}' is not a PCD type (expected I, U or F)"),
                        )),
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                types = Some((line_no, t));
            }
            "COUNT" => {
                once(counts.is_some())?;
                counts = Some((line_no, numbers("elements per field")?));
            }
            "WIDTH" => {
                once(width.is_some())?;
                width = Some((line_no, single("points per row")?));
            }
            "HEIGHT" => {
                once(height.is_some())?;
                height = Some((line_no, single("rows")?));
            }
            "POINTS" => {
                once(points.is_some())?;
                points = Some((line_no, single("number of points")?));
            }
            "VIEWPOINT" => {
                once(viewpoint.is_some())?;
                viewpoint = Some(parse_viewpoint(values).map_err(|m| err(line_no, m))?);
            }
            "DATA" => {
                break match values {
                    ["ascii"] => PcdData::Ascii,
                    ["binary"] => PcdData::Binary,
                    ["binary_compressed"] => PcdData::BinaryCompressed,
                    _ => {
                        return Err(err(
                            line_no,
                            format!(
                                "DATA '{}' is not a PCD data kind (expected ascii, binary or \
                                 binary_compressed)",
                                values.join(" ")
                            ),
                        ));
                    }
                };
            }
            other => {
                return Err(err(
                    line_no,
                    format!(
                        "unexpected header line starting with '{}' (expected VERSION, FIELDS, \
                         SIZE, TYPE, COUNT, WIDTH, HEIGHT, VIEWPOINT, POINTS or DATA)",
                        other.chars().take(40).collect::<String>()
                    ),
                ));
            }
        }
    };
    let data_line = line_no;

    let Some((_, names)) = names else {
        return Err(err(data_line, "the header has no FIELDS line".into()));
    };
    let n = names.len();
    let per_field =
        |entry: Option<(usize, Vec<usize>)>, key: &str| -> Result<Vec<usize>, SceneError> {
            match entry {
                Some((_, v)) if v.len() == n => Ok(v),
                Some((line, v)) => Err(err(
                    line,
                    format!("{key} has {} values but FIELDS names {n} fields", v.len()),
                )),
                None => Err(err(data_line, format!("the header has no {key} line"))),
            }
        };
    let sizes = per_field(sizes, "SIZE")?;
    let count_line = counts.as_ref().map_or(data_line, |(line, _)| *line);
    let counts = match counts {
        None => vec![1; n],
        some => per_field(some, "COUNT")?,
    };
    let (type_line, types) = match types {
        Some((line, t)) if t.len() == n => (line, t),
        Some((line, t)) => {
            return Err(err(
                line,
                format!("TYPE has {} values but FIELDS names {n} fields", t.len()),
            ));
        }
        None => return Err(err(data_line, "the header has no TYPE line".into())),
    };
    let mut fields = Vec::with_capacity(n);
    for (((name, size), kind), count) in names.into_iter().zip(sizes).zip(types).zip(counts) {
        let field = PcdField {
            name,
            size,
            kind,
            count,
        };
        if Value::of(&field).is_none() {
            return Err(err(
                type_line,
                format!(
                    "field '{}': TYPE {} with SIZE {size} is not a PCD type (I and U take 1, 2, \
                     4 or 8 bytes, F takes 4 or 8)",
                    field.name,
                    kind.letter()
                ),
            ));
        }
        if count == 0 {
            return Err(err(
                data_line,
                format!("field '{}' has COUNT 0", field.name),
            ));
        }
        fields.push(field);
    }
    // Bytes per point, checked once so that later sums cannot overflow.
    if fields
        .iter()
        .try_fold(0usize, |acc, f| {
            f.size.checked_mul(f.count)?.checked_add(acc)
        })
        .is_none()
    {
        return Err(err(
            count_line,
            "SIZE × COUNT of the fields overflows".into(),
        ));
    }

    let (points_line, points) = match (points, width, height) {
        (Some(p), _, _) => p,
        (None, Some((line, w)), h) => {
            let h = h.map_or(1, |(_, h)| h);
            let Some(p) = w.checked_mul(h) else {
                return Err(err(line, "WIDTH × HEIGHT overflows".into()));
            };
            (line, p)
        }
        (None, None, _) => {
            return Err(err(
                data_line,
                "the header has neither POINTS nor WIDTH".into(),
            ));
        }
    };
    let width = width.map_or(points, |(_, w)| w);
    let height = height.map_or(1, |(_, h)| h);
    if width.checked_mul(height) != Some(points) {
        return Err(err(
            points_line,
            format!("POINTS {points} does not equal WIDTH {width} × HEIGHT {height}"),
        ));
    }
    Ok(Parsed {
        header: PcdHeader {
            version,
            fields,
            width,
            height,
            points,
            cloud_from_sensor: viewpoint.unwrap_or_else(Isometry3::identity),
            data,
        },
        body: pos,
        lines: line_no,
    })
}

fn parse_viewpoint(values: &[&str]) -> Result<Isometry3, String> {
    let v = values
        .iter()
        .map(|s| {
            s.parse::<f64>()
                .map_err(|_| format!("VIEWPOINT: '{s}' is not a number"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let [tx, ty, tz, qw, qx, qy, qz] = v.as_slice() else {
        return Err(format!(
            "VIEWPOINT takes 7 numbers (tx ty tz qw qx qy qz), found {}",
            v.len()
        ));
    };
    if v.iter().any(|x| !x.is_finite()) {
        return Err("VIEWPOINT has a non-finite number".into());
    }
    let q = nalgebra::Quaternion::new(*qw, *qx, *qy, *qz);
    let Some(rotation) = UnitQuaternion::try_new(q, 1e-9) else {
        return Err("VIEWPOINT quaternion (qw qx qy qz) is zero".into());
    };
    Ok(Isometry3::from_parts(
        Translation3::new(*tx, *ty, *tz),
        rotation,
    ))
}

/// Load a PCD cloud. Points whose x, y or z is not finite are dropped (PCL's
/// convention for invalid pixels); the other attributes stay aligned.
pub(super) fn load_cloud(path: &Path, bytes: &[u8]) -> Result<PointCloud, SceneError> {
    let parsed = parse_header(bytes, path)?;
    let header = &parsed.header;
    let perr = |msg: String| SceneError::parse(path, None, msg);

    // The fields we use: (name, index into header.fields).
    let find = |name: &str| header.fields.iter().position(|f| f.name == name);
    let mut wanted: Vec<(&'static str, usize)> = Vec::new();
    for axis in ["x", "y", "z"] {
        let Some(i) = find(axis) else {
            return Err(perr(format!(
                "PCD file has no field '{axis}' (fields: {})",
                header
                    .fields
                    .iter()
                    .map(|f| f.name.as_str())
                    .collect::<Vec<_>>()
                    .join(" ")
            )));
        };
        wanted.push((axis, i));
    }
    let normal_fields = ["normal_x", "normal_y", "normal_z"].map(find);
    match normal_fields {
        [Some(a), Some(b), Some(c)] => wanted.extend([("nx", a), ("ny", b), ("nz", c)]),
        [None, None, None] => {}
        _ => {
            return Err(perr(
                "PCD file has only some of the fields normal_x, normal_y, normal_z".into(),
            ));
        }
    }
    if let Some(i) = find("label") {
        wanted.push(("label", i));
    }
    if let Some(i) = find("intensity") {
        wanted.push(("intensity", i));
    }
    for &(role, i) in &wanted {
        let f = &header.fields[i];
        let float_only = matches!(role, "x" | "y" | "z" | "nx" | "ny" | "nz");
        if f.count != 1 || (float_only && f.kind != PcdType::Float) {
            return Err(perr(format!(
                "field '{}' must be a single {} (COUNT 1), found SIZE {} TYPE {} COUNT {}",
                f.name,
                if float_only {
                    "float (F 4 or F 8)"
                } else {
                    "number"
                },
                f.size,
                f.kind.letter(),
                f.count
            )));
        }
    }

    let columns = match header.data {
        PcdData::Ascii => read_ascii(header, &wanted, &bytes[parsed.body..], parsed.lines, path)?,
        PcdData::Binary | PcdData::BinaryCompressed => {
            read_binary(header, &wanted, &bytes[parsed.body..], parsed.body, path)?
        }
    };
    let column = |role: &str| {
        wanted
            .iter()
            .position(|(r, _)| *r == role)
            .map(|k| columns[k].as_slice())
    };
    let (Some(x), Some(y), Some(z)) = (column("x"), column("y"), column("z")) else {
        return Err(perr("internal: x, y, z columns missing".into()));
    };
    let normals = match (column("nx"), column("ny"), column("nz")) {
        (Some(a), Some(b), Some(c)) => Some([a, b, c]),
        _ => None,
    };
    let fields = Fields {
        xyz: [x, y, z],
        normals,
        label: column("label"),
        intensity: column("intensity"),
    };
    build_cloud(path, &fields, NonFinite::Drop, |i| format!("point {i}"))
}

/// Point size in bytes, and each field's byte offset within a point record.
fn layout(header: &PcdHeader) -> (usize, Vec<usize>) {
    let mut offsets = Vec::with_capacity(header.fields.len());
    let mut size = 0;
    for f in &header.fields {
        offsets.push(size);
        size += f.size * f.count;
    }
    (size, offsets)
}

/// Read `binary` or `binary_compressed` data; `body_offset` is where `body`
/// starts in the file (for messages).
fn read_binary(
    header: &PcdHeader,
    wanted: &[(&str, usize)],
    body: &[u8],
    body_offset: usize,
    path: &Path,
) -> Result<Vec<Vec<f64>>, SceneError> {
    let perr = |msg: String| SceneError::parse(path, None, msg);
    let n = header.points;
    let (point_size, offsets) = layout(header);
    let Some(total) = n.checked_mul(point_size) else {
        return Err(perr(format!(
            "POINTS {n} × {point_size} bytes per point overflows"
        )));
    };
    let decompressed;
    // For each wanted field: where its first value is and the step between points.
    let compressed = header.data == PcdData::BinaryCompressed;
    let (data, places): (&[u8], Vec<(usize, usize)>) = if compressed {
        if n == 0 {
            return Ok(vec![Vec::new(); wanted.len()]);
        }
        let Some(sizes) = body.get(..8) else {
            return Err(perr(format!(
                "binary_compressed data truncated: needs 8 bytes (compressed and \
                 uncompressed sizes) after the header, found {}",
                body.len()
            )));
        };
        let compressed_size = u32::from_le_bytes(le(&sizes[..4])) as usize;
        let uncompressed_size = u32::from_le_bytes(le(&sizes[4..])) as usize;
        let stream = &body[8..];
        if compressed_size > stream.len() {
            return Err(perr(format!(
                "binary_compressed data truncated: the header says {compressed_size} \
                 compressed bytes but only {} follow (file truncated?)",
                stream.len()
            )));
        }
        // PCL pads compressed files with zero bytes after the block (a few
        // kilobytes in PCL's own test files); anything else there is data the
        // sizes do not account for.
        if let Some(k) = stream[compressed_size..].iter().position(|&b| b != 0) {
            return Err(perr(format!(
                "binary_compressed: the header says {compressed_size} compressed bytes but {} \
                 follow, and byte {} (after the compressed block) is data, not zero padding; \
                 a size smaller than the data?",
                stream.len(),
                body_offset + 8 + compressed_size + k
            )));
        }
        if uncompressed_size != total {
            return Err(perr(format!(
                "binary_compressed: the header says {uncompressed_size} uncompressed bytes \
                 but {n} points × {point_size} bytes need {total}"
            )));
        }
        decompressed = decompress_lzf(&stream[..compressed_size], total).map_err(perr)?;
        // Structure of arrays: each field's values for all points, field after field.
        let places = wanted
            .iter()
            .map(|&(_, i)| {
                (
                    offsets[i] * n,
                    header.fields[i].size * header.fields[i].count,
                )
            })
            .collect();
        (decompressed.as_slice(), places)
    } else {
        if body.len() < total {
            return Err(perr(format!(
                "binary data truncated: {n} points × {point_size} bytes need {total} bytes \
                 after the header, found {}",
                body.len()
            )));
        }
        if body.len() > total {
            let extra = body.len() - total;
            let points = if point_size > 0 && extra.is_multiple_of(point_size) {
                format!(" (= {} more points)", extra / point_size)
            } else {
                String::new()
            };
            return Err(perr(format!(
                "binary data longer than declared: POINTS {n} × {point_size} bytes per point = \
                 {total} bytes after the header, but the file has {} ({extra} bytes after the \
                 last declared point{points}, from byte {}); POINTS (or WIDTH × HEIGHT) \
                 smaller than the data?",
                body.len(),
                body_offset + total
            )));
        }
        let places = wanted
            .iter()
            .map(|&(_, i)| (offsets[i], point_size))
            .collect();
        (&body[..total], places)
    };
    let mut columns = Vec::with_capacity(wanted.len());
    for (&(_, i), &(start, step)) in wanted.iter().zip(&places) {
        let Some(value) = Value::of(&header.fields[i]) else {
            return Err(perr(format!(
                "field '{}' has no PCD type",
                header.fields[i].name
            )));
        };
        let size = header.fields[i].size;
        let column: Vec<f64> = (0..n)
            .map(|p| {
                let at = start + p * step;
                value.decode(&data[at..at + size])
            })
            .collect();
        columns.push(column);
    }
    Ok(columns)
}

/// Decompress a PCD LZF block that must come out `expected` bytes long.
fn decompress_lzf(compressed: &[u8], expected: usize) -> Result<Vec<u8>, String> {
    // One LZF back-reference of 3 bytes yields at most 264 bytes, so no stream
    // expands by more than 88×: refuse sizes that could only be a lie before
    // allocating the output.
    const MAX_RATIO: usize = 88;
    if compressed.is_empty() {
        return Err(format!(
            "binary_compressed: the compressed block is empty but {expected} bytes are expected"
        ));
    }
    if expected / MAX_RATIO > compressed.len() {
        return Err(format!(
            "binary_compressed: {} compressed bytes cannot hold {expected} uncompressed bytes \
             (sizes in the file are wrong)",
            compressed.len()
        ));
    }
    let out = lzf::decompress(compressed, expected).map_err(|e| {
        format!(
            "binary_compressed: LZF decompression of {} bytes into {expected} failed: {e} \
             (corrupt data)",
            compressed.len()
        )
    })?;
    if out.len() != expected {
        return Err(format!(
            "binary_compressed: LZF data decompressed to {} bytes, expected {expected} (corrupt \
             data)",
            out.len()
        ));
    }
    Ok(out)
}

fn read_ascii(
    header: &PcdHeader,
    wanted: &[(&str, usize)],
    body: &[u8],
    header_lines: usize,
    path: &Path,
) -> Result<Vec<Vec<f64>>, SceneError> {
    let n = header.points;
    // Token index of each field's first element on a line.
    let mut first_token = Vec::with_capacity(header.fields.len());
    let mut tokens_per_point = 0;
    for f in &header.fields {
        first_token.push(tokens_per_point);
        tokens_per_point += f.count;
    }
    let capacity = n.min(body.len() / tokens_per_point.max(1).saturating_mul(2));
    let mut columns = vec![Vec::with_capacity(capacity); wanted.len()];
    let mut lines = body
        .split(|&b| b == b'\n')
        .enumerate()
        .map(|(i, l)| (header_lines + 1 + i, l.strip_suffix(b"\r").unwrap_or(l)));
    // COUNT comes from the header: reserve for a sane line only (a lying
    // count is caught when the line is split).
    let mut tokens: Vec<&str> = Vec::with_capacity(tokens_per_point.min(256));
    let mut last_line = header_lines;
    for point in 0..n {
        let (line_no, text) = loop {
            let Some((line_no, raw)) = lines.next() else {
                return Err(SceneError::parse(
                    path,
                    Some(last_line + 1),
                    format!("expected {n} points after DATA, found {point} (file truncated?)"),
                ));
            };
            let Ok(text) = std::str::from_utf8(raw) else {
                return Err(SceneError::parse(path, Some(line_no), "line is not text"));
            };
            if !text.trim().is_empty() {
                last_line = line_no;
                break (line_no, text);
            }
        };
        tokens.clear();
        tokens.extend(text.split_whitespace());
        if tokens.len() != tokens_per_point {
            return Err(SceneError::parse(
                path,
                Some(line_no),
                format!(
                    "point {point}: found {} values, expected {tokens_per_point} (fields: {})",
                    tokens.len(),
                    header
                        .fields
                        .iter()
                        .map(|f| f.name.as_str())
                        .collect::<Vec<_>>()
                        .join(" ")
                ),
            ));
        }
        for (column, &(_, i)) in columns.iter_mut().zip(wanted) {
            let token = tokens[first_token[i]];
            let field = &header.fields[i];
            // A 4-byte float field holds the nearest f32, as in binary files.
            let parsed = if field.kind == PcdType::Float && field.size == 4 {
                token.parse::<f32>().map(f64::from)
            } else {
                token.parse::<f64>()
            };
            let v = parsed.map_err(|_| {
                SceneError::parse(
                    path,
                    Some(line_no),
                    format!(
                        "point {point}, field '{}': '{token}' is not a number",
                        header.fields[i].name
                    ),
                )
            })?;
            column.push(v);
        }
    }
    // Points past the declared count: POINTS too small must not silently drop
    // the rest of the file.
    let mut extra = lines.filter(|(_, raw)| !raw.trim_ascii().is_empty());
    if let Some((line_no, _)) = extra.next() {
        let more = 1 + extra.count();
        return Err(SceneError::parse(
            path,
            Some(line_no),
            format!(
                "{more} more non-blank line{} after the {n} points the header declares (POINTS \
                 {n}); POINTS (or WIDTH × HEIGHT) smaller than the data?",
                if more == 1 { "" } else { "s" },
            ),
        ));
    }
    Ok(columns)
}
