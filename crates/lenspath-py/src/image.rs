//! Images in and out, focus measures and bokeh.

use std::path::PathBuf;

use lenspath::autofocus::{FocusMeasure, Patch};
use lenspath::bokeh::{
    check_blur_memory, check_kernel_diameter, convolve_rgb, depth_blur, CircleOfConfusion, Edges, Kernel, KernelSize,
    Method,
};
use lenspath::camera::{Aperture, ApertureShape};
use lenspath::film::Image;
use lenspath::io::image::{read_image, write_image};
use numpy::{AllowTypeChange, PyArray3, PyArrayLike2, PyArrayLike3, PyUntypedArrayMethods};
use pyo3::prelude::*;

use crate::camera::{lens_from_py, parse_aperture};
use crate::error::{guarded, to_py, value_error};
use crate::render::rgb_array;

/// An (H, W, 3) float32 array as a core image.
pub(crate) fn image_from_array(image: &PyArrayLike3<'_, f32, AllowTypeChange>) -> PyResult<Image> {
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
pub(crate) fn read<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let image = read_image(&path).map_err(to_py)?;
    Ok(rgb_array(py, &image.image))
}

/// Writes linear RGB (H, W, 3) as PNG (sRGB, `exposure` stops) or EXR, atomically.
#[pyfunction]
#[pyo3(signature = (path, image, exposure = 0.0))]
pub(crate) fn write(path: PathBuf, image: PyArrayLike3<'_, f32, AllowTypeChange>, exposure: f32) -> PyResult<()> {
    write_image(&path, &image_from_array(&image)?, exposure).map_err(to_py)
}

/// A focus measure of an (H, W, 3) image (see `focus_measures()`).
#[pyfunction]
#[pyo3(signature = (image, metric = "tenengrad"))]
pub(crate) fn focus_measure(image: PyArrayLike3<'_, f32, AllowTypeChange>, metric: &str) -> PyResult<f64> {
    let measure = FocusMeasure::from_name(metric).map_err(to_py)?;
    let image = image_from_array(&image)?;
    let patch = Patch::new(image.width as usize, image.height as usize, &image.rgb).map_err(to_py)?;
    Ok(measure.evaluate(&patch))
}

/// The focus measures' names.
#[pyfunction]
pub(crate) fn focus_measures() -> Vec<&'static str> {
    lenspath::autofocus::FOCUS_MEASURES.iter().map(|(n, _)| *n).collect()
}

/// Blurs an (H, W, 3) image with a bokeh kernel: `aperture` a shape
/// ("circle", "blades:6", "star:5:0.4") `diameter_px` across, or `mask` a 2-D
/// array (resized so its longer side is `diameter_px`, if given).
#[pyfunction]
#[pyo3(signature = (image, *, aperture = None, mask = None, diameter_px = None, edges = "renormalize", method = "auto"))]
pub(crate) fn bokeh<'py>(
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
            check_kernel_diameter(diameter).map_err(to_py)?;
            let shape = ApertureShape::parse(shape).map_err(to_py)?;
            Kernel::from_aperture(&Aperture::new(&shape).map_err(to_py)?, diameter)
        }
        (None, Some(m)) => {
            let (h, w) = (m.shape()[0], m.shape()[1]);
            let size = match diameter_px {
                None => KernelSize::Native,
                Some(d) => {
                    check_kernel_diameter(d).map_err(to_py)?;
                    KernelSize::LongerSide(d.round() as u32)
                }
            };
            let values: Vec<f32> = m.as_array().iter().copied().collect();
            Kernel::from_mask(w, h, &values, size).map_err(to_py)?
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
    check_blur_memory(w, h, &kernel, method).map_err(to_py)?;
    py.detach(|| guarded(|| convolve_rgb(&mut image.rgb, w, h, &kernel, method, edges)))?;
    Ok(rgb_array(py, &image))
}

/// Depth-aware lens blur of an (H, W, 3) image by its (H, W) depths (see the stub).
#[pyfunction]
#[pyo3(signature = (image, depth, focus_distance, *, lens = None, f_number = None, focal_length_mm = None,
                    aperture_radius = None, fov_deg = None, sensor_width_mm = 36.0, scene_unit_m = 1.0,
                    aperture = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn lens_blur<'py>(
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
    let coc = match (lens, focal_length_mm, aperture_radius) {
        (None, None, Some(radius)) => {
            let fov = fov_deg.ok_or_else(|| value_error("aperture_radius needs fov_deg (the thin-lens camera's)"))?;
            CircleOfConfusion::thin_lens_camera(radius, focus_distance, fov, height).map_err(to_py)?
        }
        (Some(lens), None, None) => {
            let lens = lens_from_py(lens)?;
            let paraxial = lens.system.paraxial().map_err(to_py)?;
            let n = f_number.unwrap_or(paraxial.f_number);
            let f = paraxial.effective_focal_length_mm;
            CircleOfConfusion::thin_lens_in_scene_units(f, n, focus_distance, scene_unit_m, sensor_width_mm, width)
                .map_err(to_py)?
        }
        (None, Some(f), None) => {
            let n = f_number.ok_or_else(|| value_error("focal_length_mm needs f_number"))?;
            CircleOfConfusion::thin_lens_in_scene_units(f, n, focus_distance, scene_unit_m, sensor_width_mm, width)
                .map_err(to_py)?
        }
        _ => {
            return Err(value_error(
                "describe one lens: lens (with f_number to stop it down), focal_length_mm with f_number, \
                 or aperture_radius with fov_deg",
            ))
        }
    };
    let shape = parse_aperture(aperture)?.unwrap_or(ApertureShape::Circle);
    let aperture = Aperture::new(&shape).map_err(to_py)?;
    let depth: Vec<f32> = depth.as_array().iter().copied().collect();
    let blurred = py
        .detach(|| guarded(|| depth_blur(&image.rgb, &depth, width as usize, height as usize, &coc, &aperture)))?
        .map_err(to_py)?;
    Ok(rgb_array(py, &Image { rgb: blurred, ..image }))
}
