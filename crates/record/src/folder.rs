//! A run folder as a whole: [`Staging`] writes one so that it appears
//! whole or not at all, [`RunFolder`] opens one, checks its format version
//! and reads each of its files.

use crate::blast::{BLAST_INPUTS_JSON, BLAST_PLAN_JSON, BlastInputsFile, BlastPlan};
use crate::checkpoint::{CHECKPOINT_JSON, Checkpoint};
use crate::explore::{
    CLOUD_PLY, DISCS_CSV, DiscTable, ExploreSummary, MESH_PLY, RUN_JSON, SEGMENTS_JSON,
    SegmentsFile,
};
use crate::follow::{FollowSummary, STEPS_CSV, SURFACE_MODEL_JSON, StepRow};
use crate::snapshots::{MODEL_SNAPSHOTS_JSON, ModelSnapshots};
use crate::table::read_json;
use crate::viewpoints::{VIEWPOINTS_CSV, ViewpointRecord, read_viewpoints};
use crate::{FORMAT_VERSION, RecordError};
use geom::{Point3, TriMesh};
use serde::de::DeserializeOwned;
use std::path::{Path, PathBuf};

/// The scenario as run, written by both commands (not by a `--scene` follow run).
pub const SCENARIO_TOML: &str = "scenario.toml";
/// The run's ROS 2 bag (MCAP), which every run writes.
pub const RUN_MCAP: &str = "run.mcap";
/// The page `surveyor report` writes.
pub const REPORT_HTML: &str = "report.html";

/// A run folder being written. Every file goes into a staging folder
/// inside the output folder and is moved into place by
/// [`commit`](Self::commit): an older `run.json` is removed first and the
/// new one moved last, so at any moment the folder either holds a
/// `run.json` and every file that goes with it, or no `run.json` (an
/// unfinished run). Dropped without a commit (an error, a full disk), the
/// staging folder is removed, and so is an output folder it created.
#[derive(Debug)]
pub struct Staging {
    out: PathBuf,
    stage: PathBuf,
    created_out: bool,
    committed: bool,
}

impl Staging {
    /// Stage a run folder for `out` (created when missing; a file there is
    /// an error).
    pub fn new(out: &Path) -> Result<Self, RecordError> {
        crate::output::check_out_dir(out)?;
        let created_out = !out.exists();
        crate::output::create_out_dir(out)?;
        let stage = out.join(format!(".surveyor-staging-{}", std::process::id()));
        let mut me = Self {
            out: out.to_owned(),
            stage,
            created_out,
            committed: false,
        };
        if me.stage.exists() {
            std::fs::remove_dir_all(&me.stage).map_err(|e| RecordError::file(&me.stage, e))?;
        }
        if let Err(e) = std::fs::create_dir(&me.stage) {
            me.committed = false;
            return Err(RecordError::file(&me.stage, format!("creating: {e}")));
        }
        Ok(me)
    }

    /// The output folder.
    pub fn out(&self) -> &Path {
        &self.out
    }

    /// The staging folder: a complete run folder once every file is
    /// written (readers such as the report can read it there).
    pub fn dir(&self) -> &Path {
        &self.stage
    }

    /// Where the file `name` is staged.
    pub fn path(&self, name: &str) -> PathBuf {
        self.stage.join(name)
    }

    /// Stage the file `name` with `contents`.
    pub fn write(&self, name: &str, contents: impl AsRef<[u8]>) -> Result<(), RecordError> {
        let path = self.path(name);
        std::fs::write(&path, contents).map_err(|e| RecordError::file(&self.out.join(name), e))
    }

    /// Move the staged files into the output folder, `run.json` last (an
    /// older one is removed first).
    pub fn commit(mut self) -> Result<(), RecordError> {
        let old = self.out.join(RUN_JSON);
        if old.exists() {
            std::fs::remove_file(&old).map_err(|e| RecordError::file(&old, e))?;
        }
        let mut names: Vec<std::ffi::OsString> = std::fs::read_dir(&self.stage)
            .map_err(|e| RecordError::file(&self.stage, e))?
            .map(|e| e.map(|e| e.file_name()))
            .collect::<Result<_, _>>()
            .map_err(|e| RecordError::file(&self.stage, e))?;
        names.sort_by_key(|n| (n == RUN_JSON, n.clone()));
        for name in names {
            let dest = self.out.join(&name);
            std::fs::rename(self.stage.join(&name), &dest).map_err(|e| {
                RecordError::file(&dest, format!("moving the output into place: {e}"))
            })?;
        }
        std::fs::remove_dir(&self.stage).map_err(|e| RecordError::file(&self.stage, e))?;
        self.committed = true;
        Ok(())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if self.committed {
            return;
        }
        let _ = std::fs::remove_dir_all(&self.stage);
        if self.created_out {
            let _ = std::fs::remove_dir(&self.out);
        }
    }
}

/// Which command wrote a run folder.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunKind {
    /// `surveyor explore` (`viewpoints.csv`).
    Explore,
    /// `surveyor follow` (`steps.csv`).
    Follow,
}

/// A finished run folder of this format version, opened for reading.
#[derive(Clone, Debug)]
pub struct RunFolder {
    dir: PathBuf,
    kind: RunKind,
    summary: serde_json::Value,
}

impl RunFolder {
    /// Open the run in `dir`: which command wrote it (by `viewpoints.csv` or
    /// `steps.csv`), and its `run.json`, which must be of
    /// [`FORMAT_VERSION`] (a folder without the version is of version 1).
    pub fn open(dir: &Path) -> Result<Self, RecordError> {
        let not_a_run = |message: &str| RecordError::NotARun {
            dir: dir.display().to_string(),
            message: message.to_owned(),
        };
        if !dir.is_dir() {
            return Err(not_a_run("no such folder"));
        }
        let kind = if dir.join(VIEWPOINTS_CSV).exists() {
            RunKind::Explore
        } else if dir.join(STEPS_CSV).exists() {
            RunKind::Follow
        } else {
            return Err(not_a_run(
                "not a run folder: expected viewpoints.csv (surveyor explore) or steps.csv \
                 (surveyor follow)",
            ));
        };
        let run_json = dir.join(RUN_JSON);
        if !run_json.exists() {
            return Err(not_a_run(
                "no run.json: the run did not finish (an interrupted `surveyor explore` \
                 continues with --resume)",
            ));
        }
        let summary: serde_json::Value = read_json(&run_json)?;
        if !summary.is_object() || !summary["scenario"].is_string() {
            return Err(RecordError::file(
                &run_json,
                "expected a JSON object with a `scenario` string, as surveyor writes run.json",
            ));
        }
        let found = match summary.get("format_version") {
            None => 1,
            Some(v) => v
                .as_u64()
                .and_then(|v| u32::try_from(v).ok())
                .ok_or_else(|| RecordError::Field {
                    file: run_json.display().to_string(),
                    line: 1,
                    field: "format_version".into(),
                    message: format!("expected a whole number, found {v}"),
                })?,
        };
        if found != FORMAT_VERSION {
            return Err(RecordError::Version {
                dir: dir.display().to_string(),
                found,
                expected: FORMAT_VERSION,
                hint: if found < FORMAT_VERSION {
                    " (written by an older surveyor: run it again to make a folder this one reads)"
                } else {
                    " (written by a newer surveyor)"
                },
            });
        }
        Ok(Self {
            dir: dir.to_owned(),
            kind,
            summary,
        })
    }

    /// The folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Which command wrote it.
    pub fn kind(&self) -> RunKind {
        self.kind
    }

    /// The path of the file `name` in the folder.
    pub fn path(&self, name: &str) -> PathBuf {
        self.dir.join(name)
    }

    /// `run.json` as JSON, for display.
    pub fn summary_json(&self) -> &serde_json::Value {
        &self.summary
    }

    /// The scenario name in `run.json`.
    pub fn scenario(&self) -> &str {
        self.summary["scenario"].as_str().unwrap_or_default()
    }

    /// `run.json` of an exploration, typed.
    pub fn explore_summary(&self) -> Result<ExploreSummary, RecordError> {
        self.typed_summary()
    }

    /// `run.json` of a surface-following run, typed.
    pub fn follow_summary<O, S, M>(&self) -> Result<FollowSummary<O, S, M>, RecordError>
    where
        O: DeserializeOwned,
        S: DeserializeOwned,
        M: DeserializeOwned,
    {
        self.typed_summary()
    }

    fn typed_summary<T: DeserializeOwned>(&self) -> Result<T, RecordError> {
        read_json(&self.path(RUN_JSON))
    }

    /// The exploration's viewpoints (`viewpoints.csv`, `candidates.csv`,
    /// `path.csv`).
    pub fn viewpoints(&self) -> Result<Vec<ViewpointRecord>, RecordError> {
        read_viewpoints(&self.dir)
    }

    /// The measured points of `cloud.ply`.
    pub fn cloud(&self) -> Result<Vec<Point3>, RecordError> {
        let path = self.path(CLOUD_PLY);
        Ok(scene::io::load_cloud(&path)?.points)
    }

    /// Every `stride`-th point of `cloud.ply` (`stride` from the number of
    /// points, [`scene::io::sample_cloud_points`]) and the number of points,
    /// reading only those points.
    pub fn cloud_sample(
        &self,
        stride_of: impl FnOnce(usize) -> usize,
    ) -> Result<(usize, Vec<Point3>), RecordError> {
        let path = self.path(CLOUD_PLY);
        Ok(scene::io::sample_cloud_points(&path, stride_of)?)
    }

    /// The TSDF mesh of `mesh.ply`.
    pub fn mesh(&self) -> Result<TriMesh, RecordError> {
        let path = self.path(MESH_PLY);
        Ok(scene::io::load_mesh(&path, 1.0)?)
    }

    /// `discs.csv`.
    pub fn discs(&self) -> Result<DiscTable, RecordError> {
        DiscTable::read(&self.path(DISCS_CSV))
    }

    /// `segments.json`.
    pub fn segments(&self) -> Result<SegmentsFile, RecordError> {
        read_json(&self.path(SEGMENTS_JSON))
    }

    /// `blast_plan.json`; `T` is the tool's type (`serde_json::Value` to
    /// only show it). An exploration plans blasting when it made discs, so
    /// the file is required then and `None` otherwise.
    pub fn blast_plan<T: DeserializeOwned>(&self) -> Result<Option<BlastPlan<T>>, RecordError> {
        let path = self.path(BLAST_PLAN_JSON);
        let discs = self.summary["discs"].as_u64().unwrap_or(0);
        if discs == 0 && !path.exists() {
            return Ok(None);
        }
        read_json(&path).map(Some)
    }

    /// `blast_inputs.json`, checked for its format and version.
    pub fn blast_inputs<D, C>(&self) -> Result<BlastInputsFile<D, C>, RecordError>
    where
        D: serde::Serialize + DeserializeOwned,
        C: serde::Serialize + DeserializeOwned,
    {
        BlastInputsFile::read(&self.path(BLAST_INPUTS_JSON))
    }

    /// The exploration's checkpoint.
    pub fn checkpoint<C>(&self) -> Result<Checkpoint<C>, RecordError>
    where
        C: Clone + serde::Serialize + DeserializeOwned,
    {
        Checkpoint::read(&self.path(CHECKPOINT_JSON))
    }

    /// The surface-following run's steps.
    pub fn steps(&self) -> Result<Vec<StepRow>, RecordError> {
        crate::follow::read_steps(&self.path(STEPS_CSV))
    }

    /// The surface-following run's model.
    pub fn surface_model(&self) -> Result<surface::ModelJson, RecordError> {
        read_json(&self.path(SURFACE_MODEL_JSON))
    }

    /// The surface-following run's model snapshots.
    pub fn snapshots(&self) -> Result<ModelSnapshots, RecordError> {
        read_json(&self.path(MODEL_SNAPSHOTS_JSON))
    }

    /// The text of `scenario.toml`, which a `--scene` follow run does not
    /// write (`None` then).
    pub fn scenario_toml(&self) -> Result<Option<String>, RecordError> {
        let path = self.path(SCENARIO_TOML);
        if self.kind == RunKind::Follow && !path.exists() {
            return Ok(None);
        }
        std::fs::read_to_string(&path)
            .map(Some)
            .map_err(|e| RecordError::file(&path, e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn a_staging_dropped_without_commit_leaves_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("new");
        {
            let s = Staging::new(&out).unwrap();
            s.write("cloud.ply", b"partial").unwrap();
            s.write(RUN_JSON, b"{}").unwrap();
            assert!(out.exists());
        }
        assert!(!out.exists(), "the folder it made is removed");
        // Over an older run: the older files stay as they were.
        std::fs::create_dir(&out).unwrap();
        std::fs::write(out.join(RUN_JSON), "old").unwrap();
        {
            let s = Staging::new(&out).unwrap();
            s.write(RUN_JSON, b"new").unwrap();
        }
        assert_eq!(names(&out), vec![RUN_JSON.to_owned()]);
        assert_eq!(std::fs::read_to_string(out.join(RUN_JSON)).unwrap(), "old");
    }

    #[test]
    fn a_commit_moves_run_json_last_and_a_failed_one_leaves_no_run_json() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("run");
        let s = Staging::new(&out).unwrap();
        for name in ["a.csv", RUN_JSON, "z.ply"] {
            s.write(name, name.as_bytes()).unwrap();
        }
        s.commit().unwrap();
        assert_eq!(names(&out), vec!["a.csv", RUN_JSON, "z.ply"]);
        // A commit that fails half-way (here a file cannot take the place of
        // a folder of the same name) has removed the older run.json and not
        // moved the new one: the folder does not look finished.
        std::fs::remove_file(out.join("z.ply")).unwrap();
        std::fs::create_dir(out.join("z.ply")).unwrap();
        std::fs::write(out.join("z.ply").join("keep"), "x").unwrap();
        let s = Staging::new(&out).unwrap();
        for name in ["a.csv", RUN_JSON, "z.ply"] {
            s.write(name, b"second").unwrap();
        }
        assert!(s.commit().is_err());
        assert!(!out.join(RUN_JSON).exists());
        assert!(
            !names(&out)
                .iter()
                .any(|n| n.starts_with(".surveyor-staging"))
        );
    }
}
