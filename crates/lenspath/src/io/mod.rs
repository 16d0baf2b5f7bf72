//! Files in and out: image output (PNG, OpenEXR), mesh input (PLY, OBJ) and
//! mesh output (PLY). Every output is written to a temporary name beside the
//! target and renamed, so a reader never sees a half-written file and a failed
//! write never destroys the old one.

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

pub mod image;
pub mod mesh;

/// A hidden name beside `path`, unique to this process.
fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    path.with_file_name(format!(".{name}.{}.tmp", std::process::id()))
}

fn io_error(path: &Path, source: std::io::Error) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Runs `write` on a temporary path beside `path`, then renames the result
/// into place; on failure the temporary file is removed and `path` is untouched.
fn write_atomically(path: &Path, write: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
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

/// Writes `contents` to `path` atomically.
pub fn write_text(path: &Path, contents: &str) -> Result<()> {
    write_atomically(path, |tmp| std::fs::write(tmp, contents).map_err(|e| io_error(path, e)))
}
