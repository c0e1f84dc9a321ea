//! Outputs appear whole or not at all: single files are written through
//! [`record::output::Staged`] (temporary names next to their destination,
//! moved into place when the command has succeeded), run folders through
//! [`record::Staging`]; this module adds the `--config` files.

use anyhow::{Context, Result};
use std::path::Path;

pub use record::output::{Staged, check_out_dir};

/// Read a `--config` TOML file into a config struct (`T::default()` when no
/// file is given). Unknown fields and wrong types are errors naming the file,
/// the line and the field.
pub fn load_config<T: serde::de::DeserializeOwned + Default>(path: Option<&Path>) -> Result<T> {
    let Some(path) = path else {
        return Ok(T::default());
    };
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    toml::from_str(&text)
        .map_err(|e| anyhow::anyhow!("{}: {}", path.display(), e.to_string().trim_end()))
}

/// A config as TOML (for `--print-config`).
pub fn config_toml<T: serde::Serialize>(config: &T) -> Result<String> {
    toml::to_string(config).context("formatting the configuration as TOML")
}
