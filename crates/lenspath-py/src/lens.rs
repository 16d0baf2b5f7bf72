//! Lenses: prescriptions, their analysis, tracing and drawings.

use std::path::PathBuf;
use std::sync::OnceLock;

use glam::DVec3;
use lenspath::glass::check_wavelength_nm;
use lenspath::lens::{
    chromatic::{focal_shift, ChromaticAnalysis},
    library,
    plot::{focal_shift_svg, layout, layout_svg, Polyline},
    AnalysisSettings, Direction, LensAnalysis, LensPrescription, LensRay, LensSystem, TableConvention, FULL_FRAME_MM,
};
use lenspath::lens_report::{LensReport, LensReportSettings};
use lenspath::Error;
use numpy::ndarray::Array2;
use numpy::{AllowTypeChange, IntoPyArray, PyArray1, PyArray2, PyArrayLike1, PyArrayLike2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};

use crate::error::{deprecated, guarded, to_py, value_error};
use crate::wave::{self, SampledPsf, WaveQuestion};

/// A real compound lens: its prescription, placed wide open (or stopped down).
#[pyclass(module = "lenspath._core")]
#[derive(Clone)]
pub(crate) struct Lens {
    pub(crate) prescription: LensPrescription,
    pub(crate) system: LensSystem,
    pub(crate) analysis: LensAnalysis,
    /// The f-number it was stopped down to (None: wide open).
    pub(crate) stopped_to: Option<f64>,
    /// Its report as JSON, made the first time `analysis()` asks (it
    /// traces for up to a second) and kept: the lens does not change.
    pub(crate) report_json: OnceLock<String>,
}

impl Lens {
    /// The lens as placed, at `wavelength_nm` (None: the d line).
    fn at_wavelength(&self, wavelength_nm: Option<f64>) -> PyResult<LensSystem> {
        match wavelength_nm {
            None => Ok(self.system.clone()),
            Some(nm) => {
                check_wavelength_nm(nm).map_err(to_py)?;
                Ok(self.system.at_wavelength(nm))
            }
        }
    }

    pub(crate) fn from_prescription(prescription: LensPrescription) -> PyResult<Lens> {
        let system = guarded(|| LensSystem::new(&prescription))?;
        Lens::placed(prescription, system)
    }

    /// `prescription` placed as `system` (wide open or stopped down), analysed.
    pub(crate) fn placed(prescription: LensPrescription, system: LensSystem) -> PyResult<Lens> {
        let analysis = guarded(|| LensAnalysis::new(&system, &AnalysisSettings::default()))?.map_err(to_py)?;
        Ok(Lens {
            prescription,
            system,
            analysis,
            stopped_to: None,
            report_json: OnceLock::new(),
        })
    }
}

/// The sensor diagonal of the lens drawings: `sensor_diagonal_mm`, else a
/// 36 × 24 mm sensor's, as `lenspath lens` draws them.
pub(crate) fn drawing_diagonal_mm(sensor_diagonal_mm: Option<f64>) -> f64 {
    sensor_diagonal_mm.unwrap_or_else(|| FULL_FRAME_MM.0.hypot(FULL_FRAME_MM.1))
}

#[pymethods]
impl Lens {
    /// A shipped lens by name (see `builtin_lenses()`), or any lentil
    /// database entry (`lentil:0014`).
    #[staticmethod]
    pub(crate) fn builtin(name: &str) -> PyResult<Lens> {
        if !library::is_shipped(name) && !name.starts_with(lenspath::lens::lentil::PREFIX) {
            return Err(value_error(format!(
                "unknown built-in lens '{name}'; use one of {}",
                builtin_lenses().join(", ")
            )));
        }
        Lens::from_prescription(LensPrescription::load(name).map_err(to_py)?)
    }

    /// A lens table file (pbrt / CS184 format), a Zemax `.zmx` file or an ISET lens `.json`.
    #[staticmethod]
    pub(crate) fn load(path: PathBuf) -> PyResult<Lens> {
        if !path.is_file() {
            let source = std::io::Error::from(std::io::ErrorKind::NotFound);
            return Err(to_py(Error::Io { path, source }));
        }
        let name = path
            .to_str()
            .ok_or_else(|| value_error(format!("{}: not a UTF-8 path", path.display())))?;
        Lens::from_prescription(LensPrescription::load(name).map_err(to_py)?)
    }

    /// A lens from a table (N × 4: radius, thickness to the next surface,
    /// index, aperture diameter, all mm; radius 0 marks the stop).
    #[staticmethod]
    #[pyo3(signature = (table, name = "table"))]
    pub(crate) fn from_table(table: PyArrayLike2<'_, f64, AllowTypeChange>, name: &str) -> PyResult<Lens> {
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
        let prescription = LensPrescription::parse(&text, name, TableConvention::ThicknessToNext).map_err(to_py)?;
        Lens::from_prescription(prescription)
    }

    /// This lens stopped down to f-number `f_number`.
    pub(crate) fn stopped_down(&self, f_number: f64) -> PyResult<Lens> {
        let system = self.system.with_f_number(f_number).map_err(to_py)?;
        Ok(Lens {
            stopped_to: Some(f_number),
            ..Lens::placed(self.prescription.clone(), system)?
        })
    }

    /// Pickles as its name, table text (glass column included) and stop (`Lens._from_state`).
    pub(crate) fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyTuple>)> {
        Ok((
            py.get_type::<Lens>().getattr("_from_state")?,
            (self.name().to_string(), self.table_text(), self.stopped_to).into_pyobject(py)?,
        ))
    }

    /// The lens `__reduce__` describes.
    #[staticmethod]
    pub(crate) fn _from_state(name: &str, table_text: &str, stopped_to: Option<f64>) -> PyResult<Lens> {
        let prescription =
            LensPrescription::parse(table_text, name, TableConvention::ThicknessToNext).map_err(to_py)?;
        let lens = Lens::from_prescription(prescription)?;
        match stopped_to {
            Some(f_number) => lens.stopped_down(f_number),
            None => Ok(lens),
        }
    }

    /// The prescription as table text (pbrt / CS184 columns, thickness to the
    /// next surface, and the glass column where the lens has one).
    #[getter]
    pub(crate) fn table_text(&self) -> String {
        self.prescription.table_text()
    }

    #[getter]
    pub(crate) fn name(&self) -> &str {
        self.prescription.name()
    }

    /// The table: N × 4 (radius, thickness to next, index, aperture diameter), mm.
    #[getter]
    pub(crate) fn table<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        let surfaces = self.prescription.surfaces();
        let mut a = Array2::zeros((surfaces.len(), 4));
        for (i, s) in surfaces.iter().enumerate() {
            a[[i, 0]] = s.radius_mm;
            a[[i, 1]] = s.thickness_mm;
            a[[i, 2]] = s.ior_d();
            a[[i, 3]] = s.aperture_diameter_mm;
        }
        a.into_pyarray(py)
    }

    /// Every figure of `lenspath lens --json`, as a dict: the same
    /// serialisation of the library's analysis, read back by Python's json,
    /// so the two front ends cannot drift apart (floats round-trip exactly).
    pub(crate) fn analysis<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let text = match self.report_json.get() {
            Some(text) => text,
            None => {
                let report = py
                    .detach(|| {
                        guarded(|| {
                            LensReport::new(&self.system, &LensReportSettings::default())
                                .and_then(|r| r.with_passing_fractions(&self.prescription, self.stopped_to))
                        })
                    })?
                    .map_err(to_py)?;
                self.report_json.get_or_init(|| report.to_json())
            }
        };
        Ok(py
            .import("json")?
            .call_method1("loads", (text,))?
            .cast_into::<PyDict>()?)
    }

    /// Real-ray focal length |P′ − F′|, mm.
    #[getter]
    pub(crate) fn focal_length_mm(&self) -> f64 {
        self.analysis.focal_length_mm
    }

    /// Paraxial effective focal length, mm.
    #[getter]
    pub(crate) fn effective_focal_length_mm(&self) -> f64 {
        self.analysis.effective_focal_length_mm
    }

    /// Paraxial f-number.
    #[getter]
    pub(crate) fn f_number(&self) -> f64 {
        self.analysis.f_number
    }

    /// Sensor position (mm behind the stop) focusing infinity.
    #[getter]
    pub(crate) fn infinity_focus_mm(&self) -> f64 {
        self.analysis.infinity_focus_mm
    }

    /// Sensor position (mm behind the stop) focusing the close-focus object.
    #[getter]
    pub(crate) fn close_focus_mm(&self) -> f64 {
        self.analysis.close_focus_mm
    }

    /// Distance in focus (mm from the sensor plane) with the sensor
    /// `sensor_depth_mm` behind the stop; None when nothing in front of the lens is.
    #[pyo3(signature = (sensor_depth_mm, ray_height_mm = 0.1))]
    pub(crate) fn focus_distance_mm(&self, sensor_depth_mm: f64, ray_height_mm: f64) -> Option<f64> {
        self.system.focus_distance_mm(sensor_depth_mm, ray_height_mm)
    }

    /// Sensor depth (mm behind the stop) focusing `distance_mm` (from the sensor plane).
    #[pyo3(signature = (distance_mm, ray_height_mm = 0.1))]
    pub(crate) fn sensor_depth_mm_for(&self, distance_mm: f64, ray_height_mm: f64) -> PyResult<f64> {
        self.system
            .sensor_depth_mm_for_focus_distance(distance_mm, ray_height_mm)
            .map_err(to_py)
    }

    /// Deprecated: `focus_distance_mm`.
    #[pyo3(signature = (sensor_mm, ray_height_mm = 0.1))]
    pub(crate) fn focus_distance(&self, py: Python<'_>, sensor_mm: f64, ray_height_mm: f64) -> PyResult<Option<f64>> {
        deprecated(
            py,
            "Lens.focus_distance is deprecated; use focus_distance_mm (the same mm)",
        )?;
        Ok(self.focus_distance_mm(sensor_mm, ray_height_mm))
    }

    /// Deprecated: `sensor_depth_mm_for`.
    #[pyo3(signature = (distance_mm, ray_height_mm = 0.1))]
    pub(crate) fn sensor_for_distance(&self, py: Python<'_>, distance_mm: f64, ray_height_mm: f64) -> PyResult<f64> {
        deprecated(
            py,
            "Lens.sensor_for_distance is deprecated; use sensor_depth_mm_for (the same mm)",
        )?;
        self.sensor_depth_mm_for(distance_mm, ray_height_mm)
    }

    /// Traces rays (N × 3 origins and directions, lens coordinates in mm:
    /// z along the axis toward the sensor, the stop at 0) through every
    /// surface, `toward` "scene" or "sensor". Returns (origins, directions,
    /// passed): where each ray leaves the last surface, its unit direction,
    /// and whether it got through (False rows are NaN). At `wavelength_nm`
    /// (default: the d line, 587.56 nm) when the glasses disperse.
    #[pyo3(signature = (origins, directions, toward = "scene", wavelength_nm = None))]
    #[allow(clippy::type_complexity)]
    pub(crate) fn trace<'py>(
        &self,
        py: Python<'py>,
        origins: PyArrayLike2<'_, f64, AllowTypeChange>,
        directions: PyArrayLike2<'_, f64, AllowTypeChange>,
        toward: &str,
        wavelength_nm: Option<f64>,
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
        let system = self.at_wavelength(wavelength_nm)?;
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
            if let Some(out) = system.trace(&ray, direction) {
                for c in 0..3 {
                    out_o[[i, c]] = out.origin[c];
                    out_d[[i, c]] = out.direction[c];
                }
                passed[i] = true;
            }
        }
        Ok((out_o.into_pyarray(py), out_d.into_pyarray(py), passed.into_pyarray(py)))
    }

    /// The lens's colour figures, as `lenspath lens --json` gives them:
    /// `lines` (the g, F, d and C lines' paraxial `wavelength_nm`,
    /// `effective_focal_length_mm` and `back_focal_distance_mm`),
    /// `longitudinal_color_mm` (BFD(F) − BFD(C)), `lateral_color_mm` (F − C
    /// chief-ray heights on the d-line image plane) at
    /// `lateral_color_field_height_mm`, half the sensor's diagonal
    /// `sensor_diagonal_mm` (default: 36 × 24 mm).
    #[pyo3(signature = (sensor_diagonal_mm = None))]
    pub(crate) fn chromatic<'py>(
        &self,
        py: Python<'py>,
        sensor_diagonal_mm: Option<f64>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let c = ChromaticAnalysis::new(&self.system, 0.5 * drawing_diagonal_mm(sensor_diagonal_mm)).map_err(to_py)?;
        let lines = PyDict::new(py);
        for line in &c.lines {
            let d = PyDict::new(py);
            d.set_item("wavelength_nm", line.wavelength_nm)?;
            d.set_item("effective_focal_length_mm", line.effective_focal_length_mm)?;
            d.set_item("back_focal_distance_mm", line.back_focal_distance_mm)?;
            lines.set_item(line.line, d)?;
        }
        let d = PyDict::new(py);
        d.set_item("lines", lines)?;
        d.set_item("longitudinal_color_mm", c.longitudinal_color_mm)?;
        d.set_item("lateral_color_mm", c.lateral_color_mm)?;
        d.set_item("lateral_color_field_height_mm", c.field_height_mm)?;
        Ok(d)
    }

    /// The chromatic focal shift: for each of `wavelengths_nm`, the paraxial
    /// back focal distance there minus the d line's, mm.
    pub(crate) fn focal_shift<'py>(
        &self,
        py: Python<'py>,
        wavelengths_nm: PyArrayLike1<'_, f64, AllowTypeChange>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let wavelengths = wavelengths_nm.as_array().to_vec();
        for &nm in &wavelengths {
            check_wavelength_nm(nm).map_err(to_py)?;
        }
        let shift = focal_shift(&self.system, &wavelengths).map_err(to_py)?;
        Ok(shift.into_iter().map(|(_, mm)| mm).collect::<Vec<_>>().into_pyarray(py))
    }

    /// The chromatic focal shift plot (400–700 nm) as SVG text, as
    /// `lenspath lens --focal-shift-plot` draws it.
    pub(crate) fn focal_shift_plot(&self) -> PyResult<String> {
        focal_shift_svg(&self.system).map_err(to_py)
    }

    /// The lens layout (elements, stop, marginal and chief rays) as SVG text;
    /// the sensor `sensor_diagonal_mm` across (default: 36 × 24 mm).
    #[pyo3(signature = (sensor_diagonal_mm = None))]
    pub(crate) fn plot(&self, sensor_diagonal_mm: Option<f64>) -> String {
        layout_svg(&self.system, &self.analysis, drawing_diagonal_mm(sensor_diagonal_mm))
    }

    /// What `plot` draws, as arrays of (z, height) rows in mm: `elements`
    /// (closed outlines), `stop` (two blades), `sensor`, `rays` ((field
    /// fraction, wavelength in nm, colour, path) tuples), `z_range_mm`,
    /// `half_height_mm`, `title`.
    #[pyo3(signature = (sensor_diagonal_mm = None))]
    pub(crate) fn layout<'py>(&self, py: Python<'py>, sensor_diagonal_mm: Option<f64>) -> PyResult<Bound<'py, PyDict>> {
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
            l.rays
                .iter()
                .map(|r| (r.field_fraction, r.wavelength_nm, r.colour, array(&r.path)))
                .collect::<Vec<_>>(),
        )?;
        d.set_item("z_range_mm", l.z_range_mm)?;
        d.set_item("half_height_mm", l.half_height_mm)?;
        Ok(d)
    }

    /// The polychromatic PSF at `field_deg` (the wave-optics analysis of
    /// `lenspath lens --psf`): a unit-sum square array, rows along y
    /// (tangential), centred on the chief ray's image point, and its sample
    /// spacing (x, y) in µm. `wavelength_nm`: a number or a sequence (default:
    /// the lens's wavelength), `weights` one each (default: equal);
    /// `sensor_depth_mm` behind the stop (default: the infinity focus).
    #[pyo3(signature = (field_deg = 0.0, wavelength_nm = None, weights = None, sensor_depth_mm = None, pupil_samples = None, padding = None))]
    #[allow(clippy::too_many_arguments)] // Python's keywords, mapped onto one WaveQuestion.
    pub(crate) fn psf<'py>(
        &self,
        py: Python<'py>,
        field_deg: f64,
        wavelength_nm: Option<Bound<'py, PyAny>>,
        weights: Option<Vec<f64>>,
        sensor_depth_mm: Option<f64>,
        pupil_samples: Option<usize>,
        padding: Option<usize>,
    ) -> PyResult<SampledPsf<'py>> {
        let question =
            WaveQuestion::new(field_deg, wavelength_nm, weights, sensor_depth_mm).sampled(pupil_samples, padding);
        wave::psf(py, &self.system, &question)
    }

    /// The wave-optics figures at `field_deg` as `lenspath lens --mtf
    /// --json` gives one field (RMS wavefront, Strehl and Fringe Zernikes per
    /// wavelength, MTF50, through focus when `through_focus_per_mm` is set),
    /// with the MTF as arrays: `frequencies_per_mm`, `tangential`,
    /// `sagittal`, `diffraction_limit`. Arguments as `psf`'s.
    #[pyo3(signature = (field_deg = 0.0, frequencies_per_mm = None, wavelength_nm = None, weights = None, sensor_depth_mm = None, through_focus_per_mm = None, pupil_samples = None, padding = None))]
    #[allow(clippy::too_many_arguments)] // Python's keywords, mapped onto one WaveQuestion.
    pub(crate) fn mtf<'py>(
        &self,
        py: Python<'py>,
        field_deg: f64,
        frequencies_per_mm: Option<Vec<f64>>,
        wavelength_nm: Option<Bound<'py, PyAny>>,
        weights: Option<Vec<f64>>,
        sensor_depth_mm: Option<f64>,
        through_focus_per_mm: Option<f64>,
        pupil_samples: Option<usize>,
        padding: Option<usize>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let question = WaveQuestion::new(field_deg, wavelength_nm, weights, sensor_depth_mm)
            .sampled(pupil_samples, padding)
            .at_frequencies(frequencies_per_mm, through_focus_per_mm);
        wave::mtf(py, &self.system, &question)
    }

    pub(crate) fn __repr__(&self) -> String {
        format!(
            "<lenspath.Lens '{}': f = {:.2} mm, f/{:.2}>",
            self.prescription.name(),
            self.analysis.focal_length_mm,
            self.analysis.f_number
        )
    }
}

/// The shipped lenses' names (`lenspath lens --list`).
#[pyfunction]
pub(crate) fn builtin_lenses() -> Vec<String> {
    library::shipped().iter().map(|l| l.name.clone()).collect()
}
