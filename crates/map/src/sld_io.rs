//! Files of Scale-Like Discs: disc CSV files and the point clouds discs are
//! generated from (the algorithm is in [`crate::sld`]).
//!
//! [`write_discs_csv`] / [`parse_discs_csv`] (and the path versions
//! [`save_discs_csv`], [`load_discs_csv`]) use the header
//! `cx,cy,cz,nx,ny,nz,radius,points`, optionally followed by extra numeric
//! columns ([`ExtraColumn`]: segment, material posterior, …) that the reader
//! ignores. [`load_points`] reads a cloud file and, for PLY scans carrying
//! `ox oy oz` columns, the sensor origin of every point; a mesh file's
//! vertices come with their faces' normals.
//!
//! ```
//! use geom::{Point3, UnitVector3, Vector3};
//! use map::sld::Disc;
//! use map::sld_io::{parse_discs_csv, write_discs_csv};
//!
//! let disc = Disc {
//!     centre: Point3::new(0.1, 0.2, 0.3),
//!     normal: UnitVector3::new_unchecked(Vector3::z()),
//!     radius_m: 0.04,
//!     points: 12,
//! };
//! let mut csv = Vec::new();
//! write_discs_csv(&mut csv, &[disc], &[])?;
//! let text = String::from_utf8(csv).unwrap();
//! assert_eq!(text, "cx,cy,cz,nx,ny,nz,radius,points\n0.1,0.2,0.3,0,0,1,0.04,12\n");
//! assert_eq!(parse_discs_csv(&text, "discs.csv")?, vec![disc]);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::MapError;
use crate::sld::{Disc, Orientation};
use geom::{Point3, Real, Vector3, unit};
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

/// An extra numeric column of a disc file (segment index, a material
/// probability, …), written after the eight contract columns.
#[derive(Clone, Debug, PartialEq)]
pub struct ExtraColumn {
    /// Header name (no commas, not one of the contract names).
    pub name: String,
    /// One value per disc.
    pub values: Vec<Real>,
}

/// The contract header of disc files.
pub const DISC_CSV_HEADER: [&str; 8] = ["cx", "cy", "cz", "nx", "ny", "nz", "radius", "points"];

/// Write discs as CSV: header `cx,cy,cz,nx,ny,nz,radius,points`, then the
/// `extra` columns, one row per disc. Values use Rust's shortest round-trip
/// formatting, so [`parse_discs_csv`] reads back identical discs.
///
/// Fails with [`std::io::ErrorKind::InvalidInput`], before writing anything,
/// when an extra column has the wrong length or a bad name.
pub fn write_discs_csv(
    writer: &mut impl Write,
    discs: &[Disc],
    extra: &[ExtraColumn],
) -> std::io::Result<()> {
    for (k, c) in extra.iter().enumerate() {
        let bad_name = c.name.is_empty()
            || c.name.contains([',', '\n', '\r', '"'])
            || DISC_CSV_HEADER.contains(&c.name.as_str())
            || extra[..k].iter().any(|o| o.name == c.name);
        if bad_name || c.values.len() != discs.len() {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!(
                    "extra column `{}`: needs a unique name without commas and {} values (has {})",
                    c.name,
                    discs.len(),
                    c.values.len()
                ),
            ));
        }
    }
    let mut line = DISC_CSV_HEADER.join(",");
    for c in extra {
        line.push(',');
        line.push_str(&c.name);
    }
    line.push('\n');
    writer.write_all(line.as_bytes())?;
    for (i, d) in discs.iter().enumerate() {
        line.clear();
        let _ = write!(
            line,
            "{},{},{},{},{},{},{},{}",
            d.centre.x,
            d.centre.y,
            d.centre.z,
            d.normal.x,
            d.normal.y,
            d.normal.z,
            d.radius_m,
            d.points
        );
        for c in extra {
            let _ = write!(line, ",{}", c.values[i]);
        }
        line.push('\n');
        writer.write_all(line.as_bytes())?;
    }
    Ok(())
}

/// [`write_discs_csv`] into a new file at `path`.
///
/// An extra column of the wrong length or with a bad name is a
/// [`MapError::Io`] error (kind [`std::io::ErrorKind::InvalidInput`]) and no
/// file is created.
pub fn save_discs_csv(path: &Path, discs: &[Disc], extra: &[ExtraColumn]) -> Result<(), MapError> {
    let mut buf = Vec::new();
    write_discs_csv(&mut buf, discs, extra).map_err(|e| MapError::write(path, e))?;
    std::fs::write(path, buf).map_err(|e| MapError::write(path, e))
}

/// Read discs from CSV text with at least the contract columns
/// `cx,cy,cz,nx,ny,nz,radius,points` (in any order; other columns are
/// ignored). Normals are re-normalised; a zero or non-finite normal, a
/// non-finite centre, a non-positive radius or a non-integer point count is
/// an error naming `source_name` and the line.
pub fn parse_discs_csv(text: &str, source_name: &str) -> Result<Vec<Disc>, MapError> {
    let err = |line: Option<usize>, message: String| MapError::parse(source_name, line, message);
    let mut lines = text.lines().enumerate();
    let (_, header) = lines
        .by_ref()
        .find(|(_, l)| !l.trim().is_empty())
        .ok_or_else(|| err(None, "empty file: expected a header line".into()))?;
    let names: Vec<&str> = header.split(',').map(str::trim).collect();
    let mut col = [0usize; 8];
    for (k, want) in DISC_CSV_HEADER.iter().enumerate() {
        col[k] = names.iter().position(|n| n == want).ok_or_else(|| {
            err(
                Some(1),
                format!(
                    "missing column `{want}` (header must contain {})",
                    DISC_CSV_HEADER.join(",")
                ),
            )
        })?;
    }
    let mut discs = Vec::new();
    for (i, raw) in lines {
        let line_no = i + 1;
        if raw.trim().is_empty() {
            continue;
        }
        let fields: Vec<&str> = raw.split(',').map(str::trim).collect();
        if fields.len() < names.len() {
            return Err(err(
                Some(line_no),
                format!("expected {} fields, found {}", names.len(), fields.len()),
            ));
        }
        let mut v = [0.0; 7];
        for k in 0..7 {
            let s = fields[col[k]];
            v[k] = s
                .parse::<Real>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    err(
                        Some(line_no),
                        format!(
                            "field `{}`: expected a finite number, found `{s}`",
                            DISC_CSV_HEADER[k]
                        ),
                    )
                })?;
        }
        let s = fields[col[7]];
        let points = s.parse::<usize>().map_err(|_| {
            err(
                Some(line_no),
                format!("field `points`: expected a non-negative integer, found `{s}`"),
            )
        })?;
        let normal = unit(Vector3::new(v[3], v[4], v[5]))
            .ok_or_else(|| err(Some(line_no), "the normal (nx, ny, nz) is zero".into()))?;
        if v[6] <= 0.0 {
            return Err(err(
                Some(line_no),
                format!(
                    "field `radius`: expected a positive distance, found {}",
                    v[6]
                ),
            ));
        }
        for k in [0, 1, 2, 6] {
            if v[k].abs() > geom::MAX_COORDINATE_M {
                return Err(err(
                    Some(line_no),
                    format!(
                        "field `{}`: {} is beyond ±{:e} m",
                        DISC_CSV_HEADER[k],
                        v[k],
                        geom::MAX_COORDINATE_M
                    ),
                ));
            }
        }
        discs.push(Disc {
            centre: Point3::new(v[0], v[1], v[2]),
            normal,
            radius_m: v[6],
            points,
        });
    }
    Ok(discs)
}

/// Read a disc CSV file (see [`parse_discs_csv`]).
pub fn load_discs_csv(path: &Path) -> Result<Vec<Disc>, MapError> {
    let text = std::fs::read_to_string(path).map_err(|e| MapError::read(path, e))?;
    parse_discs_csv(&text, &path.display().to_string())
}

/// Points of a cloud file, with the sensor origin of every point when the
/// file carries them.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LoadedPoints {
    /// The points.
    pub points: Vec<Point3>,
    /// Per-point sensor origins (PLY columns `ox oy oz`, as written by
    /// `surveyor scan`), when present.
    pub origins: Option<Vec<Point3>>,
    /// Per-point normals, when the file has them.
    pub normals: Option<Vec<Vector3>>,
}

impl LoadedPoints {
    /// The best orientation these points allow: sensor origins, else the
    /// file's normals, else [`Orientation::Canonical`].
    pub fn orientation(&self) -> Orientation<'_> {
        if let Some(o) = &self.origins {
            Orientation::SensorOrigins(o)
        } else if let Some(n) = &self.normals {
            Orientation::ReferenceNormals(n)
        } else {
            Orientation::Canonical
        }
    }
}

/// Read a point cloud (any format `scene::io::load_cloud_or_mesh_vertices`
/// reads: PLY, PCD, text, OBJ/STL vertices) and, for a PLY file with `ox`,
/// `oy`, `oz` vertex properties, the per-point sensor origins.
pub fn load_points(path: &Path) -> Result<LoadedPoints, MapError> {
    // The scene reader's messages name the file already.
    let scene_err = |e: scene::SceneError| {
        let text = e.to_string();
        let named = format!("{}: ", path.display());
        let message = text.strip_prefix(&named).unwrap_or(&text).to_owned();
        MapError::parse(path.display().to_string(), None, message)
    };
    let is_ply = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("ply"));
    if is_ply {
        let table = scene::io::read_ply_vertices(path).map_err(scene_err)?;
        if sensor::Sweep::is_scan_table(&table) {
            let sweep = sensor::Sweep::from_ply_table(path, &table).map_err(|e| {
                let message = match e {
                    sensor::SensorError::ScanFile { message, .. } => message,
                    other => other.to_string(),
                };
                MapError::parse(path.display().to_string(), None, message)
            })?;
            return Ok(LoadedPoints {
                points: sweep.positions(),
                origins: Some(sweep.origins()),
                normals: None,
            });
        }
    }
    let cloud = scene::io::load_cloud_or_mesh_vertices(path).map_err(scene_err)?;
    let origins = None;
    Ok(LoadedPoints {
        points: cloud.points,
        origins,
        normals: cloud.normals,
    })
}
