//! Real compound lenses: prescriptions, exact tracing, first-order and
//! real-ray analysis, focusing, wave optics (wavefront, PSF, MTF), and the layout plot.

pub mod chromatic;
pub mod focusing;
pub mod iset;
pub mod lentil;
pub mod library;
pub mod mtf;
pub mod paraxial;
pub mod plot;
pub mod prescription;
pub mod psf;
pub mod surface;
pub mod system;
pub mod table;
pub mod through_focus;
pub mod trace;
pub mod wave_analysis;
pub mod wave_plot;
pub mod wavefront;
pub mod zemax;
pub mod zernike;

pub use mtf::{diffraction_limited_mtf, Mtf};
pub use paraxial::ParaxialData;
pub use prescription::{LensPrescription, LensSurface, BUILTIN_LENSES};
pub use psf::PointSpread;
pub use surface::{CylinderAxis, EvenAsphere, Meridian, SurfaceShape};
pub use system::{Direction, LensRay, LensSystem};
pub use table::TableConvention;
pub use through_focus::SpotBundle;
pub use wavefront::Wavefront;

use std::path::Path;

use crate::error::{Error, Result};

// Where a lens comes from, by its name's form: one rule for every front end, here above the
// formats so that none of them depends on another.
impl LensPrescription {
    /// A built-in lens by name, an entry of the lentil database
    /// (`lentil:0004`, [`lentil`]), or else the file at `name_or_path`:
    /// a Zemax `.zmx` ([`zemax`]), an ISET `.json` ([`iset`])
    /// or a lens table.
    pub fn load(name_or_path: &str) -> Result<LensPrescription> {
        if let Some(id) = name_or_path.strip_prefix(lentil::PREFIX) {
            return lentil::load(id);
        }
        let extension = Path::new(name_or_path)
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        if let Some((name, table)) = BUILTIN_LENSES.iter().find(|(n, _)| *n == name_or_path) {
            return LensPrescription::parse(table, name, TableConvention::ThicknessToNext);
        }
        let path = Path::new(name_or_path);
        if !path.exists() {
            let names: Vec<&str> = BUILTIN_LENSES.iter().map(|(n, _)| *n).collect();
            return Err(Error::InvalidArgument(format!(
                "unknown lens '{name_or_path}': not a built-in lens ({}) nor an existing file",
                names.join(", ")
            )));
        }
        match extension.as_deref() {
            Some("zmx") => return zemax::load(path),
            Some("json") => return iset::load(path),
            _ => {}
        }
        let text = crate::fs::read_text(path, crate::FileKind::Lens)?;
        LensPrescription::parse(&text, name_or_path, TableConvention::Auto)
    }
}

/// The 35 mm format (film and full-frame digital), width and height in mm:
/// the sensor a lens is analysed and drawn for unless told another.
pub const FULL_FRAME_MM: (f64, f64) = (36.0, 24.0);

/// Choices behind the real-ray figures of [`LensAnalysis`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnalysisSettings {
    /// Height of the near-axis real rays, in mm (the CS184 lens simulator used 0.1 mm).
    pub ray_height_mm: f64,
    /// Distance of the close-focus object in front of the aperture stop, in
    /// mm; `None` for 5 × the real-ray focal length.
    pub close_object_distance_mm: Option<f64>,
    /// Sensor width and height in mm, for the field of view.
    pub sensor_mm: (f64, f64),
}

impl Default for AnalysisSettings {
    fn default() -> Self {
        AnalysisSettings {
            ray_height_mm: 0.1,
            close_object_distance_mm: None,
            sensor_mm: FULL_FRAME_MM,
        }
    }
}

/// First-order and real-ray figures of one meridian of an anamorphic lens.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct MeridianFigures {
    /// Paraxial effective focal length in this meridian.
    pub effective_focal_length_mm: f64,
    /// Paraxial f-number in this meridian (its focal length over its
    /// entrance pupil's extent in it).
    pub f_number: f64,
    /// Paraxial entrance pupil extent in this meridian.
    pub entrance_pupil_diameter_mm: f64,
    /// Real ray: the sensor position where objects at infinity focus in this meridian (its line focus).
    pub infinity_focus_mm: f64,
    /// Field of view across the sensor in this meridian (its width for the
    /// horizontal, its height for the vertical), paraxial.
    pub field_of_view_deg: f64,
}

/// What makes an anamorphic lens one: its two meridians' figures.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct AnamorphicFigures {
    /// Across the sensor's width.
    pub horizontal: MeridianFigures,
    /// Across the sensor's height.
    pub vertical: MeridianFigures,
    /// Vertical over horizontal focal length: how many times more of the
    /// scene's width than of its height the sensor takes in, per mm (2 for a
    /// "2×" anamorphic); stretching the image's width by it desqueezes it.
    pub squeeze: f64,
}

/// Everything `lenspath lens` reports. Positions are along the axis in mm
/// from the aperture stop, positive toward the sensor. For an anamorphic
/// lens the paraxial figures are its horizontal meridian's, the real-ray
/// focus positions lie midway between its two meridians' line foci (where
/// the camera focuses), and [`LensAnalysis::anamorphic`] gives each meridian.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct LensAnalysis {
    /// Paraxial effective focal length.
    pub effective_focal_length_mm: f64,
    /// Paraxial rear vertex → F′.
    pub back_focal_distance_mm: f64,
    /// Paraxial F → front vertex.
    pub front_focal_distance_mm: f64,
    /// Paraxial front principal plane P.
    pub front_principal_plane_mm: f64,
    /// Paraxial rear principal plane P′.
    pub rear_principal_plane_mm: f64,
    /// Paraxial entrance pupil position.
    pub entrance_pupil_mm: f64,
    /// Paraxial entrance pupil diameter.
    pub entrance_pupil_diameter_mm: f64,
    /// Paraxial exit pupil position.
    pub exit_pupil_mm: f64,
    /// Paraxial exit pupil diameter.
    pub exit_pupil_diameter_mm: f64,
    /// Paraxial f-number (wide open unless stopped down).
    pub f_number: f64,
    /// Diagonal field of view for the sensor, paraxial (2·atan(half diagonal / EFL)).
    pub diagonal_fov_deg: f64,
    /// Horizontal field of view for the sensor, paraxial.
    pub horizontal_fov_deg: f64,
    /// Real ray: sensor position at which objects at infinity focus.
    pub infinity_focus_mm: f64,
    /// Real ray: sensor position focusing the close-focus object.
    pub close_focus_mm: f64,
    /// Distance of that object in front of the stop.
    pub close_focus_object_distance_mm: f64,
    /// Real ray: |P′ − F′|.
    pub focal_length_mm: f64,
    /// Height of the real rays used.
    pub ray_height_mm: f64,
    /// Front vertex position.
    pub front_vertex_mm: f64,
    /// Rear vertex position.
    pub rear_vertex_mm: f64,
    /// Each meridian's figures, for a lens that is not rotationally symmetric.
    pub anamorphic: Option<AnamorphicFigures>,
}

impl LensAnalysis {
    /// Analyses `system` (paraxial traces and real rays at `settings.ray_height_mm`).
    pub fn new(system: &LensSystem, settings: &AnalysisSettings) -> Result<LensAnalysis> {
        let p = system.paraxial()?;
        let h = settings.ray_height_mm;
        let (horizontal_focus, real_principal) = system.real_focus_at_infinity(h)?;
        let focal_length = (horizontal_focus - real_principal).abs();
        let infinity_focus = system.infinity_focus_z_mm(h)?;
        let close_distance = settings.close_object_distance_mm.unwrap_or(5.0 * focal_length);
        let close_focus = system.real_image_z_mm(-close_distance, h)?;
        let (w, ht) = settings.sensor_mm;
        // Paraxial field of view across a half-width `half_mm` through a focal length.
        let fov_deg = |half_mm: f64, focal_mm: f64| 2.0 * (half_mm / focal_mm.abs()).atan().to_degrees();
        let fov = |half_mm: f64| fov_deg(half_mm, p.effective_focal_length_mm);
        let anamorphic = match system.is_rotationally_symmetric() {
            true => None,
            false => {
                let figures = |p: &ParaxialData, line_focus_mm: f64, half_sensor_mm: f64| MeridianFigures {
                    effective_focal_length_mm: p.effective_focal_length_mm,
                    f_number: p.f_number,
                    entrance_pupil_diameter_mm: p.entrance_pupil_diameter_mm,
                    infinity_focus_mm: line_focus_mm,
                    field_of_view_deg: fov_deg(half_sensor_mm, p.effective_focal_length_mm),
                };
                // The horizontal meridian is what `p` and `horizontal_focus` traced.
                let vertical = system.paraxial_in(Meridian::Vertical)?;
                let vertical_focus = system.real_focus_at_infinity_in(h, Meridian::Vertical)?.0;
                Some(AnamorphicFigures {
                    horizontal: figures(&p, horizontal_focus, 0.5 * w),
                    vertical: figures(&vertical, vertical_focus, 0.5 * ht),
                    // As `LensSystem::squeeze`: f_v / f_h.
                    squeeze: vertical.effective_focal_length_mm / p.effective_focal_length_mm,
                })
            }
        };
        // An anamorphic lens's diagonal: each half-side through its own focal length.
        let diagonal_fov_deg = match anamorphic {
            None => fov(0.5 * w.hypot(ht)),
            Some(a) => {
                let tan = (0.5 * w / a.horizontal.effective_focal_length_mm)
                    .hypot(0.5 * ht / a.vertical.effective_focal_length_mm);
                2.0 * tan.atan().to_degrees()
            }
        };
        Ok(LensAnalysis {
            effective_focal_length_mm: p.effective_focal_length_mm,
            back_focal_distance_mm: p.back_focal_distance_mm,
            front_focal_distance_mm: p.front_focal_distance_mm,
            front_principal_plane_mm: p.front_principal_plane_z_mm,
            rear_principal_plane_mm: p.rear_principal_plane_z_mm,
            entrance_pupil_mm: p.entrance_pupil_z_mm,
            entrance_pupil_diameter_mm: p.entrance_pupil_diameter_mm,
            exit_pupil_mm: p.exit_pupil_z_mm,
            exit_pupil_diameter_mm: p.exit_pupil_diameter_mm,
            f_number: p.f_number,
            diagonal_fov_deg,
            horizontal_fov_deg: fov(0.5 * w),
            infinity_focus_mm: infinity_focus,
            close_focus_mm: close_focus,
            close_focus_object_distance_mm: close_distance,
            focal_length_mm: focal_length,
            ray_height_mm: h,
            front_vertex_mm: system.front_z_mm(),
            rear_vertex_mm: system.rear_z_mm(),
            anamorphic,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builtins_parse_with_one_stop() {
        for (name, table) in BUILTIN_LENSES {
            let lens = LensPrescription::load(name).unwrap();
            // Every row read (the cemented achromat has four, the others seven or more).
            let rows = table
                .lines()
                .filter(|l| !l.trim().is_empty() && !l.trim().starts_with('#'))
                .count();
            assert!(lens.surfaces.len() == rows && rows >= 4, "{name}");
            assert!(lens.surfaces[lens.stop_index()].is_stop());
        }
    }

    #[test]
    fn a_lens_file_that_is_not_text_is_named_in_the_error() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("binary.dat");
        std::fs::write(&path, b"50.0 5.0 1.5 20.0\n\xff\xfe 1 1 8\n").unwrap();
        let err = LensPrescription::load(path.to_str().unwrap()).unwrap_err().to_string();
        assert!(
            err.contains("binary.dat") && err.contains("not UTF-8 text (byte 18"),
            "{err}"
        );
    }

    #[test]
    fn unknown_lens_name_lists_the_builtins() {
        let err = LensPrescription::load("no-such-lens").unwrap_err().to_string();
        assert!(err.contains("dgauss50") && err.contains("fisheye10"), "{err}");
    }
}
