//! The scan file: a [`Sweep`] as a binary little-endian PLY, the one reader
//! and writer of it in the workspace.
//!
//! One `vertex` element, one `float` property per column, world frame:
//!
//! | property | meaning |
//! |---|---|
//! | `x y z` | the measured point |
//! | `intensity` | return intensity |
//! | `ox oy oz` | origin of the ray that measured it (the scanner) |
//! | `scan ray` | the (scan, ray) grid cell (A eq. 5.1), when the sweep keeps its grid |
//! | `material` | ground-truth material index (simulated sweeps only; −1 unknown) |
//!
//! Grid indices and material indices are small integers, exact in `float`
//! (below 2²⁴). A file without `scan`/`ray` is read as a sweep without a grid;
//! one without `intensity` gets intensity 0; `x y z ox oy oz` are required.

use crate::SensorError;
use crate::sweep::{GridCell, Sweep, SweepPoint};
use geom::Point3;
use scene::MaterialId;
use scene::io::PlyTable;
use std::path::Path;

/// Largest grid index a scan file may hold: `float` is exact below 2²⁴.
const MAX_INDEX: f64 = 16_777_215.0;

fn file_error(path: &Path, message: impl Into<String>) -> SensorError {
    SensorError::ScanFile {
        path: path.to_owned(),
        message: message.into(),
    }
}

/// A whole number in `[lo, MAX_INDEX]`, or an error naming the vertex and property.
fn index(path: &Path, v: f64, row: usize, name: &str, lo: f64) -> Result<f64, SensorError> {
    if v.is_finite() && v.fract() == 0.0 && (lo..=MAX_INDEX).contains(&v) {
        Ok(v)
    } else {
        Err(file_error(
            path,
            format!(
                "vertex {row}: `{name}` is {v}, expected a whole number in [{lo}, {MAX_INDEX}]"
            ),
        ))
    }
}

impl Sweep {
    /// Read a scan file (see the [module docs](crate::scan_file)). Errors name
    /// the file, the vertex and the property.
    pub fn read_ply(path: &Path) -> Result<Self, SensorError> {
        Self::from_ply_table(path, &scene::io::read_ply_vertices(path)?)
    }

    /// `true` when a PLY vertex table has the ray-origin columns of a scan file.
    pub fn is_scan_table(table: &PlyTable) -> bool {
        ["ox", "oy", "oz"].iter().all(|c| table.column(c).is_some())
    }

    /// A sweep from the vertex table of a scan file already read from `path`
    /// (see [`Sweep::read_ply`]).
    pub fn from_ply_table(path: &Path, table: &PlyTable) -> Result<Self, SensorError> {
        let column = |name: &str| {
            table.column(name).ok_or_else(|| {
                file_error(
                    path,
                    format!(
                        "no vertex property `{name}` (scan files carry x y z and the ray origin ox oy oz)"
                    ),
                )
            })
        };
        let xyz = [column("x")?, column("y")?, column("z")?];
        let o = [column("ox")?, column("oy")?, column("oz")?];
        for (c, name) in xyz.iter().chain(&o).zip(["x", "y", "z", "ox", "oy", "oz"]) {
            if let Some(row) = c.iter().position(|v| !v.is_finite()) {
                return Err(file_error(
                    path,
                    format!("vertex {row}: `{name}` is not finite ({})", c[row]),
                ));
            }
        }
        let intensity = table.column("intensity");
        if let Some(row) = intensity.and_then(|c| c.iter().position(|v| !v.is_finite())) {
            return Err(file_error(
                path,
                format!("vertex {row}: `intensity` is not finite"),
            ));
        }
        let grid = match (table.column("scan"), table.column("ray")) {
            (Some(s), Some(r)) => Some((s, r)),
            (None, None) => None,
            _ => {
                return Err(file_error(
                    path,
                    "a scan file with a grid needs both `scan` and `ray` vertex properties",
                ));
            }
        };
        let material = table.column("material");
        let n = table.len();
        let mut points = Vec::with_capacity(n);
        for row in 0..n {
            let cell = match grid {
                Some((s, r)) => Some(GridCell {
                    scan: index(path, s[row], row, "scan", 0.0)? as u32,
                    ray: index(path, r[row], row, "ray", 0.0)? as u32,
                }),
                None => None,
            };
            let material = match material {
                Some(m) => {
                    let v = index(path, m[row], row, "material", -1.0)?;
                    if v > f64::from(u16::MAX) {
                        return Err(file_error(
                            path,
                            format!(
                                "vertex {row}: `material` is {v}, expected a material index in [-1, {}]",
                                u16::MAX
                            ),
                        ));
                    }
                    (v >= 0.0).then_some(MaterialId(v as u16))
                }
                None => None,
            };
            points.push(SweepPoint {
                point: Point3::new(xyz[0][row], xyz[1][row], xyz[2][row]),
                origin: Point3::new(o[0][row], o[1][row], o[2][row]),
                intensity: intensity.map_or(0.0, |c| c[row]),
                material,
                cell,
            });
        }
        Sweep::from_points(points).map_err(|e| match e {
            SensorError::Sweep { message } => file_error(path, message),
            other => other,
        })
    }

    /// Write the sweep as a scan file (see the [module docs](crate::scan_file)):
    /// `scan ray` when it keeps its grid, `material` when any return knows its
    /// material.
    pub fn write_ply(&self, path: &Path) -> Result<(), SensorError> {
        let mut names = vec!["x", "y", "z", "intensity", "ox", "oy", "oz"];
        let with_grid = self.grid_shape().is_some();
        let with_material = self.points().iter().any(|p| p.material.is_some());
        if with_grid {
            names.extend(["scan", "ray"]);
        }
        if with_material {
            names.push("material");
        }
        let n = self.len();
        let mut cols: Vec<Vec<f32>> = names.iter().map(|_| Vec::with_capacity(n)).collect();
        for p in self.points() {
            let mut row = vec![
                p.point.x as f32,
                p.point.y as f32,
                p.point.z as f32,
                p.intensity as f32,
                p.origin.x as f32,
                p.origin.y as f32,
                p.origin.z as f32,
            ];
            if let Some(c) = p.cell.filter(|_| with_grid) {
                row.push(c.scan as f32);
                row.push(c.ray as f32);
            }
            if with_material {
                row.push(p.material.map_or(-1.0, |m| f32::from(m.0)));
            }
            for (c, v) in cols.iter_mut().zip(row) {
                c.push(v);
            }
        }
        let refs: Vec<&[f32]> = cols.iter().map(Vec::as_slice).collect();
        scene::io::write_ply_vertices_file(path, &names, &refs)?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use geom::{Isometry3, Real, Translation3, UnitQuaternion};

    fn grid_sweep() -> Sweep {
        let bearings = [-0.1, 0.0, 0.1];
        let poses = [
            Isometry3::from_parts(Translation3::new(0.0, 0.0, 1.0), UnitQuaternion::identity()),
            Isometry3::from_parts(
                Translation3::new(0.0, 0.0, 1.0),
                UnitQuaternion::from_euler_angles(0.0, 0.05, 0.0),
            ),
        ];
        let ranges: Vec<Option<Real>> =
            vec![Some(1.0), None, Some(1.25), Some(2.0), Some(2.5), None];
        Sweep::from_range_grid(&bearings, &poses, &ranges).unwrap()
    }

    #[test]
    fn round_trip_keeps_grid_and_points() {
        let sweep = grid_sweep();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.ply");
        sweep.write_ply(&path).unwrap();
        let back = Sweep::read_ply(&path).unwrap();
        assert_eq!(back.len(), 4);
        assert_eq!(back.grid_shape().unwrap().scans, 2);
        for (a, b) in sweep.points().iter().zip(back.points()) {
            assert_eq!(a.cell, b.cell);
            assert!((a.point - b.point).norm() < 1e-6);
            assert!((a.origin - b.origin).norm() < 1e-6);
        }
        assert_eq!(sweep.grid_neighbours(), back.grid_neighbours());
    }

    /// A two-point scan file whose `scan` and `ray` columns are given.
    fn two_point_file(path: &std::path::Path, scan: [f32; 2], ray: [f32; 2]) {
        let cols: Vec<Vec<f32>> = vec![
            vec![0.0, 1.0],
            vec![0.0, 0.0],
            vec![1.0, 1.0],
            vec![0.0, 0.0],
            vec![0.0, 0.0],
            vec![0.0, 0.0],
            scan.to_vec(),
            ray.to_vec(),
        ];
        let refs: Vec<&[f32]> = cols.iter().map(Vec::as_slice).collect();
        scene::io::write_ply_vertices_file(
            path,
            &["x", "y", "z", "ox", "oy", "oz", "scan", "ray"],
            &refs,
        )
        .unwrap();
    }

    #[test]
    fn bad_grid_indices_name_the_vertex() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.ply");
        two_point_file(&path, [0.0, 0.0], [0.0, 0.5]);
        let e = Sweep::read_ply(&path).unwrap_err().to_string();
        assert!(e.contains("vertex 1") && e.contains("`ray`"), "{e}");
        // Cells out of order are an error too.
        two_point_file(&path, [1.0, 0.0], [0.0, 0.0]);
        let e = Sweep::read_ply(&path).unwrap_err().to_string();
        assert!(e.contains("strictly increasing"), "{e}");
    }
}
