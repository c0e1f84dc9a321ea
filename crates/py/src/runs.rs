//! Whole runs from Python: `surveyor.explore` and `surveyor.follow` run the
//! jobs `surveyor explore` and `surveyor follow` run, into a run folder;
//! `surveyor.Run.load` reads a run folder through `record::RunFolder`.
//!
//! The Python side (`python/surveyor/_runs.py`) splits keyword arguments
//! into the job's options and scenario overrides and hands both over as
//! JSON; this module parses them with serde (unknown options refused by
//! name), merges the overrides into the scenario's TOML (so the scenario's
//! own checks judge them) and runs the job with the GIL released.

use crate::errors::{scenario_error, value_error};
use numpy::PyArray2;
use numpy::ndarray::Array2;
use pyo3::exceptions::PyOSError;
use pyo3::prelude::*;
use scenario::job::explore::{ExploreOptions, OracleOption};
use scenario::{LoadedScenario, Scenario};
use serde::Deserialize;
use sim::follow_job::{DEFAULT_MAX_SETS, FollowRunOptions, SimFollow};
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

/// The options of `surveyor.explore` (the flags of `surveyor explore`).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct ExploreKw {
    /// `"both"` (default) or `"one"`.
    stages: Option<String>,
    max_viewpoints: Option<usize>,
    /// `"information"` (default) or `"thesis"`.
    stage_one: Option<String>,
    /// Compute the coverage oracle (default true, as the CLI).
    oracle: Option<bool>,
    /// Record wall-clock times (default false: reruns are byte-identical).
    timings: Option<bool>,
    /// Write report.html (default true, as the CLI).
    report: Option<bool>,
}

/// The options of `surveyor.follow` (the flags of `surveyor follow`).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct FollowKw {
    robot: Option<String>,
    max_sets: Option<u64>,
    noise_m: Option<f64>,
    timings: Option<bool>,
    report: Option<bool>,
}

fn parse<T: serde::de::DeserializeOwned + Default>(what: &str, json: &str) -> PyResult<T> {
    if json.is_empty() {
        return Ok(T::default());
    }
    serde_json::from_str(json).map_err(|e| value_error(format!("{what}: {e}")))
}

/// `name_or_file` loaded, with `overrides_json` (a JSON object of scenario
/// keys, nested tables as objects) merged into its TOML and checked again.
fn scenario_with(name_or_file: &str, overrides_json: &str) -> PyResult<LoadedScenario> {
    let loaded = Scenario::load(name_or_file).map_err(|e| scenario_error(&e))?;
    let overrides: serde_json::Value = if overrides_json.is_empty() {
        serde_json::Value::Object(serde_json::Map::new())
    } else {
        serde_json::from_str(overrides_json)
            .map_err(|e| value_error(format!("scenario overrides: {e}")))?
    };
    let serde_json::Value::Object(keys) = overrides else {
        return Err(value_error(
            "scenario overrides: expected a dict of scenario keys",
        ));
    };
    if keys.is_empty() {
        return Ok(loaded);
    }
    let text = loaded.scenario.to_toml().map_err(|e| scenario_error(&e))?;
    let mut table: toml::Table =
        toml::from_str(&text).map_err(|e| value_error(format!("the scenario as TOML: {e}")))?;
    for (key, value) in keys {
        let value = toml::Value::try_from(&value).map_err(|e| {
            value_error(format!("scenario key `{key}`: {e} (None has no TOML form)"))
        })?;
        merge(&mut table, &key, value);
    }
    let text = toml::to_string(&table).map_err(|e| value_error(format!("scenario: {e}")))?;
    let scenario = Scenario::from_toml(&text, &format!("{name_or_file} with overrides"))
        .map_err(|e| scenario_error(&e))?;
    Ok(LoadedScenario {
        scenario,
        base_dir: loaded.base_dir,
    })
}

/// Set `key` of `table` to `value`; two tables merge key by key.
fn merge(table: &mut toml::Table, key: &str, value: toml::Value) {
    match (table.get_mut(key), value) {
        (Some(toml::Value::Table(old)), toml::Value::Table(new)) => {
            for (k, v) in new {
                merge(old, &k, v);
            }
        }
        (_, value) => {
            table.insert(key.to_owned(), value);
        }
    }
}

/// A job's error as a Python exception: a file the job could not write is
/// an `OSError`, anything else a `ValueError`.
fn job_error(e: &dyn std::fmt::Display, io: bool) -> PyErr {
    if io {
        PyOSError::new_err(e.to_string())
    } else {
        value_error(e.to_string())
    }
}

/// Whether a simulator error is about a file.
fn is_io(e: &sim::SimError) -> bool {
    matches!(e, sim::SimError::Record(r) if matches!(**r, record::RecordError::File { .. }))
}

/// The report of a staged explore run folder, when asked for, in the two
/// steps of `scenario::job::explore::Finish`.
fn finish_explore(
    report: bool,
) -> impl FnMut(&record::Staging) -> Result<scenario::job::explore::Complete, String> {
    move |staging| {
        if report {
            report::in_two_steps(staging)
        } else {
            scenario::job::explore::no_files(staging)
        }
    }
}

/// The report of a staged run folder, when asked for.
fn finish(report: bool) -> impl FnMut(&record::Staging) -> Result<(), String> {
    move |staging| {
        if report {
            report::write_staged(staging).map_err(|e| e.to_string())
        } else {
            Ok(())
        }
    }
}

/// Run AXBAM exploration of `scenario` (a built-in name or a scenario file)
/// into the run folder `out`, as `surveyor explore --scenario S --seed N
/// --out OUT` does. `options` and `overrides` are JSON (see
/// `surveyor.explore`).
#[pyfunction]
#[pyo3(signature = (scenario, seed, out, options = "", overrides = ""))]
#[expect(
    clippy::needless_pass_by_value,
    reason = "PyO3 extracts owned arguments"
)]
pub fn _explore(
    py: Python<'_>,
    scenario: &str,
    seed: u64,
    out: PathBuf,
    options: &str,
    overrides: &str,
) -> PyResult<()> {
    let (loaded, kw, checked) = check_explore(scenario, options, overrides)?;
    let options = ExploreOptions {
        seed,
        oracle: if kw.oracle.unwrap_or(true) {
            OracleOption::On(Some(ExploreOptions::default_oracle_cache(&loaded)))
        } else {
            OracleOption::Off
        },
        cspace_cache: Some(
            ExploreOptions::default_cspace_cache(&loaded).map_err(|e| job_error(&e, false))?,
        ),
        lrc_cache: Some(ExploreOptions::default_lrc_cache(seed)),
        ..checked
    };
    let report = kw.report.unwrap_or(true);
    py.detach(|| {
        sim::explore_job::explore(
            &loaded,
            &options,
            &out,
            &mut |_| {},
            &mut finish_explore(report),
        )
        .map(|_| ())
        .map_err(|e| (e.to_string(), is_io(&e)))
    })
    .map_err(|(message, io)| job_error(&message, io))
}

/// What `_explore` checks before it runs: the options, the scenario with
/// its overrides, the stages and the Stage One rule.
fn check_explore(
    scenario: &str,
    options: &str,
    overrides: &str,
) -> PyResult<(LoadedScenario, ExploreKw, ExploreOptions)> {
    let kw: ExploreKw = parse("explore options", options)?;
    let loaded = scenario_with(scenario, overrides)?;
    let stage_two = match kw.stages.as_deref().unwrap_or("both") {
        "both" => true,
        "one" => false,
        other => {
            return Err(value_error(format!(
                "stages={other:?}: expected \"one\" or \"both\""
            )));
        }
    };
    if kw.max_viewpoints == Some(0) {
        return Err(value_error(
            "max_viewpoints=0: expected at least 1 (the start pose's sweep is one)",
        ));
    }
    let rule = kw.stage_one.as_deref().unwrap_or("information");
    let Some(config) = ExploreOptions::stage_one_config(&loaded, rule) else {
        return Err(value_error(format!(
            "stage_one={rule:?}: expected \"information\" or \"thesis\""
        )));
    };
    let options = ExploreOptions {
        max_viewpoints: kw.max_viewpoints,
        config,
        timings: kw.timings.unwrap_or(false),
        stage_two,
        ..ExploreOptions::default()
    };
    Ok((loaded, kw, options))
}

/// Check `surveyor.explore`'s arguments without running (a campaign checks
/// every combination before Ray starts): a `ValueError` as `_explore`
/// raises it.
#[pyfunction]
#[pyo3(signature = (scenario, options = "", overrides = ""))]
pub fn _check_explore(scenario: &str, options: &str, overrides: &str) -> PyResult<()> {
    check_explore(scenario, options, overrides).map(|_| ())
}

/// Run Pudney's surface following of `scenario` into the run folder `out`,
/// as `surveyor follow --scenario S --seed N --out OUT` does. `options` is
/// JSON (see `surveyor.follow`).
#[pyfunction]
#[pyo3(signature = (scenario, seed, out, options = ""))]
#[expect(
    clippy::needless_pass_by_value,
    reason = "PyO3 extracts owned arguments"
)]
pub fn _follow(
    py: Python<'_>,
    scenario: &str,
    seed: u64,
    out: PathBuf,
    options: &str,
) -> PyResult<()> {
    let kw: FollowKw = parse("follow options", options)?;
    let loaded = Scenario::load(scenario).map_err(|e| scenario_error(&e))?;
    if kw.max_sets == Some(0) {
        return Err(value_error("max_sets=0: expected at least 1 sensor set"));
    }
    let options = FollowRunOptions {
        seed,
        max_sets: kw.max_sets.unwrap_or(DEFAULT_MAX_SETS),
        noise_sigma_m: kw.noise_m,
        robot: kw.robot,
        timings: kw.timings.unwrap_or(false),
        ..FollowRunOptions::default()
    };
    let report = kw.report.unwrap_or(true);
    let toml = loaded
        .standalone()
        .to_toml()
        .map_err(|e| scenario_error(&e))?;
    py.detach(|| {
        let setup = SimFollow::from_scenario(&loaded, &options)?;
        let stop = AtomicBool::new(false);
        sim::follow_job::follow(
            setup,
            Some(toml),
            &out,
            &stop,
            &mut |_, _| {},
            &mut finish(report),
        )
        .map(|_| ())
    })
    .map_err(|e| value_error(e.to_string()))
}

/// A run folder opened through `record::RunFolder` (format version and
/// kind checked); `surveyor.Run` wraps it.
#[pyclass(name = "_RunFolder", module = "surveyor", frozen)]
pub struct PyRunFolder {
    folder: record::RunFolder,
}

fn record_error(e: &record::RecordError) -> PyErr {
    match e {
        record::RecordError::File { .. } => PyOSError::new_err(e.to_string()),
        _ => value_error(e.to_string()),
    }
}

#[pymethods]
impl PyRunFolder {
    #[new]
    #[expect(
        clippy::needless_pass_by_value,
        reason = "PyO3 extracts owned arguments"
    )]
    fn new(dir: PathBuf) -> PyResult<Self> {
        if !dir.is_dir() {
            return Err(pyo3::exceptions::PyFileNotFoundError::new_err(format!(
                "{}: no such run folder",
                dir.display()
            )));
        }
        let folder = record::RunFolder::open(&dir).map_err(|e| record_error(&e))?;
        Ok(Self { folder })
    }

    /// `"explore"` or `"follow"`.
    #[getter]
    fn kind(&self) -> &'static str {
        match self.folder.kind() {
            record::RunKind::Explore => "explore",
            record::RunKind::Follow => "follow",
        }
    }

    /// run.json as JSON text.
    fn summary_json(&self) -> String {
        self.folder.summary_json().to_string()
    }

    /// The folder.
    #[getter]
    fn dir(&self) -> PathBuf {
        self.folder.dir().to_path_buf()
    }

    /// Every measured point of cloud.ply: float64 (n, 3).
    fn cloud<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let points = self.folder.cloud().map_err(|e| record_error(&e))?;
        Ok(PyArray2::from_owned_array(
            py,
            Array2::from_shape_fn((points.len(), 3), |(k, c)| points[k][c]),
        ))
    }

    /// mesh.ply: vertices float64 (m, 3) and triangles int64 (k, 3).
    #[expect(
        clippy::type_complexity,
        reason = "the (vertices, triangles) pair Python receives"
    )]
    fn mesh<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyArray2<f64>>, Bound<'py, PyArray2<i64>>)> {
        let mesh = self.folder.mesh().map_err(|e| record_error(&e))?;
        let v = &mesh.vertices;
        let t = &mesh.triangles;
        Ok((
            PyArray2::from_owned_array(py, Array2::from_shape_fn((v.len(), 3), |(k, c)| v[k][c])),
            PyArray2::from_owned_array(
                py,
                Array2::from_shape_fn((t.len(), 3), |(k, c)| i64::from(t[k][c])),
            ),
        ))
    }

    /// The path of a file of the folder.
    fn path(&self, name: &str) -> PathBuf {
        self.folder.path(name)
    }
}
