//! Serialisable summaries: the `occupancy.json` report of `surveyor map`.

use crate::regions::Region;
use geom::Real;
use serde::{Deserialize, Serialize};

/// Voxel counts of one region (nested: A2 includes A1, A3 is the grid).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RegionReport {
    /// Which region.
    pub region: Region,
    /// Voxels in the region.
    pub total: u64,
    /// Free voxels.
    pub free: u64,
    /// Unknown voxels `n_u,Ak`.
    pub unknown: u64,
    /// Occupied voxels.
    pub occupied: u64,
    /// Unknown voxels flagged as occluded (A§4.2.1).
    pub important_unknown: u64,
}

/// Occupancy counts per region and the entropies of A§4.2–4.3, in nats.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OccupancyReport {
    /// Voxel edge, metres.
    pub voxel_m: Real,
    /// Voxels per axis of the grid.
    pub dims: [usize; 3],
    /// Region weights `{c_w1, c_w2, c_w3}`.
    pub weights: [Real; 3],
    /// Importance `ι` of an occluded unknown voxel.
    pub importance: Real,
    /// A1, A2, A3.
    pub regions: [RegionReport; 3],
    /// `n_u ln 2` over A3 (A eq. 4.10).
    pub h1_unweighted: Real,
    /// A eq. 4.11 with occlusion importance.
    pub h1_weighted: Real,
    /// A eq. 4.14 over unknown voxels (0 until C-space probabilities are set).
    pub h2: Real,
}

impl OccupancyReport {
    /// Pretty JSON.
    pub fn to_json(&self) -> String {
        // Serialising plain numbers and strings cannot fail; an error would be
        // a serde_json bug, reported in-band rather than by a panic.
        serde_json::to_string_pretty(self).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
    }
}
