//! Voxel ↔ node interference (A§4.3, Fig. 4.8) and the probability of C-space
//! interference `P(ʲx_c)` (eq. 4.13): a voxel interferes with node `Q` when
//! its centre lies inside a bounding ellipsoid of one of the links 1.. at `Q`
//! (algebraic distance below 1); `P(ʲx_c)` is the usage likelihood of the
//! nodes it interferes with, summed and normalised by the sum over all nodes.

use crate::roadmap::Roadmap;
use crate::{PlanError, Safety};
use geom::Real;
use map::VoxelKey;
use rayon::prelude::*;
use std::collections::HashMap;

/// Nodes handled per parallel batch (bounds the memory of the voxel lists).
const BATCH: usize = 64;

/// The voxels (centres) inside the ellipsoids of links 1.. at `q`, sorted.
pub fn interfering_voxels(
    safety: &Safety,
    q: &[Real],
    voxel_m: Real,
) -> Result<Vec<VoxelKey>, PlanError> {
    let mut keys = Vec::new();
    for e in safety.ellipsoids(q)? {
        let bb = e.bounding_box();
        let (Some(lo), Some(hi)) = (
            VoxelKey::of_point(&bb.min, voxel_m),
            VoxelKey::of_point(&bb.max, voxel_m),
        ) else {
            continue;
        };
        let (lo, hi) = (lo.coords(), hi.coords());
        for z in lo[2]..=hi[2] {
            for y in lo[1]..=hi[1] {
                for x in lo[0]..=hi[0] {
                    let k = VoxelKey::new(x, y, z);
                    if e.algebraic_distance(&k.center(voxel_m)) < 1.0 {
                        keys.push(k);
                    }
                }
            }
        }
    }
    keys.sort_unstable();
    keys.dedup();
    Ok(keys)
}

/// What the offline interference search found.
#[derive(Clone, Debug, PartialEq)]
pub struct Interference {
    /// `P(ʲx_c)` of every voxel some node interferes with, sorted by key.
    pub probabilities: Vec<(VoxelKey, Real)>,
    /// Number of voxels each node interferes with.
    pub voxels_per_node: Vec<u32>,
    /// Number of nodes each listed voxel interferes with (`ʲn_Q`, Fig. 4.8a),
    /// in the order of `probabilities`.
    pub nodes_per_voxel: Vec<u32>,
}

/// Search every node's interfering voxels and turn the usage likelihoods into
/// `P(ʲx_c)` (eq. 4.13). Sums run in node order, so the result is
/// deterministic.
pub fn interference(
    safety: &Safety,
    roadmap: &Roadmap,
    usage: &[Real],
    voxel_m: Real,
) -> Result<Interference, PlanError> {
    let total: Real = usage.iter().sum();
    let mut sums: HashMap<VoxelKey, (Real, u32)> = HashMap::new();
    let mut voxels_per_node = Vec::with_capacity(roadmap.len());
    let nodes: Vec<&[Real]> = roadmap.nodes().collect();
    for (b, batch) in nodes.chunks(BATCH).enumerate() {
        let lists: Vec<Vec<VoxelKey>> = batch
            .par_iter()
            .map(|q| interfering_voxels(safety, q, voxel_m))
            .collect::<Result<_, _>>()?;
        for (k, list) in lists.iter().enumerate() {
            let l = usage.get(b * BATCH + k).copied().unwrap_or(0.0);
            voxels_per_node.push(list.len() as u32);
            for key in list {
                let e = sums.entry(*key).or_insert((0.0, 0));
                e.0 += l;
                e.1 += 1;
            }
        }
    }
    let mut listed: Vec<(VoxelKey, (Real, u32))> = sums.into_iter().collect();
    listed.sort_unstable_by_key(|(k, _)| *k);
    let probabilities = listed
        .iter()
        .map(|(k, (l, _))| {
            let p = if total > 0.0 {
                (l / total).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (*k, p)
        })
        .collect();
    let nodes_per_voxel = listed.iter().map(|(_, (_, n))| *n).collect();
    Ok(Interference {
        probabilities,
        voxels_per_node,
        nodes_per_voxel,
    })
}
