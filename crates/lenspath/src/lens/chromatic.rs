//! Colour: how a lens's focus and magnification change with wavelength,
//! the figures a lens designer reads first (paraxial, from the glasses'
//! dispersion; a lens without a glass column has none).

use serde::Serialize;

use super::system::LensSystem;
use crate::error::Result;
use crate::glass::{C_LINE_NM, D_LINE_NM, FRAUNHOFER_LINES, F_LINE_NM};

/// Paraxial focus at one spectral line.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct LineFocus {
    /// The line's name (`g`, `F`, `d`, `C`).
    #[serde(skip)]
    pub line: &'static str,
    /// Its wavelength, nm.
    pub wavelength_nm: f64,
    /// Paraxial effective focal length there, mm.
    pub effective_focal_length_mm: f64,
    /// Rear vertex to the paraxial focus there, mm.
    pub back_focal_distance_mm: f64,
}

/// A lens's chromatic aberrations.
#[derive(Clone, Debug, PartialEq)]
pub struct ChromaticAnalysis {
    /// The g, F, d and C lines' foci.
    pub lines: Vec<LineFocus>,
    /// Longitudinal (axial) colour: BFD(F) − BFD(C), mm. Negative when blue
    /// focuses nearer the lens, as in an uncorrected positive lens.
    pub longitudinal_color_mm: f64,
    /// Lateral colour: the F chief ray's height minus the C chief ray's on
    /// the d line's image plane (infinity focus), mm, at the field height
    /// below.
    pub lateral_color_mm: f64,
    /// The d-line image height the lateral colour is given at, mm.
    pub field_height_mm: f64,
}

impl ChromaticAnalysis {
    /// The figures of `system` (its stop as set), lateral colour at image
    /// height `field_height_mm` (the sensor's half diagonal, say).
    pub fn new(system: &LensSystem, field_height_mm: f64) -> Result<Self> {
        let lines = FRAUNHOFER_LINES
            .iter()
            .map(|&(line, nm)| {
                let p = system.at_wavelength(nm).paraxial()?;
                Ok(LineFocus {
                    line,
                    wavelength_nm: nm,
                    effective_focal_length_mm: p.effective_focal_length_mm,
                    back_focal_distance_mm: p.back_focal_distance_mm,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let at = |nm: f64| {
            lines
                .iter()
                .find(|l| l.wavelength_nm == nm)
                .expect("every Fraunhofer line is in `lines`")
        };
        let d = at(D_LINE_NM);
        let tan_field = field_height_mm / d.effective_focal_length_mm;
        // The d line's paraxial image plane: rear vertex + its back focal distance.
        let image_z = system.rear_z() + d.back_focal_distance_mm;
        let height = |nm: f64| system.at_wavelength(nm).paraxial_chief_ray_height(tan_field, image_z);
        Ok(ChromaticAnalysis {
            longitudinal_color_mm: at(F_LINE_NM).back_focal_distance_mm - at(C_LINE_NM).back_focal_distance_mm,
            lateral_color_mm: height(F_LINE_NM) - height(C_LINE_NM),
            field_height_mm,
            lines,
        })
    }
}

/// The chromatic focal shift: for each of `wavelengths_nm`, the paraxial
/// back focal distance there minus the d line's, mm (focus against
/// wavelength, the curve lens designers plot).
pub fn focal_shift(system: &LensSystem, wavelengths_nm: &[f64]) -> Result<Vec<(f64, f64)>> {
    let d = system
        .at_wavelength(crate::glass::D_LINE_NM)
        .paraxial()?
        .back_focal_distance_mm;
    wavelengths_nm
        .iter()
        .map(|&nm| Ok((nm, system.at_wavelength(nm).paraxial()?.back_focal_distance_mm - d)))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lens::{LensPrescription, TableConvention};

    fn lens(table: &str) -> LensSystem {
        LensSystem::new(&LensPrescription::parse(table, "t", TableConvention::ThicknessToNext).unwrap())
    }

    /// A thin N-BK7 singlet: its focal length follows the lensmaker's
    /// equation at each line, so its longitudinal colour is f_F − f_C of
    /// that equation, within 1% of the classic −f / V_d.
    #[test]
    fn singlet_longitudinal_colour_is_f_over_v() {
        let system = lens("100 0.001 1.5168 20 N-BK7\n-100 1 1 20\n0 1 0 10\n");
        let chromatic = ChromaticAnalysis::new(&system, 5.0).unwrap();
        let bk7 = crate::glass::find("N-BK7").unwrap().dispersion;
        for line in &chromatic.lines {
            let n = bk7.index(line.wavelength_nm);
            let lensmaker = 1.0 / ((n - 1.0) * (2.0 / 100.0));
            assert!(
                (line.effective_focal_length_mm / lensmaker - 1.0).abs() < 1e-4,
                "{line:?}"
            );
        }
        let lensmaker = |nm: f64| 1.0 / ((bk7.index(nm) - 1.0) * (2.0 / 100.0));
        let expected = lensmaker(F_LINE_NM) - lensmaker(C_LINE_NM);
        assert!(
            (chromatic.longitudinal_color_mm / expected - 1.0).abs() < 1e-3,
            "{chromatic:?}"
        );
        let classic = -chromatic.lines[2].effective_focal_length_mm / bk7.abbe_number();
        assert!((chromatic.longitudinal_color_mm / classic - 1.0).abs() < 0.01);
        // A four-column table: no colour at all.
        let plain = lens("100 0.001 1.5168 20\n-100 1 1 20\n0 1 0 10\n");
        let none = ChromaticAnalysis::new(&plain, 5.0).unwrap();
        assert_eq!(none.longitudinal_color_mm, 0.0);
        assert_eq!(none.lateral_color_mm, 0.0);
    }

    /// A thin singlet behind a stop s = 20 mm in front of it: the chief ray
    /// meets the lens at h = s·tanθ and the lateral colour is −h / V_d
    /// (thin-lens theory: y(λ) = f_d tanθ + h (1 − f_d / f_λ)).
    #[test]
    fn a_stop_in_front_of_a_singlet_gives_its_lateral_colour() {
        let system = lens("0 20 0 10\n100 0.001 1.5168 40 N-BK7\n-100 1 1 40\n");
        let chromatic = ChromaticAnalysis::new(&system, 10.0).unwrap();
        let f_d = chromatic.lines[2].effective_focal_length_mm;
        let h = 20.0 * 10.0 / f_d;
        let expected = -h / crate::glass::find("N-BK7").unwrap().dispersion.abbe_number();
        assert!(
            (chromatic.lateral_color_mm / expected - 1.0).abs() < 2e-3,
            "{chromatic:?} vs {expected}"
        );
    }
}
