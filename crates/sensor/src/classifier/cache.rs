//! The trained LRC cached on disk ([`Lrc::load_or_train`]), as the C-space
//! model is (`plan::CspaceModel::load_or_build`): training simulates
//! hundreds of observations per material (seconds), and its result depends
//! only on its inputs, which the file records and a load compares.

use super::training::TrainingConfig;
use super::{Lrc, LrcConfig, LrcError};
use crate::scanner::ScannerConfig;
use scene::Material;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Version of the cache file's layout and of the training it stores: a
/// change to either (to [`Lrc::train`] or anything it calls) must bump it,
/// so that older files are trained over.
pub const LRC_CACHE_FORMAT: u32 = 1;

/// How [`Lrc::load_or_train`] obtained the model.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum LrcCacheOutcome {
    /// Read from the cache file.
    Loaded,
    /// Trained (and the cache file written); why the file was not used.
    Trained(String),
}

/// Everything [`Lrc::train`] depends on.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct TrainingInputs {
    config: LrcConfig,
    training: TrainingConfig,
    materials: Vec<Material>,
    scanner: ScannerConfig,
    seed: u64,
}

/// The cache file.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct CacheFile {
    format: u32,
    /// The `sensor` crate's version that wrote it.
    version: String,
    inputs: TrainingInputs,
    lrc: Lrc,
}

impl Lrc {
    /// [`Lrc::train`], or the model a previous call with the same inputs
    /// wrote to `path`. A file that cannot be read or parsed, of another
    /// format or version, or trained on other inputs is trained over (the
    /// outcome says why); a file that cannot be written is an error. The
    /// file is written to a temporary name of its own and renamed, so
    /// neither an interrupted write nor two runs at once leave a half file.
    pub fn load_or_train(
        path: &Path,
        config: LrcConfig,
        training: &TrainingConfig,
        materials: &[Material],
        scanner: &ScannerConfig,
        seed: u64,
    ) -> Result<(Self, LrcCacheOutcome), LrcError> {
        let inputs = TrainingInputs {
            config,
            training: *training,
            materials: materials.to_vec(),
            scanner: *scanner,
            seed,
        };
        let reason = match load(path, &inputs) {
            Ok(lrc) => return Ok((lrc, LrcCacheOutcome::Loaded)),
            Err(reason) => reason,
        };
        let lrc = Self::train(config, training, materials, scanner, seed)?;
        save(path, inputs, &lrc)?;
        Ok((lrc, LrcCacheOutcome::Trained(reason)))
    }
}

/// The model in `path` when it was trained on `inputs`; `Err` says why not.
fn load(path: &Path, inputs: &TrainingInputs) -> Result<Lrc, String> {
    let text = std::fs::read(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => "no cache file yet".to_owned(),
        _ => format!("cannot read it ({e})"),
    })?;
    let file: CacheFile =
        serde_json::from_slice(&text).map_err(|e| format!("not an LRC cache ({e})"))?;
    if file.format != LRC_CACHE_FORMAT || file.version != env!("CARGO_PKG_VERSION") {
        return Err(format!(
            "format {} of version {} (this version {} writes {LRC_CACHE_FORMAT})",
            file.format,
            file.version,
            env!("CARGO_PKG_VERSION")
        ));
    }
    if file.inputs != *inputs {
        return Err(
            "trained on other inputs (materials, scanner, LRC constraints, training or seed)"
                .into(),
        );
    }
    let lrc = file.lrc;
    if lrc.config != inputs.config || lrc.materials.len() != inputs.materials.len() {
        return Err("its model does not match its inputs".into());
    }
    Ok(lrc)
}

/// Write `lrc`, trained on `inputs`, to `path` through a temporary file.
fn save(path: &Path, inputs: TrainingInputs, lrc: &Lrc) -> Result<(), LrcError> {
    static SAVES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let err = |message: String| LrcError::Cache {
        path: path.to_path_buf(),
        message,
    };
    let file = CacheFile {
        format: LRC_CACHE_FORMAT,
        version: env!("CARGO_PKG_VERSION").to_owned(),
        inputs,
        lrc: lrc.clone(),
    };
    let text = serde_json::to_vec(&file).map_err(|e| err(e.to_string()))?;
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| err(format!("cannot create its folder: {e}")))?;
    }
    // A temporary name of this process and call: two runs sharing the
    // default cache file must not write into one temporary file.
    let n = SAVES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp = path.with_extension(format!("tmp.{}.{n}", std::process::id()));
    let written = std::fs::write(&tmp, text)
        .map_err(|e| err(format!("cannot write: {e}")))
        .and_then(|()| {
            std::fs::rename(&tmp, path).map_err(|e| err(format!("cannot rename into place: {e}")))
        });
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}

#[cfg(test)]
mod tests {
    use super::*;

    fn inputs() -> (LrcConfig, TrainingConfig, Vec<Material>, ScannerConfig) {
        let training = TrainingConfig {
            observations_per_material: 12,
            ..TrainingConfig::default()
        };
        let materials = vec![
            Material::new("painted", 0.2, 0.6),
            Material::new("rusty", 0.05, 0.9),
        ];
        (
            LrcConfig::default(),
            training,
            materials,
            ScannerConfig::default(),
        )
    }

    /// A second call loads what the first trained, the same model to the
    /// bit; other inputs, a damaged file and a foreign file are trained over
    /// with the reason said, never a panic; an unwritable path is an error.
    #[test]
    fn the_cache_round_trips_and_refuses_what_is_not_its_own() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("lrc.json");
        let (config, training, materials, scanner) = inputs();
        let train = |seed: u64, materials: &[Material]| {
            Lrc::load_or_train(&path, config, &training, materials, &scanner, seed).unwrap()
        };
        let (first, how) = train(3, &materials);
        assert_eq!(how, LrcCacheOutcome::Trained("no cache file yet".into()));
        assert_eq!(
            first,
            Lrc::train(config, &training, &materials, &scanner, 3).unwrap()
        );
        let (again, how) = train(3, &materials);
        assert_eq!(how, LrcCacheOutcome::Loaded);
        assert_eq!(again, first);
        // Another seed, then other materials: trained over.
        let (other, how) = train(4, &materials);
        assert!(
            matches!(&how, LrcCacheOutcome::Trained(w) if w.contains("other inputs")),
            "{how:?}"
        );
        assert_ne!(other, first);
        let mut rougher = materials.clone();
        rougher[1].roughness = 0.8;
        let (_, how) = train(4, &rougher);
        assert!(
            matches!(&how, LrcCacheOutcome::Trained(w) if w.contains("other inputs")),
            "{how:?}"
        );
        // A damaged file (cut in half), a foreign one, an older format.
        let text = std::fs::read(&path).unwrap();
        std::fs::write(&path, &text[..text.len() / 2]).unwrap();
        let (_, how) = train(4, &rougher);
        assert!(
            matches!(&how, LrcCacheOutcome::Trained(w) if w.contains("not an LRC cache")),
            "{how:?}"
        );
        std::fs::write(&path, b"{\"format\": 1, \"fingerprint\": \"00\"}").unwrap();
        let (_, how) = train(4, &rougher);
        assert!(
            matches!(&how, LrcCacheOutcome::Trained(w) if w.contains("not an LRC cache")),
            "{how:?}"
        );
        let mut v: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&path).unwrap()).unwrap();
        v["format"] = serde_json::json!(LRC_CACHE_FORMAT + 1);
        std::fs::write(&path, serde_json::to_vec(&v).unwrap()).unwrap();
        let (_, how) = train(4, &rougher);
        assert!(
            matches!(&how, LrcCacheOutcome::Trained(w) if w.contains("format")),
            "{how:?}"
        );
        assert_eq!(train(4, &rougher).1, LrcCacheOutcome::Loaded);
        // No temporary file is left beside it.
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
        // A cache path under a file cannot be written: an error that names it.
        let blocked = dir.path().join("lrc.json").join("x.json");
        let e =
            Lrc::load_or_train(&blocked, config, &training, &materials, &scanner, 3).unwrap_err();
        assert!(e.to_string().contains("x.json"), "{e}");
    }
}
