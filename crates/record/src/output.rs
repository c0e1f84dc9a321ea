//! Outputs appear whole or not at all: every command writes its files under
//! temporary names next to their destination and renames them into place
//! only when the whole command has succeeded. When a command fails, nothing
//! new is left behind: temporary files are removed, and so is an output
//! folder the command created. A process killed mid-way (Ctrl-C) may leave
//! hidden `.surveyor-tmp-<pid>-*` files, but never a partial file under an
//! output's own name.

use crate::RecordError;
use std::path::{Path, PathBuf};

type Result<T> = std::result::Result<T, RecordError>;

/// A set of output files staged under temporary names.
#[derive(Debug, Default)]
pub struct Staged {
    /// (temporary, final) pairs.
    files: Vec<(PathBuf, PathBuf)>,
    /// Folders this command created (deepest last), removed on failure.
    created: Vec<PathBuf>,
    committed: bool,
}

impl Staged {
    /// Nothing staged yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Make sure `dir` exists, creating it (and missing parents) if needed;
    /// folders created here are removed again unless the outputs are committed.
    pub fn ensure_dir(&mut self, dir: &Path) -> Result<()> {
        let mut missing = Vec::new();
        let mut d = Some(dir);
        while let Some(p) = d {
            if p.as_os_str().is_empty() || p.exists() {
                break;
            }
            missing.push(p.to_owned());
            d = p.parent();
        }
        create_out_dir(dir)?;
        self.created.extend(missing.into_iter().rev());
        Ok(())
    }

    /// The temporary path to write `dest` under (its folder is created if
    /// missing). The file appears at `dest` on [`Staged::commit`]. A symbolic
    /// link is followed (its target is written); a device, FIFO or socket is
    /// written in place, not replaced; a folder is an error.
    pub fn file(&mut self, dest: &Path) -> Result<PathBuf> {
        let dest = follow_link(dest)?;
        match std::fs::metadata(&dest) {
            Ok(m) if m.is_dir() => {
                return Err(RecordError::file(
                    &dest,
                    "is a folder, expected a file path",
                ));
            }
            Ok(m) if !m.is_file() => {
                self.files.push((dest.clone(), dest.clone()));
                return Ok(dest);
            }
            _ => {}
        }
        if let Some(parent) = dest.parent() {
            self.ensure_dir(parent)?;
        }
        let name = dest
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        // Keep the extension last: writers choose the format by it.
        let tmp = dest.with_file_name(format!(".{}-{name}", tag()));
        self.files.push((tmp.clone(), dest));
        Ok(tmp)
    }

    /// The temporary path for `name` inside the output folder `dir`.
    pub fn file_in(&mut self, dir: &Path, name: &str) -> Result<PathBuf> {
        self.file(&dir.join(name))
    }

    /// Move every staged file into place.
    pub fn commit(mut self) -> Result<()> {
        for (tmp, dest) in &self.files {
            if tmp == dest {
                continue;
            }
            std::fs::rename(tmp, dest).map_err(|e| {
                RecordError::file(dest, format!("moving the output into place: {e}"))
            })?;
        }
        self.committed = true;
        Ok(())
    }
}

/// An error when `dir` exists and is not a folder (checked before the work
/// whose outputs go there).
pub fn check_out_dir(dir: &Path) -> Result<()> {
    if dir.exists() && !dir.is_dir() {
        return Err(RecordError::file(dir, "exists and is not a folder"));
    }
    Ok(())
}

/// Create the output folder `dir` (and missing parents) unless it exists.
pub fn create_out_dir(dir: &Path) -> Result<()> {
    check_out_dir(dir)?;
    std::fs::create_dir_all(dir).map_err(|e| RecordError::file(dir, format!("creating: {e}")))
}

/// `path`, or the file a symbolic link at `path` points to (followed to the
/// end; a dangling link's last target, to be created).
fn follow_link(path: &Path) -> Result<PathBuf> {
    let mut p = path.to_owned();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&p) {
            Ok(m) if m.file_type().is_symlink() => {
                let target = std::fs::read_link(&p)
                    .map_err(|e| RecordError::file(&p, format!("reading the link: {e}")))?;
                p = match p.parent() {
                    Some(dir) if target.is_relative() => dir.join(target),
                    _ => target,
                };
            }
            _ => return Ok(p),
        }
    }
    Err(RecordError::file(path, "too many levels of symbolic links"))
}

/// A name part unique to this process.
fn tag() -> String {
    format!("surveyor-tmp-{}", std::process::id())
}

impl Drop for Staged {
    fn drop(&mut self) {
        if self.committed {
            return;
        }
        for (tmp, dest) in &self.files {
            if tmp == dest {
                continue;
            }
            let _ = std::fs::remove_file(tmp);
        }
        // Only folders that are empty again (remove_dir refuses others).
        for dir in self.created.iter().rev() {
            let _ = std::fs::remove_dir(dir);
        }
    }
}

/// Write `bytes` to `path` through a temporary name of this process and call
/// in the same folder, renamed into place (an interruption leaves the file
/// as it was; two processes writing one path never share a temporary file).
/// The folder is created when missing.
pub fn replace_file(path: &Path, bytes: &[u8]) -> Result<()> {
    static WRITES: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)
            .map_err(|e| RecordError::file(dir, format!("cannot create the folder: {e}")))?;
    }
    let n = WRITES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp = path.with_extension(format!("tmp.{}.{n}", std::process::id()));
    let written = std::fs::write(&tmp, bytes)
        .map_err(|e| RecordError::file(path, format!("cannot write: {e}")))
        .and_then(|()| {
            std::fs::rename(&tmp, path)
                .map_err(|e| RecordError::file(path, format!("cannot rename into place: {e}")))
        });
    if written.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    written
}
