//! Cameras: what a caller describes (`lenspath::setup::CameraDescription`), pickled and built once per setup.

use std::sync::{Arc, Mutex};

use lenspath::camera::{ApertureShape, Camera as CameraTrait, CameraPose, LensFocus};
use lenspath::setup::{CameraDescription, CameraSettings, RealisticDescription, RenderSetup};
use numpy::ndarray::Array2;
use numpy::{AllowTypeChange, IntoPyArray, PyArrayLike2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyTuple;

use crate::error::{renamed, to_py, value_error};
use crate::lens::Lens;

/// A camera for `render`: `Camera.pinhole(...)`, `Camera.thin_lens(...)` or
/// `Camera.realistic(...)`; what it leaves unset comes from the scene (the
/// library resolves it: [`lenspath::setup::resolve_camera`]).
#[pyclass(module = "lenspath._core")]
#[derive(Clone)]
pub(crate) struct Camera {
    pub(crate) description: CameraDescription,
    /// The camera last built from it, and for what (resolved settings, pose,
    /// image size): a realistic camera's exit-pupil tables take a tenth of a
    /// second, which repeated renders (tiles, patches) need not pay again.
    pub(crate) built: Arc<Mutex<Option<BuiltCamera>>>,
}

/// A camera as built for a render, and what it was built for.
pub(crate) type BuiltCamera = (CameraSettings, CameraPose, (u32, u32), Arc<dyn CameraTrait>);

impl Camera {
    pub(crate) fn new(description: CameraDescription) -> Camera {
        Camera {
            description,
            built: Arc::default(),
        }
    }

    /// The camera of `setup` (resolved from this camera's description), built
    /// once per resolved settings, pose and image size.
    pub(crate) fn built_for(&self, setup: &RenderSetup) -> PyResult<Arc<dyn CameraTrait>> {
        // Compared by value: a mask's `Debug` form gives only its size.
        let size = (setup.settings.width, setup.settings.height);
        let mut built = self.built.lock().unwrap_or_else(|p| p.into_inner());
        if let Some((settings, pose, built_size, camera)) = built.as_ref() {
            if (settings, pose, built_size) == (&setup.camera, &setup.pose, &size) {
                return Ok(camera.clone());
            }
        }
        let camera = setup.build_camera().map_err(to_py)?;
        *built = Some((setup.camera.clone(), setup.pose, size, camera.clone()));
        Ok(camera)
    }

    /// The realistic camera's description, or the error other cameras get where one is needed.
    pub(crate) fn realistic_description(&self) -> PyResult<&RealisticDescription> {
        match &self.description {
            CameraDescription::Realistic(r) => Ok(r),
            _ => Err(value_error("this needs a realistic camera (Camera.realistic)")),
        }
    }
}

/// A `Lens`, or a built-in lens by name.
pub(crate) fn lens_from_py(lens: &Bound<'_, PyAny>) -> PyResult<Lens> {
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
pub(crate) fn parse_aperture(aperture: Option<&Bound<'_, PyAny>>) -> PyResult<Option<ApertureShape>> {
    let Some(aperture) = aperture else {
        return Ok(None);
    };
    if let Ok(name) = aperture.extract::<String>() {
        return ApertureShape::parse(&name).map(Some).map_err(to_py);
    }
    let mask = aperture
        .extract::<PyArrayLike2<'_, f32, AllowTypeChange>>()
        .map_err(|_| value_error("aperture must be a shape name (such as 'blades:6') or a 2-D array (a mask)"))?;
    let (height, width) = (mask.shape()[0], mask.shape()[1]);
    let values = mask.as_array().iter().copied().collect();
    ApertureShape::mask(width, height, values).map(Some).map_err(to_py)
}

/// An aperture shape as Python gives it: its name (such as "blades:6:0:0.5") or its mask array.
pub(crate) fn aperture_to_py<'py>(py: Python<'py>, shape: &ApertureShape) -> PyResult<Bound<'py, PyAny>> {
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

/// An aperture shape as `repr` shows it: its name, or the mask's size.
fn aperture_repr(shape: &ApertureShape) -> String {
    match shape {
        ApertureShape::Mask(mask) => format!("<{}x{} mask>", mask.width, mask.height),
        ApertureShape::Circle => "'circle'".into(),
        ApertureShape::Blades {
            count,
            rotation_deg,
            curvature,
        } => format!("'blades:{count}:{rotation_deg}:{curvature}'"),
        ApertureShape::Star {
            points,
            inner_ratio,
            rotation_deg,
        } => format!("'star:{points}:{inner_ratio}:{rotation_deg}'"),
    }
}

#[pymethods]
impl Camera {
    /// The constructor call that makes this camera, naming the settings given (the rest come from
    /// the scene): `Camera.realistic(lens='dgauss50', f_number=2.8)`.
    pub(crate) fn __repr__(&self) -> String {
        fn set<T: std::fmt::Display>(name: &str, value: Option<T>) -> Option<String> {
            value.map(|v| format!("{name}={v}"))
        }
        let python_bool = |b: bool| if b { "True" } else { "False" };
        let (kind, given): (&str, Vec<Option<String>>) = match &self.description {
            CameraDescription::Pinhole { fov_y_deg } => ("pinhole", vec![set("fov_deg", *fov_y_deg)]),
            CameraDescription::ThinLens {
                fov_y_deg,
                aperture_radius,
                focus_distance,
                aperture,
            } => (
                "thin_lens",
                vec![
                    set("fov_deg", *fov_y_deg),
                    set("aperture_radius", *aperture_radius),
                    set("focus_distance", *focus_distance),
                    set("aperture", aperture.as_ref().map(aperture_repr)),
                ],
            ),
            CameraDescription::Realistic(r) => (
                "realistic",
                vec![
                    set("lens", r.lens.as_ref().map(|l| format!("'{}'", l.name()))),
                    match r.focus {
                        Some(LensFocus::Distance(d)) => set("focus_distance", Some(d)),
                        Some(LensFocus::SensorDepthMm(mm)) => set("sensor_depth_mm", Some(mm)),
                        None => None,
                    },
                    set("f_number", r.f_number),
                    set("sensor_width_mm", r.sensor_width_mm),
                    set("aperture", r.aperture.as_ref().map(aperture_repr)),
                    set("scene_unit_m", r.scene_unit_m),
                    set("dispersion", r.dispersion.map(python_bool)),
                    set("diffraction", r.diffraction.map(python_bool)),
                    set("desqueeze", r.desqueeze.map(python_bool)),
                ],
            ),
        };
        let given: Vec<String> = given.into_iter().flatten().collect();
        format!("Camera.{kind}({})", given.join(", "))
    }

    /// Pickles as its kind and settings (`Camera._from_state`).
    pub(crate) fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
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
                    Some(LensFocus::SensorDepthMm(mm)) => Some(mm),
                    _ => None,
                },
                r.sensor_width_mm,
                r.f_number,
                r.scene_unit_m,
                r.dispersion,
                r.desqueeze,
                r.diffraction,
            ),
            _ => (None, None, None, None, None, None, None),
        };
        Ok((
            py.get_type::<Camera>().getattr("_from_state")?,
            (state, realistic).into_pyobject(py)?,
        ))
    }

    /// The camera `__reduce__` describes.
    #[staticmethod]
    #[allow(clippy::type_complexity)]
    pub(crate) fn _from_state(
        py: Python<'_>,
        state: (
            String,
            Option<f32>,
            Option<f32>,
            Option<f64>,
            Option<Bound<'_, PyAny>>,
            Option<Bound<'_, PyAny>>,
        ),
        realistic: (
            Option<f64>,
            Option<f64>,
            Option<f64>,
            Option<f64>,
            Option<bool>,
            Option<bool>,
            Option<bool>,
        ),
    ) -> PyResult<Camera> {
        let (kind, fov_deg, aperture_radius, focus_distance, aperture, lens) = state;
        let (aperture, lens) = (aperture.filter(|a| !a.is_none()), lens.filter(|l| !l.is_none()));
        let (sensor_depth_mm, sensor_width_mm, f_number, scene_unit_m, dispersion, desqueeze, diffraction) = realistic;
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
                dispersion,
                desqueeze,
                diffraction,
            ),
        }
    }

    /// An ideal pinhole; `fov_deg` (vertical) defaults to the scene's.
    #[staticmethod]
    #[pyo3(signature = (fov_deg = None))]
    pub(crate) fn pinhole(fov_deg: Option<f32>) -> Camera {
        Camera::new(CameraDescription::Pinhole { fov_y_deg: fov_deg })
    }

    /// An ideal thin lens of `aperture_radius` (scene units; default 0.05)
    /// focused at `focus_distance` (default: the scene's subject); `aperture`
    /// a shape such as "blades:6" or "star:5:0.4" (default: the scene file's).
    #[staticmethod]
    #[pyo3(signature = (aperture_radius = None, focus_distance = None, fov_deg = None, aperture = None))]
    pub(crate) fn thin_lens(
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
    /// sensor and an `aperture` shape; `dispersion=False` gives every glass
    /// its d-line index (default: the scene file's, else glasses disperse);
    /// `desqueeze=True` stretches an anamorphic lens's image by its squeeze;
    /// `diffraction=True` spreads each film point by the aperture's
    /// Fraunhofer pattern (default: the scene file's, else off).
    #[staticmethod]
    #[pyo3(signature = (lens = None, *, focus_distance = None, sensor_depth_mm = None, sensor_mm = None,
                        f_number = None, sensor_width_mm = None, aperture = None, scene_unit_m = None,
                        dispersion = None, desqueeze = None, diffraction = None))]
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn realistic(
        py: Python<'_>,
        lens: Option<&Bound<'_, PyAny>>,
        focus_distance: Option<f64>,
        sensor_depth_mm: Option<f64>,
        sensor_mm: Option<f64>,
        f_number: Option<f64>,
        sensor_width_mm: Option<f64>,
        aperture: Option<&Bound<'_, PyAny>>,
        scene_unit_m: Option<f64>,
        dispersion: Option<bool>,
        desqueeze: Option<bool>,
        diffraction: Option<bool>,
    ) -> PyResult<Camera> {
        let sensor_depth_mm = renamed(
            py,
            "Camera.realistic",
            ("sensor_depth_mm", sensor_depth_mm),
            ("sensor_mm", sensor_mm),
            "the same mm behind the stop",
        )?;
        let lens = lens.map(lens_from_py).transpose()?;
        let focus = match (focus_distance, sensor_depth_mm) {
            (Some(_), Some(_)) => return Err(value_error("give focus_distance or sensor_depth_mm, not both")),
            (Some(d), None) => Some(LensFocus::Distance(d)),
            (None, Some(mm)) => Some(LensFocus::SensorDepthMm(mm)),
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
            dispersion,
            diffraction,
            desqueeze,
        })))
    }
}
