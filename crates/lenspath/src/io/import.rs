//! What every scene loader shares: the loaded result ([`LoadedScene`]) with
//! the render settings a file may carry ([`SceneOptions`]), counted warnings, a
//! polygon-to-triangle mesh builder that skips degenerate faces, and the
//! defaults a bare mesh file needs (a camera that frames it, a light).

use std::collections::BTreeMap;
use std::fmt;

use glam::{Mat4, Vec3};

use crate::camera::CameraPose;
use crate::error::Result;
use crate::lights::Light;
use crate::materials::Material;
use crate::math::{Bounds3, Rgb};
pub use crate::options::{LensOptions, SceneOptions};
use crate::scene::{Scene, SceneView};
use crate::shapes::{MaterialId, TriangleMesh};

/// Vertical field of view of the camera lenspath adds to a file that has none (degrees).
pub const DEFAULT_FOV_Y_DEG: f32 = 40.0;

/// Most triangles a file may expand to (through instancing, or a header's
/// counts): beyond this a loader fails fast instead of exhausting memory.
pub const MAX_TRIANGLES: usize = 200_000_000;

/// A scene read from a file, with what the file says about rendering it.
#[derive(Clone, Debug)]
pub struct LoadedScene {
    /// Shapes, materials, lights and the view (always set: a file without a
    /// camera gets one that frames its bounds).
    pub scene: Scene,
    /// Render settings the file gives (the CLI's flags override them).
    pub options: SceneOptions,
    /// Cameras the file defines (the first is used).
    pub cameras: usize,
    /// Recoverable oddities that were skipped or replaced, counted.
    pub warnings: Warnings,
    /// Format name ("COLLADA", "OBJ", "PLY", "glTF", "lenspath TOML").
    pub format: &'static str,
}

/// Warnings counted by kind, in the order first seen.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Warnings {
    order: Vec<String>,
    counts: BTreeMap<String, usize>,
}

impl LoadedScene {
    /// A loader's result, completed by [`complete_scene`] (a camera and a light when missing).
    pub fn completed(
        mut scene: Scene,
        options: SceneOptions,
        cameras: usize,
        mut warnings: Warnings,
        format: &'static str,
    ) -> Self {
        complete_scene(&mut scene, &mut warnings);
        LoadedScene {
            scene,
            options,
            cameras,
            warnings,
            format,
        }
    }

    /// The built-in scene `name` as if loaded from a file: one camera, its
    /// format "built-in", no settings and no warnings.
    pub fn builtin(name: &str, mesh_triangles: usize) -> Result<Self> {
        Ok(LoadedScene {
            scene: crate::builtin::builtin_scene(name, mesh_triangles)?,
            options: SceneOptions::default(),
            cameras: 1,
            warnings: Warnings::default(),
            format: "built-in",
        })
    }
}

impl Warnings {
    /// Records `count` occurrences of `what` (nothing when `count` is 0).
    pub fn add_n(&mut self, what: impl Into<String>, count: usize) {
        if count == 0 {
            return;
        }
        let what = what.into();
        match self.counts.get_mut(&what) {
            Some(n) => *n += count,
            None => {
                self.order.push(what.clone());
                self.counts.insert(what, count);
            }
        }
    }

    /// Records one occurrence of `what`.
    pub fn add(&mut self, what: impl Into<String>) {
        self.add_n(what, 1);
    }

    /// True when nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.order.is_empty()
    }

    /// Each kind with its count, in the order first seen.
    pub fn iter(&self) -> impl Iterator<Item = (&str, usize)> {
        self.order.iter().map(|w| (w.as_str(), self.counts[w]))
    }
}

impl fmt::Display for Warnings {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, (what, n)) in self.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            if n == 1 {
                write!(f, "{what}")?;
            } else {
                write!(f, "{what} (×{n})")?;
            }
        }
        Ok(())
    }
}

/// Builds one triangle mesh from polygons, fan-triangulating them and leaving
/// out degenerate triangles (repeated corners or zero area), which are counted.
#[derive(Default)]
pub struct MeshBuilder {
    /// The mesh so far.
    pub mesh: TriangleMesh,
    /// Degenerate triangles left out.
    pub degenerate: usize,
    /// Polygons with fewer than three corners left out.
    pub short_polygons: usize,
}

impl MeshBuilder {
    /// Adds a polygon of vertex indices (already checked to be in range).
    pub fn polygon(&mut self, corners: &[u32]) {
        if corners.len() < 3 {
            self.short_polygons += 1;
            return;
        }
        for k in 1..corners.len() - 1 {
            self.triangle([corners[0], corners[k], corners[k + 1]]);
        }
    }

    /// Adds a triangle of vertex indices (already checked to be in range).
    pub fn triangle(&mut self, t: [u32; 3]) {
        let p = &self.mesh.positions;
        let [a, b, c] = t.map(|i| p[i as usize]);
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] || (b - a).cross(c - a).length_squared() == 0.0 {
            self.degenerate += 1;
        } else {
            self.mesh.indices.push(t);
        }
    }

    /// The mesh, recording what was left out in `warnings` under `what` (a file or element name).
    pub fn finish(self, what: &str, warnings: &mut Warnings) -> TriangleMesh {
        warnings.add_n(format!("{what}: skipped degenerate triangles"), self.degenerate);
        warnings.add_n(
            format!("{what}: skipped polygons with fewer than 3 vertices"),
            self.short_polygons,
        );
        self.mesh
    }
}

/// `mesh` moved by `m`: positions as points, normals by the inverse transpose;
/// a mirroring transform reverses the winding so the front face stays in front.
pub fn transform_mesh(mesh: &mut TriangleMesh, m: &Mat4) {
    for p in &mut mesh.positions {
        *p = m.transform_point3(*p);
    }
    if let Some(normals) = &mut mesh.normals {
        let normal_matrix = m.inverse().transpose();
        for n in normals.iter_mut() {
            *n = normal_matrix.transform_vector3(*n).normalize_or_zero();
        }
    }
    if m.determinant() < 0.0 {
        for t in &mut mesh.indices {
            t.swap(1, 2);
        }
    }
}

/// Bounds of every shape in `scene` (empty when it has none).
pub fn scene_bounds(scene: &Scene) -> Bounds3 {
    let mut b = Bounds3::EMPTY;
    for m in &scene.meshes {
        for &p in &m.positions {
            b = b.grow(p.into());
        }
    }
    for s in &scene.spheres {
        b = b.union(s.bounds());
    }
    b
}

/// The distance from `pose`'s eye to the centre of `bounds`, along the view axis:
/// the focus distance a file's camera gets when the file does not give one.
pub fn subject_distance(pose: &CameraPose, bounds: &Bounds3) -> f32 {
    let eye = pose.render_from_camera.translation;
    let forward = pose.render_from_camera.matrix3.z_axis;
    let along = forward.dot(bounds.centroid() - eye);
    if along.is_finite() && along > 0.0 {
        along
    } else {
        1.0
    }
}

/// Sets the view's focus distance to [`subject_distance`] of the scene's bounds.
pub fn focus_on_subject(scene: &mut Scene) {
    let bounds = scene_bounds(scene);
    if let Some(view) = &mut scene.view {
        view.focus_distance = subject_distance(&view.pose, &bounds);
    }
}

/// Gives a scene what rendering needs when its file left it out: a camera on
/// the +z side framing the bounds (y up), and, when nothing emits light, a
/// white environment. Each addition is a warning.
pub fn complete_scene(scene: &mut Scene, warnings: &mut Warnings) {
    let bounds = scene_bounds(scene);
    if scene.view.is_none() && !bounds.is_empty() {
        let center = Vec3::from(bounds.centroid());
        let radius = 0.5 * bounds.diagonal().length();
        let distance = radius / (0.5 * DEFAULT_FOV_Y_DEG.to_radians()).sin();
        let eye = center + Vec3::Z * distance;
        let pose = CameraPose::look_at(eye, center, Vec3::Y);
        scene.view = Some(SceneView {
            pose,
            fov_y_deg: DEFAULT_FOV_Y_DEG,
            focus_distance: distance,
        });
        warnings.add("no camera: added one on the +z side that frames the whole scene");
    }
    let emits = scene
        .meshes
        .iter()
        .any(|m| m.emission.as_ref().is_some_and(|e| !e.is_black()))
        || scene
            .spheres
            .iter()
            .any(|s| s.emission.as_ref().is_some_and(|e| !e.is_black()));
    if scene.lights.is_empty() && !emits {
        scene.lights.push(Light::Environment {
            radiance: Rgb::ONE.into(),
        });
        warnings.add("no lights: added a white environment light (radiance 1)");
    }
}

/// A scene of one mesh (a PLY file) in grey diffuse, completed with a camera and light.
pub fn mesh_scene(mut mesh: TriangleMesh, warnings: Warnings, format: &'static str) -> LoadedScene {
    let mut scene = Scene::default();
    mesh.material = intern_material(&mut scene, DEFAULT_MATERIAL);
    scene.meshes.push(mesh);
    LoadedScene::completed(scene, SceneOptions::default(), 0, warnings, format)
}

/// Index of `material` in `scene.materials`, adding it when new.
pub fn intern_material(scene: &mut Scene, material: Material) -> MaterialId {
    match scene.materials.iter().position(|m| *m == material) {
        Some(i) => i as MaterialId,
        None => {
            scene.materials.push(material);
            (scene.materials.len() - 1) as MaterialId
        }
    }
}

/// A conductor whose normal-incidence reflectance is `f0` (per channel), for
/// formats that describe metals by colour: with η = 1 the Fresnel reflectance
/// at normal incidence is k²/(4 + k²), so k = 2√(f0 / (1 − f0)).
pub fn conductor_from_reflectance(f0: Rgb, alpha: f32) -> Material {
    let f0 = f0.clamp(Rgb::ZERO, Rgb::splat(0.999));
    Material::Conductor {
        eta: Rgb::ONE,
        k: 2.0 * (f0 / (Rgb::ONE - f0)).powf(0.5),
        alpha,
    }
}

/// Reflectance of surfaces whose file gives no colour.
pub const DEFAULT_REFLECTANCE: Rgb = Rgb::splat(0.8);

/// Grey diffuse, for geometry without a material.
pub const DEFAULT_MATERIAL: Material = Material::Diffuse {
    reflectance: DEFAULT_REFLECTANCE,
};

/// Black diffuse, the surface of emitters.
pub const EMITTER_MATERIAL: Material = Material::Diffuse { reflectance: Rgb::ZERO };
