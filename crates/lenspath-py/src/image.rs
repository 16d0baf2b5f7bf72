//! Images in and out, focus measures and bokeh.

use std::collections::BTreeMap;
use std::path::PathBuf;

use lenspath::autofocus::{FocusMeasure, Patch};
use lenspath::bokeh::{
    check_blur_memory, check_kernel_diameter, convolve_rgb, depth_blur, CircleOfConfusion, Edges, Kernel, KernelSize,
    Method,
};
use lenspath::camera::{self, Aperture, ApertureShape};
use lenspath::color::srgb_to_linear;
use lenspath::film::Image;
use lenspath::io::exr::{self, read_exr_image, ExrImage, HeaderValue};
use lenspath::io::image::{exr_of_image, read_image, write_image, ImageFormat, ImageHeader};
use lenspath::names::Named;
use numpy::ndarray::Array2;
use numpy::IntoPyArray;
use numpy::{
    AllowTypeChange, PyArray3, PyArrayDyn, PyArrayLike2, PyArrayLikeDyn, PyArrayMethods, PyUntypedArrayMethods,
};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyTuple};

use crate::camera::{lens_from_py, parse_aperture};
use crate::error::{guarded, named, to_py, value_error};
use crate::render::rgb_array;

/// An image as numpy users hold it, as a core image in linear light:
/// (H, W, 3) RGB or (H, W) / (H, W, 1) grey; floats are linear values,
/// uint8 and uint16 are sRGB-encoded (what `imageio`, Pillow and OpenCV give
/// for a PNG or JPEG) and are decoded from it, as `read` decodes those files.
pub(crate) fn image_from_py(image: &Bound<'_, PyAny>) -> PyResult<Image> {
    let array = image.py().import("numpy")?.call_method1("asarray", (image,))?;
    let encoded = |full_scale: f32| move |v: f32| srgb_to_linear(v / full_scale);
    let (shape, values): (Vec<usize>, Vec<f32>) = if let Ok(a) = array.cast::<PyArrayDyn<u8>>() {
        let a = a.readonly();
        (
            a.shape().to_vec(),
            a.as_array().iter().map(|&v| encoded(255.0)(f32::from(v))).collect(),
        )
    } else if let Ok(a) = array.cast::<PyArrayDyn<u16>>() {
        let a = a.readonly();
        (
            a.shape().to_vec(),
            a.as_array().iter().map(|&v| encoded(65535.0)(f32::from(v))).collect(),
        )
    } else {
        let a: PyArrayLikeDyn<'_, f32, AllowTypeChange> = array.extract().map_err(|_| {
            value_error(format!(
                "images are arrays of numbers, got {}",
                array.getattr("dtype").map_or_else(|_| "?".into(), |d| d.to_string())
            ))
        })?;
        (a.shape().to_vec(), a.as_array().iter().copied().collect())
    };
    let (height, width, rgb) = match shape[..] {
        [h, w] | [h, w, 1] => (h, w, values.iter().flat_map(|&v| [v; 3]).collect()),
        [h, w, 3] => (h, w, values),
        _ => {
            return Err(value_error(format!(
                "images are H x W x 3 (RGB) or H x W (grey) arrays, got shape {shape:?}{}",
                if shape.len() == 3 && shape[2] == 4 {
                    "; drop the alpha channel with image[..., :3]"
                } else {
                    ""
                }
            )))
        }
    };
    Ok(Image {
        width: width as u32,
        height: height as u32,
        rgb,
        depth: vec![f32::INFINITY; width * height],
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

/// Writes an image as PNG (sRGB, `exposure` stops) or EXR (with `depth` as Z and `attributes`), atomically.
#[pyfunction]
#[pyo3(signature = (path, image, exposure = 0.0, *, depth = None, attributes = None))]
pub(crate) fn write(
    path: PathBuf,
    image: &Bound<'_, PyAny>,
    exposure: f32,
    depth: Option<PyArrayLike2<'_, f32, AllowTypeChange>>,
    attributes: Option<&Bound<'_, PyDict>>,
) -> PyResult<()> {
    let image = image_from_py(image)?;
    match ImageFormat::from_path(&path).map_err(to_py)? {
        ImageFormat::Png if depth.is_some() || attributes.is_some() => Err(value_error(format!(
            "{}: a PNG keeps no depth and no attributes; write an .exr",
            path.display()
        ))),
        ImageFormat::Png => write_image(&path, &image, exposure).map_err(to_py),
        ImageFormat::Exr => {
            let header = ImageHeader {
                frame: None,
                attributes: attributes.map(attributes_from_py).transpose()?.unwrap_or_default(),
            };
            let mut exr = exr_of_image(&image, &header);
            match depth {
                None => {
                    exr.channels.remove("Z");
                }
                Some(z) => {
                    if z.shape() != [image.height as usize, image.width as usize] {
                        return Err(value_error(format!(
                            "depth must be {} x {} like the image, got {:?}",
                            image.height,
                            image.width,
                            z.shape()
                        )));
                    }
                    exr.channels.insert("Z".into(), z.as_array().iter().copied().collect());
                }
            }
            exr::write_exr(&path, &exr).map_err(to_py)
        }
    }
}

/// Reads every channel of an EXR and its header (see the stub).
#[pyfunction]
pub(crate) fn read_exr<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let exr = read_exr_image(&path).map_err(to_py)?;
    let (h, w) = (exr.height as usize, exr.width as usize);
    let channels = PyDict::new(py);
    for (name, values) in exr.channels {
        let array = Array2::from_shape_vec((h, w), values).expect("a channel holds one value per pixel");
        channels.set_item(name, array.into_pyarray(py))?;
    }
    let attributes = PyDict::new(py);
    for (name, value) in &exr.attributes {
        attributes.set_item(name, header_value_to_py(py, value)?)?;
    }
    let out = PyDict::new(py);
    out.set_item("channels", channels)?;
    out.set_item("attributes", attributes)?;
    out.set_item("display_window", exr.display_size)?;
    out.set_item("data_origin", exr.data_origin)?;
    Ok(out)
}

/// Writes named channels (each H x W) as an EXR (see the stub), atomically.
#[pyfunction]
#[pyo3(signature = (path, channels, attributes = None, display_window = None, data_origin = None))]
pub(crate) fn write_exr(
    path: PathBuf,
    channels: &Bound<'_, PyDict>,
    attributes: Option<&Bound<'_, PyDict>>,
    display_window: Option<(u32, u32)>,
    data_origin: Option<(i32, i32)>,
) -> PyResult<()> {
    let mut size = None;
    let mut values = BTreeMap::new();
    for (name, array) in channels.iter() {
        let name: String = name.extract()?;
        let array: PyArrayLike2<'_, f32, AllowTypeChange> = array
            .extract()
            .map_err(|_| value_error(format!("channel '{name}' must be a 2-D array of numbers")))?;
        let shape = (array.shape()[0], array.shape()[1]);
        if *size.get_or_insert(shape) != shape {
            return Err(value_error(format!(
                "channel '{name}' is {shape:?}, the others {:?}",
                size.unwrap_or(shape)
            )));
        }
        values.insert(name, array.as_array().iter().copied().collect());
    }
    let Some((height, width)) = size else {
        return Err(value_error("an EXR needs at least one channel"));
    };
    let mut exr = ExrImage::new(width as u32, height as u32);
    exr.channels = values;
    exr.display_size = display_window.unwrap_or((exr.width, exr.height));
    exr.data_origin = data_origin.unwrap_or((0, 0));
    if let Some(attributes) = attributes {
        exr.attributes.extend(attributes_from_py(attributes)?);
    }
    exr::write_exr(&path, &exr).map_err(to_py)
}

/// An EXR attribute as Python holds it (the stub's table).
fn header_value_to_py<'py>(py: Python<'py>, value: &HeaderValue) -> PyResult<Bound<'py, PyAny>> {
    Ok(match value {
        HeaderValue::Int(v) => v.into_pyobject(py)?.into_any(),
        HeaderValue::Float(v) => v.into_pyobject(py)?.into_any(),
        HeaderValue::Double(v) => py.import("numpy")?.getattr("float64")?.call1((*v,))?,
        HeaderValue::Text(t) => t.into_pyobject(py)?.into_any(),
        HeaderValue::IntPair(p) => (p[0], p[1]).into_pyobject(py)?.into_any(),
        HeaderValue::FloatPair(p) => (p[0], p[1]).into_pyobject(py)?.into_any(),
        HeaderValue::Matrix(m) => Array2::from_shape_vec((4, 4), m.to_vec())
            .expect("16 values")
            .into_pyarray(py)
            .into_any(),
        HeaderValue::Chromaticities(c) => PyTuple::new(py, c)?.into_any(),
    })
}

/// EXR attributes from a Python dict: int, float (numpy.float64: double), str, a pair of ints
/// or of floats, a 4 x 4 matrix, 8 chromaticities.
fn attributes_from_py(attributes: &Bound<'_, PyDict>) -> PyResult<BTreeMap<String, HeaderValue>> {
    let float32 = attributes.py().import("numpy")?.getattr("float32")?;
    let mut out = BTreeMap::new();
    for (name, value) in attributes.iter() {
        let name: String = name.extract()?;
        let unsupported = || {
            value_error(format!(
                "EXR attribute '{name}': use an int, a float, a str, two ints, two floats, a 4 x 4 matrix \
                 or 8 chromaticities, got {value}"
            ))
        };
        let converted = if value.is_instance_of::<PyBool>() {
            return Err(unsupported());
        } else if value.is_exact_instance_of::<PyFloat>() || value.is_instance(&float32)? {
            HeaderValue::Float(value.extract()?)
        } else if value.is_instance_of::<PyFloat>() {
            HeaderValue::Double(value.extract()?)
        } else if let Ok(v) = value.extract::<i32>() {
            HeaderValue::Int(v)
        } else if let Ok(t) = value.extract::<String>() {
            HeaderValue::Text(t)
        } else if let Ok(m) = value.extract::<PyArrayLike2<'_, f32, AllowTypeChange>>() {
            if m.shape() != [4, 4] {
                return Err(unsupported());
            }
            HeaderValue::Matrix(std::array::from_fn(|i| m.as_array()[[i / 4, i % 4]]))
        } else if let Ok(p) = value.extract::<(i32, i32)>() {
            HeaderValue::IntPair([p.0, p.1])
        } else if let Ok(p) = value.extract::<(f32, f32)>() {
            HeaderValue::FloatPair([p.0, p.1])
        } else if let Ok(c) = value.extract::<[f32; 8]>() {
            HeaderValue::Chromaticities(c)
        } else {
            return Err(unsupported());
        };
        out.insert(name, converted);
    }
    Ok(out)
}

/// A focus measure of an (H, W, 3) image (see `focus_measures()`).
#[pyfunction]
#[pyo3(signature = (image, metric = None))]
pub(crate) fn focus_measure(image: &Bound<'_, PyAny>, metric: Option<&str>) -> PyResult<f64> {
    let measure = named::<FocusMeasure>(metric)?.unwrap_or_default();
    let image = image_from_py(image)?;
    let patch = Patch::new(image.width as usize, image.height as usize, &image.rgb).map_err(to_py)?;
    Ok(measure.evaluate(&patch))
}

/// The focus measures' names.
#[pyfunction]
pub(crate) fn focus_measures() -> Vec<&'static str> {
    FocusMeasure::names()
}

/// Blurs an (H, W, 3) image with a bokeh kernel: `aperture` a shape
/// ("circle", "blades:6", "star:5:0.4") `diameter_px` across, or `mask` a 2-D
/// array (resized so its longer side is `diameter_px`, if given).
#[pyfunction]
#[pyo3(signature = (image, *, aperture = None, mask = None, diameter_px = None, edges = None, method = None))]
pub(crate) fn bokeh<'py>(
    py: Python<'py>,
    image: &Bound<'_, PyAny>,
    aperture: Option<&str>,
    mask: Option<PyArrayLike2<'_, f32, AllowTypeChange>>,
    diameter_px: Option<f64>,
    edges: Option<&str>,
    method: Option<&str>,
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
    let edges = named::<Edges>(edges)?.unwrap_or_default();
    let method = named::<Method>(method)?.unwrap_or_default();
    let mut image = image_from_py(image)?;
    let (w, h) = (image.width as usize, image.height as usize);
    check_blur_memory(w, h, &kernel, method).map_err(to_py)?;
    py.detach(|| guarded(|| convolve_rgb(&mut image.rgb, w, h, &kernel, method, edges)))?;
    Ok(rgb_array(py, &image))
}

/// Depth-aware lens blur of an (H, W, 3) image by its (H, W) depths (see the stub).
#[pyfunction]
#[pyo3(signature = (image, depth, focus_distance, *, lens = None, f_number = None, focal_length_mm = None,
                    aperture_radius = None, fov_deg = None, sensor_width_mm = None, scene_unit_m = None,
                    aperture = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn lens_blur<'py>(
    py: Python<'py>,
    image: &Bound<'_, PyAny>,
    depth: PyArrayLike2<'_, f32, AllowTypeChange>,
    focus_distance: f64,
    lens: Option<&Bound<'_, PyAny>>,
    f_number: Option<f64>,
    focal_length_mm: Option<f64>,
    aperture_radius: Option<f64>,
    fov_deg: Option<f64>,
    sensor_width_mm: Option<f64>,
    scene_unit_m: Option<f64>,
    aperture: Option<&Bound<'_, PyAny>>,
) -> PyResult<Bound<'py, PyArray3<f32>>> {
    let sensor_width_mm = sensor_width_mm.unwrap_or(camera::DEFAULT_SENSOR_WIDTH_MM);
    let scene_unit_m = scene_unit_m.unwrap_or(camera::DEFAULT_SCENE_UNIT_M);
    let image = image_from_py(image)?;
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
