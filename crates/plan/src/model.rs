//! The C-space model (A§4.3) as one value: the roadmap, the node usage
//! likelihoods and the voxel interference probabilities, computed once per
//! robot, placement, voxel size and parameters and cached to a file that a
//! later run loads. The file records a fingerprint of every input; a changed
//! input (another robot or URDF, other limits or ellipsoids, another base pose,
//! voxel size or parameter) invalidates it and the model is rebuilt.

use crate::interference::{Interference, interference};
use crate::roadmap::{Roadmap, RoadmapParts};
use crate::{PlanConfig, PlanError, Safety};
use geom::{Isometry3, Real};
use map::{OccupancyGrid, VoxelKey};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use robot::Robot;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Version of the cache format; bumped when the file or the algorithm changes.
const FORMAT: u32 = 1;

/// The configuration-space model of one robot in one placement.
#[derive(Clone, Debug)]
pub struct CspaceModel {
    config: PlanConfig,
    voxel_m: Real,
    fingerprint: u64,
    roadmap: Roadmap,
    usage: Vec<Real>,
    interference: Interference,
    safety: Safety,
}

/// How [`CspaceModel::load_or_build`] obtained the model.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum CacheOutcome {
    /// Read from the cache file.
    Loaded,
    /// Computed (and written to the cache file); the reason the file was not
    /// used.
    Built(String),
}

#[derive(Serialize, Deserialize)]
struct CacheFile {
    format: u32,
    fingerprint: String,
    voxel_m: Real,
    roadmap: RoadmapParts,
    usage: Vec<Real>,
    /// `[x, y, z, P(x_c), ʲn_Q]` per interfering voxel.
    voxels: Vec<(i32, i32, i32, Real, u32)>,
    voxels_per_node: Vec<u32>,
}

/// Most voxel–node interference pairs the offline search may visit (about
/// 480 times the VM-6083's 1.4e5 at the 0.1 m planning voxel: a voxel of
/// 13 mm or more). The search's time grows with them, and one node's voxel
/// list with `1/voxel³` (a 1 mm voxel asked for 1.6 GB for one node and
/// exhausted the memory).
pub const MAX_INTERFERENCE_PAIRS: Real = 67_108_864.0;

/// Refuse a voxel size whose interference search would exceed
/// [`MAX_INTERFERENCE_PAIRS`]: the links' ellipsoid volume over a voxel's,
/// times `n_Q`, estimated before anything is built.
fn check_interference_budget(
    robot: &Robot,
    world_from_base: &Isometry3,
    voxel_m: Real,
    config: &PlanConfig,
) -> Result<(), PlanError> {
    let probe = Safety::new(
        robot.clone(),
        *world_from_base,
        config,
        vec![1.0; robot.dof()],
    )?;
    let volume: Real = probe
        .ellipsoids(&vec![0.0; robot.dof()])?
        .iter()
        .map(geom::Ellipsoid::volume)
        .sum();
    let pairs = volume / voxel_m.powi(3) * config.n_q as Real;
    if pairs > MAX_INTERFERENCE_PAIRS {
        return Err(PlanError::config(
            "explore.planning_voxel_m",
            "a voxel size for which n_Q × the voxels in the links' ellipsoids stays within \
             MAX_INTERFERENCE_PAIRS (6.7e7; 0.1 m gives 1.4e5 with the VM-6083)",
            format!("{voxel_m} m, about {pairs:.1e} pairs"),
        ));
    }
    Ok(())
}

impl CspaceModel {
    /// Build the model: sample and connect the roadmap, plan between all
    /// pairs of nodes for `L(cᵢ)`, search each node's interfering voxels at
    /// voxel size `voxel_m` and form `P(ʲx_c)`.
    pub fn build(
        robot: &Robot,
        world_from_base: &Isometry3,
        voxel_m: Real,
        config: &PlanConfig,
    ) -> Result<Self, PlanError> {
        if !(voxel_m.is_finite() && voxel_m > 0.0) {
            return Err(PlanError::config("voxel_m", "a positive length", voxel_m));
        }
        check_interference_budget(robot, world_from_base, voxel_m, config)?;
        let roadmap = Roadmap::build(robot, config)?;
        let safety = Safety::new(
            robot.clone(),
            *world_from_base,
            config,
            roadmap.weights().to_vec(),
        )?;
        let usage = roadmap.usage_likelihood();
        let interference = interference(&safety, &roadmap, &usage, voxel_m)?;
        Ok(Self {
            config: config.clone(),
            voxel_m,
            fingerprint: fingerprint(robot, world_from_base, voxel_m, config)?,
            roadmap,
            usage,
            interference,
            safety,
        })
    }

    /// Load the model from `path` when the file was made from the same inputs;
    /// otherwise build it and write it there. A file that cannot be read,
    /// parsed or matched is rebuilt over (the outcome says why); a file that
    /// cannot be written is an error.
    pub fn load_or_build(
        path: &Path,
        robot: &Robot,
        world_from_base: &Isometry3,
        voxel_m: Real,
        config: &PlanConfig,
    ) -> Result<(Self, CacheOutcome), PlanError> {
        let reason = match Self::load(path, robot, world_from_base, voxel_m, config) {
            Ok(model) => return Ok((model, CacheOutcome::Loaded)),
            Err(reason) => reason,
        };
        let model = Self::build(robot, world_from_base, voxel_m, config)?;
        model.save(path)?;
        Ok((model, CacheOutcome::Built(reason)))
    }

    /// Read the model from `path`; `Err` says why it cannot be used.
    pub fn load(
        path: &Path,
        robot: &Robot,
        world_from_base: &Isometry3,
        voxel_m: Real,
        config: &PlanConfig,
    ) -> Result<Self, String> {
        let text = std::fs::read(path).map_err(|e| match e.kind() {
            std::io::ErrorKind::NotFound => "no cache file yet".to_owned(),
            _ => format!("cannot read it ({e})"),
        })?;
        let file: CacheFile =
            serde_json::from_slice(&text).map_err(|e| format!("not a C-space cache ({e})"))?;
        if file.format != FORMAT {
            return Err(format!(
                "format {} (this version writes {FORMAT})",
                file.format
            ));
        }
        let expected =
            fingerprint(robot, world_from_base, voxel_m, config).map_err(|e| e.to_string())?;
        if file.fingerprint != format!("{expected:016x}") {
            return Err(
                "made for other inputs (robot, placement, voxel size or parameters)".into(),
            );
        }
        let roadmap = Roadmap::from_parts(file.roadmap)?;
        let n = roadmap.len();
        if file.usage.len() != n || file.voxels_per_node.len() != n {
            return Err(format!("expected {n} usage values and voxel counts"));
        }
        if roadmap.dof() != robot.dof() {
            return Err(format!("nodes have {} joints", roadmap.dof()));
        }
        if let Some(v) = file.voxels.iter().find(|v| !(0.0..=1.0).contains(&v.3)) {
            return Err(format!(
                "voxel ({}, {}, {}) has P(x_c) = {} outside [0, 1]",
                v.0, v.1, v.2, v.3
            ));
        }
        let safety = Safety::new(
            robot.clone(),
            *world_from_base,
            config,
            roadmap.weights().to_vec(),
        )
        .map_err(|e| e.to_string())?;
        Ok(Self {
            config: config.clone(),
            voxel_m,
            fingerprint: expected,
            roadmap,
            usage: file.usage,
            interference: Interference {
                probabilities: file
                    .voxels
                    .iter()
                    .map(|v| (VoxelKey::new(v.0, v.1, v.2), v.3))
                    .collect(),
                nodes_per_voxel: file.voxels.iter().map(|v| v.4).collect(),
                voxels_per_node: file.voxels_per_node,
            },
            safety,
        })
    }

    /// Write the model to `path` (JSON; written to a temporary file of its
    /// own first and renamed, so neither an interrupted write nor two runs
    /// writing at once leave a half file).
    pub fn save(&self, path: &Path) -> Result<(), PlanError> {
        static SAVES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
        let err = |message: String| PlanError::Cache {
            path: path.to_path_buf(),
            message,
        };
        let file = CacheFile {
            format: FORMAT,
            fingerprint: format!("{:016x}", self.fingerprint),
            voxel_m: self.voxel_m,
            roadmap: self.roadmap.to_parts(),
            usage: self.usage.clone(),
            voxels: self
                .interference
                .probabilities
                .iter()
                .zip(&self.interference.nodes_per_voxel)
                .map(|((k, p), n)| {
                    let [x, y, z] = k.coords();
                    (x, y, z, *p, *n)
                })
                .collect(),
            voxels_per_node: self.interference.voxels_per_node.clone(),
        };
        let text = serde_json::to_vec(&file).map_err(|e| err(e.to_string()))?;
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)
                .map_err(|e| err(format!("cannot create its folder: {e}")))?;
        }
        // A temporary name of this process and call: two runs sharing the
        // default cache file must not write into one temporary file.
        let n = SAVES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let tmp = path.with_extension(format!("tmp.{}.{n}", std::process::id()));
        let written = std::fs::write(&tmp, text)
            .map_err(|e| err(format!("cannot write: {e}")))
            .and_then(|()| {
                std::fs::rename(&tmp, path)
                    .map_err(|e| err(format!("cannot rename into place: {e}")))
            });
        if written.is_err() {
            // No temporary file of this call is left behind.
            let _ = std::fs::remove_file(&tmp);
        }
        written
    }

    /// Give every voxel of `grid` that some node interferes with its
    /// `P(ʲx_c)`, so the grid's `H2` (eq. 4.14) follows this model. Voxels
    /// outside the grid are skipped. Fails, changing nothing, when the grid's
    /// voxel size differs from the model's.
    pub fn apply_to(&self, grid: &mut OccupancyGrid) -> Result<usize, PlanError> {
        let v = grid.geometry().voxel_m();
        if (v - self.voxel_m).abs() > 1e-12 * self.voxel_m {
            return Err(PlanError::config(
                "occupancy.voxel_m",
                "the C-space model's voxel size",
                format!("{v} (model: {})", self.voxel_m),
            ));
        }
        let inside: Vec<(VoxelKey, Real)> = self
            .interference
            .probabilities
            .iter()
            .filter(|(k, _)| grid.geometry().contains(*k))
            .copied()
            .collect();
        let n = inside.len();
        grid.set_cspace_probabilities(inside)?;
        Ok(n)
    }

    /// The roadmap.
    pub fn roadmap(&self) -> &Roadmap {
        &self.roadmap
    }

    /// `L(cᵢ)` per node.
    pub fn usage(&self) -> &[Real] {
        &self.usage
    }

    /// The interference search's result.
    pub fn interference(&self) -> &Interference {
        &self.interference
    }

    /// The safety measure (robot, placement, weights) the model was made with.
    pub fn safety(&self) -> &Safety {
        &self.safety
    }

    /// The voxel size of the interference sets.
    pub fn voxel_m(&self) -> Real {
        self.voxel_m
    }

    /// The parameters.
    pub fn config(&self) -> &PlanConfig {
        &self.config
    }

    /// The inputs' fingerprint (as stored in the cache file).
    pub fn fingerprint(&self) -> u64 {
        self.fingerprint
    }
}

/// FNV-1a (64 bit): a hash that is the same on every platform and release,
/// which std's `DefaultHasher` does not promise.
fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// A fingerprint of everything the model depends on. The robot enters through
/// what planning uses of it: joint kinds and limits, and the link frames and
/// posed ellipsoids at fixed probe configurations (so a changed URDF origin,
/// axis, offset or ellipsoid changes it).
fn fingerprint(
    robot: &Robot,
    world_from_base: &Isometry3,
    voxel_m: Real,
    config: &PlanConfig,
) -> Result<u64, PlanError> {
    let dof = robot.dof();
    let mut probes = vec![vec![0.0; dof]];
    let mut rng = ChaCha8Rng::seed_from_u64(0x5eed);
    for _ in 0..3 {
        probes.push((0..dof).map(|_| rng.random_range(-1.0..1.0)).collect());
    }
    let mut posed = Vec::new();
    for q in &probes {
        let frames = robot.forward_kinematics(q)?;
        posed.push((robot.posed_ellipsoids(&frames), frames));
    }
    let text = serde_json::to_string(&(
        FORMAT,
        robot.joint_kinds(),
        robot.limits(),
        posed,
        world_from_base,
        voxel_m,
        config,
    ))
    .map_err(|e| PlanError::Robot {
        robot: robot.name.clone(),
        message: format!("cannot fingerprint: {e}"),
    })?;
    Ok(fnv1a(text.as_bytes()))
}

#[cfg(test)]
mod tests {
    use super::fnv1a;

    #[test]
    fn fnv1a_matches_published_vectors() {
        // Test vectors of the FNV reference (fnv-1a 64).
        assert_eq!(fnv1a(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a(b"foobar"), 0x8594_4171_f739_67e8);
    }
}
