#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! | module | files |
//! |---|---|
//! | [`folder`] | [`Staging`] (a run folder written whole or not at all), [`RunFolder`] (open one of this [`FORMAT_VERSION`], read each file) |
//! | [`viewpoints`] | `viewpoints.csv`, `candidates.csv`, `path.csv` from [`ViewpointRecord`]s, and back |
//! | [`explore`] | `run.json` of an exploration ([`ExploreSummary`]), `discs.csv` ([`DiscTable`]), `segments.json`, `cloud.ply`, `mesh.ply` |
//! | [`checkpoint`] | `checkpoint.json` ([`Checkpoint`]) |
//! | [`bag`] | `run.mcap` ([`bag::RunBag`]: the run's ROS 2 bag, MCAP of CDR messages) and robots' bags read back ([`bag::sweeps_from_bag`], [`bag::sets_from_bag`]) |
//! | [`blast`] | `blast_inputs.json` ([`blast::BlastInputsFile`]), `blast_plan.json` and `.csv` ([`blast::BlastPlan`]) |
//! | [`coverage`] | the coverage reports a judged run records |
//! | [`follow`] | `steps.csv` ([`StepRow`]), `path.ply`, `run.json` of a surface-following run ([`FollowSummary`]) |
//! | [`snapshots`] | `model_snapshots.json` ([`ModelSnapshots`]) |
//! | [`table`] | reading CSV tables by column name, JSON files, with file, line and field in errors |
//! | [`output`] | single output files written under temporary names and moved into place ([`output::Staged`]) |

pub mod bag;
pub mod blast;
pub mod checkpoint;
pub mod coverage;
mod error;
pub mod explore;
pub mod folder;
pub mod follow;
pub mod output;
pub mod snapshots;
pub mod table;
pub mod viewpoints;

pub use checkpoint::Checkpoint;
pub use coverage::{CoverageReport, MaterialCoverage};
pub use error::RecordError;
pub use explore::{DiscRecord, DiscTable, ExploreSummary};
pub use folder::{RunFolder, RunKind, Staging};
pub use follow::{Collision, FollowSummary, StepRow, StepTimes};
pub use snapshots::ModelSnapshots;
pub use viewpoints::{ScoredCandidate, UnsafeConfiguration, ViewpointRecord};

/// The version of the run folder's format, in every `run.json` as
/// `format_version`. Version 1 (no `format_version`) was written before
/// `record` owned the folder; version 2 is the first with a version.
pub const FORMAT_VERSION: u32 = 2;

/// Pretty JSON of `value` with a final newline; `name` names the file in
/// errors.
pub(crate) fn pretty_json<T: serde::Serialize>(
    value: &T,
    name: &str,
) -> Result<String, RecordError> {
    serde_json::to_string_pretty(value)
        .map(|s| s + "\n")
        .map_err(|e| RecordError::named(name, e))
}

/// [`pretty_json`] with every object's keys in alphabetical order.
pub(crate) fn sorted_json<T: serde::Serialize>(
    value: &T,
    name: &str,
) -> Result<String, RecordError> {
    let value = sort_keys(serde_json::to_value(value).map_err(|e| RecordError::named(name, e))?);
    pretty_json(&value, name)
}

/// `value` with every object's keys sorted, whatever order
/// `serde_json::Map` keeps (`preserve_order` may be on in the workspace).
fn sort_keys(value: serde_json::Value) -> serde_json::Value {
    use serde_json::Value;
    match value {
        Value::Object(map) => {
            let mut entries: Vec<(String, Value)> = map.into_iter().collect();
            entries.sort_by(|a, b| a.0.cmp(&b.0));
            Value::Object(
                entries
                    .into_iter()
                    .map(|(k, v)| (k, sort_keys(v)))
                    .collect(),
            )
        }
        Value::Array(items) => Value::Array(items.into_iter().map(sort_keys).collect()),
        other => other,
    }
}
