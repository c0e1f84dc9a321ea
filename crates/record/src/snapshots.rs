//! The surface model's evolution during a run (Pudney Figs 44 and 46): copies
//! of the model at evenly spaced sensor-set counts, and at the end.
//!
//! The run's length is not known in advance (it ends when the follower
//! reports the surface complete), so [`ModelSnapshots`] keeps the model after
//! every `stride`-th set, with `stride` a power of two: once
//! [`MAX_SNAPSHOTS`] are held and another is due, every other one is dropped
//! and the stride doubles. Whatever the run's length, between
//! `MAX_SNAPSHOTS / 2` and [`MAX_SNAPSHOTS`] snapshots (fewer only for runs
//! shorter than that many sets) lie at `stride, 2·stride, …`, and
//! [`ModelSnapshots::finish`] adds the final model. Which sets are kept
//! depends only on the number of sets, so the file is deterministic; a copy
//! is made about `MAX_SNAPSHOTS + (MAX_SNAPSHOTS / 2)·log2(sets)` times in a
//! run, which costs nothing next to the run.

use serde::{Deserialize, Serialize};
use surface::{ModelJson, SurfaceModel};

/// The file of the snapshots.
pub const MODEL_SNAPSHOTS_JSON: &str = "model_snapshots.json";

/// Most snapshots held before the final one.
pub const MAX_SNAPSHOTS: usize = 6;

/// The model after `sets` sensor sets.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ModelSnapshot {
    /// Sensor sets processed when the copy was taken.
    pub sets: u64,
    /// The model, in the `surface_model.json` layout.
    pub model: ModelJson,
}

/// `model_snapshots.json`: the snapshots in set order, the last one the
/// final model.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ModelSnapshots {
    /// The spacing of the snapshots before the final one, in sensor sets.
    pub stride_sets: u64,
    /// The snapshots, in increasing `sets`.
    pub snapshots: Vec<ModelSnapshot>,
}

impl ModelSnapshots {
    /// No snapshot yet; the first is due after one set.
    pub fn new() -> Self {
        Self {
            stride_sets: 1,
            snapshots: Vec::new(),
        }
    }

    /// Called after every sensor set: `sets` processed so far (1, 2, …).
    pub fn observe(&mut self, sets: u64, model: &SurfaceModel) {
        if sets == 0 || !sets.is_multiple_of(self.stride_sets) {
            return;
        }
        if self.snapshots.len() >= MAX_SNAPSHOTS {
            let wider = 2 * self.stride_sets;
            self.snapshots.retain(|s| s.sets.is_multiple_of(wider));
            self.stride_sets = wider;
            if !sets.is_multiple_of(wider) {
                return;
            }
        }
        self.snapshots.push(ModelSnapshot {
            sets,
            model: model.to_model_json(),
        });
    }

    /// Add the final model after `sets` sets (replacing a snapshot already
    /// taken at that count).
    pub fn finish(&mut self, sets: u64, model: &SurfaceModel) {
        if self.snapshots.last().is_some_and(|s| s.sets == sets) {
            self.snapshots.pop();
        }
        self.snapshots.push(ModelSnapshot {
            sets,
            model: model.to_model_json(),
        });
    }

    /// The set counts of the snapshots.
    pub fn sets(&self) -> Vec<u64> {
        self.snapshots.iter().map(|s| s.sets).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(n: u64) -> ModelSnapshots {
        let model = SurfaceModel::new(surface::SurfaceConfig::default()).unwrap();
        let mut s = ModelSnapshots::new();
        for k in 1..=n {
            s.observe(k, &model);
        }
        s.finish(n, &model);
        s
    }

    #[test]
    fn snapshots_are_evenly_spaced_whatever_the_length() {
        assert_eq!(run(3).sets(), [1, 2, 3]);
        assert_eq!(run(6).sets(), [1, 2, 3, 4, 5, 6]);
        assert_eq!(run(7).sets(), [2, 4, 6, 7]);
        assert_eq!(run(100).sets(), [16, 32, 48, 64, 80, 96, 100]);
        assert_eq!(run(128).sets(), [32, 64, 96, 128]);
        for n in [13, 50, 333, 1000, 4097] {
            let s = run(n);
            let before = &s.snapshots[..s.snapshots.len() - 1];
            assert!(
                (MAX_SNAPSHOTS / 2..=MAX_SNAPSHOTS).contains(&before.len()),
                "{n}: {:?}",
                s.sets()
            );
            for (i, b) in before.iter().enumerate() {
                assert_eq!(b.sets, (i as u64 + 1) * s.stride_sets, "{n}");
            }
            assert_eq!(s.snapshots.last().map(|l| l.sets), Some(n));
        }
    }
}
