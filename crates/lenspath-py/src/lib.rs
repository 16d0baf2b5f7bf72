//! The native module `lenspath._core`: a thin binding of the `lenspath`
//! crate, wrapped by the pure-Python package `lenspath` (python/lenspath),
//! whose `.pyi` stub documents it for users.
//!
//! Library errors become Python exceptions (`error::to_py`): bad arguments
//! `ValueError`, broken scene files `lenspath.SceneError`, broken lens tables
//! `lenspath.LensError`, I/O failures `OSError`. Renders release the GIL and
//! poll for Ctrl-C (see `render::render`).
//!
//! One module per concept, as the library: `error` (exceptions), `cli` (the `lenspath` command), `scene`,
//! `emission` (light spectra), `glass`, `lens`, `camera`, `sensor`, `render`, `guiding`, `autofocus`, `image`; this file only
//! registers them.

mod autofocus;
mod camera;
mod cli;
mod emission;
mod error;
mod glass;
mod guiding;
mod image;
mod lens;
mod render;
mod scene;
mod sensor;
mod wave;

use pyo3::prelude::*;

use crate::error::{LensError, LenspathError, SceneError};

/// The native module.
#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("LenspathError", py.get_type::<LenspathError>())?;
    m.add("SceneError", py.get_type::<SceneError>())?;
    m.add("LensError", py.get_type::<LensError>())?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<glass::Glass>()?;
    m.add_class::<emission::Emission>()?;
    m.add_class::<lens::Lens>()?;
    m.add_class::<camera::Camera>()?;
    m.add_class::<sensor::Sensor>()?;
    m.add_class::<sensor::RawFrame>()?;
    m.add_function(wrap_pyfunction!(sensor::sensor_models, m)?)?;
    m.add_function(wrap_pyfunction!(sensor::_sensor_from_settings, m)?)?;
    m.add_function(wrap_pyfunction!(scene::load, m)?)?;
    m.add_function(wrap_pyfunction!(scene::builtin_scenes, m)?)?;
    m.add_function(wrap_pyfunction!(scene::builtin_scene_named, m)?)?;
    m.add_function(wrap_pyfunction!(scene::defaults, m)?)?;
    m.add_function(wrap_pyfunction!(lens::builtin_lenses, m)?)?;
    m.add_function(wrap_pyfunction!(render::render, m)?)?;
    m.add_function(wrap_pyfunction!(guiding::guide_map, m)?)?;
    m.add_function(wrap_pyfunction!(image::read, m)?)?;
    m.add_function(wrap_pyfunction!(image::write, m)?)?;
    m.add_function(wrap_pyfunction!(image::read_exr, m)?)?;
    m.add_function(wrap_pyfunction!(image::write_exr, m)?)?;
    m.add_function(wrap_pyfunction!(image::focus_measure, m)?)?;
    m.add_function(wrap_pyfunction!(image::focus_measures, m)?)?;
    m.add_function(wrap_pyfunction!(image::bokeh, m)?)?;
    m.add_function(wrap_pyfunction!(image::lens_blur, m)?)?;
    m.add_class::<autofocus::AutofocusResult>()?;
    m.add_function(wrap_pyfunction!(autofocus::autofocus, m)?)?;
    m.add_function(wrap_pyfunction!(cli::run_cli, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("MAX_SAMPLES_PER_PIXEL", lenspath::sampling::MAX_SAMPLES_PER_PIXEL)?;
    Ok(())
}
