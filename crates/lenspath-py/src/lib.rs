//! The native module `lenspath._core`: a thin binding of the `lenspath`
//! crate, wrapped by the pure-Python package `lenspath` (python/lenspath),
//! whose `.pyi` stub documents it for users.
//!
//! Library errors become Python exceptions ([`to_py`]): bad arguments
//! `ValueError`, broken scene files `lenspath.SceneError`, broken lens tables
//! `lenspath.LensError`, I/O failures `OSError`. Renders release the GIL and
//! poll for Ctrl-C (see [`render`]).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, OnceLock};
use std::time::Duration;

use glam::{DVec3, Vec3};
use lenspath::accel::BvhSettings;
use lenspath::autofocus::{FocusMeasure, Focuser, Patch};
use lenspath::bokeh::{convolve_rgb, depth_blur, CircleOfConfusion, Edges, Kernel, KernelSize, Method};
use lenspath::builtin::{builtin_scene, BUILTIN_SCENES, DEFAULT_MESH_TRIANGLES};
use lenspath::camera::{Aperture, ApertureShape, Camera as CameraTrait, CameraPose, LensFocus};
use lenspath::film::Image;
use lenspath::film::{NormalizedRect, PixelRect};
use lenspath::io::image::{read_image, write_image};
use lenspath::io::{load_scene, SceneOptions};
use lenspath::lens::{
    plot::{layout, layout_svg, Polyline},
    AnalysisSettings, Direction, LensAnalysis, LensPrescription, LensRay, LensSystem, TableConvention, BUILTIN_LENSES,
};
use lenspath::lights::Light;
use lenspath::materials::Material;
use lenspath::render::render as render_scene;
use lenspath::sampling::SamplerKind;
use lenspath::scene::{CompiledScene, Scene as CoreScene, SceneView};
use lenspath::setup::{
    resolve, resolve_autofocus, AutofocusOverrides, CameraDescription, RealisticDescription, RenderOverrides,
    RenderSetup,
};
use lenspath::shapes::{Sphere, TriangleMesh};
use lenspath::Error;
use numpy::ndarray::{Array2, Array3};
use numpy::{AllowTypeChange, IntoPyArray, PyArray2, PyArray3, PyArrayLike2, PyArrayLike3, PyUntypedArrayMethods};
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyOSError, PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

create_exception!(
    lenspath,
    LenspathError,
    PyException,
    "Base class of lenspath's own errors."
);
create_exception!(
    lenspath,
    SceneError,
    LenspathError,
    "A scene file is broken or inconsistent."
);
create_exception!(lenspath, LensError, LenspathError, "A lens table is broken.");

/// What kind of file a [`Error::Parse`] is about, to pick the exception.
#[derive(Clone, Copy)]
enum FileKind {
    Scene,
    Lens,
    Image,
}

/// A library error as the Python exception users expect.
fn to_py(error: Error, kind: FileKind) -> PyErr {
    let message = error.to_string();
    match error {
        Error::InvalidArgument(_) => PyValueError::new_err(message),
        Error::InvalidScene(_) => SceneError::new_err(message),
        Error::Parse { .. } => match kind {
            FileKind::Scene => SceneError::new_err(message),
            FileKind::Lens => LensError::new_err(message),
            FileKind::Image => PyValueError::new_err(message),
        },
        Error::Io { source, .. } => PyOSError::new_err((source.raw_os_error().unwrap_or(0), message)),
    }
}

fn value_error(message: impl Into<String>) -> PyErr {
    PyValueError::new_err(message.into())
}

// ---------------------------------------------------------------------------
// Scenes

/// Where a [`Scene`] came from: how to make it again (pickling it, and
/// `lenspath.distributed`'s workers, need that).
#[derive(Clone, Debug)]
enum SceneOrigin {
    /// `Scene.builtin(name, mesh_triangles)`.
    Builtin(String, usize),
    /// `load(path)`.
    File(PathBuf),
    /// Built or changed in Python.
    Python,
}

/// A scene: shapes, materials, lights and the view it was made for.
#[pyclass(module = "lenspath._core")]
#[derive(Clone)]
struct Scene {
    name: String,
    scene: CoreScene,
    options: SceneOptions,
    origin: SceneOrigin,
    /// Its BVH, built by the first render and kept for the next ones until the scene changes.
    compiled: OnceLock<Arc<CompiledScene>>,
}

#[pymethods]
impl Scene {
    /// An empty scene (add shapes, lights and a view to it).
    #[new]
    fn new() -> Self {
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
    fn builtin(name: &str, mesh_triangles: usize) -> PyResult<Self> {
        Ok(Scene {
            name: name.into(),
            scene: builtin_scene(name, mesh_triangles).map_err(|e| to_py(e, FileKind::Scene))?,
            options: SceneOptions::default(),
            origin: SceneOrigin::Builtin(name.into(), mesh_triangles),
            compiled: OnceLock::new(),
        })
    }

    /// The file it was loaded from, or the built-in scene's name; None once changed in Python.
    #[getter]
    fn source(&self) -> Option<String> {
        match &self.origin {
            SceneOrigin::Builtin(name, _) => Some(name.clone()),
            SceneOrigin::File(path) => Some(path.display().to_string()),
            SceneOrigin::Python => None,
        }
    }

    /// Builds its BVH now; otherwise the first render does. Kept until the scene changes.
    fn compile(&self, py: Python<'_>) -> PyResult<()> {
        self.compiled(py).map(|_| ())
    }

    /// Pickles as the way to make it again: `Scene.builtin(...)` or `load(path)`.
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let module = py.import("lenspath._core")?;
        match &self.origin {
            SceneOrigin::Builtin(name, triangles) => Ok((
                module.getattr("Scene")?.getattr("builtin")?,
                (name.clone(), *triangles).into_pyobject(py)?,
            )),
            SceneOrigin::File(path) => Ok((module.getattr("load")?, (path.clone(),).into_pyobject(py)?)),
            SceneOrigin::Python => Err(PyTypeError::new_err(format!(
                "scene '{}' was built or changed in Python and cannot be pickled; save it as a scene file \
                 and load that (lenspath.load) to send it to other processes",
                self.name
            ))),
        }
    }

    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    #[getter]
    fn mesh_count(&self) -> usize {
        self.scene.meshes.len()
    }

    #[getter]
    fn triangle_count(&self) -> usize {
        self.scene.triangle_count()
    }

    #[getter]
    fn sphere_count(&self) -> usize {
        self.scene.spheres.len()
    }

    #[getter]
    fn material_count(&self) -> usize {
        self.scene.materials.len()
    }

    #[getter]
    fn light_count(&self) -> usize {
        self.scene.lights.len() + self.scene.emitter_count()
    }

    /// The image size the scene file asks for, or None.
    #[getter]
    fn resolution(&self) -> Option<(u32, u32)> {
        self.options.resolution
    }

    /// Adds a material: `kind` is "diffuse" (reflectance), "mirror"
    /// (reflectance), "glass" (eta) or "metal" (eta, k, roughness); returns its index.
    #[pyo3(signature = (kind, *, reflectance = (0.8, 0.8, 0.8), eta = None, k = None, roughness = 0.0),
           text_signature = "($self, kind, *, reflectance=(0.8, 0.8, 0.8), eta=None, k=None, roughness=0.0)")]
    fn add_material(
        &mut self,
        kind: &str,
        reflectance: (f32, f32, f32),
        eta: Option<(f32, f32, f32)>,
        k: Option<(f32, f32, f32)>,
        roughness: f32,
    ) -> PyResult<u32> {
        self.changed();
        let rgb = |c: (f32, f32, f32)| Vec3::new(c.0, c.1, c.2);
        let material = match kind {
            "diffuse" => Material::Diffuse {
                reflectance: rgb(reflectance),
            },
            "mirror" => Material::Mirror {
                reflectance: rgb(reflectance),
            },
            "glass" => Material::clear_dielectric(eta.map_or(1.5, |e| e.0)),
            "metal" => Material::Conductor {
                eta: rgb(eta.ok_or_else(|| value_error("a metal needs eta=(r, g, b)"))?),
                k: rgb(k.ok_or_else(|| value_error("a metal needs k=(r, g, b)"))?),
                alpha: roughness,
            },
            other => {
                return Err(value_error(format!(
                    "unknown material kind '{other}'; use diffuse, mirror, glass or metal"
                )))
            }
        };
        self.scene.materials.push(material);
        Ok(self.scene.materials.len() as u32 - 1)
    }

    /// Adds a triangle mesh from `vertices` (N × 3 float32) and `indices`
    /// (M × 3 uint32) with material index `material`; `emission` makes it an area light.
    #[pyo3(signature = (vertices, indices, material, *, emission = None))]
    fn add_mesh(
        &mut self,
        vertices: PyArrayLike2<'_, f32, AllowTypeChange>,
        indices: PyArrayLike2<'_, u32, AllowTypeChange>,
        material: u32,
        emission: Option<(f32, f32, f32)>,
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
        let triangles: Vec<[u32; 3]> = indices
            .as_array()
            .rows()
            .into_iter()
            .map(|r| [r[0], r[1], r[2]])
            .collect();
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
        scene.validate().map_err(|e| to_py(e, FileKind::Scene))?;
        self.scene = scene;
        Ok(())
    }

    /// Adds a sphere; `emission` makes it an area light.
    #[pyo3(signature = (center, radius, material, *, emission = None))]
    fn add_sphere(
        &mut self,
        center: (f32, f32, f32),
        radius: f32,
        material: u32,
        emission: Option<(f32, f32, f32)>,
    ) -> PyResult<()> {
        self.changed();
        let mut scene = self.scene.clone();
        scene.spheres.push(Sphere {
            center: Vec3::new(center.0, center.1, center.2),
            radius,
            material,
            emission: emission.map(|e| light_amount("emission", e)).transpose()?,
        });
        scene.validate().map_err(|e| to_py(e, FileKind::Scene))?;
        self.scene = scene;
        Ok(())
    }

    /// Adds a uniform environment: `radiance` from every direction the scene does not block.
    fn add_environment(&mut self, radiance: (f32, f32, f32)) -> PyResult<()> {
        self.changed();
        let radiance = light_amount("radiance", radiance)?;
        self.scene.lights.push(Light::Environment { radiance });
        Ok(())
    }

    /// Adds an isotropic point light at `position`: `intensity` in W/sr per channel.
    fn add_point_light(&mut self, position: (f32, f32, f32), intensity: (f32, f32, f32)) -> PyResult<()> {
        self.changed();
        self.scene.lights.push(Light::Point {
            position: finite_point("position", position)?,
            intensity: light_amount("intensity", intensity)?,
        });
        Ok(())
    }

    /// Adds a spot light at `position` pointing along `direction`: `intensity`
    /// (W/sr) on its axis, falling off as cos^`exponent` of the angle from it,
    /// none beyond `cone_angle_deg` (the half angle).
    #[pyo3(signature = (position, direction, intensity, cone_angle_deg, exponent = 0.0))]
    fn add_spot_light(
        &mut self,
        position: (f32, f32, f32),
        direction: (f32, f32, f32),
        intensity: (f32, f32, f32),
        cone_angle_deg: f32,
        exponent: f32,
    ) -> PyResult<()> {
        self.changed();
        if !(cone_angle_deg > 0.0 && cone_angle_deg <= 180.0) {
            return Err(value_error(format!(
                "cone_angle_deg must be in (0, 180], got {cone_angle_deg}"
            )));
        }
        if !(exponent >= 0.0 && exponent.is_finite()) {
            return Err(value_error(format!("exponent must be 0 or more, got {exponent}")));
        }
        self.scene.lights.push(Light::Spot {
            position: finite_point("position", position)?,
            direction: unit_direction(direction)?,
            intensity: light_amount("intensity", intensity)?,
            cos_cutoff: cone_angle_deg.to_radians().cos(),
            exponent,
        });
        Ok(())
    }

    /// Adds a distant light (the sun) whose light travels along `direction`:
    /// `irradiance` (W/m² per channel) on a surface facing it.
    fn add_directional_light(&mut self, direction: (f32, f32, f32), irradiance: (f32, f32, f32)) -> PyResult<()> {
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
    fn look_at(
        &mut self,
        eye: (f32, f32, f32),
        target: (f32, f32, f32),
        up: (f32, f32, f32),
        fov_deg: f32,
        focus_distance: Option<f32>,
    ) -> PyResult<()> {
        self.changed();
        let (eye, target, up) = (Vec3::from(eye), Vec3::from(target), Vec3::from(up));
        if (target - eye).length() <= 0.0 || (target - eye).cross(up).length() <= 1e-6 {
            return Err(value_error(
                "look_at: eye and target must differ, and up must not be along the view",
            ));
        }
        if !(fov_deg > 0.0 && fov_deg < 180.0) {
            return Err(value_error(format!("fov_deg must be between 0 and 180, got {fov_deg}")));
        }
        self.scene.view = Some(SceneView {
            pose: CameraPose::look_at(eye, target, up),
            fov_y_deg: fov_deg,
            focus_distance: focus_distance.unwrap_or((target - eye).length()),
        });
        Ok(())
    }

    fn __repr__(&self) -> String {
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
    fn changed(&mut self) {
        self.compiled.take();
        self.origin = SceneOrigin::Python;
    }

    /// Its compiled form (BVH and lights), built once and shared by later renders.
    fn compiled(&self, py: Python<'_>) -> PyResult<Arc<CompiledScene>> {
        if let Some(c) = self.compiled.get() {
            return Ok(c.clone());
        }
        let scene = self.scene.clone();
        let compiled = Arc::new(
            py.detach(|| scene.compile(&BvhSettings::default()))
                .map_err(|e| to_py(e, FileKind::Scene))?,
        );
        Ok(self.compiled.get_or_init(|| compiled).clone())
    }

    /// The view it was made for, or the error a render without one gets.
    fn view(&self) -> PyResult<SceneView> {
        self.scene
            .view
            .ok_or_else(|| value_error(format!("scene '{}' has no view; call look_at first", self.name)))
    }
}

/// Loads a scene file (COLLADA, OBJ, PLY, glTF or lenspath TOML) by extension.
#[pyfunction]
fn load(py: Python<'_>, path: PathBuf) -> PyResult<Scene> {
    let loaded = py.detach(|| load_scene(&path)).map_err(|e| to_py(e, FileKind::Scene))?;
    Ok(Scene {
        name: path.display().to_string(),
        scene: loaded.scene,
        options: loaded.options,
        origin: SceneOrigin::File(path),
        compiled: OnceLock::new(),
    })
}

/// The library's defaults ([`lenspath::defaults`]): what a setting left out
/// of a render or an autofocus becomes when the scene file does not give it.
#[pyfunction]
fn defaults(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    use lenspath::defaults as d;
    let out = PyDict::new(py);
    out.set_item("resolution", d::IMAGE_SIZE)?;
    out.set_item("spp", d::SPP)?;
    out.set_item("max_depth", d::MAX_DEPTH)?;
    out.set_item("light_samples", d::LIGHT_SAMPLES)?;
    out.set_item("seed", d::SEED)?;
    out.set_item("sampler", d::SAMPLER.name())?;
    out.set_item("scene_unit_m", d::SCENE_UNIT_M)?;
    out.set_item("lens", d::LENS)?;
    out.set_item("sensor_width_mm", d::SENSOR_WIDTH_MM)?;
    out.set_item("thin_lens_aperture_radius", d::THIN_LENS_APERTURE_RADIUS)?;
    out.set_item("autofocus_spp", d::AUTOFOCUS_PATCH_SPP)?;
    out.set_item("autofocus_max_depth", d::AUTOFOCUS_PATCH_MAX_DEPTH)?;
    out.set_item("autofocus_seed", d::AUTOFOCUS_SEED)?;
    out.set_item("autofocus_patience", d::AUTOFOCUS_PATIENCE)?;
    out.set_item("autofocus_metric", d::AUTOFOCUS_METRIC)?;
    out.set_item("autofocus_strategy", d::AUTOFOCUS_STRATEGY)?;
    Ok(out)
}

/// The built-in scenes' names.
#[pyfunction]
fn builtin_scenes() -> Vec<&'static str> {
    BUILTIN_SCENES.to_vec()
}

// ---------------------------------------------------------------------------
// Lenses

/// The default sensor of the lens drawings, as `lenspath lens` draws them: 36 × 24 mm.
const FULL_FRAME_MM: (f64, f64) = (36.0, 24.0);

/// A real compound lens: its prescription, placed wide open (or stopped down).
#[pyclass(module = "lenspath._core")]
#[derive(Clone)]
struct Lens {
    prescription: LensPrescription,
    system: LensSystem,
    analysis: LensAnalysis,
    /// The f-number it was stopped down to (None: wide open).
    stopped_to: Option<f64>,
}

impl Lens {
    fn from_prescription(prescription: LensPrescription) -> PyResult<Lens> {
        let system = LensSystem::new(&prescription);
        Lens::placed(prescription, system)
    }

    /// `prescription` placed as `system` (wide open or stopped down), analysed.
    fn placed(prescription: LensPrescription, system: LensSystem) -> PyResult<Lens> {
        let analysis =
            LensAnalysis::new(&system, &AnalysisSettings::default()).map_err(|e| to_py(e, FileKind::Lens))?;
        Ok(Lens {
            prescription,
            system,
            analysis,
            stopped_to: None,
        })
    }
}

/// The sensor diagonal of the lens drawings: `sensor_diagonal_mm`, else a
/// 36 × 24 mm sensor's, as `lenspath lens` draws them.
fn drawing_diagonal_mm(sensor_diagonal_mm: Option<f64>) -> f64 {
    sensor_diagonal_mm.unwrap_or_else(|| FULL_FRAME_MM.0.hypot(FULL_FRAME_MM.1))
}

#[pymethods]
impl Lens {
    /// A built-in lens by name (see `builtin_lenses()`).
    #[staticmethod]
    fn builtin(name: &str) -> PyResult<Lens> {
        if !BUILTIN_LENSES.iter().any(|(n, _)| *n == name) {
            return Err(value_error(format!(
                "unknown built-in lens '{name}'; use one of {}",
                BUILTIN_LENSES.map(|(n, _)| n).join(", ")
            )));
        }
        Lens::from_prescription(LensPrescription::load(name).map_err(|e| to_py(e, FileKind::Lens))?)
    }

    /// A lens table file (pbrt / CS184 format).
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Lens> {
        if !path.is_file() {
            let source = std::io::Error::from(std::io::ErrorKind::NotFound);
            return Err(to_py(Error::Io { path, source }, FileKind::Lens));
        }
        let name = path
            .to_str()
            .ok_or_else(|| value_error(format!("{}: not a UTF-8 path", path.display())))?;
        Lens::from_prescription(LensPrescription::load(name).map_err(|e| to_py(e, FileKind::Lens))?)
    }

    /// A lens from a table (N × 4: radius, thickness to the next surface,
    /// index, aperture diameter, all mm; radius 0 marks the stop).
    #[staticmethod]
    #[pyo3(signature = (table, name = "table"))]
    fn from_table(table: PyArrayLike2<'_, f64, AllowTypeChange>, name: &str) -> PyResult<Lens> {
        if table.shape()[1] != 4 {
            return Err(value_error(format!(
                "a lens table has 4 columns (radius, thickness, index, aperture), got {}",
                table.shape()[1]
            )));
        }
        let text: String = table
            .as_array()
            .rows()
            .into_iter()
            .map(|r| format!("{} {} {} {}\n", r[0], r[1], r[2], r[3]))
            .collect();
        let prescription = LensPrescription::parse(&text, name, TableConvention::ThicknessToNext)
            .map_err(|e| to_py(e, FileKind::Lens))?;
        Lens::from_prescription(prescription)
    }

    /// This lens stopped down to f-number `f_number`.
    fn stopped_down(&self, f_number: f64) -> PyResult<Lens> {
        let system = self
            .system
            .with_f_number(f_number)
            .map_err(|e| to_py(e, FileKind::Lens))?;
        Ok(Lens {
            stopped_to: Some(f_number),
            ..Lens::placed(self.prescription.clone(), system)?
        })
    }

    /// Pickles as its name, table and stop (`Lens._from_state`).
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        Ok((
            py.get_type::<Lens>().getattr("_from_state")?,
            (self.name().to_string(), self.table(py), self.stopped_to).into_pyobject(py)?,
        ))
    }

    /// The lens `__reduce__` describes.
    #[staticmethod]
    fn _from_state(
        name: &str,
        table: PyArrayLike2<'_, f64, AllowTypeChange>,
        stopped_to: Option<f64>,
    ) -> PyResult<Lens> {
        let lens = Lens::from_table(table, name)?;
        match stopped_to {
            Some(f_number) => lens.stopped_down(f_number),
            None => Ok(lens),
        }
    }

    #[getter]
    fn name(&self) -> &str {
        self.prescription.name()
    }

    /// The table: N × 4 (radius, thickness to next, index, aperture diameter), mm.
    #[getter]
    fn table<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let surfaces = self.prescription.surfaces();
        let mut a = Array2::zeros((surfaces.len(), 4));
        for (i, s) in surfaces.iter().enumerate() {
            a[[i, 0]] = s.radius_mm;
            a[[i, 1]] = s.thickness_mm;
            a[[i, 2]] = s.ior;
            a[[i, 3]] = s.aperture_diameter_mm;
        }
        a.into_pyarray(py)
    }

    /// Every figure of `lenspath lens --json`, as a dict.
    fn analysis<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let a = &self.analysis;
        let d = PyDict::new(py);
        for (key, value) in [
            ("effective_focal_length_mm", a.effective_focal_length_mm),
            ("back_focal_distance_mm", a.back_focal_distance_mm),
            ("front_focal_distance_mm", a.front_focal_distance_mm),
            ("front_principal_plane_mm", a.front_principal_plane_mm),
            ("rear_principal_plane_mm", a.rear_principal_plane_mm),
            ("entrance_pupil_mm", a.entrance_pupil_mm),
            ("entrance_pupil_diameter_mm", a.entrance_pupil_diameter_mm),
            ("exit_pupil_mm", a.exit_pupil_mm),
            ("exit_pupil_diameter_mm", a.exit_pupil_diameter_mm),
            ("f_number", a.f_number),
            ("diagonal_fov_deg", a.diagonal_fov_deg),
            ("horizontal_fov_deg", a.horizontal_fov_deg),
            ("infinity_focus_mm", a.infinity_focus_mm),
            ("close_focus_mm", a.close_focus_mm),
            ("close_focus_object_distance_mm", a.close_focus_object_distance_mm),
            ("focal_length_mm", a.focal_length_mm),
            ("ray_height_mm", a.ray_height_mm),
            ("front_vertex_mm", a.front_vertex_mm),
            ("rear_vertex_mm", a.rear_vertex_mm),
        ] {
            d.set_item(key, value)?;
        }
        Ok(d)
    }

    /// Real-ray focal length |P′ − F′|, mm.
    #[getter]
    fn focal_length_mm(&self) -> f64 {
        self.analysis.focal_length_mm
    }

    /// Paraxial effective focal length, mm.
    #[getter]
    fn effective_focal_length_mm(&self) -> f64 {
        self.analysis.effective_focal_length_mm
    }

    /// Paraxial f-number.
    #[getter]
    fn f_number(&self) -> f64 {
        self.analysis.f_number
    }

    /// Sensor position (mm behind the stop) focusing infinity.
    #[getter]
    fn infinity_focus_mm(&self) -> f64 {
        self.analysis.infinity_focus_mm
    }

    /// Sensor position (mm behind the stop) focusing the close-focus object.
    #[getter]
    fn close_focus_mm(&self) -> f64 {
        self.analysis.close_focus_mm
    }

    /// Distance in focus (mm from the sensor plane) with the sensor at
    /// `sensor_mm` behind the stop; None when nothing in front of the lens is.
    #[pyo3(signature = (sensor_mm, ray_height_mm = 0.1))]
    fn focus_distance(&self, sensor_mm: f64, ray_height_mm: f64) -> Option<f64> {
        self.system.focus_distance_mm(sensor_mm, ray_height_mm)
    }

    /// Sensor position (mm behind the stop) focusing `distance_mm` (from the sensor plane).
    #[pyo3(signature = (distance_mm, ray_height_mm = 0.1))]
    fn sensor_for_distance(&self, distance_mm: f64, ray_height_mm: f64) -> PyResult<f64> {
        self.system
            .sensor_z_for_focus_distance(distance_mm, ray_height_mm)
            .map_err(|e| to_py(e, FileKind::Lens))
    }

    /// Traces rays (N × 3 origins and directions, lens coordinates in mm:
    /// z along the axis toward the sensor, the stop at 0) through every
    /// surface, `toward` "scene" or "sensor". Returns (origins, directions,
    /// passed): where each ray leaves the last surface, its unit direction,
    /// and whether it got through (False rows are NaN).
    #[pyo3(signature = (origins, directions, toward = "scene"))]
    #[allow(clippy::type_complexity)]
    fn trace<'py>(
        &self,
        py: Python<'py>,
        origins: PyArrayLike2<'_, f64, AllowTypeChange>,
        directions: PyArrayLike2<'_, f64, AllowTypeChange>,
        toward: &str,
    ) -> PyResult<(
        Bound<'py, PyArray2<f64>>,
        Bound<'py, PyArray2<f64>>,
        Bound<'py, numpy::PyArray1<bool>>,
    )> {
        let direction = match toward {
            "scene" => Direction::ToScene,
            "sensor" => Direction::ToSensor,
            other => {
                return Err(value_error(format!(
                    "toward must be 'scene' or 'sensor', got '{other}'"
                )))
            }
        };
        if origins.shape() != directions.shape() || origins.shape()[1] != 3 {
            return Err(value_error(format!(
                "origins and directions must both be N x 3, got {:?} and {:?}",
                origins.shape(),
                directions.shape()
            )));
        }
        let (o, d) = (origins.as_array(), directions.as_array());
        let n = o.nrows();
        let mut out_o = Array2::from_elem((n, 3), f64::NAN);
        let mut out_d = Array2::from_elem((n, 3), f64::NAN);
        let mut passed = vec![false; n];
        for i in 0..n {
            let dir = DVec3::new(d[[i, 0]], d[[i, 1]], d[[i, 2]]);
            if !dir.is_finite() || dir.length_squared() == 0.0 {
                return Err(value_error(format!("direction {i} has zero length")));
            }
            let ray = LensRay {
                origin: DVec3::new(o[[i, 0]], o[[i, 1]], o[[i, 2]]),
                direction: dir.normalize(),
            };
            if let Some(out) = self.system.trace(&ray, direction) {
                for c in 0..3 {
                    out_o[[i, c]] = out.origin[c];
                    out_d[[i, c]] = out.direction[c];
                }
                passed[i] = true;
            }
        }
        Ok((out_o.into_pyarray(py), out_d.into_pyarray(py), passed.into_pyarray(py)))
    }

    /// The lens layout (elements, stop, marginal and chief rays) as SVG text;
    /// the sensor `sensor_diagonal_mm` across (default: 36 × 24 mm).
    #[pyo3(signature = (sensor_diagonal_mm = None))]
    fn plot(&self, sensor_diagonal_mm: Option<f64>) -> String {
        layout_svg(&self.system, &self.analysis, drawing_diagonal_mm(sensor_diagonal_mm))
    }

    /// What `plot` draws, as arrays of (z, height) rows in mm: `elements`
    /// (closed outlines), `stop` (two blades), `sensor`, `rays` ((field
    /// fraction, path) pairs), `z_range_mm`, `half_height_mm`, `title`.
    #[pyo3(signature = (sensor_diagonal_mm = None))]
    fn layout<'py>(&self, py: Python<'py>, sensor_diagonal_mm: Option<f64>) -> PyResult<Bound<'py, PyDict>> {
        let l = layout(&self.system, &self.analysis, drawing_diagonal_mm(sensor_diagonal_mm));
        let array = |line: &Polyline| {
            let flat: Vec<f64> = line.iter().flat_map(|&(z, h)| [z, h]).collect();
            Array2::from_shape_vec((line.len(), 2), flat)
                .expect("two values per point")
                .into_pyarray(py)
        };
        let d = PyDict::new(py);
        d.set_item("title", &l.title)?;
        d.set_item("elements", l.elements.iter().map(array).collect::<Vec<_>>())?;
        d.set_item("stop", l.stop.iter().map(array).collect::<Vec<_>>())?;
        d.set_item("sensor", array(&l.sensor))?;
        d.set_item(
            "rays",
            l.rays.iter().map(|(f, path)| (*f, array(path))).collect::<Vec<_>>(),
        )?;
        d.set_item("z_range_mm", l.z_range_mm)?;
        d.set_item("half_height_mm", l.half_height_mm)?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!(
            "<lenspath.Lens '{}': f = {:.2} mm, f/{:.2}>",
            self.prescription.name(),
            self.analysis.focal_length_mm,
            self.analysis.f_number
        )
    }
}

/// The built-in lenses' names.
#[pyfunction]
fn builtin_lenses() -> Vec<&'static str> {
    BUILTIN_LENSES.map(|(n, _)| n).to_vec()
}

// ---------------------------------------------------------------------------
// Cameras

/// A camera for `render`: `Camera.pinhole(...)`, `Camera.thin_lens(...)` or
/// `Camera.realistic(...)`; what it leaves unset comes from the scene (the
/// library resolves it: [`lenspath::setup::resolve_camera`]).
#[pyclass(module = "lenspath._core")]
#[derive(Clone)]
struct Camera {
    description: CameraDescription,
    /// The camera last built from it, and for what (scene view and options,
    /// image size): a realistic camera's exit-pupil tables take a tenth of a
    /// second, which repeated renders (tiles, patches) need not pay again.
    built: Arc<Mutex<Option<BuiltCamera>>>,
}

/// A camera as built for a render, and the key of what it was built for.
type BuiltCamera = (String, Arc<dyn CameraTrait>);

impl Camera {
    fn new(description: CameraDescription) -> Camera {
        Camera {
            description,
            built: Arc::default(),
        }
    }

    /// The camera of `setup` (resolved from this camera's description), built
    /// once per resolved settings, pose and image size.
    fn built_for(&self, setup: &RenderSetup) -> PyResult<Arc<dyn CameraTrait>> {
        let s = &setup.settings;
        let key = format!("{:?} {:?} {}x{}", setup.camera, setup.pose, s.width, s.height);
        let mut built = self.built.lock().unwrap_or_else(|p| p.into_inner());
        if let Some((k, camera)) = built.as_ref() {
            if *k == key {
                return Ok(camera.clone());
            }
        }
        let camera = setup.build_camera().map_err(|e| to_py(e, FileKind::Lens))?;
        *built = Some((key, camera.clone()));
        Ok(camera)
    }

    /// The realistic camera's description, or the error other cameras get where one is needed.
    fn realistic_description(&self) -> PyResult<&RealisticDescription> {
        match &self.description {
            CameraDescription::Realistic(r) => Ok(r),
            _ => Err(value_error("this needs a realistic camera (Camera.realistic)")),
        }
    }
}

/// An amount of light (radiance, intensity, irradiance): finite, not negative.
fn light_amount(what: &str, value: (f32, f32, f32)) -> PyResult<Vec3> {
    let v = Vec3::from(value);
    if !(v.is_finite() && v.min_element() >= 0.0) {
        return Err(value_error(format!("{what} must be finite and non-negative, got {v}")));
    }
    Ok(v)
}

/// A point with finite coordinates.
fn finite_point(what: &str, value: (f32, f32, f32)) -> PyResult<Vec3> {
    let v = Vec3::from(value);
    if !v.is_finite() {
        return Err(value_error(format!("{what} must be finite, got {v}")));
    }
    Ok(v)
}

/// A direction, normalised; not zero.
fn unit_direction(value: (f32, f32, f32)) -> PyResult<Vec3> {
    let v = Vec3::from(value);
    v.try_normalize()
        .ok_or_else(|| value_error(format!("direction must be a finite, non-zero vector, got {v}")))
}

/// A `Lens`, or a built-in lens by name.
fn lens_from_py(lens: &Bound<'_, PyAny>) -> PyResult<Lens> {
    match lens.extract::<Lens>() {
        Ok(lens) => Ok(lens),
        Err(_) => Lens::builtin(
            &lens
                .extract::<String>()
                .map_err(|_| value_error("lens must be a lenspath.Lens or a built-in lens name"))?,
        ),
    }
}

/// An aperture shape from Python: a name such as "blades:6" or "star:5:0.4",
/// or a 2-D array of transmissions (a mask over the stop's bounding square).
fn parse_aperture(aperture: Option<&Bound<'_, PyAny>>) -> PyResult<Option<ApertureShape>> {
    let Some(aperture) = aperture else {
        return Ok(None);
    };
    let invalid = |e: Error| to_py(e, FileKind::Image);
    if let Ok(name) = aperture.extract::<String>() {
        return ApertureShape::parse(&name).map(Some).map_err(invalid);
    }
    let mask = aperture
        .extract::<PyArrayLike2<'_, f32, AllowTypeChange>>()
        .map_err(|_| value_error("aperture must be a shape name (such as 'blades:6') or a 2-D array (a mask)"))?;
    let (height, width) = (mask.shape()[0], mask.shape()[1]);
    let values = mask.as_array().iter().copied().collect();
    ApertureShape::mask(width, height, values).map(Some).map_err(invalid)
}

/// An aperture shape as Python gives it: its name (such as "blades:6:0:0.5") or its mask array.
fn aperture_to_py<'py>(py: Python<'py>, shape: &ApertureShape) -> PyResult<Bound<'py, PyAny>> {
    Ok(match shape {
        ApertureShape::Circle => "circle".into_pyobject(py)?.into_any(),
        ApertureShape::Blades {
            count,
            rotation_deg,
            curvature,
        } => format!("blades:{count}:{rotation_deg}:{curvature}")
            .into_pyobject(py)?
            .into_any(),
        ApertureShape::Star {
            points,
            inner_ratio,
            rotation_deg,
        } => format!("star:{points}:{inner_ratio}:{rotation_deg}")
            .into_pyobject(py)?
            .into_any(),
        ApertureShape::Mask(mask) => Array2::from_shape_vec((mask.height, mask.width), mask.values.clone())
            .expect("a mask holds width × height values")
            .into_pyarray(py)
            .into_any(),
    })
}

#[pymethods]
impl Camera {
    /// Pickles as its kind and settings (`Camera._from_state`).
    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        let none = || py.None().into_bound(py);
        let aperture = |a: &Option<ApertureShape>| a.as_ref().map_or_else(|| Ok(none()), |a| aperture_to_py(py, a));
        let state = match &self.description {
            CameraDescription::Pinhole { fov_y_deg } => ("pinhole", *fov_y_deg, None, None::<f64>, none(), none()),
            CameraDescription::ThinLens {
                fov_y_deg,
                aperture_radius,
                focus_distance,
                aperture: shape,
            } => (
                "thin_lens",
                *fov_y_deg,
                *aperture_radius,
                focus_distance.map(f64::from),
                aperture(shape)?,
                none(),
            ),
            CameraDescription::Realistic(r) => (
                "realistic",
                None,
                None,
                match r.focus {
                    Some(LensFocus::Distance(d)) => Some(d),
                    _ => None,
                },
                aperture(&r.aperture)?,
                r.lens
                    .clone()
                    .map(Lens::from_prescription)
                    .transpose()?
                    .into_pyobject(py)?
                    .into_any(),
            ),
        };
        let realistic = match &self.description {
            CameraDescription::Realistic(r) => (
                match r.focus {
                    Some(LensFocus::SensorPositionMm(mm)) => Some(mm),
                    _ => None,
                },
                r.sensor_width_mm,
                r.f_number,
                r.scene_unit_m,
            ),
            _ => (None, None, None, None),
        };
        Ok((
            py.get_type::<Camera>().getattr("_from_state")?,
            (state, realistic).into_pyobject(py)?,
        ))
    }

    /// The camera `__reduce__` describes.
    #[staticmethod]
    #[allow(clippy::type_complexity)]
    fn _from_state(
        py: Python<'_>,
        state: (
            String,
            Option<f32>,
            Option<f32>,
            Option<f64>,
            Option<Bound<'_, PyAny>>,
            Option<Bound<'_, PyAny>>,
        ),
        realistic: (Option<f64>, Option<f64>, Option<f64>, Option<f64>),
    ) -> PyResult<Camera> {
        let (kind, fov_deg, aperture_radius, focus_distance, aperture, lens) = state;
        let (aperture, lens) = (aperture.filter(|a| !a.is_none()), lens.filter(|l| !l.is_none()));
        let (sensor_depth_mm, sensor_width_mm, f_number, scene_unit_m) = realistic;
        match kind.as_str() {
            "pinhole" => Ok(Camera::pinhole(fov_deg)),
            "thin_lens" => Camera::thin_lens(
                aperture_radius,
                focus_distance.map(|d| d as f32),
                fov_deg,
                aperture.as_ref(),
            ),
            _ => Camera::realistic(
                py,
                lens.as_ref(),
                focus_distance,
                sensor_depth_mm,
                None,
                f_number,
                sensor_width_mm,
                aperture.as_ref(),
                scene_unit_m,
            ),
        }
    }

    /// An ideal pinhole; `fov_deg` (vertical) defaults to the scene's.
    #[staticmethod]
    #[pyo3(signature = (fov_deg = None))]
    fn pinhole(fov_deg: Option<f32>) -> Camera {
        Camera::new(CameraDescription::Pinhole { fov_y_deg: fov_deg })
    }

    /// An ideal thin lens of `aperture_radius` (scene units; default 0.05)
    /// focused at `focus_distance` (default: the scene's subject); `aperture`
    /// a shape such as "blades:6" or "star:5:0.4" (default: the scene file's).
    #[staticmethod]
    #[pyo3(signature = (aperture_radius = None, focus_distance = None, fov_deg = None, aperture = None))]
    fn thin_lens(
        aperture_radius: Option<f32>,
        focus_distance: Option<f32>,
        fov_deg: Option<f32>,
        aperture: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Camera> {
        if let Some(r) = aperture_radius.filter(|r| !(*r >= 0.0 && r.is_finite())) {
            return Err(value_error(format!(
                "aperture_radius must be zero or positive, got {r}"
            )));
        }
        Ok(Camera::new(CameraDescription::ThinLens {
            fov_y_deg: fov_deg,
            aperture_radius,
            focus_distance,
            aperture: parse_aperture(aperture)?,
        }))
    }

    /// A real lens (a `Lens` or a built-in name; default: the scene file's,
    /// else dgauss50), focused at `focus_distance` (scene units from the
    /// sensor) or with the sensor `sensor_depth_mm` behind the stop (formerly
    /// `sensor_mm`), stopped down to `f_number`, with a `sensor_width_mm` wide
    /// sensor and an `aperture` shape.
    #[staticmethod]
    #[pyo3(signature = (lens = None, *, focus_distance = None, sensor_depth_mm = None, sensor_mm = None,
                        f_number = None, sensor_width_mm = None, aperture = None, scene_unit_m = None))]
    #[allow(clippy::too_many_arguments)]
    fn realistic(
        py: Python<'_>,
        lens: Option<&Bound<'_, PyAny>>,
        focus_distance: Option<f64>,
        sensor_depth_mm: Option<f64>,
        sensor_mm: Option<f64>,
        f_number: Option<f64>,
        sensor_width_mm: Option<f64>,
        aperture: Option<&Bound<'_, PyAny>>,
        scene_unit_m: Option<f64>,
    ) -> PyResult<Camera> {
        let sensor_depth_mm = match (sensor_depth_mm, sensor_mm) {
            (Some(_), Some(_)) => return Err(value_error("give sensor_depth_mm, not also sensor_mm (its old name)")),
            (None, Some(mm)) => {
                deprecated(
                    py,
                    "Camera.realistic(sensor_mm=...) is deprecated; use sensor_depth_mm=...",
                )?;
                Some(mm)
            }
            (depth, None) => depth,
        };
        let lens = lens.map(lens_from_py).transpose()?;
        let focus = match (focus_distance, sensor_depth_mm) {
            (Some(_), Some(_)) => return Err(value_error("give focus_distance or sensor_depth_mm, not both")),
            (Some(d), None) => Some(LensFocus::Distance(d)),
            (None, Some(mm)) => Some(LensFocus::SensorPositionMm(mm)),
            (None, None) => None,
        };
        Ok(Camera::new(CameraDescription::Realistic(RealisticDescription {
            lens: lens.map(|l| l.prescription),
            focus,
            sensor_width_mm,
            f_number,
            aperture: parse_aperture(aperture)?,
            scene_unit_m,
            radiometry: None,
        })))
    }
}

/// Warns that something is deprecated (a `DeprecationWarning` naming what replaces it).
fn deprecated(py: Python<'_>, message: &str) -> PyResult<()> {
    let category = py.get_type::<pyo3::exceptions::PyDeprecationWarning>();
    PyErr::warn(
        py,
        &category,
        &std::ffi::CString::new(message).expect("no NUL in the message"),
        2,
    )
}

// ---------------------------------------------------------------------------
// Rendering

/// `rgb` (`width` × `height` × 3, row-major) as a float32 (H, W, 3) array.
fn rgb_array<'py>(py: Python<'py>, image: &Image) -> Bound<'py, PyArray3<f32>> {
    Array3::from_shape_vec((image.height as usize, image.width as usize, 3), image.rgb.clone())
        .expect("an image holds width × height × 3 values")
        .into_pyarray(py)
}

/// Renders `scene` through `camera` (see the stub for the arguments). An
/// argument left out is the scene file's, else the library's default.
#[pyfunction]
#[pyo3(signature = (scene, camera = None, *, spp = None, resolution = None, seed = None, max_depth = None,
                    light_samples = None, threads = None, aovs = None, crop = None, progress = None,
                    sampler = None))]
#[allow(clippy::too_many_arguments)]
fn render<'py>(
    py: Python<'py>,
    scene: &Scene,
    camera: Option<&Camera>,
    spp: Option<u32>,
    resolution: Option<(u32, u32)>,
    seed: Option<u32>,
    max_depth: Option<u32>,
    light_samples: Option<u32>,
    threads: Option<usize>,
    aovs: Option<Vec<String>>,
    crop: Option<(u32, u32, u32, u32)>,
    progress: Option<Bound<'py, PyAny>>,
    sampler: Option<&str>,
) -> PyResult<Bound<'py, PyAny>> {
    let sampler = sampler
        .map(|name| {
            SamplerKind::from_name(name).ok_or_else(|| {
                value_error(format!(
                    "unknown sampler '{name}'; expected one of: {}",
                    SamplerKind::NAMES.join(", ")
                ))
            })
        })
        .transpose()?;
    let want_depth = match aovs.as_deref() {
        None | Some([]) => false,
        Some(names) => {
            if let Some(bad) = names.iter().find(|n| n.as_str() != "depth") {
                return Err(value_error(format!("unknown AOV '{bad}'; lenspath renders 'depth'")));
            }
            true
        }
    };
    let overrides = RenderOverrides {
        resolution,
        spp,
        max_depth,
        light_samples,
        seed,
        sampler,
        filter: None,
        threads,
        crop: crop.map(|(x0, y0, width, height)| PixelRect { x0, y0, width, height }),
        depth: Some(want_depth),
        camera: camera.map(|c| c.description.clone()).unwrap_or_default(),
    };
    let setup = resolve(&scene.options, &scene.view()?, &overrides).map_err(|e| to_py(e, FileKind::Lens))?;
    let camera = match camera {
        Some(c) => c.built_for(&setup)?,
        None => setup.build_camera().map_err(|e| to_py(e, FileKind::Lens))?,
    };
    let settings = setup.settings;
    let compiled = scene.compiled(py)?;

    // Render on a worker thread without the GIL; this thread wakes every
    // 50 ms to report progress and to turn Ctrl-C into a cancelled render,
    // and at once when the render ends (small renders, such as tiles, take
    // less than that).
    let cancel = AtomicBool::new(false);
    let (done, total) = (AtomicU64::new(0), AtomicU64::new(0));
    let finished = AtomicBool::new(false);
    let mut interrupt: Option<PyErr> = None;
    let waiting = std::thread::current();
    let output = std::thread::scope(|s| {
        let worker = s.spawn(|| {
            let out = render_scene(
                compiled.as_ref(),
                camera.as_ref(),
                &settings,
                &|d, t| {
                    done.store(d, Ordering::Relaxed);
                    total.store(t, Ordering::Relaxed);
                },
                &cancel,
            );
            finished.store(true, Ordering::Release);
            waiting.unpark();
            out
        });
        while !finished.load(Ordering::Acquire) {
            py.detach(|| std::thread::park_timeout(Duration::from_millis(50)));
            if interrupt.is_none() {
                if let Err(e) = py.check_signals() {
                    cancel.store(true, Ordering::SeqCst);
                    interrupt = Some(e);
                    continue;
                }
                if let Some(callback) = &progress {
                    if let Err(e) = callback.call1((done.load(Ordering::Relaxed), total.load(Ordering::Relaxed))) {
                        cancel.store(true, Ordering::SeqCst);
                        interrupt = Some(e);
                    }
                }
            }
        }
        worker.join().expect("the render thread does not panic")
    });
    if let Some(e) = interrupt {
        return Err(e);
    }
    let output = output.map_err(|e| to_py(e, FileKind::Scene))?;
    if let Some(callback) = &progress {
        callback.call1((output.stats.samples, output.stats.samples))?;
    }
    let rgb = rgb_array(py, &output.image);
    if !want_depth {
        return Ok(rgb.into_any());
    }
    let image = &output.image;
    let depth = Array2::from_shape_vec((image.height as usize, image.width as usize), image.depth.clone())
        .expect("a depth per pixel")
        .into_pyarray(py);
    let d = PyDict::new(py);
    d.set_item("rgb", rgb)?;
    d.set_item("depth", depth)?;
    Ok(d.into_any())
}

// ---------------------------------------------------------------------------
// Autofocus

/// What `autofocus` found and what it cost.
#[pyclass(module = "lenspath._core", frozen, get_all)]
struct AutofocusResult {
    /// The chosen sensor position, mm behind the stop.
    sensor_mm: f64,
    /// The distance in focus there (scene units from the sensor); None beyond infinity.
    focus_distance: Option<f64>,
    /// The focus measure's name.
    metric: String,
    /// The strategy's name.
    strategy: String,
    /// Every scored patch image: (sensor_mm, score) rows, in order (patch
    /// renders and refocused light fields).
    evaluations: Py<PyArray2<f64>>,
    /// How many of the evaluations are patch renders.
    patch_renders: usize,
    /// Light fields recorded (the patch with a margin, refocused to many sensor positions).
    light_fields: usize,
    /// Camera rays traced (patch render and light-field samples and probe rays).
    camera_rays: u64,
    /// Wall time, seconds.
    seconds: f64,
    /// The depth of focus at the chosen position, mm (the unit of focus errors).
    depth_of_focus_mm: f64,
    /// The camera given, focused there.
    camera: Camera,
}

#[pymethods]
impl AutofocusResult {
    fn __repr__(&self, py: Python<'_>) -> String {
        let distance = self
            .focus_distance
            .map_or_else(|| "None".to_string(), |d| format!("{d:.4}"));
        format!(
            "AutofocusResult(strategy='{}', metric='{}', sensor_mm={:.4}, focus_distance={distance}, \
             evaluations={}, patch_renders={}, camera_rays={})",
            self.strategy,
            self.metric,
            self.sensor_mm,
            self.evaluations.bind(py).shape()[0],
            self.patch_renders,
            self.camera_rays
        )
    }
}

/// Focuses the realistic camera on `patch` (x, y, width, height in fractions
/// of the image) by rendering it (see the stub).
#[pyfunction]
#[pyo3(signature = (scene, patch, camera = None, *, metric = None, strategy = None, patience = None,
                    spp = None, resolution = None, seed = None, max_depth = None, threads = None))]
#[allow(clippy::too_many_arguments)]
fn autofocus(
    py: Python<'_>,
    scene: &Scene,
    patch: (f64, f64, f64, f64),
    camera: Option<&Camera>,
    metric: Option<String>,
    strategy: Option<String>,
    patience: Option<usize>,
    spp: Option<u32>,
    resolution: Option<(u32, u32)>,
    seed: Option<u32>,
    max_depth: Option<u32>,
    threads: Option<usize>,
) -> PyResult<AutofocusResult> {
    let invalid = |e: Error| to_py(e, FileKind::Scene);
    let patch = NormalizedRect::new(patch.0, patch.1, patch.2, patch.3).map_err(invalid)?;
    let view = scene.view()?;
    let description = match camera {
        Some(c) => c.realistic_description()?.clone(),
        None => RealisticDescription::default(),
    };
    let overrides = AutofocusOverrides {
        resolution,
        spp,
        max_depth,
        seed,
        threads,
        metric,
        strategy,
        patience,
        camera: description.clone(),
    };
    let search = resolve_autofocus(&scene.options, &view, patch, &overrides).map_err(|e| match e {
        Error::InvalidArgument(_) => invalid(e),
        other => to_py(other, FileKind::Lens),
    })?;
    let (settings, search, metric) = (search.settings, search.strategy, overrides.metric);
    let metric = metric.unwrap_or_else(|| lenspath::defaults::AUTOFOCUS_METRIC.to_string());
    let compiled = scene.compiled(py)?;
    let (result, depth_of_focus_mm) = py
        .detach(|| {
            let mut focuser = Focuser::new(&compiled, view.pose, settings)?;
            let result = focuser.run(search)?;
            let dof = focuser.depth_of_focus_mm(result.sensor_z_mm);
            Ok::<_, Error>((result, dof))
        })
        .map_err(|e| to_py(e, FileKind::Lens))?;
    let rows: Vec<f64> = result
        .evaluations
        .iter()
        .flat_map(|e| [e.sensor_z_mm, e.score])
        .collect();
    let evaluations = Array2::from_shape_vec((result.evaluations.len(), 2), rows)
        .expect("two values per evaluation")
        .into_pyarray(py)
        .unbind();
    Ok(AutofocusResult {
        sensor_mm: result.sensor_z_mm,
        focus_distance: result.focus_distance,
        metric,
        strategy: result.strategy.to_string(),
        evaluations,
        patch_renders: result.patch_renders(),
        light_fields: result.light_fields,
        camera_rays: result.camera_rays,
        seconds: result.seconds,
        depth_of_focus_mm,
        camera: Camera::new(CameraDescription::Realistic(RealisticDescription {
            focus: Some(LensFocus::SensorPositionMm(result.sensor_z_mm)),
            ..description
        })),
    })
}

// ---------------------------------------------------------------------------
// Images, focus measures, bokeh

/// An (H, W, 3) float32 array as a core image.
fn image_from_array(image: &PyArrayLike3<'_, f32, AllowTypeChange>) -> PyResult<Image> {
    let shape = image.shape();
    if shape[2] != 3 {
        return Err(value_error(format!("images are H x W x 3 arrays, got {shape:?}")));
    }
    Ok(Image {
        width: shape[1] as u32,
        height: shape[0] as u32,
        rgb: image.as_array().iter().copied().collect(),
        depth: vec![f32::INFINITY; shape[0] * shape[1]],
        spp_min: 0,
        spp_requested: 0,
    })
}

/// Reads a PNG, JPEG or EXR image as linear RGB, float32 (H, W, 3).
#[pyfunction]
fn read<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let image = read_image(&path).map_err(|e| to_py(e, FileKind::Image))?;
    Ok(rgb_array(py, &image.image))
}

/// Writes linear RGB (H, W, 3) as PNG (sRGB, `exposure` stops) or EXR, atomically.
#[pyfunction]
#[pyo3(signature = (path, image, exposure = 0.0))]
fn write(path: PathBuf, image: PyArrayLike3<'_, f32, AllowTypeChange>, exposure: f32) -> PyResult<()> {
    write_image(&path, &image_from_array(&image)?, exposure).map_err(|e| to_py(e, FileKind::Image))
}

/// A focus measure of an (H, W, 3) image (see `focus_measures()`).
#[pyfunction]
#[pyo3(signature = (image, metric = "tenengrad"))]
fn focus_measure(image: PyArrayLike3<'_, f32, AllowTypeChange>, metric: &str) -> PyResult<f64> {
    let measure = FocusMeasure::from_name(metric).map_err(|e| to_py(e, FileKind::Image))?;
    let image = image_from_array(&image)?;
    let patch =
        Patch::new(image.width as usize, image.height as usize, &image.rgb).map_err(|e| to_py(e, FileKind::Image))?;
    Ok(measure.evaluate(&patch))
}

/// The focus measures' names.
#[pyfunction]
fn focus_measures() -> Vec<&'static str> {
    lenspath::autofocus::FOCUS_MEASURES.iter().map(|(n, _)| *n).collect()
}

/// Blurs an (H, W, 3) image with a bokeh kernel: `aperture` a shape
/// ("circle", "blades:6", "star:5:0.4") `diameter_px` across, or `mask` a 2-D
/// array (resized so its longer side is `diameter_px`, if given).
#[pyfunction]
#[pyo3(signature = (image, *, aperture = None, mask = None, diameter_px = None, edges = "renormalize", method = "auto"))]
fn bokeh<'py>(
    py: Python<'py>,
    image: PyArrayLike3<'_, f32, AllowTypeChange>,
    aperture: Option<&str>,
    mask: Option<PyArrayLike2<'_, f32, AllowTypeChange>>,
    diameter_px: Option<f64>,
    edges: &str,
    method: &str,
) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let kernel = match (aperture, &mask) {
        (Some(_), Some(_)) => return Err(value_error("give aperture or mask, not both")),
        (None, None) => return Err(value_error("give aperture (such as 'blades:6') or mask (a 2-D array)")),
        (Some(shape), None) => {
            let diameter = diameter_px.ok_or_else(|| value_error("an aperture kernel needs diameter_px"))?;
            if !(diameter >= 1.0 && diameter.is_finite()) {
                return Err(value_error(format!("diameter_px must be at least 1, got {diameter}")));
            }
            let shape = ApertureShape::parse(shape).map_err(|e| to_py(e, FileKind::Image))?;
            Kernel::from_aperture(&Aperture::new(&shape).map_err(|e| to_py(e, FileKind::Image))?, diameter)
        }
        (None, Some(m)) => {
            let (h, w) = (m.shape()[0], m.shape()[1]);
            let size = match diameter_px {
                None => KernelSize::Native,
                Some(d) if d >= 1.0 && d.is_finite() => KernelSize::LongerSide(d.round() as u32),
                Some(d) => return Err(value_error(format!("diameter_px must be at least 1, got {d}"))),
            };
            let values: Vec<f32> = m.as_array().iter().copied().collect();
            Kernel::from_mask(w, h, &values, size).map_err(|e| to_py(e, FileKind::Image))?
        }
    };
    let edges = match edges {
        "renormalize" => Edges::Renormalize,
        "black" => Edges::Black,
        other => {
            return Err(value_error(format!(
                "edges must be 'renormalize' or 'black', got '{other}'"
            )))
        }
    };
    let method = match method {
        "auto" => Method::Auto,
        "direct" => Method::Direct,
        "fft" => Method::Fft,
        other => {
            return Err(value_error(format!(
                "method must be 'auto', 'direct' or 'fft', got '{other}'"
            )))
        }
    };
    let mut image = image_from_array(&image)?;
    let (w, h) = (image.width as usize, image.height as usize);
    py.detach(|| convolve_rgb(&mut image.rgb, w, h, &kernel, method, edges));
    Ok(rgb_array(py, &image))
}

/// Depth-aware lens blur of an (H, W, 3) image by its (H, W) depths (see the stub).
#[pyfunction]
#[pyo3(signature = (image, depth, focus_distance, *, lens = None, f_number = None, focal_length_mm = None,
                    aperture_radius = None, fov_deg = None, sensor_width_mm = 36.0, scene_unit_m = 1.0,
                    aperture = None))]
#[allow(clippy::too_many_arguments)]
fn lens_blur<'py>(
    py: Python<'py>,
    image: PyArrayLike3<'_, f32, AllowTypeChange>,
    depth: PyArrayLike2<'_, f32, AllowTypeChange>,
    focus_distance: f64,
    lens: Option<&Bound<'_, PyAny>>,
    f_number: Option<f64>,
    focal_length_mm: Option<f64>,
    aperture_radius: Option<f64>,
    fov_deg: Option<f64>,
    sensor_width_mm: f64,
    scene_unit_m: f64,
    aperture: Option<&Bound<'_, PyAny>>,
) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let image = image_from_array(&image)?;
    let (width, height) = (image.width, image.height);
    if depth.shape() != [height as usize, width as usize] {
        return Err(value_error(format!(
            "depth must be {height} x {width} like the image, got {:?}",
            depth.shape()
        )));
    }
    let invalid = |e: Error| to_py(e, FileKind::Lens);
    let coc = match (lens, focal_length_mm, aperture_radius) {
        (None, None, Some(radius)) => {
            let fov = fov_deg.ok_or_else(|| value_error("aperture_radius needs fov_deg (the thin-lens camera's)"))?;
            CircleOfConfusion::thin_lens_camera(radius, focus_distance, fov, height).map_err(invalid)?
        }
        (Some(lens), None, None) => {
            let lens = lens_from_py(lens)?;
            let paraxial = lens.system.paraxial().map_err(invalid)?;
            let n = f_number.unwrap_or(paraxial.f_number);
            let f = paraxial.effective_focal_length_mm;
            CircleOfConfusion::thin_lens_in_scene_units(f, n, focus_distance, scene_unit_m, sensor_width_mm, width)
                .map_err(invalid)?
        }
        (None, Some(f), None) => {
            let n = f_number.ok_or_else(|| value_error("focal_length_mm needs f_number"))?;
            CircleOfConfusion::thin_lens_in_scene_units(f, n, focus_distance, scene_unit_m, sensor_width_mm, width)
                .map_err(invalid)?
        }
        _ => {
            return Err(value_error(
                "describe one lens: lens (with f_number to stop it down), focal_length_mm with f_number, \
                 or aperture_radius with fov_deg",
            ))
        }
    };
    let shape = parse_aperture(aperture)?.unwrap_or(ApertureShape::Circle);
    let aperture = Aperture::new(&shape).map_err(|e| to_py(e, FileKind::Image))?;
    let depth: Vec<f32> = depth.as_array().iter().copied().collect();
    let blurred = py
        .detach(|| depth_blur(&image.rgb, &depth, width as usize, height as usize, &coc, &aperture))
        .map_err(|e| to_py(e, FileKind::Image))?;
    Ok(rgb_array(py, &Image { rgb: blurred, ..image }))
}

/// The native module.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("LenspathError", py.get_type::<LenspathError>())?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("LensError", py.get_type::<LensError>())?;
    m.add_class::<Scene>()?;
    m.add_class::<Lens>()?;
    m.add_class::<Camera>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(builtin_scenes, m)?)?;
    m.add_function(wrap_pyfunction!(defaults, m)?)?;
    m.add_function(wrap_pyfunction!(builtin_lenses, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(read, m)?)?;
    m.add_function(wrap_pyfunction!(write, m)?)?;
    m.add_function(wrap_pyfunction!(focus_measure, m)?)?;
    m.add_function(wrap_pyfunction!(focus_measures, m)?)?;
    m.add_function(wrap_pyfunction!(bokeh, m)?)?;
    m.add_function(wrap_pyfunction!(lens_blur, m)?)?;
    m.add_class::<AutofocusResult>()?;
    m.add_function(wrap_pyfunction!(autofocus, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
