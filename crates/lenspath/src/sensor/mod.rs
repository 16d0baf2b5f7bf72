//! The image sensor: photons to photoelectrons to digital numbers.
//!
//! A sensor render's film holds, per pixel and channel, the photoelectron
//! rate of a unit étendue ([`SpectralResponse::electron_rate`]). [`capture`]
//! turns it into a raw frame the way a CMOS sensor does (the model of the
//! EMVA 1288 standard, release 4.0, §2, and Janesick, *Photon Transfer*,
//! SPIE 2007):
//!
//! 1. mean signal μ = rate · (the lens's irradiance per unit radiance) ·
//!    pixel area · exposure time · (radiance of a scene unit), times the
//!    pixel's photo-response non-uniformity (a fixed pattern), plus the dark
//!    current's charge;
//! 2. the charge counted is Poisson(μ) (shot noise), at most the full well;
//! 3. read noise (Gaussian, e⁻ RMS) and the dark signal non-uniformity (a
//!    fixed offset per pixel, e⁻) are added;
//! 4. the analogue gain of the ISO setting converts to digital numbers, the
//!    black level is added, and the result is rounded and clipped to the
//!    bit depth.
//!
//! Each pixel keeps the channel its colour filter passes ([`Cfa`]). The
//! temporal noise of a pixel comes from a generator seeded by the frame
//! seed and the pixel's place on the full sensor, its fixed pattern from the
//! fixed-pattern seed and the same place, so a frame is bit-identical for
//! any thread count and crop, and a new frame seed gives new temporal noise
//! over the same fixed pattern.
//!
//! Every default is a real sensor's: ISETCam's model of the Sony IMX363
//! (`sensorCreate('IMX363')`, MIT licence), see [`crate::defaults`].

pub mod develop;
pub mod raw_file;
pub mod response;

use glam::{DMat3, DVec3};
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Poisson, StandardNormal};
use rand_pcg::Pcg64Mcg;
use rayon::prelude::*;

pub use response::SpectralResponse;

use crate::camera::FilmRadiometry;
use crate::defaults;
use crate::film::Image;
use crate::sampling::mix64;
use crate::spectrum::cie;
use crate::{Error, Result};

/// Luminous efficacy of 555 nm light, lm/W (the SI candela's definition).
pub const LUMINOUS_EFFICACY_LM_W: f64 = 683.0;

/// The colour filter array: which channel each pixel of a 2 × 2 block
/// reads, named by its first row then its second.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Cfa {
    /// Bayer: red, green / green, blue.
    Rggb,
    /// Bayer: blue, green / green, red.
    Bggr,
    /// Bayer: green, red / blue, green.
    Grbg,
    /// Bayer: green, blue / red, green.
    Gbrg,
    /// No colour filters: every pixel reads the response's green channel
    /// (for the ideal sensor, ȳ: a photometric sensor).
    Mono,
}

impl Cfa {
    /// Every pattern with its name.
    pub const ALL: [(Cfa, &'static str); 5] = [
        (Cfa::Rggb, "rggb"),
        (Cfa::Bggr, "bggr"),
        (Cfa::Grbg, "grbg"),
        (Cfa::Gbrg, "gbrg"),
        (Cfa::Mono, "mono"),
    ];

    /// The pattern called `name` (case-insensitive).
    pub fn parse(name: &str) -> Result<Cfa> {
        Cfa::ALL
            .iter()
            .find(|(_, n)| n.eq_ignore_ascii_case(name))
            .map(|(cfa, _)| *cfa)
            .ok_or_else(|| {
                let known: Vec<&str> = Cfa::ALL.iter().map(|(_, n)| *n).collect();
                Error::InvalidArgument(format!(
                    "unknown colour filter array '{name}' (known: {})",
                    known.join(", ")
                ))
            })
    }

    /// The pattern's name.
    pub fn name(self) -> &'static str {
        Cfa::ALL.iter().find(|(cfa, _)| *cfa == self).map_or("", |(_, n)| n)
    }

    /// The channels (0 red, 1 green, 2 blue) of the 2 × 2 block, row by row.
    pub fn block(self) -> [usize; 4] {
        match self {
            Cfa::Rggb => [0, 1, 1, 2],
            Cfa::Bggr => [2, 1, 1, 0],
            Cfa::Grbg => [1, 0, 2, 1],
            Cfa::Gbrg => [1, 2, 0, 1],
            Cfa::Mono => [1, 1, 1, 1],
        }
    }

    /// The channel pixel (`x`, `y`) of the full sensor reads.
    pub fn channel(self, x: u32, y: u32) -> usize {
        self.block()[(2 * (y % 2) + x % 2) as usize]
    }
}

/// Everything that defines the sensor and its exposure.
#[derive(Clone, Debug, PartialEq)]
pub struct SensorSettings {
    /// The channels' spectral response.
    pub response: &'static SpectralResponse,
    /// Quantum efficiency at the response's peak.
    pub peak_qe: f64,
    /// The colour filter array.
    pub cfa: Cfa,
    /// Exposure time, s.
    pub exposure_time_s: f64,
    /// ISO speed: the analogue gain is `iso / unity_gain_iso`.
    pub iso: f64,
    /// The ISO speed at analogue gain 1, where the full well reaches the
    /// white level (ISETCam's pixel: conversion gain = voltage swing / well
    /// capacity).
    pub unity_gain_iso: f64,
    /// Full-well capacity per µm² of pixel (a pixel's is this times its area).
    pub full_well_e_per_um2: f64,
    /// Read noise, e⁻ RMS per pixel.
    pub read_noise_e: f64,
    /// Dark current per µm² of pixel, e⁻/s.
    pub dark_current_e_per_s_um2: f64,
    /// Dark signal non-uniformity: RMS of the pixels' fixed offsets, e⁻.
    pub dsnu_e: f64,
    /// Photo-response non-uniformity: RMS of the pixels' relative gains.
    pub prnu: f64,
    /// Bits per digital number (the white level is 2^bits − 1).
    pub bit_depth: u32,
    /// Digital number of no light.
    pub black_level_dn: u32,
    /// Luminance of a white emitter of value 1 in the scene, cd/m²: scene
    /// emission is spectral radiance in units of this over 683 lm/W · ∫ȳ
    /// (72,983 reads emission as W·m⁻²·sr⁻¹·nm⁻¹).
    pub white_luminance_cd_m2: f64,
    /// Seed of the fixed patterns (PRNU and DSNU): the same sensor.
    pub fixed_pattern_seed: u64,
    /// Seed of the temporal noise: a new one is a new frame.
    pub frame_seed: u64,
}

impl SensorSettings {
    /// The default sensor (every value [`crate::defaults`]'s) with the
    /// spectral response `response`.
    pub fn new(response: &'static SpectralResponse) -> SensorSettings {
        SensorSettings {
            response,
            peak_qe: defaults::SENSOR_PEAK_QE,
            cfa: defaults::SENSOR_CFA,
            exposure_time_s: defaults::SENSOR_EXPOSURE_TIME_S,
            iso: defaults::SENSOR_ISO,
            unity_gain_iso: defaults::SENSOR_UNITY_GAIN_ISO,
            full_well_e_per_um2: defaults::SENSOR_FULL_WELL_E_PER_UM2,
            read_noise_e: defaults::SENSOR_READ_NOISE_E,
            dark_current_e_per_s_um2: defaults::SENSOR_DARK_CURRENT_E_PER_S_UM2,
            dsnu_e: defaults::SENSOR_DSNU_E,
            prnu: defaults::SENSOR_PRNU,
            bit_depth: defaults::SENSOR_BIT_DEPTH,
            black_level_dn: defaults::SENSOR_BLACK_LEVEL_DN,
            white_luminance_cd_m2: defaults::SENSOR_WHITE_LUMINANCE_CD_M2,
            fixed_pattern_seed: 0,
            frame_seed: 0,
        }
    }

    /// Fails, naming the setting, unless every value is in range.
    pub fn validate(&self) -> Result<()> {
        let positive = [
            ("exposure time", self.exposure_time_s),
            ("ISO", self.iso),
            ("unity-gain ISO", self.unity_gain_iso),
            ("full well", self.full_well_e_per_um2),
            ("white luminance", self.white_luminance_cd_m2),
        ];
        if !(self.peak_qe > 0.0 && self.peak_qe <= 1.0) {
            return Err(Error::InvalidArgument(format!(
                "the sensor's peak quantum efficiency must be in (0, 1], not {}",
                self.peak_qe
            )));
        }
        let non_negative = [
            ("read noise", self.read_noise_e),
            ("dark current", self.dark_current_e_per_s_um2),
            ("DSNU", self.dsnu_e),
            ("PRNU", self.prnu),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::InvalidArgument(format!(
                    "the sensor's {name} must be positive, not {v}"
                )));
            }
        }
        for (name, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::InvalidArgument(format!(
                    "the sensor's {name} must be zero or more, not {v}"
                )));
            }
        }
        if !(1..=16).contains(&self.bit_depth) {
            return Err(Error::InvalidArgument(format!(
                "the sensor's bit depth must be 1 to 16, not {}",
                self.bit_depth
            )));
        }
        if self.black_level_dn >= self.white_level_dn() {
            return Err(Error::InvalidArgument(format!(
                "the black level {} must be below the white level {} of {} bits",
                self.black_level_dn,
                self.white_level_dn(),
                self.bit_depth
            )));
        }
        Ok(())
    }

    /// The largest digital number, 2^bits − 1.
    pub fn white_level_dn(&self) -> u32 {
        (1u32 << self.bit_depth) - 1
    }

    /// Electrons per digital number at this ISO behind `optics` (the
    /// inverse of the system gain K of EMVA 1288): at unity gain the full
    /// well reaches the white level.
    pub fn electrons_per_dn(&self, optics: &FilmRadiometry) -> f64 {
        self.full_well_e(optics) / f64::from(self.white_level_dn()) * self.unity_gain_iso / self.iso
    }

    /// Spectral radiance, W·m⁻²·sr⁻¹·nm⁻¹, of a scene emission of 1.
    pub fn radiance_per_scene_unit(&self) -> f64 {
        self.white_luminance_cd_m2 / (LUMINOUS_EFFICACY_LM_W * f64::from(cie::tables().y_integral))
    }

    /// Mean photoelectrons a film reading of 1 (e⁻ s⁻¹ µm⁻² sr⁻¹ per scene
    /// unit of radiance at peak quantum efficiency 1) collects in one pixel
    /// behind `optics`.
    pub fn electrons_per_reading(&self, optics: &FilmRadiometry) -> f64 {
        self.peak_qe
            * optics.irradiance_per_reading_sr
            * optics.pixel_area_um2()
            * self.exposure_time_s
            * self.radiance_per_scene_unit()
    }

    /// A pixel's full-well capacity behind `optics`, e⁻.
    pub fn full_well_e(&self, optics: &FilmRadiometry) -> f64 {
        self.full_well_e_per_um2 * optics.pixel_area_um2()
    }
}

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
    /// The channels' reading of D65 white, largest 1 (DNG `AsShotNeutral`).
    pub neutral: DVec3,
    /// The spectral response's name (DNG `UniqueCameraModel`).
    pub sensor_name: String,
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
    let (black, white) = (f64::from(settings.black_level_dn), f64::from(settings.white_level_dn()));
    let (origin_x, origin_y) = origin;
    let mut dn = vec![0u16; image.width as usize * image.height as usize];
    dn.par_chunks_mut(image.width as usize)
        .enumerate()
        .for_each(|(row, out)| {
            let y = origin_y + row as u32;
            for (col, out) in out.iter_mut().enumerate() {
                let x = origin_x + col as u32;
                // A pixel's place on the full sensor (images are under 2^20 wide).
                let site = (u64::from(y) << 20) + u64::from(x);
                let mut fixed = Pcg64Mcg::seed_from_u64(mix(settings.fixed_pattern_seed, site));
                let (prnu, dsnu): (f64, f64) = (fixed.sample(StandardNormal), fixed.sample(StandardNormal));
                let mut temporal = Pcg64Mcg::seed_from_u64(mix(settings.frame_seed ^ 0x9e37_79b9_7f4a_7c15, site));
                let reading = f64::from(image.pixel(col as u32, row as u32)[settings.cfa.channel(x, y)]);
                let mean = (reading * per_reading * (1.0 + settings.prnu * prnu)).max(0.0) + dark;
                let collected = poisson(mean, &mut temporal).min(full_well);
                let read: f64 = temporal.sample(StandardNormal);
                let electrons = collected + settings.dsnu_e * dsnu + settings.read_noise_e * read;
                *out = (electrons / electrons_per_dn + black).round().clamp(0.0, white) as u16;
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
        neutral: settings.response.d65_neutral(),
        sensor_name: settings.response.name().to_string(),
    })
}

/// A Poisson count of mean `mean` (0 for none).
fn poisson(mean: f64, rng: &mut Pcg64Mcg) -> f64 {
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
    Cfa::ALL
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

/// Why a sensor needs the realistic camera (the ideal ones have no optics
/// to count photons through).
pub(crate) fn needs_a_lens() -> Error {
    Error::InvalidArgument("a sensor counts photons through a lens: use the realistic camera".into())
}
