//! Files in and out. Scenes come in as COLLADA, OBJ + MTL, PLY, glTF 2.0 or
//! lenspath's TOML scene file ([`load_scene`] picks the loader by extension);
//! images go out as PNG or OpenEXR, meshes as PLY, each written atomically
//! ([`crate::fs`]).

use std::path::{Path, PathBuf};

use crate::error::{Error, Result};
use crate::fs::io_error;
use crate::shapes::TriangleMesh;

pub mod checkpoint;
pub mod collada;
pub mod exr;
pub mod gltf;
pub mod image;
pub mod import;
pub mod obj;
pub mod ply;
pub mod scene_file;

pub use import::{LensOptions, LoadedScene, SceneOptions, Warnings};

/// Scene file extensions [`load_scene`] reads, lower case.
pub const SCENE_EXTENSIONS: [&str; 6] = ["dae", "obj", "ply", "gltf", "glb", "toml"];

/// The folders a scene may read the files it names from (buffers, material
/// libraries, base scenes, meshes, lens tables): the folder of the scene
/// file the user named, and folders the user allows explicitly. A scene
/// downloaded from the internet cannot read the user's other files
/// (`/etc/passwd` as a glTF buffer, `../../secrets` as a mesh).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ReadScope {
    /// Canonical folders; a file is readable when its canonical path is in one.
    roots: Vec<PathBuf>,
}

impl ReadScope {
    /// The scope of the scene file `scene`: the folder it is named in and the
    /// `allowed` ones (which must exist).
    pub fn of_scene(scene: &Path, allowed: &[PathBuf]) -> Result<ReadScope> {
        let canonical = |p: &Path| p.canonicalize().map_err(|e| io_error(p, e));
        let folder = scene
            .parent()
            .filter(|f| !f.as_os_str().is_empty())
            .unwrap_or(Path::new("."));
        // A missing folder is a missing scene file: name the file.
        let mut roots = vec![folder.canonicalize().map_err(|e| io_error(scene, e))?];
        for dir in allowed {
            roots.push(canonical(dir)?);
        }
        Ok(ReadScope { roots })
    }

    /// `file` (named by a scene) as a path to read, or why it may not be read:
    /// it is outside every folder of the scope (symbolic links and `..`
    /// resolved first).
    pub fn check(&self, file: &Path) -> Result<PathBuf> {
        let canonical = file.canonicalize().map_err(|e| io_error(file, e))?;
        if self.roots.iter().any(|root| canonical.starts_with(root)) {
            return Ok(canonical);
        }
        let roots: Vec<String> = self.roots.iter().map(|r| r.display().to_string()).collect();
        Err(Error::InvalidScene(format!(
            "{} is outside the folders this scene may read ({}); allow its folder explicitly \
             (lenspath --allow-read DIR, Python lenspath.load(..., allow_read=[DIR]))",
            file.display(),
            roots.join(", ")
        )))
    }
}

/// The scene a command line or a script names: a built-in scene's name
/// ([`BUILTIN_SCENES`](crate::builtin::BUILTIN_SCENES); `mesh_triangles`
/// sizes `cornell-mesh`) is that scene, anything else a scene file read
/// within its folder and `allowed` ([`load_scene_in`]). The one rule every
/// front end applies to a scene argument.
pub fn load_named_scene(name: &Path, allowed: &[PathBuf], mesh_triangles: usize) -> Result<LoadedScene> {
    match builtin_scene_named(name) {
        Some(builtin) => LoadedScene::builtin(builtin, mesh_triangles),
        None => load_scene_in(name, &ReadScope::of_scene(name, allowed)?),
    }
}

/// The built-in scene a scene argument names, if it names one (the rule
/// [`load_named_scene`] applies; front ends that hold on to the choice ask
/// this).
pub fn builtin_scene_named(name: &Path) -> Option<&'static str> {
    let name = name.to_str()?;
    crate::builtin::BUILTIN_SCENES
        .into_iter()
        .find(|builtin| *builtin == name)
}

/// Loads a scene file, choosing the loader by its extension; it may read
/// the files it names from its own folder ([`ReadScope::of_scene`]).
pub fn load_scene(path: &Path) -> Result<LoadedScene> {
    load_scene_in(path, &ReadScope::of_scene(path, &[])?)
}

/// [`load_scene`], reading the files the scene names within `scope`.
pub fn load_scene_in(path: &Path, scope: &ReadScope) -> Result<LoadedScene> {
    let loaded = load_scene_as_written(path, scope)?;
    // What compiling would refuse, refused now, naming the file.
    loaded.scene.validate().map_err(|e| Error::Parse {
        kind: crate::FileKind::Scene,
        path: path.to_path_buf(),
        message: e.to_string(),
    })?;
    Ok(loaded)
}

/// [`load_scene_in`] without the final check of the scene as a whole.
fn load_scene_as_written(path: &Path, scope: &ReadScope) -> Result<LoadedScene> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("dae") => collada::load_collada(path),
        Some("obj") => obj::load_obj(path, scope),
        Some("ply") => {
            let mut warnings = Warnings::default();
            let mesh = ply::load_ply(path, &mut warnings)?;
            Ok(import::mesh_scene(mesh, warnings, "PLY"))
        }
        Some("gltf" | "glb") => gltf::load_gltf(path, scope),
        Some("toml") => scene_file::load_scene_file(path, scope),
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
