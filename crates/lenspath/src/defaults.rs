//! Every default of a render, in one table. A value the caller leaves out
//! and the scene file does not give comes from here ([`crate::setup`]
//! applies the precedence caller > scene file > default); the CLI's help,
//! the Python signatures and the viewer show these, never their own copies.
//! Defaults that belong to a lower layer's type live beside it and are
//! re-exported here (the sensor's in [`crate::sensor::preset`], the thread
//! limit in [`crate::parallel`]), so that no module below reads this one.

use crate::integrator::IntegratorKind;
use crate::sampling::SamplerKind;

// Rendering.

/// Image size in pixels, (width, height).
pub const IMAGE_SIZE: (u32, u32) = (640, 480);
/// Samples per pixel.
pub const SPP: u32 = 64;
/// The integrator: the path tracer, unguided.
pub const INTEGRATOR: IntegratorKind = IntegratorKind::Path;
/// The guided integrator's training: samples per pixel of the whole image
/// spent on iterations of 1, 2, 4 and 8 before the render.
pub const GUIDE_TRAINING_SPP: u32 = 15;
/// Maximum path depth (scattering events; 1 is direct lighting only).
pub const MAX_DEPTH: u32 = 16;
/// Shadow rays per area or environment light at each non-specular hit (a
/// point, spot or directional light takes one: its samples would all be one ray).
pub const LIGHT_SAMPLES: u32 = 1;
/// Seed of the sample sequences.
pub const SEED: u32 = 0;
/// The sample sequence.
pub const SAMPLER: SamplerKind = SamplerKind::Sobol;
/// Edge of the square tiles a render is cut into, pixels.
pub const TILE_SIZE: u32 = 16;
pub use crate::parallel::MAX_THREADS;

// Cameras.

/// Metres per scene unit.
pub const SCENE_UNIT_M: f64 = 1.0;
/// The realistic camera's lens: a 50 mm f/2 Double-Gauss.
pub const LENS: &str = "dgauss50";

/// Whether a lens's glasses disperse (the realistic camera traces each ray
/// at its own wavelength) unless the caller or the scene file says not.
pub const LENS_DISPERSION: bool = true;

/// Whether an anamorphic lens's image is desqueezed (its width stretched by
/// the lens's squeeze) rather than shown as the sensor records it.
pub const LENS_DESQUEEZE: bool = false;
/// The realistic camera's sensor width (a full-frame 35 mm sensor), mm; its
/// height follows the image's aspect.
pub const SENSOR_WIDTH_MM: f64 = 36.0;
/// The thin-lens camera's aperture radius, scene units.
pub const THIN_LENS_APERTURE_RADIUS: f32 = 0.05;

// Autofocus: the patch renders of a search (the scene file's integrator
// settings are for the final image, not these).

/// Samples per pixel of each patch render.
pub const AUTOFOCUS_PATCH_SPP: u32 = 16;
/// Maximum path depth of the patch renders (a full render's depth is
/// capped at this for `render --autofocus`).
pub const AUTOFOCUS_PATCH_MAX_DEPTH: u32 = 8;
/// Seed of the patch renders.
pub const AUTOFOCUS_SEED: u32 = 0;
/// The early-exit strategy's patience: steps without a new best before it stops.
pub const AUTOFOCUS_PATIENCE: usize = 12;
/// The focus measure.
pub const AUTOFOCUS_METRIC: &str = "tenengrad";
/// The search strategy.
pub const AUTOFOCUS_STRATEGY: &str = "fast";
/// What contrast autofocus reads of a sensor's frames: the raw green
/// pixels, as a camera's AF does before any development.
pub const AUTOFOCUS_SENSOR_SIGNAL: &str = "raw-green";

// The sensor's defaults live beside it (`sensor::preset`, and its enums' `#[default]` variants).
pub use crate::sensor::preset::{
    AUTO_EXPOSURE as SENSOR_AUTO_EXPOSURE, BIT_DEPTH as SENSOR_BIT_DEPTH, BLACK_LEVEL_DN as SENSOR_BLACK_LEVEL_DN,
    DARK_CURRENT_E_PER_S_UM2 as SENSOR_DARK_CURRENT_E_PER_S_UM2, DSNU_E as SENSOR_DSNU_E,
    EXPOSURE_TIME_S as SENSOR_EXPOSURE_TIME_S, FULL_WELL_E_PER_UM2 as SENSOR_FULL_WELL_E_PER_UM2, ISO as SENSOR_ISO,
    MAX_EXPOSURE_TIME_S as SENSOR_MAX_EXPOSURE_TIME_S, MAX_ISO as SENSOR_MAX_ISO, PEAK_QE as SENSOR_PEAK_QE,
    PRNU as SENSOR_PRNU, READ_NOISE_E as SENSOR_READ_NOISE_E, RESPONSE as SENSOR_RESPONSE,
    UNITY_GAIN_ISO as SENSOR_UNITY_GAIN_ISO, WHITE_LUMINANCE_CD_M2 as SENSOR_WHITE_LUMINANCE_CD_M2,
};
