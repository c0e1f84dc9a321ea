//! Run reports: one self-contained HTML page per run folder, with a WebGL
//! 3-D view and the plots the theses draw, made with plotly.js embedded in
//! the page (no network request of any kind).
//!
//! [`write()`] looks at the folder: a `surveyor explore` run (`viewpoints.csv`)
//! gets the view of Paul ch. 6; a `surveyor follow` run (`steps.csv`) the
//! view of Pudney's Figs 44–47.

pub mod data;
pub mod error;
pub mod explore;
pub mod follow;
pub mod geometry;
pub mod page;

pub use error::ReportError;
use std::path::{Path, PathBuf};

/// The page of the run in `dir`.
pub fn render(dir: &Path) -> Result<String, ReportError> {
    let page = if dir.join("viewpoints.csv").exists() {
        explore::page(dir)?
    } else if dir.join("steps.csv").exists() {
        follow::page(dir)?
    } else {
        return Err(ReportError::NotARun {
            dir: dir.display().to_string(),
            message: if dir.is_dir() {
                "not a run folder: expected viewpoints.csv (surveyor explore) or steps.csv \
                 (surveyor follow)"
            } else {
                "no such folder"
            }
            .into(),
        });
    };
    Ok(page.finish())
}

/// Write `dir/report.html`; returns its path.
pub fn write(dir: &Path) -> Result<PathBuf, ReportError> {
    let html = render(dir)?;
    let path = dir.join("report.html");
    std::fs::write(&path, html).map_err(|e| ReportError::file(&path.display().to_string(), e))?;
    Ok(path)
}
