//! Every default of a render, written once. A value the caller leaves out
//! and the scene file does not give comes from here ([`crate::setup`]
//! applies the precedence caller > scene file > default); the CLI's help,
//! the Python signatures and the viewer show these, never their own copies.

use crate::sampling::SamplerKind;

// Rendering.

/// Image size in pixels, (width, height).
pub const IMAGE_SIZE: (u32, u32) = (640, 480);
/// Samples per pixel.
pub const SPP: u32 = 64;
/// Maximum path depth (scattering events; 1 is direct lighting only).
pub const MAX_DEPTH: u32 = 16;
/// Shadow rays per light at each non-specular hit.
pub const LIGHT_SAMPLES: u32 = 1;
/// Seed of the sample sequences.
pub const SEED: u32 = 0;
/// The sample sequence.
pub const SAMPLER: SamplerKind = SamplerKind::Sobol;
/// Edge of the square tiles a render is cut into, pixels.
pub const TILE_SIZE: u32 = 16;

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
