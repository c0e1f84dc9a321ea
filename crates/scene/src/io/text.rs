//! Plain-text point clouds: one point per line, whitespace- or comma-separated.

use super::{Fields, NonFinite, build_cloud, to_label};
use crate::{PointCloud, SceneError};
use std::path::Path;

/// How positional columns are read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Layout {
    /// `x y z`, `x y z nx ny nz` or `x y z nx ny nz label`.
    Plain,
    /// Leica PTS: optional count line, then `x y z`, `x y z intensity` or
    /// `x y z intensity r g b`.
    LeicaPts,
}

/// What a column holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Role {
    X,
    Y,
    Z,
    Nx,
    Ny,
    Nz,
    Label,
    Intensity,
    Ignored,
}

impl Role {
    fn from_name(name: &str) -> Self {
        match name.to_ascii_lowercase().as_str() {
            "x" => Self::X,
            "y" => Self::Y,
            "z" => Self::Z,
            "nx" | "normal_x" => Self::Nx,
            "ny" | "normal_y" => Self::Ny,
            "nz" | "normal_z" => Self::Nz,
            "label" | "instance" | "class" => Self::Label,
            "intensity" => Self::Intensity,
            _ => Self::Ignored,
        }
    }

    /// Must the value be finite?
    fn must_be_finite(self) -> bool {
        self != Self::Ignored
    }
}

/// The column roles and their names, for messages.
struct Columns {
    roles: Vec<Role>,
    names: Vec<String>,
    /// The line that fixed the layout.
    line: usize,
    /// Whether the roles were inferred from the column count (not named).
    positional: bool,
}

/// Split a data line into values: by commas when it has any, else by whitespace.
fn split(line: &str) -> Vec<&str> {
    if line.contains(',') {
        line.split(',').map(str::trim).collect()
    } else {
        line.split_whitespace().collect()
    }
}

/// The line without its `#` comment, trimmed.
fn strip_comment(line: &str) -> &str {
    line.split_once('#').map_or(line, |(data, _)| data).trim()
}

fn positional(count: usize, layout: Layout, line: usize) -> Result<Columns, String> {
    use Role::{Ignored, Intensity, Label, Nx, Ny, Nz, X, Y, Z};
    let (roles, names): (Vec<Role>, &[&str]) = match (layout, count) {
        (_, 3) => (vec![X, Y, Z], &["x", "y", "z"]),
        (Layout::Plain, 6) => (
            vec![X, Y, Z, Nx, Ny, Nz],
            &["x", "y", "z", "nx", "ny", "nz"],
        ),
        (Layout::Plain, 7) => (
            vec![X, Y, Z, Nx, Ny, Nz, Label],
            &["x", "y", "z", "nx", "ny", "nz", "label"],
        ),
        (Layout::LeicaPts, 4) => (vec![X, Y, Z, Intensity], &["x", "y", "z", "intensity"]),
        (Layout::LeicaPts, 7) => (
            vec![X, Y, Z, Intensity, Ignored, Ignored, Ignored],
            &["x", "y", "z", "intensity", "r", "g", "b"],
        ),
        (Layout::Plain, _) => {
            return Err(format!(
                "found {count} values; expected 3 (x y z), 6 (x y z nx ny nz) or 7 \
                 (x y z nx ny nz label)"
            ));
        }
        (Layout::LeicaPts, _) => {
            return Err(format!(
                "found {count} values; a .pts line holds 3 (x y z), 4 (x y z intensity) or 7 \
                 (x y z intensity r g b)"
            ));
        }
    };
    Ok(Columns {
        roles,
        names: names.iter().map(|s| (*s).to_owned()).collect(),
        line,
        positional: true,
    })
}

fn named(names: &[&str], line: usize) -> Result<Columns, String> {
    let roles: Vec<Role> = names.iter().map(|n| Role::from_name(n)).collect();
    for (i, role) in roles.iter().enumerate() {
        if *role != Role::Ignored && roles[..i].contains(role) {
            return Err(format!("column name '{}' gives a role twice", names[i]));
        }
    }
    for (need, name) in [(Role::X, "x"), (Role::Y, "y"), (Role::Z, "z")] {
        if !roles.contains(&need) {
            return Err(format!(
                "the header line names no '{name}' column (found: {})",
                names.join(" ")
            ));
        }
    }
    let normals = [Role::Nx, Role::Ny, Role::Nz]
        .iter()
        .filter(|r| roles.contains(r))
        .count();
    if normals != 0 && normals != 3 {
        return Err("the header line names only some of nx, ny, nz".into());
    }
    Ok(Columns {
        roles,
        names: names.iter().map(|s| (*s).to_owned()).collect(),
        line,
        positional: false,
    })
}

pub(super) fn load_cloud(
    path: &Path,
    bytes: &[u8],
    layout: Layout,
) -> Result<PointCloud, SceneError> {
    let err = |line: usize, msg: String| SceneError::parse(path, Some(line), msg);
    let mut columns: Option<Columns> = None;
    let mut declared: Option<(usize, usize)> = None;
    let mut data: Vec<Vec<f64>> = Vec::new();
    let mut rows = 0usize;
    for (i, raw) in bytes.split(|&b| b == b'\n').enumerate() {
        let line_no = i + 1;
        let raw = raw.strip_suffix(b"\r").unwrap_or(raw);
        let Ok(text) = std::str::from_utf8(raw) else {
            return Err(err(line_no, "line is not text".into()));
        };
        let text = strip_comment(text);
        if text.is_empty() {
            continue;
        }
        let values = split(text);
        if columns.is_none() {
            // The first data line fixes the layout: a .pts count line, a line
            // of column names, or the first point.
            if layout == Layout::LeicaPts
                && declared.is_none()
                && values.len() == 1
                && let Ok(n) = values[0].parse::<usize>()
            {
                declared = Some((line_no, n));
                continue;
            }
            let numeric = values.iter().any(|v| v.parse::<f64>().is_ok());
            let c = if numeric {
                positional(values.len(), layout, line_no)
            } else {
                // CloudCompare writes its header as `//X,Y,Z,...`.
                let mut names = values.clone();
                if let Some(first) = names.first_mut() {
                    *first = first.trim_start_matches("//");
                }
                named(&names, line_no)
            }
            .map_err(|m| err(line_no, m))?;
            data = vec![Vec::new(); c.roles.len()];
            columns = Some(c);
            if !numeric {
                continue;
            }
        }
        let Some(cols) = &columns else {
            continue;
        };
        if values.len() != cols.roles.len() {
            return Err(err(
                line_no,
                format!(
                    "found {} values, expected {} ({}) as fixed by line {}",
                    values.len(),
                    cols.roles.len(),
                    cols.names.join(" "),
                    cols.line
                ),
            ));
        }
        for (k, value) in values.iter().enumerate() {
            let role = cols.roles[k];
            let name = &cols.names[k];
            if value.is_empty() {
                return Err(err(line_no, format!("column {} ({name}) is empty", k + 1)));
            }
            let v = value.parse::<f64>().map_err(|_| {
                err(
                    line_no,
                    format!("column {} ({name}): '{value}' is not a number", k + 1),
                )
            })?;
            if role.must_be_finite() && !v.is_finite() {
                return Err(err(
                    line_no,
                    format!(
                        "column {} ({name}) is {v}; a text cloud has no invalid-point convention, \
                         every value must be finite",
                        k + 1
                    ),
                ));
            }
            if cols.positional && matches!(role, Role::Nx | Role::Ny | Role::Nz) && v.abs() > 1.001
            {
                return Err(err(
                    line_no,
                    format!(
                        "column {} ({name}) is {v}, which cannot be a unit-normal component; if \
                         columns 4-6 are something else (colours?), name the columns in a first \
                         line, e.g. 'x y z r g b'",
                        k + 1
                    ),
                ));
            }
            if role == Role::Label {
                to_label(v).map_err(|m| err(line_no, format!("column {} ({name}): {m}", k + 1)))?;
            }
            data[k].push(v);
        }
        rows += 1;
    }
    if let Some((line, n)) = declared
        && n != rows
    {
        return Err(err(
            line,
            format!("the count line declares {n} points but the file has {rows}"),
        ));
    }
    let Some(cols) = columns else {
        return Err(SceneError::invalid(
            path.display().to_string(),
            "the file has no points (no data lines)",
        ));
    };
    let find = |role: Role| {
        cols.roles
            .iter()
            .position(|r| *r == role)
            .map(|k| data[k].as_slice())
    };
    let (Some(x), Some(y), Some(z)) = (find(Role::X), find(Role::Y), find(Role::Z)) else {
        return Err(SceneError::parse(
            path,
            Some(cols.line),
            "no x, y, z columns",
        ));
    };
    let normals = match (find(Role::Nx), find(Role::Ny), find(Role::Nz)) {
        (Some(a), Some(b), Some(c)) => Some([a, b, c]),
        _ => None,
    };
    let fields = Fields {
        xyz: [x, y, z],
        normals,
        label: find(Role::Label),
        intensity: find(Role::Intensity),
    };
    build_cloud(path, &fields, NonFinite::Reject, |i| format!("point {i}"))
}
