//! Scenes: built-in, loaded from files or built in Python; each keeps its
//! compiled form (BVH and lights) for the next render.

use std::path::PathBuf;
use std::sync::{Arc, OnceLock};

use glam::Vec3;
use lenspath::accel::BvhSettings;
use lenspath::autofocus::{FocusMeasure, SensorSignal, Strategy};
use lenspath::builtin::{builtin_scene, BUILTIN_SCENES, DEFAULT_MESH_TRIANGLES};
use lenspath::camera::CameraPose;
use lenspath::glass::Dispersion;
use lenspath::integrator::IntegratorKind;
use lenspath::io::{load_scene_in, ReadScope};
use lenspath::lights::Light;
use lenspath::materials::Material;
use lenspath::names::Named;
use lenspath::options::SceneOptions;
use lenspath::sampling::SamplerKind;
use lenspath::scene::{CompiledScene, Scene as CoreScene, SceneView};
use lenspath::shapes::{Sphere, TriangleMesh};
use lenspath::spectrum::Emission as LibraryEmission;
use numpy::{AllowTypeChange, PyArrayLike2, PyUntypedArrayMethods};
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::emission::Emission;
use crate::error::{deprecated, guarded, renamed, to_py, value_error};

/// Where a [`Scene`] came from: how to make it again (pickling it, and
/// `lenspath.distributed`'s workers, need that).
#[derive(Clone, Debug)]
pub(crate) enum SceneOrigin {
    /// `Scene.builtin(name, mesh_triangles)`.
    Builtin(String, usize),
    /// `load(path, allow_read)`.
    File(PathBuf, Vec<PathBuf>),
    /// Built or changed in Python.
    Python,
}

/// A scene: shapes, materials, lights and the view it was made for.
#[pyclass(module = "lenspath._core")]
#[derive(Clone)]
pub(crate) struct Scene {
    pub(crate) name: String,
    pub(crate) scene: CoreScene,
    pub(crate) options: SceneOptions,
    pub(crate) origin: SceneOrigin,
    /// Its BVH, built by the first render and kept for the next ones until the scene changes.
    pub(crate) compiled: OnceLock<Arc<CompiledScene>>,
}

#[pymethods]
impl Scene {
    /// An empty scene (add shapes, lights and a view to it).
    #[new]
    pub(crate) fn new() -> Self {
        Scene {
            name: "scene".into(),
            scene: CoreScene::default(),
            options: SceneOptions::default(),
            origin: SceneOrigin::Python,
            compiled: OnceLock::new(),
        }
    }

    /// A built-in scene by name (see `builtin_scenes()`).
    #[staticmethod]
    #[pyo3(signature = (name, mesh_triangles = DEFAULT_MESH_TRIANGLES),
           text_signature = "(name, mesh_triangles=1000000)")]
    pub(crate) fn builtin(name: &str, mesh_triangles: usize) -> PyResult<Self> {
        Ok(Scene {
            name: name.into(),
            scene: builtin_scene(name, mesh_triangles).map_err(to_py)?,
            options: SceneOptions::default(),
            origin: SceneOrigin::Builtin(name.into(), mesh_triangles),
            compiled: OnceLock::new(),
        })
    }

    /// The file it was loaded from, or the built-in scene's name; None once changed in Python.
    #[getter]
    pub(crate) fn source(&self) -> Option<String> {
        match &self.origin {
            SceneOrigin::Builtin(name, _) => Some(name.clone()),
            SceneOrigin::File(path, _) => Some(path.display().to_string()),
            SceneOrigin::Python => None,
        }
    }

    /// Builds its BVH now, on `threads` threads (default: all cores);
    /// otherwise the first render does, on that render's threads. Kept
    /// until the scene changes; the tree is the same for any thread count.
    #[pyo3(signature = (*, threads = None))]
    pub(crate) fn compile(&self, py: Python<'_>, threads: Option<usize>) -> PyResult<()> {
        self.compiled(py, threads).map(|_| ())
    }

    /// Pickles as the way to make it again: `Scene.builtin(...)` or `load(path)`.
    pub(crate) fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let module = py.import("lenspath._core")?;
        match &self.origin {
            SceneOrigin::Builtin(name, triangles) => Ok((
                module.getattr("Scene")?.getattr("builtin")?,
                (name.clone(), *triangles).into_pyobject(py)?,
            )),
            SceneOrigin::File(path, allowed) => Ok((
                module.getattr("load")?,
                (path.clone(), allowed.clone()).into_pyobject(py)?,
            )),
            SceneOrigin::Python => Err(PyTypeError::new_err(format!(
                "scene '{}' was built or changed in Python and cannot be pickled; save it as a scene file \
                 and load that (lenspath.load) to send it to other processes",
                self.name
            ))),
        }
    }

    #[getter]
    pub(crate) fn name(&self) -> &str {
        &self.name
    }

    #[getter]
    pub(crate) fn mesh_count(&self) -> usize {
        self.scene.meshes.len()
    }

    #[getter]
    pub(crate) fn triangle_count(&self) -> usize {
        self.scene.triangle_count()
    }

    #[getter]
    pub(crate) fn sphere_count(&self) -> usize {
        self.scene.spheres.len()
    }

    #[getter]
    pub(crate) fn material_count(&self) -> usize {
        self.scene.materials.len()
    }

    #[getter]
    pub(crate) fn light_count(&self) -> usize {
        self.scene.lights.len() + self.scene.emitter_count()
    }

    /// The image size the scene file asks for, or None.
    #[getter]
    pub(crate) fn resolution(&self) -> Option<(u32, u32)> {
        self.options.resolution
    }

    /// Adds a material: `kind` is "diffuse" (reflectance), "mirror"
    /// (reflectance), "dielectric" (eta, or a catalogue `glass`, or `n_d`
    /// with `v_d`) or "conductor" (eta and k, or a measured `metal`; alpha:
    /// the GGX roughness), as in scene files; returns its index. "glass",
    /// "metal" and `roughness` are the deprecated old names.
    #[pyo3(signature = (kind, *, reflectance = (0.8, 0.8, 0.8), eta = None, k = None, alpha = None, roughness = None, glass = None, n_d = None, v_d = None, metal = None),
           text_signature = "($self, kind, *, reflectance=(0.8, 0.8, 0.8), eta=None, k=None, alpha=None, roughness=None, glass=None, n_d=None, v_d=None, metal=None)")]
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn add_material(
        &mut self,
        py: Python<'_>,
        kind: &str,
        reflectance: (f32, f32, f32),
        eta: Option<(f32, f32, f32)>,
        k: Option<(f32, f32, f32)>,
        alpha: Option<f32>,
        roughness: Option<f32>,
        glass: Option<&str>,
        n_d: Option<f64>,
        v_d: Option<f64>,
        metal: Option<&str>,
    ) -> PyResult<u32> {
        let alpha = renamed(
            py,
            "add_material",
            ("alpha", alpha),
            ("roughness", roughness),
            "the same GGX alpha",
        )?
        .unwrap_or(0.0);
        let kind = match kind {
            "glass" | "metal" => {
                let new = if kind == "glass" { "dielectric" } else { "conductor" };
                deprecated(py, &format!("material kind '{kind}' is deprecated; use '{new}'"))?;
                new
            }
            other => other,
        };
        let rgb = |c: (f32, f32, f32)| Vec3::new(c.0, c.1, c.2);
        let material = match kind {
            "diffuse" => Material::Diffuse {
                reflectance: rgb(reflectance),
            },
            "mirror" => Material::Mirror {
                reflectance: rgb(reflectance),
            },
            "dielectric" => Material::Dielectric {
                eta: Dispersion::described(eta.map(|e| f64::from(e.0)), glass, n_d, v_d).map_err(to_py)?,
                reflectance: Vec3::ONE,
                transmittance: Vec3::ONE,
            },
            "conductor" => Material::conductor(eta.map(rgb), k.map(rgb), metal, alpha).map_err(to_py)?,
            other => {
                return Err(value_error(format!(
                    "unknown material kind '{other}'; use diffuse, mirror, dielectric or conductor"
                )))
            }
        };
        self.changed();
        self.scene.materials.push(material);
        Ok(self.scene.materials.len() as u32 - 1)
    }

    /// Adds a triangle mesh from `vertices` (N × 3 float32) and `indices`
    /// (M × 3 uint32) with material index `material`; `emission` makes it an area light.
    #[pyo3(signature = (vertices, indices, material, *, emission = None))]
    pub(crate) fn add_mesh(
        &mut self,
        vertices: PyArrayLike2<'_, f32, AllowTypeChange>,
        // As floats, so 1.7 or -1 is refused rather than cast to 1 or 4294967295.
        indices: PyArrayLike2<'_, f64, AllowTypeChange>,
        material: u32,
        emission: Option<LightAmount>,
    ) -> PyResult<()> {
        self.changed();
        if vertices.shape()[1] != 3 || indices.shape()[1] != 3 {
            return Err(value_error(format!(
                "vertices and indices must be N x 3 arrays, got {:?} and {:?}",
                vertices.shape(),
                indices.shape()
            )));
        }
        let positions: Vec<Vec3> = vertices
            .as_array()
            .rows()
            .into_iter()
            .map(|r| Vec3::new(r[0], r[1], r[2]))
            .collect();
        let whole = |t: usize, v: f64| {
            if v.fract() == 0.0 && (0.0..=f64::from(u32::MAX)).contains(&v) {
                Ok(v as u32)
            } else {
                Err(value_error(format!(
                    "indices must be whole numbers from 0; triangle {t} has {v}"
                )))
            }
        };
        let triangles: Vec<[u32; 3]> = indices
            .as_array()
            .rows()
            .into_iter()
            .enumerate()
            .map(|(t, r)| Ok([whole(t, r[0])?, whole(t, r[1])?, whole(t, r[2])?]))
            .collect::<PyResult<_>>()?;
        let mut scene = self.scene.clone();
        scene.meshes.push(TriangleMesh {
            positions,
            normals: None,
            uvs: None,
            indices: triangles,
            material,
            emission: emission.map(|e| light_amount("emission", e)).transpose()?,
        });
        // Checked now, so a bad mesh is reported where it was added.
        scene.validate().map_err(to_py)?;
        self.scene = scene;
        Ok(())
    }

    /// Adds a sphere; `emission` makes it an area light.
    #[pyo3(signature = (center, radius, material, *, emission = None))]
    pub(crate) fn add_sphere(
        &mut self,
        center: (f32, f32, f32),
        radius: f32,
        material: u32,
        emission: Option<LightAmount>,
    ) -> PyResult<()> {
        self.changed();
        let mut scene = self.scene.clone();
        scene.spheres.push(Sphere {
            center: Vec3::new(center.0, center.1, center.2),
            radius,
            material,
            emission: emission.map(|e| light_amount("emission", e)).transpose()?,
        });
        scene.validate().map_err(to_py)?;
        self.scene = scene;
        Ok(())
    }

    /// Adds a uniform environment: `radiance` from every direction the scene does not block.
    pub(crate) fn add_environment(&mut self, radiance: LightAmount) -> PyResult<()> {
        self.changed();
        let radiance = light_amount("radiance", radiance)?;
        self.scene.lights.push(Light::Environment { radiance });
        Ok(())
    }

    /// Adds an isotropic point light at `position`: `intensity` in W/sr per channel.
    pub(crate) fn add_point_light(&mut self, position: (f32, f32, f32), intensity: LightAmount) -> PyResult<()> {
        self.changed();
        self.scene.lights.push(Light::Point {
            position: finite_point("position", position)?,
            intensity: light_amount("intensity", intensity)?,
        });
        Ok(())
    }

    /// Adds a spot light at `position` pointing along `direction`: `intensity`
    /// (W/sr) on its axis, falling off as cos^`exponent` of the angle from it,
    /// none beyond `cutoff_angle_deg`, the cone's half angle (`cone_angle_deg`
    /// is its deprecated old name, also the half angle).
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (position, direction, intensity, cutoff_angle_deg = None, exponent = 0.0, *, cone_angle_deg = None))]
    pub(crate) fn add_spot_light(
        &mut self,
        py: Python<'_>,
        position: (f32, f32, f32),
        direction: (f32, f32, f32),
        intensity: LightAmount,
        cutoff_angle_deg: Option<f32>,
        exponent: f32,
        cone_angle_deg: Option<f32>,
    ) -> PyResult<()> {
        let cutoff_angle_deg = renamed(
            py,
            "add_spot_light",
            ("cutoff_angle_deg", cutoff_angle_deg),
            ("cone_angle_deg", cone_angle_deg),
            "the same half angle",
        )?
        .ok_or_else(|| value_error("a spot light needs cutoff_angle_deg (the cone's half angle)"))?;
        let light = Light::spot(
            finite_point("position", position)?,
            Vec3::from(direction),
            light_amount("intensity", intensity)?,
            cutoff_angle_deg,
            exponent,
        )
        .map_err(to_py)?;
        self.changed();
        self.scene.lights.push(light);
        Ok(())
    }

    /// Adds a distant light (the sun) whose light travels along `direction`:
    /// `irradiance` (W/m² per channel) on a surface facing it.
    pub(crate) fn add_directional_light(
        &mut self,
        direction: (f32, f32, f32),
        irradiance: LightAmount,
    ) -> PyResult<()> {
        self.changed();
        self.scene.lights.push(Light::Directional {
            direction: unit_direction(direction)?,
            irradiance: light_amount("irradiance", irradiance)?,
        });
        Ok(())
    }

    /// Sets the view: a camera at `eye` looking at `target`, vertical field
    /// of view `fov_deg` (pinhole), subject at `focus_distance` (default: the target).
    #[pyo3(signature = (eye, target, up = (0.0, 1.0, 0.0), fov_deg = 40.0, focus_distance = None),
           text_signature = "($self, eye, target, up=(0.0, 1.0, 0.0), fov_deg=40.0, focus_distance=None)")]
    pub(crate) fn look_at(
        &mut self,
        eye: (f32, f32, f32),
        target: (f32, f32, f32),
        up: (f32, f32, f32),
        fov_deg: f32,
        focus_distance: Option<f32>,
    ) -> PyResult<()> {
        self.changed();
        let (eye, target, up) = (Vec3::from(eye), Vec3::from(target), Vec3::from(up));
        let pose = CameraPose::try_look_at(eye, target, up).map_err(|m| value_error(format!("look_at: {m}")))?;
        lenspath::camera::check_fov_deg(fov_deg).map_err(|m| value_error(format!("fov_deg: {m}")))?;
        self.scene.view = Some(SceneView {
            pose,
            fov_y_deg: fov_deg,
            focus_distance: focus_distance.unwrap_or((target - eye).length()),
        });
        Ok(())
    }

    pub(crate) fn __repr__(&self) -> String {
        format!(
            "<lenspath.Scene '{}': {} meshes ({} triangles), {} spheres, {} materials>",
            self.name,
            self.scene.meshes.len(),
            self.scene.triangle_count(),
            self.scene.spheres.len(),
            self.scene.materials.len()
        )
    }
}

impl Scene {
    /// Called by every method that changes the scene: the BVH must be built
    /// again, and the scene can no longer be made from its origin.
    pub(crate) fn changed(&mut self) {
        self.compiled.take();
        self.origin = SceneOrigin::Python;
    }

    /// Its compiled form (BVH and lights), built once (on `threads` threads,
    /// default all cores) and shared by later renders.
    pub(crate) fn compiled(&self, py: Python<'_>, threads: Option<usize>) -> PyResult<Arc<CompiledScene>> {
        if let Some(c) = self.compiled.get() {
            return Ok(c.clone());
        }
        let scene = self.scene.clone();
        let compiled = Arc::new(
            py.detach(|| guarded(|| scene.compile_on(&BvhSettings::default(), threads)))?
                .map_err(to_py)?,
        );
        Ok(self.compiled.get_or_init(|| compiled).clone())
    }

    /// The view it was made for, or the error a render without one gets.
    pub(crate) fn view(&self) -> PyResult<SceneView> {
        self.scene
            .view
            .ok_or_else(|| value_error(format!("scene '{}' has no view; call look_at first", self.name)))
    }
}

/// Loads a scene file (COLLADA, OBJ, PLY, glTF or lenspath TOML) by extension.
#[pyfunction]
#[pyo3(signature = (path, allow_read = None))]
pub(crate) fn load(py: Python<'_>, path: PathBuf, allow_read: Option<Vec<PathBuf>>) -> PyResult<Scene> {
    let allowed = allow_read.unwrap_or_default();
    let scope = ReadScope::of_scene(&path, &allowed).map_err(to_py)?;
    let loaded = py.detach(|| guarded(|| load_scene_in(&path, &scope)))?.map_err(to_py)?;
    Ok(Scene {
        name: path.display().to_string(),
        scene: loaded.scene,
        options: loaded.options,
        origin: SceneOrigin::File(path, allowed),
        compiled: OnceLock::new(),
    })
}

/// The library's defaults ([`lenspath::defaults`]): what a setting left out
/// of a render or an autofocus becomes when the scene file does not give it.
#[pyfunction]
pub(crate) fn defaults(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    use lenspath::defaults as d;
    let out = PyDict::new(py);
    out.set_item("resolution", d::IMAGE_SIZE)?;
    out.set_item("spp", d::SPP)?;
    out.set_item("max_depth", d::MAX_DEPTH)?;
    out.set_item("light_samples", d::LIGHT_SAMPLES)?;
    out.set_item("seed", d::SEED)?;
    out.set_item("sampler", SamplerKind::default().name())?;
    out.set_item("integrator", IntegratorKind::default().name())?;
    out.set_item("guide_training_spp", d::GUIDE_TRAINING_SPP)?;
    out.set_item("scene_unit_m", d::SCENE_UNIT_M)?;
    out.set_item("lens", d::LENS)?;
    out.set_item("sensor_width_mm", d::SENSOR_WIDTH_MM)?;
    out.set_item("thin_lens_aperture_radius", d::THIN_LENS_APERTURE_RADIUS)?;
    out.set_item("autofocus_spp", d::AUTOFOCUS_PATCH_SPP)?;
    out.set_item("autofocus_max_depth", d::AUTOFOCUS_PATCH_MAX_DEPTH)?;
    out.set_item("autofocus_seed", d::AUTOFOCUS_SEED)?;
    out.set_item("autofocus_patience", d::AUTOFOCUS_PATIENCE)?;
    out.set_item("autofocus_metric", FocusMeasure::default().name())?;
    out.set_item("autofocus_strategy", Strategy::default().name())?;
    out.set_item("autofocus_sensor_signal", SensorSignal::default().name())?;
    Ok(out)
}

/// The built-in scenes' names.
#[pyfunction]
pub(crate) fn builtin_scenes() -> Vec<&'static str> {
    BUILTIN_SCENES.to_vec()
}

/// The built-in scene a scene argument names, if any (the library's rule,
/// [`lenspath::io::builtin_scene_named`]).
#[pyfunction]
pub(crate) fn builtin_scene_named(name: PathBuf) -> Option<&'static str> {
    lenspath::io::builtin_scene_named(&name)
}

/// An amount of light as Python gives it: RGB, or a spectrum.
#[derive(FromPyObject)]
pub(crate) enum LightAmount {
    /// A spectrum (`lenspath.Emission`).
    Spectral(Emission),
    /// (r, g, b).
    Rgb((f32, f32, f32)),
}

/// An amount of light (radiance, intensity, irradiance): a spectrum, or
/// RGB that is finite and not negative.
pub(crate) fn light_amount(what: &str, value: LightAmount) -> PyResult<LibraryEmission> {
    match value {
        LightAmount::Spectral(e) => Ok(e.emission),
        LightAmount::Rgb(rgb) => {
            let v = Vec3::from(rgb);
            if !(v.is_finite() && v.min_element() >= 0.0) {
                return Err(value_error(format!("{what} must be finite and non-negative, got {v}")));
            }
            Ok(v.into())
        }
    }
}

/// A point with finite coordinates.
pub(crate) fn finite_point(what: &str, value: (f32, f32, f32)) -> PyResult<Vec3> {
    let v = Vec3::from(value);
    if !v.is_finite() {
        return Err(value_error(format!("{what} must be finite, got {v}")));
    }
    Ok(v)
}

/// A direction, normalised; not zero.
pub(crate) fn unit_direction(value: (f32, f32, f32)) -> PyResult<Vec3> {
    let v = Vec3::from(value);
    v.try_normalize()
        .ok_or_else(|| value_error(format!("direction must be a finite, non-zero vector, got {v}")))
}
