//! What defines a realistic camera: the lens, the sensor, the focus, the
//! f-number, the scene unit, the radiometry and the aperture's shape.

use crate::camera::ApertureShape;
use crate::defaults;
use crate::lens::LensPrescription;

/// Where the sensor goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LensFocus {
    /// Focus at this distance from the sensor plane, in scene units, by the
    /// exact real-ray conjugate.
    Distance(f64),
    /// Put the sensor this many mm behind the aperture stop.
    SensorPositionMm(f64),
}

/// What a reading of 1 means.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Radiometry {
    /// The image centre reads the radiance of a uniform scene at any f-number.
    Normalized,
    /// Normalised wide open: stopping down from N₁ to N₂ darkens by (N₂/N₁)², as on a real camera.
    Physical,
}

/// Everything that defines a realistic camera.
#[derive(Clone, Debug, PartialEq)]
pub struct RealisticCameraSettings {
    /// The lens.
    pub lens: LensPrescription,
    /// Sensor width and height in mm.
    pub sensor_mm: (f64, f64),
    /// Focus.
    pub focus: LensFocus,
    /// Paraxial f-number to stop down to (`None`: wide open).
    pub f_number: Option<f64>,
    /// Metres per scene unit.
    pub scene_unit_m: f64,
    /// Exposure normalisation.
    pub radiometry: Radiometry,
    /// Shape of the opening at the aperture stop.
    pub aperture: ApertureShape,
    /// Whether glasses that disperse do (default): each ray is traced at its
    /// sample's hero wavelength and the others are weighted by where the
    /// lens takes them (`camera/realistic/lanes.rs`). Off, every glass has
    /// its d-line index: the lens shows no colour, and every wavelength of
    /// a camera ray weighs the same (a little less colour noise, no tracing
    /// back).
    pub dispersion: bool,
}

impl RealisticCameraSettings {
    /// `lens` with a `sensor_mm` sensor, focused by `focus`: wide open, one
    /// metre per scene unit, normalised exposure.
    pub fn new(lens: LensPrescription, sensor_mm: (f64, f64), focus: LensFocus) -> Self {
        RealisticCameraSettings {
            lens,
            sensor_mm,
            focus,
            f_number: None,
            scene_unit_m: defaults::SCENE_UNIT_M,
            radiometry: Radiometry::Normalized,
            aperture: ApertureShape::Circle,
            dispersion: defaults::LENS_DISPERSION,
        }
    }
}

/// A sensor `width_mm` wide with the aspect of a `width` × `height` image.
pub fn sensor_for_image(width_mm: f64, width: u32, height: u32) -> (f64, f64) {
    (width_mm, width_mm * f64::from(height) / f64::from(width))
}
