//! Replaying recorded sensor sets through the model: the loop behind
//! `surveyor model`, as a library call so other front ends (and tests) get the
//! same behaviour.
//!
//! Each set's update is timed (wall time of [`SurfaceModel::update`] alone,
//! for the statistics in `stats.json`; nothing is displayed here).

use crate::config::SurfaceConfig;
use crate::error::SurfaceError;
use crate::export::{StatsJson, UpdateTimes};
use crate::input::SensorSet;
use crate::model::SurfaceModel;
use geom::{Point3, Real};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// How to replay.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ReplayOptions {
    /// Run the invariant checker after every update.
    pub check_invariants: bool,
}

/// Why a replay stopped. The model is left as it was after the last good set.
#[derive(Debug, thiserror::Error)]
pub enum ReplayError {
    /// The configuration was refused.
    #[error("{0}")]
    Config(SurfaceError),
    /// An initial segment was refused.
    #[error("initial segment {index}: {source}")]
    Initial {
        /// 0-based index in the initial-segment list.
        index: usize,
        /// Why.
        source: SurfaceError,
    },
    /// An initial segment overlaps an earlier one on the same surface
    /// ([`SurfaceError::InitialOverlap`], by the segments' indices).
    #[error(
        "initial segment {index} overlaps initial segment {other} over {area_m2:.3e} m² of the same surface (facing the same way, within λ of it); initial segments never merge, so that surface would be modelled twice"
    )]
    InitialOverlap {
        /// 0-based index of the refused segment in the initial-segment list.
        index: usize,
        /// 0-based index of the segment it overlaps (earlier in the list).
        other: usize,
        /// The common area, m².
        area_m2: Real,
    },
    /// A sensor set was refused.
    #[error("set {index}: {source}")]
    Set {
        /// 0-based index of the set (line `index + 1` of a JSONL file).
        index: usize,
        /// Why.
        source: SurfaceError,
    },
    /// The invariant checker found the model broken after a set.
    #[error("invariant violated after set {index}: {message}")]
    Invariant {
        /// 0-based index of the set.
        index: usize,
        /// What is broken.
        message: String,
    },
    /// An output could not be formatted.
    #[error("formatting the output: {message}")]
    Format {
        /// What failed.
        message: String,
    },
    /// An output file could not be written.
    #[error("{path}: cannot write: {message}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The operating-system error.
        message: String,
    },
}

/// A replayed model with its per-update times.
#[derive(Clone, Debug)]
pub struct Replay {
    /// The model after every set.
    pub model: SurfaceModel,
    /// Wall time of each update, µs.
    pub update_us: Vec<Real>,
}

/// Build a model from `config`, add the a-priori `initial` segments (P§4.3),
/// then feed `sets` in order, calling `progress(done)` after each.
pub fn replay(
    config: SurfaceConfig,
    initial: &[Vec<Point3>],
    sets: &[SensorSet],
    options: ReplayOptions,
    progress: &mut dyn FnMut(usize),
) -> Result<Replay, ReplayError> {
    let mut model = SurfaceModel::new(config).map_err(ReplayError::Config)?;
    let mut initial_ids = Vec::with_capacity(initial.len());
    for (index, vertices) in initial.iter().enumerate() {
        let id = model.add_initial_segment(vertices).map_err(|source| {
            match &source {
                SurfaceError::InitialOverlap { other, area_m2 } => initial_ids
                    .iter()
                    .position(|id| id == other)
                    .map(|other| ReplayError::InitialOverlap {
                        index,
                        other,
                        area_m2: *area_m2,
                    }),
                _ => None,
            }
            .unwrap_or(ReplayError::Initial { index, source })
        })?;
        initial_ids.push(id);
    }
    let mut update_us = Vec::with_capacity(sets.len());
    for (index, set) in sets.iter().enumerate() {
        let t0 = Instant::now();
        model
            .update(set)
            .map_err(|source| ReplayError::Set { index, source })?;
        update_us.push(1e6 * t0.elapsed().as_secs_f64());
        if options.check_invariants {
            model
                .check_invariants()
                .map_err(|e| ReplayError::Invariant {
                    index,
                    message: e.to_string(),
                })?;
        }
        progress(index + 1);
    }
    Ok(Replay { model, update_us })
}

impl Replay {
    /// Median, 95th percentile and maximum update time.
    pub fn times(&self) -> UpdateTimes {
        UpdateTimes::from_micros(&self.update_us)
    }

    /// The statistics of `stats.json`.
    pub fn stats(&self) -> StatsJson {
        self.model.stats().to_json(self.times())
    }

    /// The output files by name: `surface_model.json`, `surface_model.obj`
    /// and `stats.json`.
    pub fn outputs(&self) -> Result<[(&'static str, String); 3], ReplayError> {
        Ok([
            ("surface_model.json", pretty(&self.model.to_model_json())?),
            ("surface_model.obj", self.model.to_obj()),
            ("stats.json", pretty(&self.stats())?),
        ])
    }

    /// Write [`Replay::outputs`] into `dir` (which must exist).
    pub fn write(&self, dir: &Path) -> Result<(), ReplayError> {
        for (name, text) in self.outputs()? {
            let path = dir.join(name);
            std::fs::write(&path, text).map_err(|e| ReplayError::Write {
                path,
                message: e.to_string(),
            })?;
        }
        Ok(())
    }
}

/// Pretty JSON of one of our output types.
fn pretty(v: &impl serde::Serialize) -> Result<String, ReplayError> {
    serde_json::to_string_pretty(v).map_err(|e| ReplayError::Format {
        message: e.to_string(),
    })
}
