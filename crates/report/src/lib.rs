#![doc = include_str!("../README.md")]
//!
//! # Map of the crate
//!
//! [`write()`] (and [`write_staged`] for a folder being staged) opens the
//! folder through [`record::RunFolder`] (its format version checked there): a
//! `surveyor explore` run gets the page of [`explore`] (Paul ch. 6), a
//! `surveyor follow` run the page of [`follow`] (Pudney's Figs 44–47); the
//! page ([`page`]) embeds plotly.js, so it opens offline.

pub mod error;
pub mod explore;
pub mod follow;
pub mod geometry;
pub mod page;

pub use error::ReportError;
use record::{RunFolder, RunKind, Staging};
use std::path::{Path, PathBuf};

/// The page of the run in `dir`, naming the folder `shown`.
pub fn render_as(dir: &Path, shown: &Path) -> Result<String, ReportError> {
    let folder = RunFolder::open(dir)?;
    let page = match folder.kind() {
        RunKind::Explore => explore::page(&folder, shown)?,
        RunKind::Follow => follow::page(&folder, shown)?,
    };
    Ok(page.finish())
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

/// Write the report of a run folder being staged ([`Staging`]), naming it
/// by its final place.
pub fn write_staged(staging: &Staging) -> Result<(), ReportError> {
    let html = render_as(staging.dir(), staging.out())?;
    staging.write(record::folder::REPORT_HTML, html)?;
    Ok(())
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
