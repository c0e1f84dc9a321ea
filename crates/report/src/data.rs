//! Reading a run folder's files: CSV tables by column name, JSON.

use crate::ReportError;
use geom::Real;
use std::path::Path;

/// A CSV table held as text cells, read by column name.
#[derive(Clone, Debug)]
pub struct Table {
    /// The file, for errors.
    pub source: String,
    header: Vec<String>,
    rows: Vec<Vec<String>>,
}

impl Table {
    /// Read `path` (a header row, then records).
    pub fn read(path: &Path) -> Result<Self, ReportError> {
        let source = path.display().to_string();
        let mut reader = csv::ReaderBuilder::new()
            .flexible(false)
            .from_path(path)
            .map_err(|e| ReportError::file(&source, e))?;
        let header = reader
            .headers()
            .map_err(|e| ReportError::file(&source, e))?
            .iter()
            .map(str::to_owned)
            .collect();
        let mut rows = Vec::new();
        for record in reader.records() {
            let record = record.map_err(|e| ReportError::file(&source, e))?;
            rows.push(record.iter().map(str::to_owned).collect());
        }
        Ok(Self {
            source,
            header,
            rows,
        })
    }

    /// Number of records.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// No records.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// Whether the table has column `name`.
    pub fn has(&self, name: &str) -> bool {
        self.header.iter().any(|h| h == name)
    }

    /// Column names starting with `prefix`, in order.
    pub fn columns_with_prefix(&self, prefix: &str) -> Vec<String> {
        self.header
            .iter()
            .filter(|h| h.starts_with(prefix))
            .cloned()
            .collect()
    }

    fn index(&self, name: &str) -> Result<usize, ReportError> {
        self.header
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| ReportError::Field {
                file: self.source.clone(),
                line: 1,
                field: name.to_owned(),
                message: "missing column".into(),
            })
    }

    /// Column `name` parsed cell by cell (`None` for an empty cell when
    /// `empty_ok`); a cell that does not parse is an error naming its line
    /// and `expected`.
    fn parsed<T: std::str::FromStr>(
        &self,
        name: &str,
        empty_ok: bool,
        expected: &str,
    ) -> Result<Vec<Option<T>>, ReportError> {
        let c = self.index(name)?;
        self.rows
            .iter()
            .enumerate()
            .map(|(i, row)| {
                let cell = row[c].trim();
                if empty_ok && cell.is_empty() {
                    return Ok(None);
                }
                cell.parse::<T>().map(Some).map_err(|_| ReportError::Field {
                    file: self.source.clone(),
                    line: i + 2,
                    field: name.to_owned(),
                    message: format!("expected {expected}, found `{cell}`"),
                })
            })
            .collect()
    }

    /// Column `name` as finite numbers; an empty cell is `None`.
    pub fn optional(&self, name: &str) -> Result<Vec<Option<Real>>, ReportError> {
        let values = self.parsed::<Real>(name, true, "a number")?;
        if let Some((i, v)) = values
            .iter()
            .enumerate()
            .find_map(|(i, v)| v.filter(|v| !v.is_finite()).map(|v| (i, v)))
        {
            return Err(ReportError::Field {
                file: self.source.clone(),
                line: i + 2,
                field: name.to_owned(),
                message: format!("expected a finite number, found `{v}`"),
            });
        }
        Ok(values)
    }

    /// Column `name` as numbers, every cell required.
    pub fn numbers(&self, name: &str) -> Result<Vec<Real>, ReportError> {
        self.optional(name)?
            .into_iter()
            .enumerate()
            .map(|(i, v)| {
                v.ok_or_else(|| ReportError::Field {
                    file: self.source.clone(),
                    line: i + 2,
                    field: name.to_owned(),
                    message: "expected a number, found an empty cell".into(),
                })
            })
            .collect()
    }

    /// Column `name` as text.
    pub fn text(&self, name: &str) -> Result<Vec<&str>, ReportError> {
        let c = self.index(name)?;
        Ok(self.rows.iter().map(|row| row[c].trim()).collect())
    }

    /// Column `name` as non-negative integers.
    pub fn indices(&self, name: &str) -> Result<Vec<usize>, ReportError> {
        Ok(self
            .parsed(name, false, "a non-negative integer")?
            .into_iter()
            .flatten()
            .collect())
    }
}

/// Read a JSON file.
pub fn read_json(path: &Path) -> Result<serde_json::Value, ReportError> {
    parse_json(path)
}

/// Read a run's `run.json`: a JSON object naming its `scenario`.
pub fn read_run_json(path: &Path) -> Result<serde_json::Value, ReportError> {
    let run = read_json(path)?;
    if !run.is_object() || !run["scenario"].is_string() {
        return Err(ReportError::file(
            &path.display().to_string(),
            "expected a JSON object with a `scenario` string, as surveyor writes run.json",
        ));
    }
    Ok(run)
}

/// Read a JSON file into `T`; an error names the file, line and column.
pub fn parse_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, ReportError> {
    let source = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| ReportError::file(&source, e))?;
    // serde_json's message ends with "at line L column C".
    serde_json::from_str(&text).map_err(|e| ReportError::file(&source, e))
}
