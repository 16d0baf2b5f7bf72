//! Autofocus: the options map onto `lenspath::setup::AutofocusOverrides`.

use lenspath::autofocus::{FocusMeasure, Focuser, SensorSignal, Strategy};
use lenspath::camera::LensFocus;
use lenspath::film::NormalizedRect;
use lenspath::names::Named;
use lenspath::setup::{resolve_autofocus, AutofocusOverrides, CameraDescription, RealisticDescription};
use lenspath::Error;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::camera::Camera;
use crate::error::{deprecated, guarded, named, to_py, whole_number};
use crate::scene::Scene;
use crate::sensor::Sensor;

/// What `autofocus` found and what it cost.
#[pyclass(module = "lenspath._core", frozen, get_all)]
pub(crate) struct AutofocusResult {
    /// The chosen sensor position, mm behind the stop.
    pub(crate) sensor_depth_mm: f64,
    /// The distance in focus there (scene units from the sensor); None beyond infinity.
    pub(crate) focus_distance: Option<f64>,
    /// The focus measure's name.
    pub(crate) metric: String,
    /// The strategy's name.
    pub(crate) strategy: String,
    /// Every scored patch image: (sensor_mm, score) rows, in order (patch
    /// renders and refocused light fields).
    pub(crate) evaluations: Py<PyArray2<f64>>,
    /// How many of the evaluations are patch renders.
    pub(crate) patch_renders: usize,
    /// Light fields recorded (the patch with a margin, refocused to many sensor positions).
    pub(crate) light_fields: usize,
    /// Camera rays traced (patch render and light-field samples and probe rays).
    pub(crate) camera_rays: u64,
    /// Wall time, seconds.
    pub(crate) seconds: f64,
    /// The depth of focus at the chosen position, mm (the unit of focus errors).
    pub(crate) depth_of_focus_mm: f64,
    /// The camera given, focused there.
    pub(crate) camera: Camera,
    /// Through a sensor: the exposure time its frames were taken at, s (None without one).
    pub(crate) exposure_time_s: Option<f64>,
    /// Through a sensor: the ISO speed its frames were taken at.
    pub(crate) iso: Option<f64>,
    /// What the strategy could not do as its name says, and what it did instead (empty when it
    /// did all of it).
    pub(crate) fallbacks: Vec<String>,
}

#[pymethods]
impl AutofocusResult {
    /// Deprecated: `sensor_depth_mm`.
    #[getter]
    pub(crate) fn sensor_mm(&self, py: Python<'_>) -> PyResult<f64> {
        deprecated(py, "AutofocusResult.sensor_mm is deprecated; use sensor_depth_mm")?;
        Ok(self.sensor_depth_mm)
    }

    pub(crate) fn __repr__(&self, py: Python<'_>) -> String {
        let distance = self
            .focus_distance
            .map_or_else(|| "None".to_string(), |d| format!("{d:.4}"));
        format!(
            "AutofocusResult(strategy='{}', metric='{}', sensor_depth_mm={:.4}, focus_distance={distance}, \
             evaluations={}, patch_renders={}, camera_rays={}, fallbacks={:?})",
            self.strategy,
            self.metric,
            self.sensor_depth_mm,
            self.evaluations.bind(py).shape()[0],
            self.patch_renders,
            self.camera_rays,
            self.fallbacks
        )
    }
}

/// Focuses the realistic camera on `patch` (x, y, width, height in fractions
/// of the image) by rendering it (see the stub).
#[pyfunction]
#[pyo3(signature = (scene, patch, camera = None, *, metric = None, strategy = None, patience = None,
                    spp = None, resolution = None, seed = None, max_depth = None, threads = None,
                    sensor = None, sensor_signal = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn autofocus(
    py: Python<'_>,
    scene: &Scene,
    patch: (f64, f64, f64, f64),
    camera: Option<&Camera>,
    metric: Option<String>,
    strategy: Option<String>,
    patience: Option<i64>,
    spp: Option<i64>,
    resolution: Option<(u32, u32)>,
    seed: Option<i64>,
    max_depth: Option<i64>,
    threads: Option<i64>,
    sensor: Option<&Sensor>,
    sensor_signal: Option<String>,
) -> PyResult<AutofocusResult> {
    let patch = NormalizedRect::new(patch.0, patch.1, patch.2, patch.3).map_err(to_py)?;
    let view = scene.view()?;
    let description = match camera {
        Some(c) => c.realistic_description()?.clone(),
        None => RealisticDescription::default(),
    };
    let overrides = AutofocusOverrides {
        resolution,
        spp: whole_number("spp", spp)?,
        max_depth: whole_number("max_depth", max_depth)?,
        seed: whole_number("seed", seed)?,
        threads: whole_number("threads", threads)?,
        metric: named::<FocusMeasure>(metric.as_deref())?,
        strategy: named::<Strategy>(strategy.as_deref())?,
        patience: whole_number("patience", patience)?,
        camera: description.clone(),
        sensor: sensor.map(|s| s.description.clone()),
        sensor_signal: named::<SensorSignal>(sensor_signal.as_deref())?,
    };
    let search = resolve_autofocus(&scene.options, &view, patch, &overrides).map_err(to_py)?;
    let metric = search.settings.measure.name().to_string();
    let compiled = scene.compiled(py, search.settings.threads)?;
    let (result, depth_of_focus_mm) = py
        .detach(|| {
            guarded(|| {
                let mut focuser = Focuser::new(&compiled, search.pose, search.settings)?;
                let result = focuser.run(search.strategy)?;
                let dof = focuser.depth_of_focus_mm(result.sensor_depth_mm);
                Ok::<_, Error>((result, dof))
            })
        })?
        .map_err(to_py)?;
    let rows: Vec<f64> = result
        .evaluations
        .iter()
        .flat_map(|e| [e.sensor_depth_mm, e.score])
        .collect();
    let evaluations = Array2::from_shape_vec((result.evaluations.len(), 2), rows)
        .expect("two values per evaluation")
        .into_pyarray(py)
        .unbind();
    Ok(AutofocusResult {
        sensor_depth_mm: result.sensor_depth_mm,
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
            focus: Some(LensFocus::SensorDepthMm(result.sensor_depth_mm)),
            ..description
        })),
        exposure_time_s: result.exposure_time_s,
        iso: result.iso,
        fallbacks: result.fallbacks,
    })
}
