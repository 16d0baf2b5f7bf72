//! What defines a realistic camera: the lens, the sensor, the focus, the
//! f-number, the scene unit, the radiometry and the aperture's shape.

use crate::camera::ApertureShape;
use crate::lens::LensPrescription;
use crate::names::Named;

/// The realistic camera's lens when the scene file names none: a 50 mm f/2 Double-Gauss.
pub const DEFAULT_LENS: &str = "dgauss50";
/// The sensor's width when the scene file gives none (a full-frame 35 mm
/// sensor's), mm; its height follows the image's aspect.
pub const DEFAULT_SENSOR_WIDTH_MM: f64 = crate::lens::FULL_FRAME_MM.0;
/// Metres per scene unit when the scene file does not say.
pub const DEFAULT_SCENE_UNIT_M: f64 = 1.0;
/// Whether a lens's glasses disperse (each ray traced at its own
/// wavelength) unless the caller or the scene file says not.
pub const DEFAULT_DISPERSION: bool = true;
/// Whether the realistic camera renders diffraction at its pupil
/// (`camera/diffraction.rs`) unless the caller or the scene file says.
/// Off until the render is held to the wave-optics analysis off the axis
/// too (the edge MTF at a field point, the starburst's spikes).
pub const DEFAULT_DIFFRACTION: bool = false;
/// Whether an anamorphic lens's image is desqueezed (its width stretched by
/// the lens's squeeze) rather than shown as the sensor records it.
pub const DEFAULT_DESQUEEZE: bool = false;

/// Where the sensor goes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LensFocus {
    /// Focus at this distance from the sensor plane, in scene units, by the
    /// exact real-ray conjugate.
    Distance(f64),
    /// Put the sensor this many mm behind the aperture stop.
    SensorDepthMm(f64),
}

/// What a reading of 1 means.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Radiometry {
    /// The image centre reads the radiance of a uniform scene at any f-number (the default).
    #[default]
    Normalized,
    /// Normalised wide open: stopping down from N₁ to N₂ darkens by (N₂/N₁)², as on a real camera.
    Physical,
}

impl Named for Radiometry {
    const WHAT: &'static str = "radiometry";
    const NAMED: &'static [(Radiometry, &'static str)] = &[
        (Radiometry::Normalized, "normalized"),
        (Radiometry::Physical, "physical"),
    ];
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
    /// Whether the pupil diffracts: each film point is displaced by a draw
    /// from the aperture's Fraunhofer pattern at the ray's wavelength and
    /// the lens's working f-number, so the image is the geometric one
    /// convolved with the diffraction pattern (`camera/diffraction.rs`).
    pub diffraction: bool,
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
            scene_unit_m: DEFAULT_SCENE_UNIT_M,
            radiometry: Radiometry::default(),
            aperture: ApertureShape::Circle,
            dispersion: DEFAULT_DISPERSION,
            diffraction: DEFAULT_DIFFRACTION,
        }
    }
}

/// A sensor `width_mm` wide with the aspect of a `width` × `height` image.
pub fn sensor_for_image(width_mm: f64, width: u32, height: u32) -> (f64, f64) {
    (width_mm, width_mm * f64::from(height) / f64::from(width))
}
