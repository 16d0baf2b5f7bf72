//! What a scene file says about rendering it: every field optional, as each
//! loader found it. Neutral ground between the loaders (`io`), which fill it,
//! and [`crate::setup`], which resolves it against what a caller asks and the
//! library's defaults.

use crate::camera::ApertureShape;
use crate::integrator::IntegratorKind;
use crate::sampling::SamplerKind;
use crate::sensor::SensorDescription;

/// Render settings a scene file may give; every field is optional.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SceneOptions {
    /// Image width and height in pixels.
    pub resolution: Option<(u32, u32)>,
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// The integrator (`[integrator] type`).
    pub integrator: Option<IntegratorKind>,
    /// Maximum path depth.
    pub max_depth: Option<u32>,
    /// Shadow rays per area or environment light per hit.
    pub light_samples: Option<u32>,
    /// Seed of the sample sequences.
    pub seed: Option<u32>,
    /// The sample sequence.
    pub sampler: Option<SamplerKind>,
    /// Metres per scene unit (COLLADA `<unit meter>`, glTF: 1).
    pub scene_unit_m: Option<f64>,
    /// Lens settings for the realistic camera.
    pub lens: Option<LensOptions>,
    /// The image sensor the scene is recorded through (`[sensor]`).
    pub sensor: Option<SensorDescription>,
}

/// A file's lens settings for the realistic camera.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LensOptions {
    /// Built-in lens name or lens table path (relative paths are resolved against the scene file).
    pub lens: Option<String>,
    /// f-number to stop down to.
    pub f_number: Option<f64>,
    /// Sensor width and height in mm.
    pub sensor_mm: Option<(f64, f64)>,
    /// Focus distance from the sensor, scene units.
    pub focus_distance: Option<f64>,
    /// Focus by the sensor's place instead: mm behind the aperture stop.
    pub sensor_depth_mm: Option<f64>,
    /// Shape of the aperture (`None`: the circle).
    pub aperture: Option<ApertureShape>,
    /// Whether the lens's glasses disperse (`None`: they do).
    pub dispersion: Option<bool>,
    /// Whether the pupil diffracts (`None`: the library's default).
    pub diffraction: Option<bool>,
    /// Whether an anamorphic lens's image is desqueezed (`None`: it is not).
    pub desqueeze: Option<bool>,
}
