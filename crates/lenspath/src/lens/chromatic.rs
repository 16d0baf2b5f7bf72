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
        let image_z = system.rear_z_mm() + d.back_focal_distance_mm;
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

    /// Against rayoptics (PyPI, `bench/peers/lens_vs_rayoptics.py`, with its own Schott catalogue from the
    /// opticalglass package), each lens's paraxial EFL and back focal distance at
    /// g, F, d and C agree to 2e-5 relative (they agree to about 1e-12). Its numbers,
    /// recorded here, are `fod.efl` and `fod.bfl` (last glass surface to focus)
    /// with the reference wavelength set to each line. The lenspath tables add
    /// a stop; where it comes after the glass, `stop_behind_mm` behind the last
    /// glass surface, lenspath's back focal distance is measured from it. The
    /// triplet is rayoptics' documented Cooke triplet.
    #[test]
    fn lines_agree_with_rayoptics() {
        // Rayoptics' (EFL, bfl) at g, F, d and C.
        type LineFigures = [(f64, f64); 4];
        let cases: [(&str, &str, f64, LineFigures); 3] = [
            (
                "singlet",
                "100 0.001 1.5168 20 N-BK7\n-100 1 1 20\n0 1 0 10\n",
                1.0,
                [
                    (94.9336424197596, 94.93331491212197),
                    (95.7166065269103, 95.71627809243506),
                    (96.74938436834957, 96.74905472644528),
                    (97.21546259079562, 97.21513240954326),
                ],
            ),
            (
                "achromat",
                "61.07 4.0 1.5168 25 N-BK7\n-44.17 2.5 1.6727 25 SF5\n-128.89 1 1 25\n0 5 0 20\n",
                1.0,
                [
                    (99.39174287090019, 96.4453572508743),
                    (99.25698668570944, 96.3057593684452),
                    (99.2527101596016, 96.29428913992479),
                    (99.31996227726393, 96.35801512565003),
                ],
            ),
            (
                "triplet",
                "23.713 4.831 1.691 16 N-LAK9\n7331.288 5.86 1 16\n0 0 0 12\n-24.456 0.975 1.67271 16 N-SF5\n\
                 21.896 4.822 1 16\n86.759 3.127 1.691 16 N-LAK9\n-20.4942 41.2365 1 16\n",
                0.0,
                [
                    (50.07244147680867, 41.29978344223038),
                    (49.98662812256108, 41.21723621183222),
                    (50.00098928993641, 41.23764895362289),
                    (50.05088435384096, 41.29082185067254),
                ],
            ),
        ];
        for (name, table, stop_behind_mm, expected) in cases {
            let chromatic = ChromaticAnalysis::new(&lens(table), 1.0).unwrap();
            for (line, (efl, bfl)) in chromatic.lines.iter().zip(expected) {
                let close = |a: f64, b: f64| (a / b - 1.0).abs() < 2e-5;
                assert!(close(line.effective_focal_length_mm, efl), "{name} {line:?}: EFL {efl}");
                assert!(
                    close(line.back_focal_distance_mm, bfl - stop_behind_mm),
                    "{name} {line:?}: BFD {bfl}"
                );
            }
        }
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
