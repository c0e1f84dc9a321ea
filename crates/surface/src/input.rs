//! Input: sensor sets (P§2.3) and initial segments (P§4.3), from memory or files.
//!
//! * Sensor sets, JSON lines — one set per line, blank lines ignored:
//!   `{"points": [[x,y,z], ...], "axes": [[ax,ay,az], ...]}`, where `axes[i]` is
//!   the unit sensing axis of the sensor that measured `points[i]` (world frame,
//!   pointing from the sensor into the surface).
//! * Initial segments, one JSON document:
//!   `{"segments": [[[x,y,z], ...], ...]}` — each segment a list of at least three
//!   coplanar vertices, anticlockwise about the outward normal (so the table under
//!   an object, seen from above, runs anticlockwise).

use crate::config::DEFAULT_MAX_SET_POINTS;
use crate::error::SurfaceError;
use geom::{Point3, Real, UnitVector3, Vector3};
use serde::Deserialize;
use std::io::BufRead;

/// Largest accepted deviation of a sensing axis' norm from 1.
pub const AXIS_NORM_TOLERANCE: Real = 1e-6;

/// One set of sensor points (P§2.3) with their sensing axes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SensorSet {
    /// The sensor points, world frame.
    pub points: Vec<Point3>,
    /// `axes[i]`: unit sensing axis of the sensor that measured `points[i]`.
    pub axes: Vec<UnitVector3>,
}

impl SensorSet {
    /// A checked set: equal lengths, finite coordinates, unit axes.
    ///
    /// ```
    /// use geom::{Point3, Vector3};
    /// use surface::SensorSet;
    /// let set = SensorSet::new(vec![Point3::new(0.0, 0.0, 1.0)], vec![-Vector3::z_axis()]).unwrap();
    /// assert_eq!(set.len(), 1);
    /// assert!(SensorSet::new(vec![Point3::new(f64::NAN, 0.0, 0.0)], vec![Vector3::z_axis()]).is_err());
    /// ```
    pub fn new(points: Vec<Point3>, axes: Vec<UnitVector3>) -> Result<Self, SurfaceError> {
        let set = Self { points, axes };
        set.validate()?;
        Ok(set)
    }

    /// A set from raw axis vectors, each checked to be of unit length.
    pub fn from_vectors(points: Vec<Point3>, axes: &[Vector3]) -> Result<Self, SurfaceError> {
        let axes = axes
            .iter()
            .map(|a| UnitVector3::new_unchecked(*a))
            .collect();
        Self::new(points, axes)
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// `true` when the set has no point.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Check the set (the fields are public, so [`SurfaceModel::update`](crate::SurfaceModel::update)
    /// checks again).
    pub fn validate(&self) -> Result<(), SurfaceError> {
        if self.points.len() != self.axes.len() {
            return Err(SurfaceError::SensorSet {
                field: "axes".into(),
                message: format!(
                    "{} axes for {} points (one axis per point)",
                    self.axes.len(),
                    self.points.len()
                ),
            });
        }
        for (i, p) in self.points.iter().enumerate() {
            if !p
                .iter()
                .all(|c| c.is_finite() && c.abs() <= geom::MAX_COORDINATE_M)
            {
                return Err(SurfaceError::SensorSet {
                    field: format!("points[{i}]"),
                    message: format!(
                        "not finite or beyond ±{:e} m: [{}, {}, {}]",
                        geom::MAX_COORDINATE_M,
                        p.x,
                        p.y,
                        p.z
                    ),
                });
            }
        }
        for (i, a) in self.axes.iter().enumerate() {
            let norm = a.norm();
            if !(norm.is_finite() && (norm - 1.0).abs() <= AXIS_NORM_TOLERANCE) {
                return Err(SurfaceError::SensorSet {
                    field: format!("axes[{i}]"),
                    message: format!("not a unit vector (norm {norm})"),
                });
            }
        }
        Ok(())
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawSet {
    points: Vec<[Real; 3]>,
    axes: Vec<[Real; 3]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RawInitial {
    segments: Vec<Vec<[Real; 3]>>,
}

fn parse_error(source_name: &str, line: usize, field: &str, message: String) -> SurfaceError {
    SurfaceError::Parse {
        source_name: source_name.to_owned(),
        line,
        field: field.to_owned(),
        message,
    }
}

/// Read sensor sets from JSON lines (format in the [module docs](self)), at most
/// [`DEFAULT_MAX_SET_POINTS`] points a set. Errors name the source, the 1-based
/// line and the field.
///
/// ```
/// let text = "{\"points\": [[0, 0, 1]], \"axes\": [[0, 0, -1]]}\n\n{\"points\": [], \"axes\": []}\n";
/// let sets = surface::read_sets_jsonl(text.as_bytes(), "sets.jsonl").unwrap();
/// assert_eq!(sets.len(), 2);
/// let bad = "{\"points\": [[0, 0, 1]], \"axes\": [[0, 0, -2]]}";
/// let err = surface::read_sets_jsonl(bad.as_bytes(), "sets.jsonl").unwrap_err();
/// assert_eq!(err.to_string(), "sets.jsonl:1: axes[0]: not a unit vector (norm 2)");
/// ```
pub fn read_sets_jsonl(
    reader: impl BufRead,
    source_name: &str,
) -> Result<Vec<SensorSet>, SurfaceError> {
    read_sets_jsonl_limited(reader, source_name, DEFAULT_MAX_SET_POINTS)
}

/// [`read_sets_jsonl`] with at most `max_set_points` points a set (pass the
/// model's [`SurfaceConfig::max_set_points`](crate::SurfaceConfig::max_set_points)).
///
/// ```
/// let text = "{\"points\": [[0, 0, 1], [0, 1, 1]], \"axes\": [[0, 0, -1], [0, 0, -1]]}";
/// let err = surface::read_sets_jsonl_limited(text.as_bytes(), "sets.jsonl", 1).unwrap_err();
/// assert!(err.to_string().starts_with("sets.jsonl:1: points: 2 points, more than max_set_points = 1"));
/// ```
pub fn read_sets_jsonl_limited(
    reader: impl BufRead,
    source_name: &str,
    max_set_points: usize,
) -> Result<Vec<SensorSet>, SurfaceError> {
    let mut sets = Vec::new();
    for (i, line) in reader.lines().enumerate() {
        let line_no = i + 1;
        let line = line.map_err(|e| SurfaceError::Io {
            source_name: source_name.to_owned(),
            message: format!("line {line_no}: {e}"),
        })?;
        if line.trim().is_empty() {
            continue;
        }
        let raw: RawSet = serde_json::from_str(&line).map_err(|e| {
            let field = ["points", "axes"]
                .into_iter()
                .find(|f| e.to_string().contains(f))
                .unwrap_or("json");
            parse_error(source_name, line_no, field, e.to_string())
        })?;
        if raw.points.len() > max_set_points {
            return Err(parse_error(
                source_name,
                line_no,
                "points",
                format!(
                    "{} points, more than max_set_points = {max_set_points} (split the set or raise the limit)",
                    raw.points.len()
                ),
            ));
        }
        let set = SensorSet {
            points: raw.points.iter().map(|p| Point3::from(*p)).collect(),
            axes: raw
                .axes
                .iter()
                .map(|a| UnitVector3::new_unchecked(Vector3::from(*a)))
                .collect(),
        };
        set.validate().map_err(|e| match e {
            SurfaceError::SensorSet { field, message } => {
                parse_error(source_name, line_no, &field, message)
            }
            other => other,
        })?;
        sets.push(set);
    }
    Ok(sets)
}

/// Read initial segments (format in the [module docs](self)): one vertex list per
/// segment. Only the syntax and finiteness are checked here;
/// [`SurfaceModel::add_initial_segment`](crate::SurfaceModel::add_initial_segment)
/// checks the geometry.
///
/// ```
/// let text = r#"{"segments": [[[-2, -2, 0], [2, -2, 0], [2, 2, 0], [-2, 2, 0]]]}"#;
/// let segs = surface::read_initial_segments_json(text, "table.json").unwrap();
/// assert_eq!(segs[0].len(), 4);
/// ```
pub fn read_initial_segments_json(
    text: &str,
    source_name: &str,
) -> Result<Vec<Vec<Point3>>, SurfaceError> {
    read_initial_segments_located(text, source_name).map(|s| s.segments)
}

/// Initial segments as read from a file, with where each is written.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct InitialSegments {
    /// One vertex list per segment.
    pub segments: Vec<Vec<Point3>>,
    /// `lines[i]`: the 1-based line on which segment `i`'s vertex list opens.
    pub lines: Vec<usize>,
}

/// [`read_initial_segments_json`], with the line each segment opens on, for
/// messages about the segments that name their lines. Its own errors name the
/// segment's line too.
///
/// ```
/// let text = "{\"segments\": [\n  [[0, 0, 0], [1, 0, 0], [1, 1, 0]],\n  [[0, 0, 1], [1, 0, 1], [1, 1, 1]]\n]}";
/// let read = surface::read_initial_segments_located(text, "two.json").unwrap();
/// assert_eq!(read.lines, [2, 3]);
/// let bad = "{\"segments\": [\n  [[0, 0, 0], [1, 0, 0], [1, 1, 0]],\n  [[0, 0, 1], [1, 0, 1]]\n]}";
/// let err = surface::read_initial_segments_located(bad, "two.json").unwrap_err();
/// assert!(err.to_string().starts_with("two.json:3: segments[1]: 2 vertices"), "{err}");
/// ```
pub fn read_initial_segments_located(
    text: &str,
    source_name: &str,
) -> Result<InitialSegments, SurfaceError> {
    let raw: RawInitial = serde_json::from_str(text).map_err(|e| {
        let field = if e.to_string().contains("segments") {
            "segments"
        } else {
            "json"
        };
        parse_error(source_name, e.line().max(1), field, e.to_string())
    })?;
    let mut lines = segment_lines(text);
    lines.resize(raw.segments.len(), 1);
    let mut out = Vec::with_capacity(raw.segments.len());
    for (s, verts) in raw.segments.iter().enumerate() {
        if verts.len() < 3 {
            return Err(parse_error(
                source_name,
                lines[s],
                &format!("segments[{s}]"),
                format!("{} vertices (at least 3 needed)", verts.len()),
            ));
        }
        let mut pts = Vec::with_capacity(verts.len());
        for (v, p) in verts.iter().enumerate() {
            if !p
                .iter()
                .all(|c| c.is_finite() && c.abs() <= geom::MAX_COORDINATE_M)
            {
                return Err(parse_error(
                    source_name,
                    lines[s],
                    &format!("segments[{s}][{v}]"),
                    format!("not finite or beyond ±{:e} m", geom::MAX_COORDINATE_M),
                ));
            }
            pts.push(Point3::from(*p));
        }
        out.push(pts);
    }
    Ok(InitialSegments {
        segments: out,
        lines,
    })
}

/// The 1-based line on which each element of the top-level `"segments"` array
/// of a JSON document opens (`text` parsed already, so well formed): a scan
/// of brackets outside strings.
fn segment_lines(text: &str) -> Vec<usize> {
    let mut lines = Vec::new();
    let (mut line, mut depth) = (1, 0usize);
    let (mut in_string, mut escaped) = (false, false);
    let mut string_start = 0;
    // The last string closed at depth 1 (a key of the top-level object), and
    // whether the array being read at depth 2 is that of `"segments"`.
    let mut last_key: Option<&str> = None;
    let mut in_segments = false;
    for (i, c) in text.char_indices() {
        if c == '\n' {
            line += 1;
        }
        if in_string {
            if escaped {
                escaped = false;
            } else if c == '\\' {
                escaped = true;
            } else if c == '"' {
                in_string = false;
                if depth == 1 {
                    last_key = text.get(string_start..=i);
                }
            }
            continue;
        }
        match c {
            '"' => {
                in_string = true;
                string_start = i;
            }
            '[' | '{' => {
                depth += 1;
                if depth == 2 {
                    in_segments = c == '['
                        && last_key
                            .and_then(|k| serde_json::from_str::<String>(k).ok())
                            .is_some_and(|k| k == "segments");
                } else if depth == 3 && in_segments {
                    lines.push(line);
                }
            }
            ']' | '}' => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
    lines
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jsonl_errors_name_line_and_field() {
        let text = "{\"points\": [[0,0,1]], \"axes\": [[0,0,-1]]}\n{\"points\": [[0,0,1]], \"axes\": []}\n";
        let err = read_sets_jsonl(text.as_bytes(), "s").unwrap_err();
        assert!(err.to_string().starts_with("s:2: axes:"), "{err}");
        let err = read_sets_jsonl("{\"points\": 3, \"axes\": []}".as_bytes(), "s").unwrap_err();
        assert!(err.to_string().starts_with("s:1: "), "{err}");
        let err = read_sets_jsonl("{\"pts\": []}".as_bytes(), "s").unwrap_err();
        assert!(matches!(err, SurfaceError::Parse { line: 1, .. }));
        let err =
            read_initial_segments_json(r#"{"segments": [[[0,0,0],[1,0,0]]]}"#, "i").unwrap_err();
        assert!(err.to_string().contains("segments[0]"), "{err}");
    }
}
