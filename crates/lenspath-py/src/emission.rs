//! Light spectra: what a light or an emitting shape gives off when an RGB
//! colour is not enough (a black body, a measured lamp).

use lenspath::spectrum::Emission as LibraryEmission;
use pyo3::prelude::*;

use crate::error::{to_py, value_error};

/// A spectrum a light or an emitting shape gives off, scaled to a
/// luminance (1: as bright as RGB white). Wherever the scene methods take an
/// RGB amount of light (`intensity`, `irradiance`, `radiance`, `emission`),
/// they also take one of these.
#[pyclass(module = "lenspath._core", frozen)]
#[derive(Clone)]
pub(crate) struct Emission {
    pub(crate) emission: LibraryEmission,
    description: String,
}

#[pymethods]
impl Emission {
    /// Planck's black body at `temperature_k` (500 K or more), with luminance `luminance`.
    #[staticmethod]
    #[pyo3(signature = (temperature_k, luminance = 1.0))]
    fn blackbody(temperature_k: f32, luminance: f32) -> PyResult<Self> {
        Ok(Emission {
            emission: LibraryEmission::blackbody(temperature_k, luminance).map_err(to_py)?,
            description: format!("blackbody {temperature_k} K, luminance {luminance}"),
        })
    }

    /// A spectrum given as `values` at `wavelengths_nm` (increasing; linear
    /// between them, zero beyond the ends), scaled to luminance `luminance`.
    #[staticmethod]
    #[pyo3(signature = (wavelengths_nm, values, luminance = 1.0))]
    fn tabulated(wavelengths_nm: Vec<f32>, values: Vec<f32>, luminance: f32) -> PyResult<Self> {
        if wavelengths_nm.len() != values.len() {
            return Err(value_error(format!(
                "wavelengths_nm and values must have one value each, got {} and {}",
                wavelengths_nm.len(),
                values.len()
            )));
        }
        let pairs: Vec<(f32, f32)> = wavelengths_nm.iter().copied().zip(values.iter().copied()).collect();
        Ok(Emission {
            emission: LibraryEmission::tabulated(&pairs, luminance).map_err(to_py)?,
            description: format!(
                "table of {} values, {}-{} nm, luminance {luminance}",
                pairs.len(),
                wavelengths_nm.first().copied().unwrap_or(0.0),
                wavelengths_nm.last().copied().unwrap_or(0.0)
            ),
        })
    }

    /// Its colour as linear sRGB (r, g, b).
    #[getter]
    fn rgb(&self) -> (f32, f32, f32) {
        self.emission.to_rgb().into()
    }

    fn __repr__(&self) -> String {
        format!("<lenspath.Emission {}>", self.description)
    }
}
