//! The image sensor: `Sensor` (what a caller describes, spelt as a scene
//! file's `[sensor]` table: `lenspath::io::scene_file::SensorTable`) and
//! `RawFrame` (a frame read out, its mosaic as numpy, developed on demand).

use std::path::PathBuf;

use lenspath::io::scene_file::SensorTable;
use lenspath::names::Named;
use lenspath::sensor::develop::develop;
use lenspath::sensor::raw_file::write_raw;
use lenspath::sensor::{Demosaic, Development, RawFrame as LibRawFrame, SensorDescription, ToneCurve};
use numpy::ndarray::{Array2, Array3};
use numpy::{IntoPyArray, PyArray2, PyArray3};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::error::{guarded, to_py};

/// An image sensor for `render(..., sensor=...)`; every argument left out is
/// the scene file's `[sensor]`, else the library's default.
#[pyclass(module = "lenspath._core", frozen)]
#[derive(Clone)]
pub(crate) struct Sensor {
    pub(crate) description: SensorDescription,
    /// As given, for `repr` and pickling.
    table: SensorTable,
}

#[pymethods]
impl Sensor {
    #[new]
    #[pyo3(signature = (model = None, *, cfa = None, exposure_time_s = None, iso = None, white_luminance_cd_m2 = None,
                        peak_qe = None, read_noise_e = None, full_well_e_per_um2 = None,
                        dark_current_e_per_s_um2 = None, dsnu_e = None, prnu = None, bit_depth = None,
                        black_level_dn = None, frame_seed = None, fixed_pattern_seed = None, white_balance = None,
                        demosaic = None, tone_curve = None, auto_exposure = None, max_exposure_time_s = None,
                        max_iso = None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        model: Option<String>,
        cfa: Option<String>,
        exposure_time_s: Option<f64>,
        iso: Option<f64>,
        white_luminance_cd_m2: Option<f64>,
        peak_qe: Option<f64>,
        read_noise_e: Option<f64>,
        full_well_e_per_um2: Option<f64>,
        dark_current_e_per_s_um2: Option<f64>,
        dsnu_e: Option<f64>,
        prnu: Option<f64>,
        bit_depth: Option<u32>,
        black_level_dn: Option<u32>,
        frame_seed: Option<u64>,
        fixed_pattern_seed: Option<u64>,
        white_balance: Option<String>,
        demosaic: Option<String>,
        tone_curve: Option<String>,
        auto_exposure: Option<bool>,
        max_exposure_time_s: Option<f64>,
        max_iso: Option<f64>,
    ) -> PyResult<Sensor> {
        let table = SensorTable {
            model,
            cfa,
            exposure_time_s,
            iso,
            white_luminance_cd_m2,
            peak_qe,
            read_noise_e,
            full_well_e_per_um2,
            dark_current_e_per_s_um2,
            dsnu_e,
            prnu,
            bit_depth,
            black_level_dn,
            frame_seed,
            fixed_pattern_seed,
            white_balance,
            demosaic,
            tone_curve,
            auto_exposure,
            max_exposure_time_s,
            max_iso,
        };
        let description = table.description().map_err(to_py)?;
        // Checked now, as a camera's settings are, though the scene file's
        // `[sensor]` may still fill what this leaves out.
        description.resolve().map_err(to_py)?;
        Ok(Sensor { description, table })
    }

    /// Every setting, the defaults filled in (a scene file's `[sensor]` is
    /// not consulted here).
    fn settings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let resolved = self.description.resolve().map_err(to_py)?;
        table_dict(py, &SensorTable::of(&resolved.description()))
    }

    fn __repr__(&self) -> String {
        let args: Vec<String> = table_fields(&self.table)
            .into_iter()
            .map(|(k, v)| match v {
                serde_json::Value::String(s) => format!("{k}='{s}'"),
                serde_json::Value::Bool(b) => format!("{k}={}", if b { "True" } else { "False" }),
                other => format!("{k}={other}"),
            })
            .collect();
        format!("Sensor({})", args.join(", "))
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyDict>,))> {
        let constructor = py.import("lenspath._core")?.getattr("_sensor_from_settings")?;
        Ok((constructor, (table_dict(py, &self.table)?,)))
    }
}

/// `Sensor(**settings)`: what unpickling calls (`__reduce__`'s arguments
/// are positional).
#[pyfunction]
pub(crate) fn _sensor_from_settings<'py>(py: Python<'py>, settings: Bound<'py, PyDict>) -> PyResult<Bound<'py, PyAny>> {
    py.get_type::<Sensor>().call((), Some(&settings))
}

/// The table's fields that are set, in its order.
fn table_fields(table: &SensorTable) -> serde_json::Map<String, serde_json::Value> {
    match serde_json::to_value(table) {
        Ok(serde_json::Value::Object(fields)) => fields,
        _ => serde_json::Map::new(),
    }
}

/// The table's fields that are set, as a dict of str, int and float.
fn table_dict<'py>(py: Python<'py>, table: &SensorTable) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    for (k, v) in table_fields(table) {
        match v {
            serde_json::Value::String(s) => d.set_item(k, s)?,
            serde_json::Value::Bool(b) => d.set_item(k, b)?,
            serde_json::Value::Number(n) => match n.as_u64() {
                Some(i) => d.set_item(k, i)?,
                None => d.set_item(k, n.as_f64())?,
            },
            other => d.set_item(k, other.to_string())?,
        }
    }
    Ok(d)
}

/// The spectral responses a `Sensor` may name.
#[pyfunction]
pub(crate) fn sensor_models() -> Vec<&'static str> {
    lenspath::sensor::response::names().collect()
}

/// A raw frame a sensor read out: the mosaic of digital numbers and what a
/// raw developer needs, with the development the render asked for.
#[pyclass(module = "lenspath._core", frozen)]
pub(crate) struct RawFrame {
    frame: LibRawFrame,
    development: Development,
}

impl RawFrame {
    pub(crate) fn new(frame: LibRawFrame, development: Development) -> RawFrame {
        RawFrame { frame, development }
    }
}

#[pymethods]
impl RawFrame {
    /// The digital numbers, uint16, shape (height, width).
    #[getter]
    fn mosaic<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<u16>> {
        let f = &self.frame;
        Array2::from_shape_vec((f.height as usize, f.width as usize), f.dn.clone())
            .expect("a digital number per pixel")
            .into_pyarray(py)
    }

    /// The colour filter array at the top-left pixel: "rggb", ..., "mono".
    #[getter]
    fn cfa(&self) -> &'static str {
        self.frame.cfa.name()
    }

    /// Digital number of no light.
    #[getter]
    fn black_level_dn(&self) -> u32 {
        self.frame.black_level_dn
    }

    /// Largest digital number.
    #[getter]
    fn white_level_dn(&self) -> u32 {
        self.frame.white_level_dn
    }

    /// Electrons per digital number (the inverse of the system gain).
    #[getter]
    fn electrons_per_dn(&self) -> f64 {
        self.frame.electrons_per_dn
    }

    /// CIE XYZ to the sensor's channels under D65 (DNG ColorMatrix1), 3 × 3.
    #[getter]
    fn xyz_to_camera<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let m = self.frame.xyz_to_camera;
        let rows = [m.row(0), m.row(1), m.row(2)];
        Array2::from_shape_fn((3, 3), |(r, c)| rows[r][c]).into_pyarray(py)
    }

    /// The channels' reading of the balanced-for white, largest 1 (DNG AsShotNeutral).
    #[getter]
    fn as_shot_neutral(&self) -> (f64, f64, f64) {
        let n = self.frame.as_shot_neutral;
        (n.x, n.y, n.z)
    }

    /// The spectral response's name.
    #[getter]
    fn sensor_name(&self) -> &str {
        &self.frame.exposure.sensor_name
    }

    /// The exposure time, s (metered, with auto exposure).
    #[getter]
    fn exposure_time_s(&self) -> f64 {
        self.frame.exposure.exposure_time_s
    }

    /// The ISO speed (metered, with auto exposure).
    #[getter]
    fn iso(&self) -> f64 {
        self.frame.exposure.iso
    }

    /// The frame developed (white balance, demosaic, colour matrix, tone
    /// curve) to linear sRGB, float32, shape (height, width, 3); what is
    /// left out is the render's development.
    #[pyo3(signature = (*, demosaic = None, tone_curve = None))]
    fn develop<'py>(
        &self,
        py: Python<'py>,
        demosaic: Option<&str>,
        tone_curve: Option<&str>,
    ) -> PyResult<Bound<'py, PyArray3<f32>>> {
        let how = Development {
            demosaic: demosaic
                .map(Demosaic::parse)
                .transpose()
                .map_err(to_py)?
                .unwrap_or(self.development.demosaic),
            tone_curve: tone_curve
                .map(ToneCurve::parse)
                .transpose()
                .map_err(to_py)?
                .unwrap_or(self.development.tone_curve),
        };
        let image = py.detach(|| guarded(|| develop(&self.frame, &how)))?;
        Ok(
            Array3::from_shape_vec((image.height as usize, image.width as usize, 3), image.rgb)
                .expect("three channels per pixel")
                .into_pyarray(py),
        )
    }

    /// Writes the frame: .dng (raw developers read it), or .png / .tif (the
    /// 16-bit mosaic).
    fn write(&self, path: PathBuf) -> PyResult<()> {
        write_raw(&path, &self.frame).map_err(to_py)
    }

    fn __repr__(&self) -> String {
        let f = &self.frame;
        format!(
            "RawFrame({}x{}, {}, {}, black {} DN, white {} DN, {:.4} e-/DN)",
            f.width,
            f.height,
            f.exposure.sensor_name,
            f.cfa.name(),
            f.black_level_dn,
            f.white_level_dn,
            f.electrons_per_dn
        )
    }
}
