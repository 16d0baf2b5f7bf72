//! A sensor's spectral response: the quantum efficiency of its three
//! channels (the photodiode's times the colour filter's), what a photon of
//! each wavelength yields in each channel, and the colour matrix that
//! relates the channels to CIE XYZ.
//!
//! The film of a sensor render records, per channel, the photoelectron rate
//! a unit étendue would collect, ∫ L(λ) QE_c(λ) λ/(hc) dλ (Janesick,
//! *Photon Transfer*, SPIE 2007, ch. 2: photons per joule are λ/(hc)), so
//! [`super::capture`] needs only the lens's irradiance per unit radiance,
//! the pixel's area and the exposure time to count electrons.

use std::fmt;
use std::sync::OnceLock;

use glam::{DMat3, DVec3, Vec3};

use crate::math::Rgb;
use crate::spectrum::cie::{self, CieTables};
use crate::spectrum::{SampledSpectrum, SampledWavelengths, Spectrum, Tabulated, LAMBDA_MAX_NM, LAMBDA_MIN_NM};
use crate::{Error, Result};

/// Planck's constant, J·s (SI 2019, exact).
const PLANCK_J_S: f64 = 6.626_070_15e-34;
/// The speed of light, m/s (exact).
const LIGHT_M_S: f64 = 299_792_458.0;

/// The name of the ideal sensor: its channels count x̄, ȳ, z̄ of the light
/// (quantum efficiency x̄ȳz̄ over λ: the Luther condition met exactly), the
/// tallest peaking at the peak quantum efficiency.
pub const IDEAL_SENSOR: &str = "ideal";

/// The measured cameras: (name, their r, g, b sensitivities as
/// `wavelength_nm,r,g,b` rows, green peak 1), from pbrt-v4
/// (`data/sensors/`, provenance in `data/README.md`).
const CAMERAS: &[(&str, &str)] = &[
    ("canon_eos_100d", include_str!("../../data/sensors/canon_eos_100d.csv")),
    (
        "canon_eos_1dx_mkii",
        include_str!("../../data/sensors/canon_eos_1dx_mkii.csv"),
    ),
    ("canon_eos_200d", include_str!("../../data/sensors/canon_eos_200d.csv")),
    (
        "canon_eos_200d_mkii",
        include_str!("../../data/sensors/canon_eos_200d_mkii.csv"),
    ),
    ("canon_eos_5d", include_str!("../../data/sensors/canon_eos_5d.csv")),
    (
        "canon_eos_5d_mkii",
        include_str!("../../data/sensors/canon_eos_5d_mkii.csv"),
    ),
    (
        "canon_eos_5d_mkiii",
        include_str!("../../data/sensors/canon_eos_5d_mkiii.csv"),
    ),
    (
        "canon_eos_5d_mkiv",
        include_str!("../../data/sensors/canon_eos_5d_mkiv.csv"),
    ),
    ("canon_eos_5ds", include_str!("../../data/sensors/canon_eos_5ds.csv")),
    ("canon_eos_m", include_str!("../../data/sensors/canon_eos_m.csv")),
    (
        "hasselblad_l1d_20c",
        include_str!("../../data/sensors/hasselblad_l1d_20c.csv"),
    ),
    ("nikon_d810", include_str!("../../data/sensors/nikon_d810.csv")),
    ("nikon_d850", include_str!("../../data/sensors/nikon_d850.csv")),
    ("sony_ilce_6400", include_str!("../../data/sensors/sony_ilce_6400.csv")),
    ("sony_ilce_7m3", include_str!("../../data/sensors/sony_ilce_7m3.csv")),
    ("sony_ilce_7rm3", include_str!("../../data/sensors/sony_ilce_7rm3.csv")),
    ("sony_ilce_9", include_str!("../../data/sensors/sony_ilce_9.csv")),
];

/// Every spectral response by name: the ideal sensor, then the cameras.
pub fn names() -> impl Iterator<Item = &'static str> {
    std::iter::once(IDEAL_SENSOR).chain(CAMERAS.iter().map(|(name, _)| *name))
}

/// Photoelectrons per second per µm² per steradian that one nm of spectral
/// radiance 1 W·m⁻²·sr⁻¹·nm⁻¹ at `lambda_nm` frees at quantum efficiency 1:
/// λ/(hc) photons per joule, 10⁻¹² m² per µm².
pub fn electrons_per_energy(lambda_nm: f64) -> f64 {
    lambda_nm * 1e-9 / (PLANCK_J_S * LIGHT_M_S) * 1e-12
}

/// A sensor's three channels, tabulated at 1 nm over the renderer's
/// wavelengths, relative to the most sensitive channel's peak (the sensor's
/// peak quantum efficiency, [`super::SensorSettings::peak_qe`], scales them).
pub struct SpectralResponse {
    name: &'static str,
    /// Relative quantum efficiency of each channel, 1 nm apart from `LAMBDA_MIN_NM`.
    qe: Vec<DVec3>,
    /// The same times λ/(hc): electrons s⁻¹ µm⁻² sr⁻¹ per W·m⁻²·sr⁻¹·nm⁻¹ per nm.
    yield_per_nm: Vec<Vec3>,
    /// The colour matrix and D65's neutral, fitted when first asked for.
    colour: OnceLock<Colour>,
}

/// How a response relates to CIE XYZ under D65.
#[derive(Clone, Copy)]
struct Colour {
    xyz_to_camera: DMat3,
    /// The channels' reading of D65 white, largest 1.
    neutral: DVec3,
}

impl PartialEq for SpectralResponse {
    // One response per name ([`SpectralResponse::named`]).
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
    }
}

impl fmt::Debug for SpectralResponse {
    // The tables say nothing a reader of a settings dump needs.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "SpectralResponse({})", self.name)
    }
}

impl SpectralResponse {
    /// The response called `name` (see [`names`]), made once.
    pub fn named(name: &str) -> Result<&'static SpectralResponse> {
        static MADE: OnceLock<Vec<SpectralResponse>> = OnceLock::new();
        let made = MADE.get_or_init(|| names().map(SpectralResponse::tabulate).collect());
        made.iter().find(|r| r.name == name).ok_or_else(|| {
            Error::InvalidArgument(format!(
                "unknown sensor '{name}' (known: {})",
                names().collect::<Vec<_>>().join(", ")
            ))
        })
    }

    fn tabulate(name: &'static str) -> SpectralResponse {
        let relative = relative_curves(name);
        let peak = relative.iter().map(|c| c.max_element()).fold(0.0, f64::max);
        let qe: Vec<DVec3> = relative.iter().map(|c| *c / peak).collect();
        let yield_per_nm = qe
            .iter()
            .enumerate()
            .map(|(i, c)| (*c * electrons_per_energy(LAMBDA_MIN_NM as f64 + i as f64)).as_vec3())
            .collect();
        SpectralResponse {
            name,
            qe,
            yield_per_nm,
            colour: OnceLock::new(),
        }
    }

    /// The response's name.
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// Quantum efficiency of the three channels at `lambda_nm` relative to
    /// the peak (0 outside the renderer's wavelengths).
    pub fn relative_qe(&self, lambda_nm: f32) -> DVec3 {
        match CieTables::locate(lambda_nm) {
            Some((i, t)) => self.qe[i].lerp(self.qe[i + 1], f64::from(t)),
            None => DVec3::ZERO,
        }
    }

    /// The Monte Carlo estimate of each channel's electron rate at peak
    /// quantum efficiency 1, e⁻ s⁻¹ µm⁻² sr⁻¹, from the spectral radiance `l` (W·m⁻²·sr⁻¹·nm⁻¹ per
    /// scene unit) carried at `lambda`: what a sensor render's film sums.
    #[inline(always)]
    pub fn electron_rate(&self, lambda: &SampledWavelengths, l: SampledSpectrum) -> Rgb {
        lambda.estimate(l, |nm| CieTables::interpolate(&self.yield_per_nm, nm))
    }

    /// The 3 × 3 matrix taking CIE XYZ to this sensor's channels, fitted by
    /// least squares over surface colours lit by D65 (how pbrt-v4's
    /// `PixelSensor` and Adobe's DNG `ColorMatrix1` relate a camera to XYZ),
    /// scaled so D65 white (Y = 1) gives 1 in its largest channel, as DNG
    /// asks. Exact for the ideal sensor.
    pub fn xyz_to_camera(&self) -> DMat3 {
        self.colour().xyz_to_camera
    }

    /// The channels' reading of D65 white through [`Self::xyz_to_camera`],
    /// largest 1 (DNG `AsShotNeutral` for a D65 scene).
    pub fn d65_neutral(&self) -> DVec3 {
        self.colour().neutral
    }

    fn colour(&self) -> Colour {
        *self.colour.get_or_init(|| self.fit_colour())
    }

    /// Each channel's photoelectron rate at peak quantum efficiency 1,
    /// e⁻ s⁻¹ µm⁻² sr⁻¹, from the spectral radiance `radiance_at(nm)`
    /// (W·m⁻²·sr⁻¹·nm⁻¹), integrated at 1 nm by the trapezoid rule (as
    /// [`cie::CieTables::spectrum_to_xyz`]): what [`Self::electron_rate`]
    /// estimates.
    pub fn reading(&self, radiance_at: impl Fn(f64) -> f64) -> DVec3 {
        self.yield_per_nm
            .iter()
            .enumerate()
            .map(|(i, y)| y.as_dvec3() * (cie::trapezoid_weight(i) * radiance_at(LAMBDA_MIN_NM as f64 + i as f64)))
            .sum()
    }

    fn fit_colour(&self) -> Colour {
        let t = cie::tables();
        // Under D65, per unit reflectance; the camera counts photons as
        // it does in a render.
        let xyz_of = |reflectance: &dyn Fn(f64) -> f64| -> DVec3 {
            t.spectrum_to_xyz(|nm| t.d65(nm) * reflectance(f64::from(nm)) as f32)
                .as_dvec3()
        };
        let camera_of =
            |reflectance: &dyn Fn(f64) -> f64| self.reading(|nm| f64::from(t.d65(nm as f32)) * reflectance(nm));
        // Normal equations of camera ≈ M · xyz over the training colours.
        let (mut xx, mut cx) = (DMat3::ZERO, DMat3::ZERO);
        for rgb in training_colours() {
            let spectrum = Spectrum::reflectance(rgb);
            let reflectance = |l: f64| f64::from(spectrum.at(l as f32));
            let (xyz, cam) = (xyz_of(&reflectance), camera_of(&reflectance));
            xx += outer(xyz, xyz);
            cx += outer(cam, xyz);
        }
        let m = cx * xx.inverse();
        let white = m * xyz_of(&|_| 1.0);
        Colour {
            xyz_to_camera: m * (1.0 / white.max_element()),
            neutral: white / white.max_element(),
        }
    }
}

/// a bᵀ.
fn outer(a: DVec3, b: DVec3) -> DMat3 {
    DMat3::from_cols(a * b.x, a * b.y, a * b.z)
}

/// Surface colours the colour matrix is fitted over: a 5³ grid of sRGB
/// reflectances from 0.05 to 0.95, each upsampled to a smooth spectrum.
fn training_colours() -> impl Iterator<Item = Rgb> {
    let level = |k: u32| 0.05 + 0.225 * k as f32;
    (0..125).map(move |i| Vec3::new(level(i % 5), level(i / 5 % 5), level(i / 25)))
}

/// A response's channels relative to each other, 1 nm apart from
/// `LAMBDA_MIN_NM` to `LAMBDA_MAX_NM`; zero where the measurement stops
/// (the cameras' infrared filters cut beyond it).
fn relative_curves(name: &str) -> Vec<DVec3> {
    let wavelengths = (LAMBDA_MIN_NM as u32..=LAMBDA_MAX_NM as u32).map(|nm| nm as f32);
    let csv = match CAMERAS.iter().find(|(n, _)| *n == name) {
        Some((_, csv)) => csv,
        None => {
            // The ideal sensor counts photons, so its quantum efficiency is
            // x̄ȳz̄ over λ: its electrons are then proportional to XYZ.
            let t = cie::tables();
            return wavelengths
                .map(|nm| t.xyz_bar(nm).as_dvec3() * (555.0 / f64::from(nm)))
                .collect();
        }
    };
    let rows: Vec<[f32; 4]> = csv
        .lines()
        .skip(1)
        .map(|line| {
            let mut v = line.split(',').map(|x| x.trim().parse().expect("embedded table"));
            std::array::from_fn(|_| v.next().expect("four columns"))
        })
        .collect();
    let channel =
        |c: usize| Tabulated::new(&rows.iter().map(|r| (r[0], r[c])).collect::<Vec<_>>()).expect("embedded table");
    let (r, g, b) = (channel(1), channel(2), channel(3));
    let measured = rows[0][0]..=rows[rows.len() - 1][0];
    wavelengths
        .map(|nm| {
            if measured.contains(&nm) {
                Vec3::new(r.at(nm), g.at(nm), b.at(nm)).as_dvec3()
            } else {
                DVec3::ZERO
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_camera_reads_with_its_green_peak_at_1() {
        for name in names() {
            let r = SpectralResponse::named(name).unwrap();
            let qe = |nm: u32| r.relative_qe(nm as f32);
            let peak = (360..=830).map(|nm| qe(nm).max_element()).fold(0.0, f64::max);
            assert!((peak - 1.0).abs() < 1e-12, "{name}: {peak}");
            if name != IDEAL_SENSOR {
                // Green is the measured curves' peak, at 500-560 nm for every camera.
                let g_peak = (360..=830).max_by(|a, b| qe(*a).y.total_cmp(&qe(*b).y)).unwrap();
                assert!((500..=560).contains(&g_peak), "{name}: {g_peak}");
                assert_eq!(r.relative_qe(375.0), DVec3::ZERO);
            }
        }
        let unknown = SpectralResponse::named("leica_m3").unwrap_err().to_string();
        assert!(unknown.contains("sony_ilce_7m3"), "{unknown}");
    }

    #[test]
    fn a_photon_at_555_nm_carries_hc_over_lambda() {
        // 1 W at 555 nm is 2.7941e18 photons/s (h c / λ = 3.5789e-19 J).
        assert!((electrons_per_energy(555.0) * 1e12 / 2.794_1e18 - 1.0).abs() < 1e-4);
    }

    #[test]
    fn the_ideal_sensors_colour_matrix_is_xyz_itself() {
        let m = SpectralResponse::named(IDEAL_SENSOR).unwrap().xyz_to_camera();
        // Channels are x̄ȳz̄, so camera ∝ XYZ: diagonal, equal.
        let scale = m.x_axis.x;
        assert!(
            (m - DMat3::from_diagonal(DVec3::splat(scale)))
                .abs()
                .to_cols_array()
                .iter()
                .all(|v| *v < 1e-6 * scale),
            "{m}"
        );
    }
}
