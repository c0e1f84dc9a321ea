//! The library side of `surveyor map`: integrate sweeps into the occupancy
//! grid and the TSDF, then write `mesh.ply` and `occupancy.json`.
//!
//! Integration is one call per sweep ([`Mapper::integrate_sweep`]) so the
//! caller can time each; nothing here reads the clock.

use crate::MapError;
use crate::occupancy::{IntegrationStats, OccupancyConfig, OccupancyGrid};
use crate::stats::OccupancyReport;
use crate::tsdf::{TsdfConfig, TsdfMap, TsdfStats};
use geom::Real;
use scene::TriMesh;
use sensor::Sweep;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Configuration of both maps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MapConfig {
    /// The occupancy grid.
    pub occupancy: OccupancyConfig,
    /// The TSDF.
    pub tsdf: TsdfConfig,
}

impl MapConfig {
    /// Both maps at voxel size `voxel_m` (the TSDF truncation scales to four
    /// voxels), other fields as given.
    pub fn with_voxel_m(self, voxel_m: Real) -> Self {
        Self {
            occupancy: OccupancyConfig {
                voxel_m,
                ..self.occupancy
            },
            tsdf: TsdfConfig {
                voxel_m,
                truncation_m: 4.0 * voxel_m,
                ..self.tsdf
            },
        }
    }

    /// Check both parts.
    pub fn validate(&self) -> Result<(), MapError> {
        self.occupancy.validate()?;
        self.tsdf.validate()
    }
}

/// What integrating one sweep did to each map.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SweepSummary {
    /// Occupancy changes.
    pub occupancy: IntegrationStats,
    /// TSDF updates.
    pub tsdf: TsdfStats,
}

/// Both maps, fed sweep by sweep.
#[derive(Clone, Debug)]
pub struct Mapper {
    occupancy: OccupancyGrid,
    tsdf: TsdfMap,
}

impl Mapper {
    /// Empty maps.
    pub fn new(config: &MapConfig) -> Result<Self, MapError> {
        config.validate()?;
        Ok(Self {
            occupancy: OccupancyGrid::new(config.occupancy)?,
            tsdf: TsdfMap::new(config.tsdf)?,
        })
    }

    /// Integrate a sweep into both maps.
    pub fn integrate_sweep(&mut self, sweep: &Sweep) -> SweepSummary {
        SweepSummary {
            occupancy: self.occupancy.integrate_sweep(sweep),
            tsdf: self.tsdf.integrate_sweep(sweep),
        }
    }

    /// The occupancy grid.
    pub fn occupancy(&self) -> &OccupancyGrid {
        &self.occupancy
    }

    /// The occupancy grid, mutable (C-space probabilities, known-free voxels).
    pub fn occupancy_mut(&mut self) -> &mut OccupancyGrid {
        &mut self.occupancy
    }

    /// The TSDF.
    pub fn tsdf(&self) -> &TsdfMap {
        &self.tsdf
    }

    /// The mesh and the occupancy report.
    pub fn outputs(&self) -> MapOutputs {
        MapOutputs {
            mesh: self.tsdf.extract_mesh(),
            report: self.occupancy.report(),
        }
    }
}

/// The products of `surveyor map`.
#[derive(Clone, Debug, PartialEq)]
pub struct MapOutputs {
    /// The TSDF's zero level set.
    pub mesh: TriMesh,
    /// Counts per region and entropies.
    pub report: OccupancyReport,
}

impl MapOutputs {
    /// Write `dir/mesh.ply` (binary PLY) and `dir/occupancy.json`, creating
    /// `dir` if needed.
    pub fn write(&self, dir: &Path) -> Result<(), MapError> {
        std::fs::create_dir_all(dir).map_err(|e| MapError::write(dir, e))?;
        scene::io::write_mesh_ply(&dir.join("mesh.ply"), &self.mesh)?;
        let json = dir.join("occupancy.json");
        std::fs::write(&json, self.report.to_json() + "\n").map_err(|e| MapError::write(&json, e))
    }
}

/// Integrate every sweep, in order, and return the mesh and report.
///
/// ```
/// use geom::Point3;
/// use map::{MapConfig, build_from_scans};
/// use sensor::{Sweep, SweepPoint};
/// // One ray straight up from the first joint to a point 1 m above it.
/// let sweep = Sweep::from_points(vec![SweepPoint {
///     point: Point3::new(0.0, 0.0, 1.475),
///     origin: Point3::new(0.0, 0.0, 0.475),
///     intensity: 0.0,
///     material: None,
///     cell: None,
/// }])?;
/// let config = MapConfig::default().with_voxel_m(0.05);
/// let out = build_from_scans(&[sweep], &config)?;
/// assert_eq!(out.report.regions[2].occupied, 1);
/// assert_eq!(out.report.regions[2].free, 20); // 1 m at 5 cm, the hit excluded
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn build_from_scans(sweeps: &[Sweep], config: &MapConfig) -> Result<MapOutputs, MapError> {
    let mut mapper = Mapper::new(config)?;
    for s in sweeps {
        mapper.integrate_sweep(s);
    }
    Ok(mapper.outputs())
}
