//! Everything known about a lens on a sensor, in one serialisable report:
//! what `lenspath lens --json` prints, Python's `Lens.analysis()` returns and
//! the viewer's lens panel reads. First-order and real-ray figures
//! ([`LensAnalysis`]), the colour lines ([`ChromaticAnalysis`]), the share
//! of rays the camera lets through, and the two focus questions a caller may
//! ask (where the sensor goes for a distance, what distance a sensor depth
//! focuses), and on request the wave-optics figures at chosen fields
//! ([`WaveAnalysis`]).

use std::collections::BTreeMap;

use glam::{Vec2, Vec3};
use serde::Serialize;

use crate::camera::{CameraPose, LensFocus, RealisticCamera, RealisticCameraSettings};
use crate::error::{Error, Result};
use crate::lens::chromatic::{ChromaticAnalysis, LineFocus};
use crate::lens::wave_analysis::{WaveAnalysis, WaveAnalysisSettings};
use crate::lens::{AnalysisSettings, LensAnalysis, LensPrescription, LensSystem};

/// Camera samples each passing fraction is estimated from.
pub const PASSING_SAMPLES: usize = 20_000;

/// The film width, pixels, the passing fractions' camera is made with (its
/// corner is the centre of its corner pixel).
const PASSING_FILM_WIDTH_PX: u32 = 1000;

/// What a report is asked for besides the lens.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LensReportSettings {
    /// The real-ray figures' choices and the sensor.
    pub analysis: AnalysisSettings,
    /// Also answer: where must the sensor be to focus this far, metres from
    /// the sensor plane?
    pub focus_distance_m: Option<f64>,
    /// Also answer: what distance does a sensor this far behind the stop, mm, focus?
    pub sensor_depth_mm: Option<f64>,
}

/// The share of camera rays that get through the lens, the sensor at the
/// infinity focus: at the image centre and at its corner (vignetting).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct PassingFractions {
    /// At the centre of the image.
    pub passing_fraction_centre: f64,
    /// At the image's corner pixel.
    pub passing_fraction_corner: f64,
}

/// The answers to [`LensReportSettings`]' focus questions.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct FocusAnswers {
    /// The distance asked about, m.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub focus_distance_m: Option<f64>,
    /// The sensor depth behind the stop that focuses it, mm.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sensor_depth_for_focus_distance_mm: Option<f64>,
    /// The sensor depth asked about, mm behind the stop.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sensor_depth_mm: Option<f64>,
    /// The distance it focuses, m from the sensor plane; `Some(None)` when
    /// nothing in front of the lens is in focus there (nearer than the
    /// infinity focus).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub focus_distance_for_sensor_depth_m: Option<Option<f64>>,
}

/// The report on one lens, as placed (wide open or stopped down), on one
/// sensor. Serialised, its fields are flat: the analysis's, then `lines`
/// (each colour line's foci by its name), the colour figures, the passing
/// fractions when measured, and the focus answers asked for.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LensReport {
    /// The lens's name.
    pub lens: String,
    /// The sensor's width, mm.
    pub sensor_width_mm: f64,
    /// The sensor's height, mm.
    pub sensor_height_mm: f64,
    /// First-order and real-ray figures.
    #[serde(flatten)]
    pub analysis: LensAnalysis,
    /// The g, F, d and C lines' paraxial foci, by line name.
    pub lines: BTreeMap<&'static str, LineFocus>,
    /// BFD(F) − BFD(C), mm ([`ChromaticAnalysis::longitudinal_color_mm`]).
    pub longitudinal_color_mm: f64,
    /// The F minus the C chief ray's height, mm, at
    /// `lateral_color_field_height_mm` ([`ChromaticAnalysis::lateral_color_mm`]).
    pub lateral_color_mm: f64,
    /// The image height the lateral colour is given at: the sensor's half diagonal, mm.
    pub lateral_color_field_height_mm: f64,
    /// The rays that get through, once measured ([`LensReport::with_passing_fractions`]).
    #[serde(flatten)]
    pub passing: Option<PassingFractions>,
    /// The focus questions' answers.
    #[serde(flatten)]
    pub focus: FocusAnswers,
    /// The wave-optics figures at the fields asked
    /// ([`LensReport::with_wave_analysis`]); absent unless asked.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub wave: Vec<WaveAnalysis>,
}

impl LensReport {
    /// The report on `system`: its analysis, colour and the focus answers
    /// asked for; without the passing fractions, which need a camera
    /// ([`LensReport::with_passing_fractions`]). Fails for a sensor depth
    /// in front of the rear element, and where the analysis fails.
    pub fn new(system: &LensSystem, settings: &LensReportSettings) -> Result<LensReport> {
        let analysis = LensAnalysis::new(system, &settings.analysis)?;
        let (width_mm, height_mm) = settings.analysis.sensor_mm;
        let colour = ChromaticAnalysis::new(system, 0.5 * width_mm.hypot(height_mm))?;
        let h = settings.analysis.ray_height_mm;
        let sensor_depth_for_focus_distance_mm = settings
            .focus_distance_m
            .map(|m| system.sensor_depth_mm_for_focus_distance(m * 1e3, h))
            .transpose()?;
        let focus_distance_for_sensor_depth_m = match settings.sensor_depth_mm {
            Some(z) if z.is_nan() || z <= system.rear_z_mm() => {
                return Err(Error::InvalidArgument(format!(
                    "sensor depth {z} mm must lie behind the rear element ({:.3} mm)",
                    system.rear_z_mm()
                )))
            }
            Some(z) => Some(system.focus_distance_mm(z, h).map(|mm| mm * 1e-3)),
            None => None,
        };
        Ok(LensReport {
            lens: system.prescription().name().to_string(),
            sensor_width_mm: width_mm,
            sensor_height_mm: height_mm,
            analysis,
            lines: colour.lines.iter().map(|l| (l.line, *l)).collect(),
            longitudinal_color_mm: colour.longitudinal_color_mm,
            lateral_color_mm: colour.lateral_color_mm,
            lateral_color_field_height_mm: colour.field_height_mm,
            passing: None,
            focus: FocusAnswers {
                focus_distance_m: settings.focus_distance_m,
                sensor_depth_for_focus_distance_mm,
                sensor_depth_mm: settings.sensor_depth_mm,
                focus_distance_for_sensor_depth_m,
            },
            wave: Vec::new(),
        })
    }

    /// This report with its passing fractions measured: [`PASSING_SAMPLES`]
    /// camera rays at the image centre and at its corner through
    /// `prescription` stopped to `f_number` (the lens the report is on), the
    /// sensor at the infinity focus.
    pub fn with_passing_fractions(mut self, prescription: &LensPrescription, f_number: Option<f64>) -> Result<Self> {
        let (width_mm, height_mm) = (self.sensor_width_mm, self.sensor_height_mm);
        let width_px = PASSING_FILM_WIDTH_PX;
        let height_px = (f64::from(width_px) * height_mm / width_mm).round().max(1.0) as u32;
        let camera = RealisticCamera::new(
            CameraPose::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y),
            width_px,
            height_px,
            &RealisticCameraSettings {
                f_number,
                ..RealisticCameraSettings::new(
                    prescription.clone(),
                    (width_mm, height_mm),
                    LensFocus::SensorDepthMm(self.analysis.infinity_focus_mm),
                )
            },
        )?;
        let centre = Vec2::new(width_px as f32, height_px as f32) * 0.5;
        self.passing = Some(PassingFractions {
            passing_fraction_centre: camera.passing_fraction(centre, PASSING_SAMPLES),
            passing_fraction_corner: camera.passing_fraction(Vec2::splat(0.5), PASSING_SAMPLES),
        });
        Ok(self)
    }

    /// This report with the wave-optics analysis of `system` at each of
    /// `fields_deg`, the rest as `settings` asks.
    pub fn with_wave_analysis(
        mut self,
        system: &LensSystem,
        fields_deg: &[f64],
        settings: &WaveAnalysisSettings,
    ) -> Result<Self> {
        self.wave = fields_deg
            .iter()
            .map(|&field_deg| {
                WaveAnalysis::new(
                    system,
                    &WaveAnalysisSettings {
                        field_deg,
                        ..settings.clone()
                    },
                )
            })
            .collect::<Result<_>>()?;
        Ok(self)
    }

    /// The report as JSON, its keys in name order (as `lenspath lens --json` prints it).
    pub fn to_json(&self) -> String {
        serde_json::to_value(self)
            .expect("a report's numbers, strings and nulls always serialise")
            .to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The report holds the analysis and the colour figures it is made of,
    /// answers its focus questions consistently (the sensor depth for a
    /// distance focuses that distance), flattens to one JSON object, and
    /// measures more rays through at the centre than at the corner.
    #[test]
    fn a_report_holds_its_parts_and_answers_its_questions() {
        let prescription = LensPrescription::load("dgauss50").unwrap();
        let system = LensSystem::new(&prescription);
        let settings = LensReportSettings {
            focus_distance_m: Some(2.0),
            ..LensReportSettings::default()
        };
        let report = LensReport::new(&system, &settings).unwrap();
        assert_eq!(report.analysis, LensAnalysis::new(&system, &settings.analysis).unwrap());
        let colour = ChromaticAnalysis::new(&system, 0.5 * 36f64.hypot(24.0)).unwrap();
        assert_eq!(report.longitudinal_color_mm, colour.longitudinal_color_mm);
        assert_eq!(report.lines.keys().copied().collect::<Vec<_>>(), ["C", "F", "d", "g"]);
        let z = report.focus.sensor_depth_for_focus_distance_mm.unwrap();
        let asked = LensReportSettings {
            sensor_depth_mm: Some(z),
            ..LensReportSettings::default()
        };
        let back = LensReport::new(&system, &asked).unwrap();
        let metres = back.focus.focus_distance_for_sensor_depth_m.unwrap().unwrap();
        assert!((metres - 2.0).abs() < 1e-6, "{metres}");
        let too_near = LensReportSettings {
            sensor_depth_mm: Some(system.rear_z_mm() - 1.0),
            ..LensReportSettings::default()
        };
        let err = LensReport::new(&system, &too_near).unwrap_err().to_string();
        assert!(err.contains("must lie behind the rear element"), "{err}");

        let measured = report.with_passing_fractions(&prescription, None).unwrap();
        let passing = measured.passing.unwrap();
        assert!(
            passing.passing_fraction_centre > passing.passing_fraction_corner,
            "{passing:?}"
        );
        let json: serde_json::Value = serde_json::from_str(&measured.to_json()).unwrap();
        for key in [
            "effective_focal_length_mm",
            "lines",
            "passing_fraction_corner",
            "sensor_depth_for_focus_distance_mm",
            "lens",
        ] {
            assert!(json.get(key).is_some(), "{key} missing from {json}");
        }
        assert!(json.get("sensor_depth_mm").is_none(), "not asked, not printed");
    }
}
