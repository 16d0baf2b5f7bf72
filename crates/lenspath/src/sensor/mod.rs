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
//! (`sensorCreate('IMX363')`, MIT licence), see [`preset`].

mod capture;
pub mod develop;
pub mod preset;
pub mod raw_file;
pub mod response;
mod white_balance;

pub use capture::{capture, capture_through, Exposure, RawFrame};
pub use develop::{Demosaic, Development, ToneCurve};
pub use response::SpectralResponse;
pub use white_balance::WhiteBalance;

use crate::film::FilmRadiometry;
use crate::film::Image;
use crate::names::Named;
use crate::spectrum::cie;
use crate::{Error, Result};

/// Luminous efficacy of 555 nm light, lm/W (the SI candela's definition).
pub const LUMINOUS_EFFICACY_LM_W: f64 = 683.0;

/// The colour filter array: which channel each pixel of a 2 × 2 block
/// reads, named by its first row then its second.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Cfa {
    /// Bayer: red, green / green, blue (the default).
    #[default]
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

impl Named for Cfa {
    const WHAT: &'static str = "colour filter array";
    const NAMED: &'static [(Cfa, &'static str)] = &[
        (Cfa::Rggb, "rggb"),
        (Cfa::Bggr, "bggr"),
        (Cfa::Grbg, "grbg"),
        (Cfa::Gbrg, "gbrg"),
        (Cfa::Mono, "mono"),
    ];
}

impl Cfa {
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
    /// The light the camera is balanced for (the raw file's as-shot neutral).
    pub white_balance: WhiteBalance,
    /// How the raw frame is developed into an image.
    pub development: Development,
    /// Set the exposure time and ISO from the film, within these limits,
    /// instead of taking them as given (`None`).
    pub auto_exposure: Option<AutoExposure>,
}

/// A camera's program exposure: the exposure time that brings the frame's
/// mean green to [`AutoExposure::MID_GREY`] of the full well at the base
/// ISO; past the longest exposure time, the gain makes up the rest, up to
/// the highest ISO (below that the frame is dark, as a camera's is).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AutoExposure {
    /// The longest exposure time, s.
    pub max_exposure_time_s: f64,
    /// The highest ISO speed.
    pub max_iso: f64,
}

impl AutoExposure {
    /// The fraction of the full well a frame's mean green is exposed to:
    /// 18% grey, what a reflected-light meter renders a scene's average as
    /// (ISO 2720's calibration).
    pub const MID_GREY: f64 = 0.18;
}

impl SensorSettings {
    /// The default sensor (every value [`preset`]'s, or its type's default) with the
    /// spectral response `response`.
    pub fn new(response: &'static SpectralResponse) -> SensorSettings {
        SensorSettings {
            response,
            peak_qe: preset::PEAK_QE,
            cfa: Cfa::default(),
            exposure_time_s: preset::EXPOSURE_TIME_S,
            iso: preset::ISO,
            unity_gain_iso: preset::UNITY_GAIN_ISO,
            full_well_e_per_um2: preset::FULL_WELL_E_PER_UM2,
            read_noise_e: preset::READ_NOISE_E,
            dark_current_e_per_s_um2: preset::DARK_CURRENT_E_PER_S_UM2,
            dsnu_e: preset::DSNU_E,
            prnu: preset::PRNU,
            bit_depth: preset::BIT_DEPTH,
            black_level_dn: preset::BLACK_LEVEL_DN,
            white_luminance_cd_m2: preset::WHITE_LUMINANCE_CD_M2,
            fixed_pattern_seed: 0,
            frame_seed: 0,
            white_balance: WhiteBalance::default(),
            development: Development::default(),
            auto_exposure: None,
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
        self.white_balance.validate()?;
        if let Some(auto) = &self.auto_exposure {
            if !(auto.max_exposure_time_s > 0.0 && auto.max_exposure_time_s.is_finite()) {
                return Err(Error::InvalidArgument(format!(
                    "the sensor's longest exposure time must be positive, not {}",
                    auto.max_exposure_time_s
                )));
            }
            if !(auto.max_iso >= self.unity_gain_iso && auto.max_iso.is_finite()) {
                return Err(Error::InvalidArgument(format!(
                    "the sensor's highest ISO must be at least its base ISO {}, not {}",
                    self.unity_gain_iso, auto.max_iso
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

    /// The description that resolves to these settings, every field given.
    pub fn description(&self) -> SensorDescription {
        SensorDescription {
            model: Some(self.response.name().to_string()),
            peak_qe: Some(self.peak_qe),
            cfa: Some(self.cfa),
            exposure_time_s: Some(self.exposure_time_s),
            iso: Some(self.iso),
            white_luminance_cd_m2: Some(self.white_luminance_cd_m2),
            read_noise_e: Some(self.read_noise_e),
            full_well_e_per_um2: Some(self.full_well_e_per_um2),
            dark_current_e_per_s_um2: Some(self.dark_current_e_per_s_um2),
            dsnu_e: Some(self.dsnu_e),
            prnu: Some(self.prnu),
            bit_depth: Some(self.bit_depth),
            black_level_dn: Some(self.black_level_dn),
            frame_seed: Some(self.frame_seed),
            fixed_pattern_seed: Some(self.fixed_pattern_seed),
            white_balance: Some(self.white_balance),
            demosaic: Some(self.development.demosaic),
            tone_curve: Some(self.development.tone_curve),
            auto_exposure: Some(self.auto_exposure.is_some()),
            max_exposure_time_s: Some(
                self.auto_exposure
                    .map_or(preset::MAX_EXPOSURE_TIME_S, |a| a.max_exposure_time_s),
            ),
            max_iso: Some(self.auto_exposure.map_or(preset::MAX_ISO, |a| a.max_iso)),
        }
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

    /// These settings with the exposure time and ISO a program exposure
    /// chooses for `film` behind `optics` ([`AutoExposure`]); unchanged
    /// without auto exposure. The film metered is the one given: a crop
    /// meters itself.
    pub fn metered(&self, film: &Image, optics: &FilmRadiometry) -> SensorSettings {
        let Some(auto) = self.auto_exposure else {
            return self.clone();
        };
        let pixels = (film.rgb.len() / 3).max(1) as f64;
        let mean_green = film.rgb.chunks_exact(3).map(|p| f64::from(p[1])).sum::<f64>() / pixels;
        let per_second = SensorSettings {
            exposure_time_s: 1.0,
            ..self.clone()
        }
        .electrons_per_reading(optics)
            * mean_green;
        // At the base ISO the full well is the white level.
        let target = AutoExposure::MID_GREY * self.full_well_e(optics);
        let wanted_s = if per_second > 0.0 {
            target / per_second
        } else {
            f64::INFINITY
        };
        let exposure_time_s = wanted_s.min(auto.max_exposure_time_s);
        // The ratio first: at the base ISO it is exactly 1 (ISO × time / time is not).
        let iso = (self.unity_gain_iso * (wanted_s / exposure_time_s)).clamp(self.unity_gain_iso, auto.max_iso);
        SensorSettings {
            exposure_time_s,
            iso,
            ..self.clone()
        }
    }
}

/// An image sensor as a caller or a scene file describes it: each field
/// left `None` is the default's ([`preset`], ISETCam's Sony
/// IMX363). Every front end maps its own spelling onto this.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SensorDescription {
    /// The spectral response by name ([`response::names`]).
    pub model: Option<String>,
    /// Peak quantum efficiency.
    pub peak_qe: Option<f64>,
    /// The colour filter array.
    pub cfa: Option<Cfa>,
    /// Exposure time, s.
    pub exposure_time_s: Option<f64>,
    /// ISO speed.
    pub iso: Option<f64>,
    /// Luminance of a white emitter of value 1, cd/m².
    pub white_luminance_cd_m2: Option<f64>,
    /// Read noise, e⁻ RMS.
    pub read_noise_e: Option<f64>,
    /// Full-well capacity per µm², e⁻.
    pub full_well_e_per_um2: Option<f64>,
    /// Dark current per µm², e⁻/s.
    pub dark_current_e_per_s_um2: Option<f64>,
    /// Dark signal non-uniformity, e⁻ RMS.
    pub dsnu_e: Option<f64>,
    /// Photo-response non-uniformity, RMS gain.
    pub prnu: Option<f64>,
    /// Bits per digital number.
    pub bit_depth: Option<u32>,
    /// Black level, DN.
    pub black_level_dn: Option<u32>,
    /// Seed of the temporal noise (a new one is a new frame).
    pub frame_seed: Option<u64>,
    /// Seed of the fixed patterns (a new one is another sensor of the model).
    pub fixed_pattern_seed: Option<u64>,
    /// The light the camera is balanced for.
    pub white_balance: Option<WhiteBalance>,
    /// The demosaicking method of the development.
    pub demosaic: Option<Demosaic>,
    /// The development's tone curve.
    pub tone_curve: Option<ToneCurve>,
    /// Whether the exposure time and ISO are metered from the film.
    pub auto_exposure: Option<bool>,
    /// Auto exposure's longest exposure time, s.
    pub max_exposure_time_s: Option<f64>,
    /// Auto exposure's highest ISO.
    pub max_iso: Option<f64>,
}

impl SensorDescription {
    /// This description's fields, else `under`'s (a caller's over a scene
    /// file's, a scene file's over its base's).
    pub fn over(&self, under: &SensorDescription) -> SensorDescription {
        SensorDescription {
            model: self.model.clone().or_else(|| under.model.clone()),
            peak_qe: self.peak_qe.or(under.peak_qe),
            cfa: self.cfa.or(under.cfa),
            exposure_time_s: self.exposure_time_s.or(under.exposure_time_s),
            iso: self.iso.or(under.iso),
            white_luminance_cd_m2: self.white_luminance_cd_m2.or(under.white_luminance_cd_m2),
            read_noise_e: self.read_noise_e.or(under.read_noise_e),
            full_well_e_per_um2: self.full_well_e_per_um2.or(under.full_well_e_per_um2),
            dark_current_e_per_s_um2: self.dark_current_e_per_s_um2.or(under.dark_current_e_per_s_um2),
            dsnu_e: self.dsnu_e.or(under.dsnu_e),
            prnu: self.prnu.or(under.prnu),
            bit_depth: self.bit_depth.or(under.bit_depth),
            black_level_dn: self.black_level_dn.or(under.black_level_dn),
            frame_seed: self.frame_seed.or(under.frame_seed),
            fixed_pattern_seed: self.fixed_pattern_seed.or(under.fixed_pattern_seed),
            white_balance: self.white_balance.or(under.white_balance),
            demosaic: self.demosaic.or(under.demosaic),
            tone_curve: self.tone_curve.or(under.tone_curve),
            auto_exposure: self.auto_exposure.or(under.auto_exposure),
            max_exposure_time_s: self.max_exposure_time_s.or(under.max_exposure_time_s),
            max_iso: self.max_iso.or(under.max_iso),
        }
    }

    /// The sensor it describes, defaults filled in and checked.
    pub fn resolve(&self) -> Result<SensorSettings> {
        let response = SpectralResponse::named(self.model.as_deref().unwrap_or(preset::RESPONSE))?;
        let d = SensorSettings::new(response);
        let sensor = SensorSettings {
            peak_qe: self.peak_qe.unwrap_or(d.peak_qe),
            cfa: self.cfa.unwrap_or(d.cfa),
            exposure_time_s: self.exposure_time_s.unwrap_or(d.exposure_time_s),
            iso: self.iso.unwrap_or(d.iso),
            white_luminance_cd_m2: self.white_luminance_cd_m2.unwrap_or(d.white_luminance_cd_m2),
            read_noise_e: self.read_noise_e.unwrap_or(d.read_noise_e),
            full_well_e_per_um2: self.full_well_e_per_um2.unwrap_or(d.full_well_e_per_um2),
            dark_current_e_per_s_um2: self.dark_current_e_per_s_um2.unwrap_or(d.dark_current_e_per_s_um2),
            dsnu_e: self.dsnu_e.unwrap_or(d.dsnu_e),
            prnu: self.prnu.unwrap_or(d.prnu),
            bit_depth: self.bit_depth.unwrap_or(d.bit_depth),
            black_level_dn: self.black_level_dn.unwrap_or(d.black_level_dn),
            frame_seed: self.frame_seed.unwrap_or(d.frame_seed),
            fixed_pattern_seed: self.fixed_pattern_seed.unwrap_or(d.fixed_pattern_seed),
            white_balance: self.white_balance.unwrap_or(d.white_balance),
            development: Development {
                demosaic: self.demosaic.unwrap_or(d.development.demosaic),
                tone_curve: self.tone_curve.unwrap_or(d.development.tone_curve),
            },
            auto_exposure: self
                .auto_exposure
                .unwrap_or(preset::AUTO_EXPOSURE)
                .then(|| AutoExposure {
                    max_exposure_time_s: self.max_exposure_time_s.unwrap_or(preset::MAX_EXPOSURE_TIME_S),
                    max_iso: self.max_iso.unwrap_or(preset::MAX_ISO),
                }),
            ..d
        };
        sensor.validate()?;
        Ok(sensor)
    }
}

/// Why a sensor needs the realistic camera (the ideal ones have no optics
/// to count photons through).
pub(crate) fn needs_a_lens() -> Error {
    Error::InvalidArgument("a sensor counts photons through a lens: use the realistic camera".into())
}
