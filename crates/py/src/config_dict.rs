//! Configuration dicts: a Python dict of a library `*Config`'s fields in
//! (through JSON and the config's own serde rules: defaults for missing
//! fields, unknown fields refused), the config in effect out as a dict.
//!
//! Every problem is a `ValueError` naming the argument and the key:
//! `config['lamda']: unknown field ...`, `config['mu_deg']: invalid type ...`,
//! `config['lambda']: Out of range float values are not JSON compliant` (a
//! NaN or an infinity).

use crate::errors::value_error;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};
use serde::Serialize;
use serde::de::DeserializeOwned;
use serde_json::{Map, Value};

/// The config `T` from the dict `obj` (argument `name`), or `T::default()`
/// for `None`. Missing fields keep their defaults; range checks are the
/// caller's (the config's `validate`).
pub fn config_from_dict<T: DeserializeOwned + Default>(
    name: &str,
    obj: Option<&Bound<'_, PyAny>>,
) -> PyResult<T> {
    let Some(obj) = obj.filter(|o| !o.is_none()) else {
        return Ok(T::default());
    };
    let py = obj.py();
    let dict = obj.cast::<PyDict>().map_err(|_| {
        value_error(format!(
            "{name}: expected a dict of configuration fields, got a {}",
            obj.get_type()
                .name()
                .map_or_else(|_| "object".to_owned(), |n| n.to_string())
        ))
    })?;
    let dumps = py.import("json")?.getattr("dumps")?;
    let kwargs = PyDict::new(py);
    kwargs.set_item("allow_nan", false)?;
    let mut map = Map::new();
    for (key, value) in dict.iter() {
        let key: String = key
            .cast::<PyString>()
            .map_err(|_| value_error(format!("{name}: keys must be field names (str), got {key}")))?
            .to_string();
        let text: String = dumps
            .call((&value,), Some(&kwargs))
            .map_err(|e| value_error(format!("{name}['{key}']: {}", e.value(py))))?
            .extract()?;
        let value: Value = serde_json::from_str(&text)
            .map_err(|e| value_error(format!("{name}['{key}']: {e}")))?;
        map.insert(key, value);
    }
    match serde_json::from_value::<T>(Value::Object(map.clone())) {
        Ok(config) => Ok(config),
        Err(e) => {
            // Name the key: the first that fails on its own.
            for (key, value) in &map {
                let alone = Map::from_iter([(key.clone(), value.clone())]);
                if let Err(e) = serde_json::from_value::<T>(Value::Object(alone)) {
                    return Err(value_error(format!("{name}['{key}']: {e}")));
                }
            }
            Err(value_error(format!("{name}: {e}")))
        }
    }
}

/// A serialisable value (a config, a report) as Python objects: dicts,
/// lists, numbers, strings, `None`.
pub fn to_python<'py>(py: Python<'py>, value: &impl Serialize) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(value)
        .map_err(|e| value_error(format!("formatting the value as JSON: {e}")))?;
    py.import("json")?.getattr("loads")?.call1((text,))
}
