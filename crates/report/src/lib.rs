#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! [`write()`] (and [`write_staged`] for a folder being staged) opens the
//! folder through [`record::RunFolder`] (its format version checked there): a
//! `surveyor explore` run gets the page of [`explore`] (Paul ch. 6), a
//! `surveyor follow` run the page of [`follow`] (Pudney's Figs 44–47); the
//! page ([`page`]) embeds plotly.js, so it opens offline.

pub mod cards;
pub mod error;
pub mod explore;
pub mod follow;
pub mod geometry;
pub mod page;

pub use error::ReportError;
use record::{RunFolder, RunKind, Staging};
use std::path::{Path, PathBuf};

/// A page drawn from a run folder's files but for the parts made from its
/// final `run.json` (the summary cards and the table of every figure),
/// which [`Draft::complete`] adds: a run's timings are final only once its
/// report has been drawn.
#[derive(Debug)]
pub struct Draft {
    page: page::Page,
    kind: RunKind,
}

impl Draft {
    /// The page of the run in `dir`, naming the folder `shown`.
    pub fn of(dir: &Path, shown: &Path) -> Result<Self, ReportError> {
        let folder = RunFolder::open(dir)?;
        let kind = folder.kind();
        let page = match kind {
            RunKind::Explore => explore::page(&folder, shown)?,
            RunKind::Follow => follow::page(&folder, shown)?,
        };
        Ok(Self { page, kind })
    }

    /// The whole page, with the summary cards and the table of `run`
    /// (the run's `run.json`).
    pub fn complete(&self, run: &serde_json::Value) -> String {
        let (cards, skip): (_, &[&str]) = match self.kind {
            RunKind::Explore => (cards::explore(run), &["reports", "format_version"]),
            RunKind::Follow => (cards::follow(run), &["initial_segments", "format_version"]),
        };
        self.page.finish_with(&cards, Some((run, skip)))
    }

    /// Complete the page with the `run.json` now in `staging` and write it
    /// there as `report.html`.
    pub fn write_staged(&self, staging: &Staging) -> Result<(), ReportError> {
        let folder = RunFolder::open(staging.dir())?;
        staging.write(
            record::folder::REPORT_HTML,
            self.complete(folder.summary_json()),
        )?;
        Ok(())
    }
}

/// The page of the run in `dir`, naming the folder `shown`.
pub fn render_as(dir: &Path, shown: &Path) -> Result<String, ReportError> {
    let draft = Draft::of(dir, shown)?;
    let folder = RunFolder::open(dir)?;
    Ok(draft.complete(folder.summary_json()))
}

/// The page of the run in `dir`.
pub fn render(dir: &Path) -> Result<String, ReportError> {
    render_as(dir, dir)
}

/// Write `dir/report.html` (through a temporary file, so a failure leaves
/// no partial page); returns its path.
pub fn write(dir: &Path) -> Result<PathBuf, ReportError> {
    let html = render(dir)?;
    let path = dir.join(record::folder::REPORT_HTML);
    let mut staged = record::output::Staged::new();
    let tmp = staged.file(&path)?;
    std::fs::write(&tmp, html).map_err(|e| ReportError::file(&path.display().to_string(), e))?;
    staged.commit()?;
    Ok(path)
}

/// The draft of the report of a run folder being staged ([`Staging`]),
/// naming it by its final place; [`Draft::write_staged`] completes and
/// writes it.
pub fn draft_staged(staging: &Staging) -> Result<Draft, ReportError> {
    Draft::of(staging.dir(), staging.out())
}

/// The step that completes a staged report ([`Draft::write_staged`]), its
/// errors as text.
pub type CompleteStaged = Box<dyn FnOnce(&Staging) -> Result<(), String>>;

/// [`draft_staged`], returning the step that completes and writes the page
/// once the staged `run.json` is final: the two steps an explore job
/// finishes its folder with (`scenario::job::explore::Finish`).
pub fn in_two_steps(staging: &Staging) -> Result<CompleteStaged, String> {
    let draft = draft_staged(staging).map_err(|e| e.to_string())?;
    Ok(Box::new(move |staging: &Staging| {
        draft.write_staged(staging).map_err(|e| e.to_string())
    }))
}

/// Write the report of a run folder being staged ([`Staging`]), naming it
/// by its final place, from the `run.json` it holds now.
pub fn write_staged(staging: &Staging) -> Result<(), ReportError> {
    draft_staged(staging)?.write_staged(staging)
}

/// The scenario a run folder holds (`scenario.toml`, its paths absolute),
/// `None` for a run without one (a `surveyor follow --scene` run).
pub(crate) fn scenario_of(
    folder: &RunFolder,
) -> Result<Option<scenario::LoadedScenario>, ReportError> {
    let Some(text) = folder.scenario_toml()? else {
        return Ok(None);
    };
    let path = folder.path(record::folder::SCENARIO_TOML);
    let scenario = scenario::Scenario::from_toml(&text, &path.display().to_string())?;
    Ok(Some(scenario::LoadedScenario {
        scenario,
        base_dir: folder.dir().to_owned(),
    }))
}
