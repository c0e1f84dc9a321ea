//! Reading a run folder's tables (CSV, by column name) and JSON files, each
//! error naming the file, line and field.

use crate::RecordError;
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
    pub fn read(path: &Path) -> Result<Self, RecordError> {
        let source = path.display().to_string();
        let mut reader = csv::ReaderBuilder::new()
            .flexible(false)
            .from_path(path)
            .map_err(|e| csv_error(&source, &e))?;
        let header = reader
            .headers()
            .map_err(|e| csv_error(&source, &e))?
            .iter()
            .map(str::to_owned)
            .collect();
        let mut rows = Vec::new();
        for record in reader.records() {
            let record = record.map_err(|e| csv_error(&source, &e))?;
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

    /// Number of columns.
    pub fn width(&self) -> usize {
        self.header.len()
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

    fn index(&self, name: &str) -> Result<usize, RecordError> {
        self.header
            .iter()
            .position(|h| h == name)
            .ok_or_else(|| RecordError::Field {
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
    ) -> Result<Vec<Option<T>>, RecordError> {
        let c = self.index(name)?;
        self.rows
            .iter()
            .enumerate()
            .map(|(i, row)| {
                let cell = row[c].trim();
                if empty_ok && cell.is_empty() {
                    return Ok(None);
                }
                cell.parse::<T>().map(Some).map_err(|_| RecordError::Field {
                    file: self.source.clone(),
                    line: i + 2,
                    field: name.to_owned(),
                    message: format!("expected {expected}, found `{cell}`"),
                })
            })
            .collect()
    }

    /// Column `name` as finite numbers; an empty cell is `None`.
    pub fn optional(&self, name: &str) -> Result<Vec<Option<Real>>, RecordError> {
        let values = self.parsed::<Real>(name, true, "a number")?;
        if let Some((i, v)) = values
            .iter()
            .enumerate()
            .find_map(|(i, v)| v.filter(|v| !v.is_finite()).map(|v| (i, v)))
        {
            return Err(RecordError::Field {
                file: self.source.clone(),
                line: i + 2,
                field: name.to_owned(),
                message: format!("expected a finite number, found `{v}`"),
            });
        }
        Ok(values)
    }

    /// Column `name` as numbers, every cell required.
    pub fn numbers(&self, name: &str) -> Result<Vec<Real>, RecordError> {
        self.optional(name)?
            .into_iter()
            .enumerate()
            .map(|(i, v)| {
                v.ok_or_else(|| RecordError::Field {
                    file: self.source.clone(),
                    line: i + 2,
                    field: name.to_owned(),
                    message: "expected a number, found an empty cell".into(),
                })
            })
            .collect()
    }

    /// Column `name` as text.
    pub fn text(&self, name: &str) -> Result<Vec<&str>, RecordError> {
        let c = self.index(name)?;
        Ok(self.rows.iter().map(|row| row[c].trim()).collect())
    }

    /// Column `name` as non-negative integers; an empty cell is `None`.
    pub fn optional_indices(&self, name: &str) -> Result<Vec<Option<usize>>, RecordError> {
        self.parsed(name, true, "a non-negative integer or nothing")
    }

    /// Column `name` as non-negative integers.
    pub fn indices(&self, name: &str) -> Result<Vec<usize>, RecordError> {
        Ok(self
            .parsed(name, false, "a non-negative integer")?
            .into_iter()
            .flatten()
            .collect())
    }
}

/// A `csv` crate error as a [`RecordError`]: a record of the wrong length
/// names its line and the lengths, anything else keeps the crate's text.
fn csv_error(source: &str, e: &csv::Error) -> RecordError {
    if let csv::ErrorKind::UnequalLengths {
        pos,
        expected_len,
        len,
    } = e.kind()
    {
        return RecordError::Field {
            file: source.to_owned(),
            line: pos.as_ref().map_or(0, |p| p.line() as usize),
            field: "(row)".into(),
            message: format!("expected {expected_len} fields as in the header, found {len}"),
        };
    }
    RecordError::named(source, e)
}

/// Read a JSON file into `T`; an error names the file, line and column.
pub fn read_json<T: serde::de::DeserializeOwned>(path: &Path) -> Result<T, RecordError> {
    let text = std::fs::read_to_string(path).map_err(|e| RecordError::file(path, e))?;
    // serde_json's message ends with "at line L column C".
    serde_json::from_str(&text).map_err(|e| RecordError::file(path, e))
}
