//! Every default of a render, written once. A value the caller leaves out
//! and the scene file does not give comes from here ([`crate::setup`]
//! applies the precedence caller > scene file > default); the CLI's help,
//! the Python signatures and the viewer show these, never their own copies.

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

// The sensor (`lenspath::sensor`): ISETCam's model of the Sony IMX363
// (`sensorCreate('IMX363')`, a 1.4 µm-pixel phone sensor; ISETCam, MIT
// licence), its per-pixel figures turned into per-µm² ones where a
// render's pixel is another size.

/// The spectral response: the measured Sony α7 III (ILCE-7M3) channels.
pub const SENSOR_RESPONSE: &str = "sony_ilce_7m3";
/// Peak quantum efficiency of the most sensitive channel. An assumption
/// (typical of a back-side illuminated CMOS sensor behind Bayer filters):
/// the measured curves are relative and ISETCam's IMX363 curves are not at
/// hand.
pub const SENSOR_PEAK_QE: f64 = 0.5;
/// The colour filter array.
pub const SENSOR_CFA: crate::sensor::Cfa = crate::sensor::Cfa::Rggb;
/// Exposure time, s (IMX363: 1/60).
pub const SENSOR_EXPOSURE_TIME_S: f64 = 1.0 / 60.0;
/// ISO speed: the IMX363's base, analogue gain 1 (ISETCam's model
/// defaults to 270, which overexposes a 100 cd/m² white by two stops at
/// f/2 and 1/60 s).
pub const SENSOR_ISO: f64 = 55.0;
/// ISO speed at analogue gain 1, where the full well reaches the white
/// level (IMX363: 55; 6000 e⁻ over 1023 DN).
pub const SENSOR_UNITY_GAIN_ISO: f64 = 55.0;
/// Full-well capacity per µm² (IMX363: 6000 e⁻ in a 1.4 µm pixel).
pub const SENSOR_FULL_WELL_E_PER_UM2: f64 = 6000.0 / (1.4 * 1.4);
/// Read noise, e⁻ RMS (IMX363: 5).
pub const SENSOR_READ_NOISE_E: f64 = 5.0;
/// Dark current per µm², e⁻/s (IMX363: 0).
pub const SENSOR_DARK_CURRENT_E_PER_S_UM2: f64 = 0.0;
/// Dark signal non-uniformity, e⁻ RMS (IMX363: 0).
pub const SENSOR_DSNU_E: f64 = 0.0;
/// Photo-response non-uniformity, RMS gain (IMX363: 0.7%).
pub const SENSOR_PRNU: f64 = 0.007;
/// Bits per digital number (IMX363: 10).
pub const SENSOR_BIT_DEPTH: u32 = 10;
/// Black level, DN (IMX363: 64).
pub const SENSOR_BLACK_LEVEL_DN: u32 = 64;
/// Luminance of a white emitter of value 1, cd/m² (ISETCam's scenes
/// default to a mean luminance of 100 cd/m²).
pub const SENSOR_WHITE_LUMINANCE_CD_M2: f64 = 100.0;
/// The light the camera is balanced for: daylight, the scenes' own white
/// (an RGB emitter's white is D65).
pub const SENSOR_WHITE_BALANCE: crate::sensor::WhiteBalance = crate::sensor::WhiteBalance::Daylight;
/// Whether the exposure time and ISO are metered from the film (a
/// camera's program mode; off: the given ones).
pub const SENSOR_AUTO_EXPOSURE: bool = false;
/// Auto exposure's longest exposure time, s: 1/30, a phone camera's
/// preview and autofocus frame rate.
pub const SENSOR_MAX_EXPOSURE_TIME_S: f64 = 1.0 / 30.0;
/// Auto exposure's highest ISO: 64× the base gain (an assumption of a
/// phone sensor's range; ISETCam's IMX363 model gives none).
pub const SENSOR_MAX_ISO: f64 = 3520.0;
/// The development's demosaicking: Malvar–He–Cutler, the best linear one.
pub const SENSOR_DEMOSAIC: crate::sensor::Demosaic = crate::sensor::Demosaic::MalvarHeCutler;
/// The development's tone curve: none, so developed values stay
/// proportional to the light (as a render's image is).
pub const SENSOR_TONE_CURVE: crate::sensor::ToneCurve = crate::sensor::ToneCurve::Linear;
