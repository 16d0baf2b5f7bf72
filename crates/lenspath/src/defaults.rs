//! Every default of a render, in one table. A value the caller leaves out
//! and the scene file does not give comes from here ([`crate::setup`]
//! applies the precedence caller > scene file > default); the CLI's help,
//! the Python signatures and the viewer show these, never their own copies.
//! Each default lives beside its type and is re-exported here, so that no
//! module below reads this one; a choice among named kinds (the integrator,
//! the sampler, the focus measure, the autofocus strategy and sensor
//! signal, the sensor's enums) is its type's `#[default]` variant.

// Rendering.
pub use crate::integrator::{
    DEFAULT_GUIDE_TRAINING_SPP as GUIDE_TRAINING_SPP, DEFAULT_LIGHT_SAMPLES as LIGHT_SAMPLES,
    DEFAULT_MAX_DEPTH as MAX_DEPTH,
};
pub use crate::parallel::MAX_THREADS;
pub use crate::render::{
    DEFAULT_IMAGE_SIZE as IMAGE_SIZE, DEFAULT_SEED as SEED, DEFAULT_SPP as SPP, DEFAULT_TILE_SIZE as TILE_SIZE,
};

// Cameras.
pub use crate::camera::{
    DEFAULT_DESQUEEZE as LENS_DESQUEEZE, DEFAULT_DIFFRACTION as LENS_DIFFRACTION,
    DEFAULT_DISPERSION as LENS_DISPERSION, DEFAULT_LENS as LENS, DEFAULT_SCENE_UNIT_M as SCENE_UNIT_M,
    DEFAULT_SENSOR_WIDTH_MM as SENSOR_WIDTH_MM, DEFAULT_THIN_LENS_APERTURE_RADIUS as THIN_LENS_APERTURE_RADIUS,
};

// Autofocus: the patch renders of a search (the scene file's integrator
// settings are for the final image, not these).
pub use crate::autofocus::search::{
    DEFAULT_PATCH_MAX_DEPTH as AUTOFOCUS_PATCH_MAX_DEPTH, DEFAULT_PATCH_SPP as AUTOFOCUS_PATCH_SPP,
    DEFAULT_PATIENCE as AUTOFOCUS_PATIENCE, DEFAULT_SEED as AUTOFOCUS_SEED,
};

// The sensor's defaults live beside it (`sensor::preset`, and its enums' `#[default]` variants).
pub use crate::sensor::preset::{
    AUTO_EXPOSURE as SENSOR_AUTO_EXPOSURE, BIT_DEPTH as SENSOR_BIT_DEPTH, BLACK_LEVEL_DN as SENSOR_BLACK_LEVEL_DN,
    DARK_CURRENT_E_PER_S_UM2 as SENSOR_DARK_CURRENT_E_PER_S_UM2, DSNU_E as SENSOR_DSNU_E,
    EXPOSURE_TIME_S as SENSOR_EXPOSURE_TIME_S, FULL_WELL_E_PER_UM2 as SENSOR_FULL_WELL_E_PER_UM2, ISO as SENSOR_ISO,
    MAX_EXPOSURE_TIME_S as SENSOR_MAX_EXPOSURE_TIME_S, MAX_ISO as SENSOR_MAX_ISO, PEAK_QE as SENSOR_PEAK_QE,
    PRNU as SENSOR_PRNU, READ_NOISE_E as SENSOR_READ_NOISE_E, RESPONSE as SENSOR_RESPONSE,
    UNITY_GAIN_ISO as SENSOR_UNITY_GAIN_ISO, WHITE_LUMINANCE_CD_M2 as SENSOR_WHITE_LUMINANCE_CD_M2,
};
