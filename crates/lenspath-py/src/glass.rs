//! Optical glass: a catalogue glass's index against wavelength.

use lenspath::glass::{self, check_wavelength_nm, Dispersion};
use numpy::{IntoPyArray, PyArray1};
use pyo3::prelude::*;

use crate::error::to_py;

/// An optical glass of the embedded catalogues (Schott, Ohara, Hoya, CDGM,
/// Sumita, Hikari), by name (`"N-BK7"`, `"ohara:S-LAH59"`), or a model
/// glass from n_d and V_d (`Glass.abbe(1.5168, 64.17)`).
#[pyclass(module = "lenspath._core", frozen)]
pub(crate) struct Glass {
    maker: Option<&'static str>,
    name: String,
    dispersion: Dispersion,
}

#[pymethods]
impl Glass {
    #[new]
    fn new(name: &str) -> PyResult<Self> {
        let g = glass::find(name).map_err(to_py)?;
        Ok(Glass {
            maker: Some(g.maker),
            name: g.name.to_string(),
            dispersion: g.dispersion,
        })
    }

    /// A glass with index `n_d` at the d line and Abbe number `v_d`, by the
    /// two-term Cauchy model lens tables with only those numbers get.
    #[staticmethod]
    fn abbe(n_d: f64, v_d: f64) -> PyResult<Self> {
        Ok(Glass {
            maker: None,
            name: format!("n_d {n_d}, V_d {v_d}"),
            dispersion: Dispersion::from_abbe(n_d, v_d).map_err(to_py)?,
        })
    }

    /// The index of refraction at `wavelength_nm` (a number, or an array of them).
    fn index<'py>(&self, py: Python<'py>, wavelength_nm: &Bound<'py, PyAny>) -> PyResult<Py<PyAny>> {
        if let Ok(nm) = wavelength_nm.extract::<f64>() {
            check_wavelength_nm(nm).map_err(to_py)?;
            return Ok(self.dispersion.index(nm).into_pyobject(py)?.into_any().unbind());
        }
        let nms: Vec<f64> = wavelength_nm.extract()?;
        for &nm in &nms {
            check_wavelength_nm(nm).map_err(to_py)?;
        }
        let indices: Vec<f64> = nms.iter().map(|&nm| self.dispersion.index(nm)).collect();
        let array: Bound<'py, PyArray1<f64>> = indices.into_pyarray(py);
        Ok(array.into_any().unbind())
    }

    /// The catalogue's maker (`"schott"`), or None for a model glass.
    #[getter]
    fn maker(&self) -> Option<&'static str> {
        self.maker
    }

    /// The glass's name.
    #[getter]
    fn name(&self) -> &str {
        &self.name
    }

    /// The index at the d line (587.5618 nm).
    #[getter]
    fn n_d(&self) -> f64 {
        self.dispersion.n_d()
    }

    /// The Abbe number (n_d − 1) / (n_F − n_C).
    #[getter]
    fn v_d(&self) -> f64 {
        self.dispersion.abbe_number()
    }

    fn __repr__(&self) -> String {
        match self.maker {
            Some(maker) => format!("Glass('{maker}:{}')", self.name),
            None => format!(
                "Glass.abbe({}, {})",
                self.dispersion.n_d(),
                self.dispersion.abbe_number()
            ),
        }
    }
}
