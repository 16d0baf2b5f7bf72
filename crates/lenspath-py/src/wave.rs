//! The wave-optics analysis of a lens (`Lens.psf`, `Lens.mtf`): Python's
//! arguments mapped onto the library's `WaveAnalysisSettings`, and its
//! results onto numpy arrays.

use lenspath::lens::wave_analysis::{WaveAnalysis, WaveAnalysisSettings, WaveResult, WeightedWavelength};
use lenspath::lens::LensSystem;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::error::{guarded, to_py, value_error};

/// What `Lens.psf` and `Lens.mtf` are asked, in Python's spelling.
pub(crate) struct WaveQuestion<'py> {
    /// Degrees off the axis, in y.
    field_deg: f64,
    /// One wavelength (a float) or several (a sequence), nm; None: the lens's.
    wavelength_nm: Option<Bound<'py, PyAny>>,
    /// One per wavelength; None: equal.
    weights: Option<Vec<f64>>,
    /// Behind the stop; None: the infinity focus.
    sensor_depth_mm: Option<f64>,
    /// The MTF's frequencies, cycles per mm; None: the library's.
    frequencies_per_mm: Option<Vec<f64>>,
    /// Also the MTF through focus at this frequency.
    through_focus_per_mm: Option<f64>,
    /// Pupil samples a side; None: the library's.
    pupil_samples: Option<usize>,
    /// Zero padding before the FFT; None: the library's.
    padding: Option<usize>,
}

impl<'py> WaveQuestion<'py> {
    /// A question at `field_deg`, the rest the library's defaults.
    pub(crate) fn new(
        field_deg: f64,
        wavelength_nm: Option<Bound<'py, PyAny>>,
        weights: Option<Vec<f64>>,
        sensor_depth_mm: Option<f64>,
    ) -> Self {
        WaveQuestion {
            field_deg,
            wavelength_nm,
            weights,
            sensor_depth_mm,
            pupil_samples: None,
            padding: None,
            frequencies_per_mm: None,
            through_focus_per_mm: None,
        }
    }

    /// With the pupil's samples a side and the zero padding.
    pub(crate) fn sampled(self, pupil_samples: Option<usize>, padding: Option<usize>) -> Self {
        WaveQuestion {
            pupil_samples,
            padding,
            ..self
        }
    }

    /// With the MTF's frequencies and the through-focus frequency.
    pub(crate) fn at_frequencies(
        self,
        frequencies_per_mm: Option<Vec<f64>>,
        through_focus_per_mm: Option<f64>,
    ) -> Self {
        WaveQuestion {
            frequencies_per_mm,
            through_focus_per_mm,
            ..self
        }
    }

    /// The library's settings; the library's defaults where Python gave None.
    fn settings(&self) -> PyResult<WaveAnalysisSettings> {
        let wavelengths: Vec<f64> = match &self.wavelength_nm {
            None => Vec::new(),
            Some(value) => match value.extract::<f64>() {
                Ok(nm) => vec![nm],
                Err(_) => value
                    .extract::<Vec<f64>>()
                    .map_err(|_| value_error("wavelength_nm is a number or a sequence of numbers (nm)"))?,
            },
        };
        let weights = match &self.weights {
            None => vec![1.0; wavelengths.len()],
            Some(w) if w.len() == wavelengths.len() => w.clone(),
            Some(w) => {
                return Err(value_error(format!(
                    "weights gives {} weights for {} wavelengths",
                    w.len(),
                    wavelengths.len()
                )))
            }
        };
        let defaults = WaveAnalysisSettings::default();
        Ok(WaveAnalysisSettings {
            field_deg: self.field_deg,
            spectrum: wavelengths
                .into_iter()
                .zip(weights)
                .map(|(wavelength_nm, weight)| WeightedWavelength { wavelength_nm, weight })
                .collect(),
            sensor_depth_mm: self.sensor_depth_mm,
            pupil_samples: self.pupil_samples.unwrap_or(defaults.pupil_samples),
            padding: self.padding.unwrap_or(defaults.padding),
            frequencies_per_mm: self
                .frequencies_per_mm
                .clone()
                .unwrap_or_else(|| defaults.frequencies_per_mm.clone()),
            through_focus_frequency_per_mm: self.through_focus_per_mm,
        })
    }

    /// The analysis of `system`, run without the GIL.
    fn run(&self, py: Python<'_>, system: &LensSystem) -> PyResult<WaveResult> {
        let settings = self.settings()?;
        py.detach(|| guarded(|| WaveAnalysis::with_psf(system, &settings)))?
            .map_err(to_py)
    }
}

/// A PSF and its sample spacing (x, y), µm.
pub(crate) type SampledPsf<'py> = (Bound<'py, PyArray2<f64>>, (f64, f64));

/// `Lens.psf`: the polychromatic PSF (rows along y, tangential; unit sum)
/// and its sample spacing (x, y) in µm.
pub(crate) fn psf<'py>(
    py: Python<'py>,
    system: &LensSystem,
    question: &WaveQuestion<'py>,
) -> PyResult<SampledPsf<'py>> {
    let result = question.run(py, system)?;
    let size = result.psf.size();
    let image = Array2::from_shape_vec((size, size), result.psf.intensity().to_vec())
        .expect("a PSF is size × size")
        .into_pyarray(py);
    let [dx, dy] = result.analysis.psf_spacing_um;
    Ok((image, (dx, dy)))
}

/// `Lens.mtf`: the analysis as `lenspath lens --mtf --json` prints one
/// field, with its MTF samples as numpy arrays (`frequencies_per_mm`,
/// `tangential`, `sagittal`, `diffraction_limit`) instead of a list.
pub(crate) fn mtf<'py>(
    py: Python<'py>,
    system: &LensSystem,
    question: &WaveQuestion<'py>,
) -> PyResult<Bound<'py, PyDict>> {
    let analysis = question.run(py, system)?.analysis;
    let text = serde_json::to_string(&analysis).map_err(|e| value_error(e.to_string()))?;
    let d = py
        .import("json")?
        .call_method1("loads", (text,))?
        .cast_into::<PyDict>()?;
    d.del_item("mtf")?;
    let column = |pick: fn(&lenspath::lens::wave_analysis::MtfSample) -> f64| {
        analysis.mtf.iter().map(pick).collect::<Vec<f64>>().into_pyarray(py)
    };
    d.set_item("frequencies_per_mm", column(|s| s.frequency_per_mm))?;
    d.set_item("tangential", column(|s| s.tangential))?;
    d.set_item("sagittal", column(|s| s.sagittal))?;
    d.set_item("diffraction_limit", column(|s| s.diffraction_limit))?;
    Ok(d)
}
