//! The wave-optics figures of a lens at one field point, as a lens report
//! gives them (Zemax OpticStudio's FFT MTF, FFT PSF, Strehl and Zernike
//! Fringe reports in one): per wavelength the RMS wavefront error, the
//! Strehl ratio and the Fringe Zernike coefficients; for the spectrum the
//! polychromatic PSF's MTF at chosen frequencies beside the diffraction
//! limit, its MTF50, and optionally the MTF through focus at one frequency.
//!
//! Choices: the sensor defaults to the infinity focus at the first
//! wavelength (the report's own); the diffraction limit is that of a
//! circular pupil at the paraxial working f-number (N/n′ for an object at
//! infinity) at the spectrum's weighted mean wavelength, exact on axis and
//! the usual reference off it, as OpticStudio draws it.

use rayon::prelude::*;
use serde::Serialize;

use super::mtf::{diffraction_limited_mtf, Mtf};
use super::psf::PointSpread;
use super::system::LensSystem;
use super::wavefront::Wavefront;
use super::AnalysisSettings;
use crate::error::{Error, Result};
use crate::glass::{C_LINE_NM, D_LINE_NM, F_LINE_NM};

/// One wavelength of a spectrum and its weight.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct WeightedWavelength {
    /// Wavelength, nm.
    pub wavelength_nm: f64,
    /// Relative weight (any positive scale).
    pub weight: f64,
}

impl WeightedWavelength {
    /// The d, F and C lines, equal weights, the d line first (the primary):
    /// the visible spectrum a photographic lens is corrected and analysed over.
    pub fn visible_lines() -> Vec<WeightedWavelength> {
        [D_LINE_NM, F_LINE_NM, C_LINE_NM]
            .map(|wavelength_nm| WeightedWavelength {
                wavelength_nm,
                weight: 1.0,
            })
            .to_vec()
    }
}

/// The fields a lens's MTF is shown at when none are asked (the viewer's
/// lens panel): the axis, half and 0.85 of the half-diagonal field of view.
pub const SHOWN_FIELD_FRACTIONS: [f64; 3] = [0.0, 0.5, 0.85];

/// What a [`WaveAnalysis`] is asked.
#[derive(Clone, Debug, PartialEq)]
pub struct WaveAnalysisSettings {
    /// The field angle, degrees off the axis in the vertical (tangential) meridian.
    pub field_deg: f64,
    /// The wavelengths and weights; empty: the lens system's own wavelength alone.
    pub spectrum: Vec<WeightedWavelength>,
    /// The sensor's depth behind the stop, mm; `None`: the infinity focus at the first wavelength.
    pub sensor_depth_mm: Option<f64>,
    /// Pupil samples a side.
    pub pupil_samples: usize,
    /// Zero padding of the pupil before the FFT (the PSF's samples per λN/…, see [`super::psf`]).
    pub padding: usize,
    /// The spatial frequencies the MTF is reported at, cycles (line pairs) per mm.
    pub frequencies_per_mm: Vec<f64>,
    /// Also the MTF through focus at this frequency, cycles per mm.
    pub through_focus_frequency_per_mm: Option<f64>,
}

impl Default for WaveAnalysisSettings {
    fn default() -> Self {
        WaveAnalysisSettings {
            field_deg: 0.0,
            spectrum: Vec::new(),
            sensor_depth_mm: None,
            pupil_samples: 128,
            padding: 4,
            frequencies_per_mm: (0..=20).map(|k| 5.0 * f64::from(k)).collect(),
            through_focus_frequency_per_mm: None,
        }
    }
}

/// Sensor positions the through-focus MTF is sampled at, spread evenly over
/// ±[`THROUGH_FOCUS_HALF_RANGE_RAYLEIGH`] Rayleigh depths of focus (2λN²).
pub const THROUGH_FOCUS_STEPS: usize = 41;
/// The through-focus range each side of the sensor, in Rayleigh depths of focus.
pub const THROUGH_FOCUS_HALF_RANGE_RAYLEIGH: f64 = 4.0;

/// The figures at one wavelength.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MonochromaticFigures {
    /// Wavelength, nm.
    pub wavelength_nm: f64,
    /// Its weight in the spectrum.
    pub weight: f64,
    /// RMS wavefront error about its mean, waves.
    pub rms_wavefront_waves: f64,
    /// The PSF's peak over a perfect pupil's of the same shape.
    pub strehl_ratio: f64,
    /// The share of the paraxial pupil's circle that passes the lens.
    pub pupil_passing_fraction: f64,
    /// Fringe Zernike coefficients Z1…Z37, waves ([`super::zernike`]).
    pub zernike_fringe_waves: Vec<f64>,
}

/// The MTF at one frequency.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct MtfSample {
    /// Spatial frequency, cycles per mm.
    pub frequency_per_mm: f64,
    /// Frequencies along the field's direction (y).
    pub tangential: f64,
    /// Frequencies across it (x).
    pub sagittal: f64,
    /// A perfect lens's at the same working f-number.
    pub diffraction_limit: f64,
}

/// The MTF at one frequency and one sensor position.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ThroughFocusSample {
    /// The sensor's depth behind the stop, mm.
    pub sensor_depth_mm: f64,
    /// Tangential MTF.
    pub tangential: f64,
    /// Sagittal MTF.
    pub sagittal: f64,
}

/// The wave-optics figures at one field point (what `lenspath lens --mtf` prints).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WaveAnalysis {
    /// Field angle, degrees.
    pub field_deg: f64,
    /// The sensor's depth behind the stop, mm.
    pub sensor_depth_mm: f64,
    /// The paraxial working f-number the diffraction limit is drawn at.
    pub working_f_number: f64,
    /// The PSF's sample spacing on the sensor (x, y), µm.
    pub psf_spacing_um: [f64; 2],
    /// Per wavelength.
    pub wavelengths: Vec<MonochromaticFigures>,
    /// The polychromatic Strehl ratio: the weighted mean of the wavelengths'.
    pub strehl_ratio: f64,
    /// The polychromatic MTF at the asked frequencies.
    pub mtf: Vec<MtfSample>,
    /// The frequency where the tangential MTF falls to 0.5, cycles per mm.
    pub mtf50_tangential_per_mm: Option<f64>,
    /// The frequency where the sagittal MTF falls to 0.5, cycles per mm.
    pub mtf50_sagittal_per_mm: Option<f64>,
    /// The MTF through focus, when asked.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub through_focus: Vec<ThroughFocusSample>,
    /// The frequency of `through_focus`, cycles per mm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub through_focus_frequency_per_mm: Option<f64>,
}

/// A wave analysis and the polychromatic PSF and MTF it was read from.
#[derive(Clone, Debug)]
pub struct WaveResult {
    /// The figures.
    pub analysis: WaveAnalysis,
    /// The polychromatic PSF.
    pub psf: PointSpread,
    /// Its MTF.
    pub mtf: Mtf,
    /// A perfect lens's polychromatic PSF at the same working f-number and
    /// spectrum, on the same kind of grid: the reference a PSF is drawn against.
    pub diffraction_limited_psf: PointSpread,
}

impl WaveAnalysis {
    /// The analysis of `system` (as placed: stopped down or wide open).
    /// Fails for an unusable field, spectrum, grid or sensor depth.
    pub fn new(system: &LensSystem, settings: &WaveAnalysisSettings) -> Result<WaveAnalysis> {
        Self::with_psf(system, settings).map(|result| result.analysis)
    }

    /// The analysis with its polychromatic PSF and MTF.
    pub fn with_psf(system: &LensSystem, settings: &WaveAnalysisSettings) -> Result<WaveResult> {
        let spectrum = checked_spectrum(system, settings)?;
        let primary = system.at_wavelength(spectrum[0].wavelength_nm);
        let sensor_depth_mm = match settings.sensor_depth_mm {
            Some(z) if !(z.is_finite() && z > system.rear_z_mm()) => {
                return Err(Error::InvalidArgument(format!(
                    "sensor depth {z} mm must lie behind the rear element ({:.3} mm)",
                    system.rear_z_mm()
                )))
            }
            Some(z) => z,
            None => primary.infinity_focus_z_mm(AnalysisSettings::default().ray_height_mm)?,
        };
        let (psf, wavelengths) = polychromatic_psf(system, settings, &spectrum, sensor_depth_mm)?;
        let mtf = psf.mtf();
        let total_weight: f64 = spectrum.iter().map(|w| w.weight).sum();
        let mean_wavelength_nm = spectrum.iter().map(|w| w.wavelength_nm * w.weight).sum::<f64>() / total_weight;
        let paraxial = primary.paraxial()?;
        let image_index = primary.surfaces.last().map_or(1.0, |s| s.ior_back);
        let working_f_number = paraxial.f_number / image_index;
        let through_focus = match settings.through_focus_frequency_per_mm {
            Some(frequency) => through_focus(
                system,
                settings,
                &spectrum,
                sensor_depth_mm,
                working_f_number,
                frequency,
            )?,
            None => Vec::new(),
        };
        let analysis = WaveAnalysis {
            field_deg: settings.field_deg,
            sensor_depth_mm,
            working_f_number,
            psf_spacing_um: psf.spacing_mm().map(|d| d * 1e3),
            strehl_ratio: psf.strehl_ratio(),
            wavelengths,
            mtf: settings
                .frequencies_per_mm
                .iter()
                .map(|&frequency_per_mm| MtfSample {
                    frequency_per_mm,
                    tangential: mtf.tangential(frequency_per_mm),
                    sagittal: mtf.sagittal(frequency_per_mm),
                    diffraction_limit: diffraction_limited_mtf(frequency_per_mm, mean_wavelength_nm, working_f_number),
                })
                .collect(),
            mtf50_tangential_per_mm: mtf.mtf50_per_mm(1),
            mtf50_sagittal_per_mm: mtf.mtf50_per_mm(0),
            through_focus,
            through_focus_frequency_per_mm: settings.through_focus_frequency_per_mm,
        };
        let perfect: Vec<(PointSpread, f64)> = spectrum
            .iter()
            .map(|w| {
                Wavefront::diffraction_limited(settings.pupil_samples, working_f_number, w.wavelength_nm)
                    .psf(settings.padding)
                    .map(|psf| (psf, w.weight))
            })
            .collect::<Result<_>>()?;
        Ok(WaveResult {
            analysis,
            psf,
            mtf,
            diffraction_limited_psf: PointSpread::polychromatic(&perfect)?,
        })
    }
}

/// The spectrum asked for, or the system's wavelength; checked.
fn checked_spectrum(system: &LensSystem, settings: &WaveAnalysisSettings) -> Result<Vec<WeightedWavelength>> {
    if !settings.field_deg.is_finite() || settings.field_deg.abs() >= 90.0 {
        return Err(Error::InvalidArgument(format!(
            "a field angle lies within ±90°, got {}",
            settings.field_deg
        )));
    }
    let spectrum = if settings.spectrum.is_empty() {
        vec![WeightedWavelength {
            wavelength_nm: system.wavelength_nm(),
            weight: 1.0,
        }]
    } else {
        settings.spectrum.clone()
    };
    if let Some(bad) = spectrum
        .iter()
        .find(|w| !(w.wavelength_nm > 0.0 && w.wavelength_nm.is_finite() && w.weight >= 0.0 && w.weight.is_finite()))
    {
        return Err(Error::InvalidArgument(format!(
            "a wavelength must be positive and its weight non-negative, got {} nm weighing {}",
            bad.wavelength_nm, bad.weight
        )));
    }
    if let Some(f) = settings
        .frequencies_per_mm
        .iter()
        .find(|f| !(**f >= 0.0 && f.is_finite()))
    {
        return Err(Error::InvalidArgument(format!(
            "an MTF frequency must be non-negative, got {f} per mm"
        )));
    }
    Ok(spectrum)
}

/// The weighted PSF over `spectrum` with the sensor at `sensor_depth_mm`, and each wavelength's figures.
fn polychromatic_psf(
    system: &LensSystem,
    settings: &WaveAnalysisSettings,
    spectrum: &[WeightedWavelength],
    sensor_depth_mm: f64,
) -> Result<(PointSpread, Vec<MonochromaticFigures>)> {
    let mut parts = Vec::with_capacity(spectrum.len());
    let mut figures = Vec::with_capacity(spectrum.len());
    for w in spectrum {
        let wavefront = system.at_wavelength(w.wavelength_nm).wavefront(
            settings.field_deg,
            sensor_depth_mm,
            settings.pupil_samples,
        )?;
        let psf = wavefront.psf(settings.padding)?;
        figures.push(MonochromaticFigures {
            wavelength_nm: w.wavelength_nm,
            weight: w.weight,
            rms_wavefront_waves: wavefront.rms_waves(),
            strehl_ratio: psf.strehl_ratio(),
            pupil_passing_fraction: wavefront.passing_fraction(),
            zernike_fringe_waves: wavefront.zernike_fringe()?.coefficients,
        });
        parts.push((psf, w.weight));
    }
    Ok((PointSpread::polychromatic(&parts)?, figures))
}

/// The MTF at `frequency_per_mm` with the sensor stepped through focus about `centre_mm`.
fn through_focus(
    system: &LensSystem,
    settings: &WaveAnalysisSettings,
    spectrum: &[WeightedWavelength],
    centre_mm: f64,
    working_f_number: f64,
    frequency_per_mm: f64,
) -> Result<Vec<ThroughFocusSample>> {
    if !(frequency_per_mm > 0.0 && frequency_per_mm.is_finite()) {
        return Err(Error::InvalidArgument(format!(
            "a through-focus frequency must be positive, got {frequency_per_mm} per mm"
        )));
    }
    let wavelength_mm = spectrum[0].wavelength_nm * 1e-6;
    let half_range_mm = THROUGH_FOCUS_HALF_RANGE_RAYLEIGH * 2.0 * wavelength_mm * working_f_number * working_f_number;
    // Each position is its own analysis: in parallel, collected in order.
    (0..THROUGH_FOCUS_STEPS)
        .into_par_iter()
        .map(|k| {
            let offset = (2.0 * k as f64 / (THROUGH_FOCUS_STEPS - 1) as f64 - 1.0) * half_range_mm;
            let sensor_depth_mm = centre_mm + offset;
            let (psf, _) = polychromatic_psf(system, settings, spectrum, sensor_depth_mm)?;
            let mtf = psf.mtf();
            Ok(ThroughFocusSample {
                sensor_depth_mm,
                tangential: mtf.tangential(frequency_per_mm),
                sagittal: mtf.sagittal(frequency_per_mm),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lens::wavefront::tests::singlet;

    #[test]
    fn a_stopped_down_singlet_on_axis_peaks_at_its_focus_and_is_near_the_limit() {
        let system = singlet().with_f_number(16.0).unwrap();
        let settings = WaveAnalysisSettings {
            pupil_samples: 64,
            through_focus_frequency_per_mm: Some(40.0),
            ..WaveAnalysisSettings::default()
        };
        let analysis = WaveAnalysis::new(&system, &settings).unwrap();
        assert_eq!(analysis.mtf.len(), 21);
        for sample in &analysis.mtf {
            assert!(
                sample.tangential <= sample.diffraction_limit + 0.01
                    && sample.tangential > sample.diffraction_limit - 0.06
                    && (sample.tangential - sample.sagittal).abs() < 1e-6,
                "{sample:?}"
            );
        }
        // Through focus, the MTF peaks within a step of the middle and falls at the ends.
        let curve: Vec<f64> = analysis.through_focus.iter().map(|s| s.tangential).collect();
        let best = (0..curve.len()).max_by(|&a, &b| curve[a].total_cmp(&curve[b])).unwrap();
        let middle = THROUGH_FOCUS_STEPS / 2;
        assert!(best.abs_diff(middle) <= 2, "peak at step {best} of {curve:?}");
        assert!(curve[0] < 0.5 * curve[best] && curve[curve.len() - 1] < 0.5 * curve[best]);
        let json = serde_json::to_value(&analysis).unwrap();
        assert_eq!(
            json["wavelengths"][0]["zernike_fringe_waves"].as_array().unwrap().len(),
            37
        );
    }

    #[test]
    fn longitudinal_colour_lowers_the_polychromatic_mtf_of_a_singlet() {
        // A BK7 singlet's F and C foci lie about f/V = 50/64 ≈ 0.8 mm apart: far beyond f/16's 0.3 mm depth of focus.
        let system = singlet().with_f_number(16.0).unwrap();
        let at = |spectrum: Vec<WeightedWavelength>| {
            let settings = WaveAnalysisSettings {
                pupil_samples: 64,
                spectrum,
                ..WaveAnalysisSettings::default()
            };
            WaveAnalysis::new(&system, &settings).unwrap()
        };
        let line = |wavelength_nm| WeightedWavelength {
            wavelength_nm,
            weight: 1.0,
        };
        let mono = at(vec![line(587.56)]);
        let poly = at(vec![line(587.56), line(486.13), line(656.27)]);
        let at_40 = |a: &WaveAnalysis| a.mtf[8].tangential;
        assert!(
            at_40(&poly) < at_40(&mono) - 0.1,
            "{} against {}",
            at_40(&poly),
            at_40(&mono)
        );
        assert_eq!(poly.wavelengths.len(), 3);
        assert!(poly.wavelengths[1].rms_wavefront_waves > 3.0 * poly.wavelengths[0].rms_wavefront_waves);
    }

    #[test]
    fn bad_questions_are_refused_with_their_value() {
        let system = singlet();
        let ask = |settings: WaveAnalysisSettings| WaveAnalysis::new(&system, &settings).unwrap_err().to_string();
        assert!(ask(WaveAnalysisSettings {
            field_deg: 95.0,
            ..WaveAnalysisSettings::default()
        })
        .contains("95"));
        assert!(ask(WaveAnalysisSettings {
            sensor_depth_mm: Some(-1.0),
            ..WaveAnalysisSettings::default()
        })
        .contains("behind the rear element"));
        assert!(ask(WaveAnalysisSettings {
            spectrum: vec![WeightedWavelength {
                wavelength_nm: -5.0,
                weight: 1.0
            }],
            ..WaveAnalysisSettings::default()
        })
        .contains("-5"));
    }
}
