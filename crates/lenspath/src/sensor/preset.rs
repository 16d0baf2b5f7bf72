//! The default sensor's figures: ISETCam's model of the Sony IMX363
//! (`sensorCreate('IMX363')`, a 1.4 µm-pixel phone sensor; ISETCam, MIT
//! licence), its per-pixel figures turned into per-µm² ones where a render's
//! pixel is another size, with the measured Sony α7 III response (the
//! IMX363's own curves are not at hand). [`super::SensorSettings::new`]
//! reads them; the choices that are enum values (the CFA, white balance,
//! demosaicking, tone curve) are their types' `#[default]` variants.

/// The spectral response: the measured Sony α7 III (ILCE-7M3) channels.
pub const RESPONSE: &str = "sony_ilce_7m3";

/// Peak quantum efficiency of the most sensitive channel. An assumption
/// (typical of a back-side illuminated CMOS sensor behind Bayer filters):
/// the measured curves are relative and ISETCam's IMX363 curves are not at
/// hand.
pub const PEAK_QE: f64 = 0.5;

/// Exposure time, s (IMX363: 1/60).
pub const EXPOSURE_TIME_S: f64 = 1.0 / 60.0;

/// ISO speed: the IMX363's base, analogue gain 1 (ISETCam's model
/// defaults to 270, which overexposes a 100 cd/m² white by two stops at
/// f/2 and 1/60 s).
pub const ISO: f64 = 55.0;

/// ISO speed at analogue gain 1, where the full well reaches the white
/// level (IMX363: 55; 6000 e⁻ over 1023 DN).
pub const UNITY_GAIN_ISO: f64 = 55.0;

/// Full-well capacity per µm² (IMX363: 6000 e⁻ in a 1.4 µm pixel).
pub const FULL_WELL_E_PER_UM2: f64 = 6000.0 / (1.4 * 1.4);

/// Read noise, e⁻ RMS (IMX363: 5).
pub const READ_NOISE_E: f64 = 5.0;

/// Dark current per µm², e⁻/s (IMX363: 0).
pub const DARK_CURRENT_E_PER_S_UM2: f64 = 0.0;

/// Dark signal non-uniformity, e⁻ RMS (IMX363: 0).
pub const DSNU_E: f64 = 0.0;

/// Photo-response non-uniformity, RMS gain (IMX363: 0.7%).
pub const PRNU: f64 = 0.007;

/// Bits per digital number (IMX363: 10).
pub const BIT_DEPTH: u32 = 10;

/// Black level, DN (IMX363: 64).
pub const BLACK_LEVEL_DN: u32 = 64;

/// Luminance of a white emitter of value 1, cd/m² (ISETCam's scenes
/// default to a mean luminance of 100 cd/m²).
pub const WHITE_LUMINANCE_CD_M2: f64 = 100.0;

/// Whether the exposure time and ISO are metered from the film (a
/// camera's program mode; off: the given ones).
pub const AUTO_EXPOSURE: bool = false;

/// Auto exposure's longest exposure time, s: 1/30, a phone camera's
/// preview and autofocus frame rate.
pub const MAX_EXPOSURE_TIME_S: f64 = 1.0 / 30.0;

/// Auto exposure's highest ISO: 64× the base gain (an assumption of a
/// phone sensor's range; ISETCam's IMX363 model gives none).
pub const MAX_ISO: f64 = 3520.0;
