//! Files on disk as the library reads and writes them: the whole of a text
//! file with a clear error, errors that name their file, and atomic writes
//! (a temporary name beside the target, then a rename), so a reader never
//! sees a half-written file and a failed write never destroys the old one.
//! A leaf: the scene loaders, the lens formats and the sensor's raw files
//! all use it.

use std::path::{Path, PathBuf};

use crate::error::{Error, FileKind, Result};

/// The whole of a text file holding a `kind`, with a clear error for a missing or non-UTF-8 file.
pub fn read_text(path: &Path, kind: FileKind) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|e| io_error(path, e))?;
    String::from_utf8(bytes).map_err(|e| Error::Parse {
        kind,
        path: path.to_path_buf(),
        message: format!("not UTF-8 text (byte {} is invalid)", e.utf8_error().valid_up_to()),
    })
}

/// Removes the temporary files beside `path` that writers killed before
/// their rename left (`.NAME.PID.tmp` of a process no longer running, on
/// systems with `/proc`); best effort, silent.
pub fn remove_stale_temporaries(path: &Path) {
    let proc = Path::new("/proc");
    let Some(name) = path.file_name() else {
        return;
    };
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    if !proc.is_dir() {
        return;
    }
    let prefix = format!(".{}.", name.to_string_lossy());
    for entry in entries.flatten() {
        let file = entry.file_name();
        let pid = file
            .to_str()
            .and_then(|f| f.strip_prefix(&prefix))
            .and_then(|rest| rest.strip_suffix(".tmp"))
            .and_then(|pid| pid.parse::<u32>().ok());
        if pid.is_some_and(|pid| !proc.join(pid.to_string()).exists()) {
            let _ = std::fs::remove_file(entry.path());
        }
    }
}

/// A hidden name beside `path`, unique to this process.
fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

/// An I/O error that names the file it happened to.
pub fn io_error(path: &Path, source: std::io::Error) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Runs `write` on a temporary path beside `path`, then renames the result
/// into place; on failure the temporary file is removed and `path` is untouched.
pub(crate) fn write_atomically(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let tmp = temp_path(path);
    if let Err(e) = write(&tmp) {
        let _ = std::fs::remove_file(&tmp);
        return Err(e);
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        io_error(path, e)
    })
}

/// Fails unless a file can be written at `path` (not a directory, its folder
/// exists and is writable), before any slow work that would end by writing it.
pub fn check_writable(path: &Path) -> Result<()> {
    if path.is_dir() {
        return Err(Error::InvalidArgument(format!("{} is a directory", path.display())));
    }
    let probe = temp_path(path);
    std::fs::File::create(&probe).map_err(|e| io_error(path, e))?;
    let _ = std::fs::remove_file(&probe);
    Ok(())
}

/// Writes `contents` to `path` atomically.
pub fn write_text(path: &Path, contents: &str) -> Result<()> {
    write_atomically(path, |tmp| std::fs::write(tmp, contents).map_err(|e| io_error(path, e)))
}

/// Writes `bytes` to `path` atomically (a temporary file renamed into place).
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomically(path, |tmp| std::fs::write(tmp, bytes).map_err(|e| io_error(path, e)))
}
