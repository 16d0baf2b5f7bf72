//! The library's error type. The library never prints or exits: callers
//! (the CLI, the Python binding) decide how to report.

use std::path::PathBuf;

/// Everything that can go wrong, each with a message that names the culprit.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A setting or argument is out of range (zero size, spp 0, ...).
    #[error("{0}")]
    InvalidArgument(String),
    /// The scene description is inconsistent (unknown material, NaN vertex, ...).
    #[error("invalid scene: {0}")]
    InvalidScene(String),
    /// A file could not be parsed.
    #[error("{}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// What kind of file it is (a front end picks its exception by it).
        kind: FileKind,
        /// What is wrong, and where in the file.
        message: String,
    },
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's reason.
        source: std::io::Error,
    },
}

/// What a file that failed to parse holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FileKind {
    /// A scene (COLLADA, OBJ + MTL, PLY, glTF, lenspath TOML).
    Scene,
    /// A lens prescription table.
    Lens,
    /// An image (PNG, JPEG, EXR), an aperture mask or a bokeh kernel.
    Image,
    /// A render checkpoint.
    Checkpoint,
    /// Anything else (a JSON report, ...).
    Other,
}

/// Result with the library's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
