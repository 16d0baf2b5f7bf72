//! Files in and out. Scenes come in as COLLADA, OBJ + MTL, PLY, glTF 2.0 or
//! lenspath's TOML scene file ([`load_scene`] picks the loader by extension);
//! images go out as PNG or OpenEXR, meshes as PLY. Every output is written to a
//! temporary name beside the target and renamed, so a reader never sees a
//! half-written file and a failed write never destroys the old one.

use std::path::{Path, PathBuf};

use crate::error::{Error, FileKind, Result};
use crate::shapes::TriangleMesh;

pub mod checkpoint;
pub mod collada;
pub mod gltf;
pub mod image;
pub mod import;
pub mod obj;
pub mod ply;
pub mod scene_file;

pub use import::{LensOptions, LoadedScene, SceneOptions, Warnings};

/// Scene file extensions [`load_scene`] reads, lower case.
pub const SCENE_EXTENSIONS: [&str; 6] = ["dae", "obj", "ply", "gltf", "glb", "toml"];

/// Loads a scene file, choosing the loader by its extension.
pub fn load_scene(path: &Path) -> Result<LoadedScene> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("dae") => collada::load_collada(path),
        Some("obj") => obj::load_obj(path),
        Some("ply") => {
            let mut warnings = Warnings::default();
            let mesh = ply::load_ply(path, &mut warnings)?;
            Ok(import::mesh_scene(mesh, warnings, "PLY"))
        }
        Some("gltf" | "glb") => gltf::load_gltf(path),
        Some("toml") => scene_file::load_scene_file(path),
        _ => Err(Error::InvalidArgument(format!(
            "{}: unknown scene format; lenspath reads .{}",
            path.display(),
            SCENE_EXTENSIONS.join(", .")
        ))),
    }
}

/// All triangles of a scene file as one mesh (for benchmarks and other renderers).
pub fn load_mesh(path: &Path) -> Result<TriangleMesh> {
    let loaded = load_scene(path)?;
    let mut mesh = TriangleMesh::default();
    for m in loaded.scene.meshes {
        let base = mesh.positions.len() as u32;
        mesh.positions.extend(m.positions);
        mesh.indices.extend(m.indices.iter().map(|t| t.map(|v| v + base)));
    }
    Ok(mesh)
}

/// The whole of a text file holding a `kind`, with a clear error for a missing or non-UTF-8 file.
pub fn read_text(path: &Path, kind: FileKind) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|e| io_error(path, e))?;
    String::from_utf8(bytes).map_err(|e| Error::Parse {
        kind,
        path: path.to_path_buf(),
        message: format!("not UTF-8 text (byte {} is invalid)", e.utf8_error().valid_up_to()),
    })
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
