//! Reading a frame out of a sensor render's film: the noise model of
//! [`super`]'s heading, pixel by pixel, and the raw frame it gives.

use glam::{DMat3, DVec3};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Poisson, StandardNormal};
use rand_xoshiro::SplitMix64;
use rayon::prelude::*;

use super::{Cfa, SensorSettings};
use crate::camera::Camera;
use crate::film::FilmRadiometry;
use crate::film::Image;
use crate::names::Named;
use crate::sampling::mix64;
use crate::{Error, Result};

/// A raw frame: the mosaic of digital numbers and what a raw developer
/// needs to read it.
#[derive(Clone, Debug, PartialEq)]
pub struct RawFrame {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// Digital numbers, row-major from the top left.
    pub dn: Vec<u16>,
    /// The colour filter array, its phase at this frame's top-left pixel.
    pub cfa: Cfa,
    /// Digital number of no light.
    pub black_level_dn: u32,
    /// Largest digital number.
    pub white_level_dn: u32,
    /// Electrons per digital number.
    pub electrons_per_dn: f64,
    /// CIE XYZ to the sensor's channels (DNG `ColorMatrix1`, under D65).
    pub xyz_to_camera: DMat3,
    /// The channels' reading of the white the camera was balanced for,
    /// largest 1 (DNG `AsShotNeutral`; [`super::WhiteBalance`]).
    pub as_shot_neutral: DVec3,
    /// How it was taken: exposure time and ISO (metered, with auto
    /// exposure) and the spectral response's name (DNG `UniqueCameraModel`).
    pub exposure: Exposure,
}

/// How a frame was taken: what an image of it records (EXR `expTime`,
/// `isoSpeed` and `lenspath/sensor`).
#[derive(Clone, Debug, PartialEq)]
pub struct Exposure {
    /// The exposure time, s.
    pub exposure_time_s: f64,
    /// The ISO speed.
    pub iso: f64,
    /// The spectral response's name.
    pub sensor_name: String,
}

/// The frame `settings` read out from `film`, a sensor render's film
/// through `camera` (its pixel (0, 0) at `origin` on the full sensor): the
/// camera says what a reading is ([`Camera::film_radiometry`]); only a
/// camera with optics can.
pub fn capture_through(
    camera: &dyn Camera,
    film: &Image,
    origin: (u32, u32),
    settings: &SensorSettings,
) -> Result<RawFrame> {
    let optics = camera.film_radiometry().ok_or_else(super::needs_a_lens)?;
    capture(film, origin, &optics, settings)
}

/// A frame read out from `image`, a sensor render's film (its pixel (0, 0)
/// at `origin` on the full sensor: a crop keeps the full frame's mosaic and
/// noise), behind `optics`, by the sensor `settings`.
pub fn capture(
    image: &Image,
    origin: (u32, u32),
    optics: &FilmRadiometry,
    settings: &SensorSettings,
) -> Result<RawFrame> {
    settings.validate()?;
    let settings = &settings.metered(image, optics);
    if !(optics.irradiance_per_reading_sr > 0.0 && optics.pixel_area_um2() > 0.0) {
        return Err(Error::InvalidArgument(format!(
            "the sensor needs light and pixels: irradiance per reading {} sr, pixel {} µm²",
            optics.irradiance_per_reading_sr,
            optics.pixel_area_um2()
        )));
    }
    let per_reading = settings.electrons_per_reading(optics);
    let full_well = settings.full_well_e(optics);
    let dark = settings.dark_current_e_per_s_um2 * optics.pixel_area_um2() * settings.exposure_time_s;
    let electrons_per_dn = settings.electrons_per_dn(optics);
    let dn_per_electron = 1.0 / electrons_per_dn;
    let (black, white) = (f64::from(settings.black_level_dn), f64::from(settings.white_level_dn()));
    let (origin_x, origin_y) = origin;
    let mut dn = vec![0u16; image.width as usize * image.height as usize];
    dn.par_chunks_mut(image.width as usize)
        .enumerate()
        .for_each(|(row, out)| {
            let y = origin_y + row as u32;
            for (col, out) in out.iter_mut().enumerate() {
                let x = origin_x + col as u32;
                // A pixel's place on the full sensor (images are under 2^20
                // wide). Its generators are SplitMix64s, which cost nothing
                // to seed (one per pixel and pattern: a crop's pixels are
                // the full frame's).
                let site = (u64::from(y) << 20) + u64::from(x);
                // Drawn only when the sensor has them (an unused draw costs a
                // tenth of the pixel); PRNU first, so it is the same either way.
                let (prnu, dsnu) = if settings.prnu > 0.0 || settings.dsnu_e > 0.0 {
                    let mut fixed = SplitMix64::seed_from_u64(mix(settings.fixed_pattern_seed, site));
                    let prnu: f64 = fixed.sample(StandardNormal);
                    (
                        prnu,
                        if settings.dsnu_e > 0.0 {
                            fixed.sample(StandardNormal)
                        } else {
                            0.0
                        },
                    )
                } else {
                    (0.0, 0.0)
                };
                let mut temporal = SplitMix64::seed_from_u64(mix(settings.frame_seed ^ 0x9e37_79b9_7f4a_7c15, site));
                let reading = f64::from(image.pixel(col as u32, row as u32)[settings.cfa.channel(x, y)]);
                let mean = (reading * per_reading * (1.0 + settings.prnu * prnu)).max(0.0) + dark;
                let collected = poisson(mean, &mut temporal).min(full_well);
                let read: f64 = temporal.sample(StandardNormal);
                let electrons = collected + settings.dsnu_e * dsnu + settings.read_noise_e * read;
                // Rounded half up (clamped first: the cast truncates, and
                // f64::round is a library call on baseline x86-64).
                *out = ((electrons * dn_per_electron + black).clamp(0.0, white) + 0.5) as u16;
            }
        });
    Ok(RawFrame {
        width: image.width,
        height: image.height,
        dn,
        cfa: phase(settings.cfa, origin),
        black_level_dn: settings.black_level_dn,
        white_level_dn: settings.white_level_dn(),
        electrons_per_dn,
        xyz_to_camera: settings.response.xyz_to_camera(),
        as_shot_neutral: settings.white_balance.neutral(settings.response, image),
        exposure: Exposure {
            exposure_time_s: settings.exposure_time_s,
            iso: settings.iso,
            sensor_name: settings.response.name().to_string(),
        },
    })
}

/// Above this mean the shot noise is drawn from the normal approximation.
const NORMAL_SHOT_NOISE_E: f64 = 1000.0;

/// A Poisson count of mean `mean` (0 for none): exact below
/// [`NORMAL_SHOT_NOISE_E`], above it the normal approximation N(μ, μ)
/// rounded, as ISETCam's `noiseShot` does above 25 e⁻ (at 1000 e⁻ the
/// Poisson's skewness is 0.03; mean and variance are exact): one normal
/// draw instead of Ahrens and Dieter's rejection sampler.
fn poisson(mean: f64, rng: &mut SplitMix64) -> f64 {
    if mean > NORMAL_SHOT_NOISE_E {
        let z: f64 = rng.sample(StandardNormal);
        // Rounded by a cast (the value is made positive first).
        return ((mean + mean.sqrt() * z + 0.5).max(0.0) as u64) as f64;
    }
    match Poisson::new(mean) {
        Ok(p) => p.sample(rng),
        Err(_) => 0.0,
    }
}

/// The pattern as it starts at `origin` of the full sensor's pattern `cfa`.
fn phase(cfa: Cfa, origin: (u32, u32)) -> Cfa {
    let at = |dx, dy| cfa.channel(origin.0 + dx, origin.1 + dy);
    let block = [at(0, 0), at(1, 0), at(0, 1), at(1, 1)];
    // Every pattern's block is its own (mono's is all green).
    Cfa::NAMED
        .iter()
        .map(|(c, _)| *c)
        .find(|c| c.block() == block)
        .unwrap_or(cfa)
}

/// A 64-bit seed from a seed and a pixel's place: SplitMix64's finaliser
/// of the seed's golden-ratio multiple plus the place.
fn mix(seed: u64, site: u64) -> u64 {
    mix64(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15).wrapping_add(site))
}
