//! Real compound lenses: prescriptions, exact tracing, first-order and
//! real-ray analysis, focusing, and the layout plot.

pub mod chromatic;
pub mod iset;
pub mod lentil;
pub mod library;
pub mod plot;
pub mod prescription;
pub mod surface;
pub mod system;
pub mod through_focus;
pub mod zemax;

pub use prescription::{LensPrescription, LensSurface, TableConvention, BUILTIN_LENSES};
pub use surface::{EvenAsphere, SurfaceShape};
pub use system::{Direction, LensRay, LensSystem, ParaxialData};
pub use through_focus::SpotBundle;

use crate::error::Result;

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
            sensor_mm: (36.0, 24.0),
        }
    }
}

/// Everything `lenspath lens` reports. Positions are along the axis in mm
/// from the aperture stop, positive toward the sensor.
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
}

impl LensAnalysis {
    /// Analyses `system` (paraxial traces and real rays at `settings.ray_height_mm`).
    pub fn new(system: &LensSystem, settings: &AnalysisSettings) -> Result<LensAnalysis> {
        let p = system.paraxial()?;
        let h = settings.ray_height_mm;
        let (infinity_focus, real_principal) = system.real_focus_at_infinity(h)?;
        let focal_length = (infinity_focus - real_principal).abs();
        let close_distance = settings.close_object_distance_mm.unwrap_or(5.0 * focal_length);
        let close_focus = system.real_image_z(-close_distance, h)?;
        let (w, ht) = settings.sensor_mm;
        let fov = |half: f64| 2.0 * (half / p.effective_focal_length_mm.abs()).atan().to_degrees();
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
            diagonal_fov_deg: fov(0.5 * w.hypot(ht)),
            horizontal_fov_deg: fov(0.5 * w),
            infinity_focus_mm: infinity_focus,
            close_focus_mm: close_focus,
            close_focus_object_distance_mm: close_distance,
            focal_length_mm: focal_length,
            ray_height_mm: h,
            front_vertex_mm: system.front_z(),
            rear_vertex_mm: system.rear_z(),
        })
    }
}
