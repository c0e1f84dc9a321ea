//! `checkpoint.json`: what an exploration needs to resume after an
//! interruption, rewritten after every viewpoint. Its `config` is the
//! exploration's own parameter type (`explore::ExploreConfig`), so this
//! file's layout is generic over it.

use crate::RecordError;
use crate::viewpoints::{UnsafeConfiguration, ViewpointRecord};
use geom::Real;
use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The checkpoint's file name.
pub const CHECKPOINT_JSON: &str = "checkpoint.json";

/// Version of the checkpoint format (2: checksum, scenario text, stages).
pub const CHECKPOINT_FORMAT: u32 = 2;

/// What a checkpoint holds: enough to rebuild a run's state by replaying
/// its viewpoints' sweeps (a simulated scanner is seeded per viewpoint, so
/// the same sweeps come back) and to continue as if never stopped.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint<C> {
    /// [`CHECKPOINT_FORMAT`].
    pub format: u32,
    /// FNV-1a 64 of the checkpoint's JSON with this field 0: a checkpoint
    /// edited by hand is refused (its records are replayed without audit).
    pub checksum: u64,
    /// Scenario name.
    pub scenario: String,
    /// The scenario as run (`scenario.toml`'s text, the robot included).
    pub scenario_toml: String,
    /// Whether Stage Two follows Stage One.
    pub stage_two: bool,
    /// The run's seed.
    pub seed: u64,
    /// The exploration's parameters.
    pub config: C,
    /// The sweep taken at every viewpoint.
    pub sweep: sensor::SweepConfig,
    /// The viewpoints so far.
    pub viewpoints: Vec<ViewpointRecord>,
    /// Ground-truth contacts so far (`None`: not judged).
    pub collisions: Option<usize>,
    /// Unsafe configurations so far.
    pub unsafe_configurations: Vec<UnsafeConfiguration>,
    /// Smallest ground-truth clearance so far, metres (`None`: not judged).
    pub min_clearance_m: Option<Real>,
    /// Stage Two: the discs already tried as targets, ascending.
    #[serde(default)]
    pub stage_two_tried: Vec<usize>,
}

/// FNV-1a, 64 bits: a checksum that is the same on every platform.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(*b)).wrapping_mul(0x0100_0000_01b3)
    })
}

impl<C: Clone + Serialize + DeserializeOwned> Checkpoint<C> {
    /// The checksum of `self` (its own `checksum` field taken as 0).
    fn digest(&self) -> Result<u64, serde_json::Error> {
        let text = serde_json::to_string(&Self {
            checksum: 0,
            ..self.clone()
        })?;
        Ok(fnv1a(text.as_bytes()))
    }

    /// Write the checkpoint, sealed with its checksum, through a temporary
    /// file renamed into place (an interruption leaves the previous one).
    pub fn write(&self, path: &Path) -> Result<(), RecordError> {
        let err = |e: &dyn std::fmt::Display| {
            RecordError::file(path, format!("cannot write the checkpoint: {e}"))
        };
        let sealed = Self {
            checksum: self.digest().map_err(|e| err(&e))?,
            ..self.clone()
        };
        let text = serde_json::to_string(&sealed).map_err(|e| err(&e))?;
        let tmp = path.with_extension("tmp");
        std::fs::write(&tmp, text).map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            err(&e)
        })?;
        std::fs::rename(&tmp, path).map_err(|e| err(&e))
    }

    /// Read a checkpoint: its format first (an older one lacks today's
    /// fields), then the whole, then the checksum.
    pub fn read(path: &Path) -> Result<Self, RecordError> {
        let err = |message: String| RecordError::file(path, message);
        let text = std::fs::read(path)
            .map_err(|e| err(format!("cannot read the checkpoint to resume from: {e}")))?;
        let rerun = "; run again without --resume";
        let format = serde_json::from_slice::<serde_json::Value>(&text)
            .ok()
            .and_then(|v| v.get("format").and_then(serde_json::Value::as_u64));
        if let Some(f) = format.filter(|f| *f != u64::from(CHECKPOINT_FORMAT)) {
            return Err(err(format!(
                "checkpoint format {f} (this version reads {CHECKPOINT_FORMAT}){rerun}"
            )));
        }
        let c: Self = serde_json::from_slice(&text).map_err(|e| {
            err(format!(
                "not a checkpoint of `surveyor explore` ({e}){rerun}"
            ))
        })?;
        match c.digest() {
            Ok(d) if d == c.checksum => Ok(c),
            _ => Err(err(format!(
                "the checkpoint was changed after it was written (its checksum does not match){rerun}"
            ))),
        }
    }
}
