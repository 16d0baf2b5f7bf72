//! Path guiding: `guide_map`, what a guided render's guide learned at the
//! surface seen at a point of the image (`lenspath render --guide-map`).

use std::sync::atomic::AtomicBool;

use lenspath::guiding::map::DensityMap;
use lenspath::integrator::{guiding_can_help, IntegratorKind};
use lenspath::render::{guide_map_at_pixel, train_guide};
use lenspath::sampling::SamplerKind;
use lenspath::setup::RenderOverrides;
use lenspath::Error;
use numpy::ndarray::Array2;
use numpy::IntoPyArray;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::camera::Camera;
use crate::error::{guarded, named, to_py, value_error, whole_number};
use crate::render::prepared;
use crate::scene::Scene;

/// Trains the guide of a guided render of `scene` through `camera` and
/// returns its density at the surface seen at `at` (see the stub).
#[pyfunction]
#[pyo3(signature = (scene, camera = None, *, at, resolution = None, seed = None, max_depth = None,
                    light_samples = None, threads = None, sampler = None, size = 256))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn guide_map<'py>(
    py: Python<'py>,
    scene: &Scene,
    camera: Option<&Camera>,
    at: (f64, f64),
    resolution: Option<(u32, u32)>,
    seed: Option<i64>,
    max_depth: Option<i64>,
    light_samples: Option<i64>,
    threads: Option<i64>,
    sampler: Option<&str>,
    size: u32,
) -> PyResult<Bound<'py, PyDict>> {
    // Before the training, which takes seconds.
    DensityMap::check_size(size).map_err(to_py)?;
    let overrides = RenderOverrides {
        resolution,
        integrator: Some(IntegratorKind::Guided),
        max_depth: whole_number("max_depth", max_depth)?,
        light_samples: whole_number("light_samples", light_samples)?,
        seed: whole_number("seed", seed)?,
        sampler: named::<SamplerKind>(sampler)?,
        threads: whole_number("threads", threads)?,
        camera: camera.map(|c| c.description.clone()).unwrap_or_default(),
        ..RenderOverrides::default()
    };
    let (setup, camera, compiled) = prepared(py, scene, camera, &overrides)?;
    let settings = setup.settings;
    if !guiding_can_help(&compiled) {
        return Err(value_error(format!(
            "guiding is off for {} (nothing in it is glass, a mirror or smooth metal), so there is no guide to show",
            scene.name
        )));
    }
    let pixel = settings.pixel_at(at).map_err(to_py)?;
    let map = py
        .detach(|| {
            guarded(|| {
                let never = AtomicBool::new(false);
                let guide = train_guide(&compiled, camera.as_ref(), &settings, &never)?
                    .ok_or_else(|| Error::InvalidArgument("the guide's training was stopped".into()))?;
                guide_map_at_pixel(&compiled, camera.as_ref(), &settings, &guide, pixel, size)
            })
        })?
        .map_err(to_py)?;
    let d = PyDict::new(py);
    let density = Array2::from_shape_vec((size as usize, size as usize), map.density_per_sr)
        .expect("a density per map pixel")
        .into_pyarray(py);
    d.set_item("density_per_sr", density)?;
    d.set_item("pixel", pixel)?;
    d.set_item("share_above_surface", map.share_above_surface)?;
    d.set_item("total_probability", map.total_probability)?;
    d.set_item("leaves", map.leaves)?;
    Ok(d)
}
