//! Rendering: the options map onto `lenspath::setup::RenderOverrides`; the render runs without the GIL.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::Arc;
use std::time::Duration;

use lenspath::camera::Camera as CameraTrait;
use lenspath::film::Image;
use lenspath::film::PixelRect;
use lenspath::integrator::IntegratorKind;
use lenspath::render::render as render_scene;
use lenspath::sampling::SamplerKind;
use lenspath::scene::CompiledScene;
use lenspath::sensor::develop::develop;
use lenspath::setup::{resolve, RenderOverrides, RenderSetup};
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray3};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::camera::Camera;
use crate::error::{guarded, named, to_py, value_error, whole_number};
use crate::scene::Scene;
use crate::sensor::{RawFrame, Sensor};

/// `rgb` (`width` × `height` × 3, row-major) as a float32 (H, W, 3) array.
pub(crate) fn rgb_array<'py>(py: Python<'py>, image: &Image) -> Bound<'py, PyArray3<f32>> {
    Array3::from_shape_vec((image.height as usize, image.width as usize, 3), image.rgb.clone())
        .expect("an image holds width × height × 3 values")
        .into_pyarray(py)
}

/// What a render of `scene` through `camera` (None: the scene's own) with
/// `overrides` needs: its resolved setup, the camera built for it and the
/// compiled scene.
pub(crate) fn prepared(
    py: Python<'_>,
    scene: &Scene,
    camera: Option<&Camera>,
    overrides: &RenderOverrides,
) -> PyResult<(RenderSetup, Arc<dyn CameraTrait>, Arc<CompiledScene>)> {
    let setup = resolve(&scene.options, &scene.view()?, overrides).map_err(to_py)?;
    let camera = match camera {
        Some(c) => c.built_for(&setup)?,
        None => setup.build_camera().map_err(to_py)?,
    };
    let compiled = scene.compiled(py, setup.settings.threads)?;
    Ok((setup, camera, compiled))
}

/// Renders `scene` through `camera` (see the stub for the arguments). An
/// argument left out is the scene file's, else the library's default.
#[pyfunction]
#[pyo3(signature = (scene, camera = None, *, spp = None, resolution = None, seed = None, max_depth = None,
                    light_samples = None, threads = None, aovs = None, crop = None, progress = None,
                    sampler = None, wavelength_nm = None, sensor = None, integrator = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn render<'py>(
    py: Python<'py>,
    scene: &Scene,
    camera: Option<&Camera>,
    spp: Option<i64>,
    resolution: Option<(u32, u32)>,
    seed: Option<i64>,
    max_depth: Option<i64>,
    light_samples: Option<i64>,
    threads: Option<i64>,
    aovs: Option<Vec<String>>,
    crop: Option<(u32, u32, u32, u32)>,
    progress: Option<Bound<'py, PyAny>>,
    sampler: Option<&str>,
    wavelength_nm: Option<f32>,
    sensor: Option<&Sensor>,
    integrator: Option<&str>,
) -> PyResult<Bound<'py, PyAny>> {
    let integrator = named::<IntegratorKind>(integrator)?;
    let sampler = named::<SamplerKind>(sampler)?;
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
        spp: whole_number("spp", spp)?,
        integrator,
        max_depth: whole_number("max_depth", max_depth)?,
        light_samples: whole_number("light_samples", light_samples)?,
        seed: whole_number("seed", seed)?,
        sampler,
        filter: None,
        threads: whole_number("threads", threads)?,
        crop: crop.map(|(x0, y0, width, height)| PixelRect { x0, y0, width, height }),
        depth: Some(want_depth),
        wavelength_nm,
        camera: camera.map(|c| c.description.clone()).unwrap_or_default(),
        sensor: sensor.map(|s| s.description.clone()),
    };
    if sensor.is_some() && want_depth {
        return Err(value_error(
            "a sensor render gives a raw frame, without AOVs: render the depth without the sensor",
        ));
    }
    let (setup, camera, compiled) = prepared(py, scene, camera, &overrides)?;
    let settings = setup.settings;

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
            // Guarded: a panic must still end the wait below.
            let out = guarded(|| {
                render_scene(
                    compiled.as_ref(),
                    camera.as_ref(),
                    &settings,
                    &|d, t| {
                        done.store(d, Ordering::Relaxed);
                        total.store(t, Ordering::Relaxed);
                    },
                    &cancel,
                )
            });
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
        worker.join().expect("the render thread's panics are caught")
    });
    if let Some(e) = interrupt {
        return Err(e);
    }
    let output = output?.map_err(to_py)?;
    if let Some(callback) = &progress {
        callback.call1((output.stats.samples, output.stats.samples))?;
    }
    // Through a sensor: the raw frame when one was asked for, else (a scene
    // file's `[sensor]`) the developed image, as `lenspath render --out`.
    if let Some((frame, development)) = setup.capture(camera.as_ref(), &output.image).map_err(to_py)? {
        if sensor.is_some() {
            return Ok(Bound::new(py, RawFrame::new(frame, development))?.into_any());
        }
        return Ok(rgb_array(py, &develop(&frame, &development)).into_any());
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
