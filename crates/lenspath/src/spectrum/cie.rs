//! Colorimetry: the CIE 1931 2° colour matching functions, the D65
//! illuminant, and the conversion from CIE XYZ to linear sRGB.
//!
//! The tables are the CIE's (`data/cie/`, copied from pbrt-v4's
//! `spectrum.cpp`; see `data/README.md`). The sRGB matrices are derived,
//! as pbrt-v4's `RGBColorSpace` does, from the primaries' chromaticities
//! (IEC 61966-2-1) and the white point the D65 table itself integrates to,
//! so a spectrum equal to D65 maps to RGB (1, 1, 1) exactly rather than to
//! within the rounding of the standard's printed white.

use std::sync::OnceLock;

use glam::{DMat3, DVec3, Mat3, Vec3, Vec4};

use super::{LAMBDA_MAX_NM, LAMBDA_MIN_NM};
use crate::math::Rgb;

/// The CIE 1931 2° observer, 360–830 nm at 1 nm: `wavelength_nm,x,y,z`.
const CIE_1931_CSV: &str = include_str!("../../data/cie/cie1931_2deg_xyz.csv");
/// The CIE standard illuminant D65, 300–830 nm at 5 nm: `wavelength_nm,value`.
const D65_CSV: &str = include_str!("../../data/cie/illuminant_d65.csv");

/// sRGB primaries' chromaticities (x, y): red, green, blue (IEC 61966-2-1).
const SRGB_PRIMARIES: [(f64, f64); 3] = [(0.64, 0.33), (0.30, 0.60), (0.15, 0.06)];

/// Number of 1 nm steps in the tables: 360..=830.
pub(crate) const SAMPLES: usize = (LAMBDA_MAX_NM - LAMBDA_MIN_NM) as usize + 1;

/// The trapezoid rule's weight of the `i`-th 1 nm sample: every integral
/// over the tables uses it (exact for the sum of their linear interpolants).
pub(crate) fn trapezoid_weight(i: usize) -> f64 {
    if i == 0 || i == SAMPLES - 1 {
        0.5
    } else {
        1.0
    }
}

/// The colorimetric tables, read once.
pub struct CieTables {
    /// x̄, ȳ, z̄ at 360, 361, … 830 nm.
    xyz_bar: Vec<Vec3>,
    /// The same as linear sRGB and divided by ∫ȳ: what one wavelength of
    /// radiance adds to a pixel.
    rgb_bar: Vec<Vec3>,
    /// D65 at the same wavelengths, scaled so its luminance is 1:
    /// ∫ D65 ȳ dλ / ∫ ȳ dλ = 1.
    d65: Vec<f32>,
    /// The wavelength sampler's table (see [`CieTables::sample_wavelength`]).
    wavelength_cells: WavelengthCells,
    /// ∫ ȳ(λ) dλ over 360–830 nm (pbrt's `CIE_Y_integral`, 106.857).
    pub y_integral: f32,
    /// CIE XYZ of the normalised D65: the white point, Y = 1.
    pub white_xyz: Vec3,
    xyz_to_rgb: Mat3,
    rgb_to_xyz: DMat3,
}

/// The tables (parsed from the embedded CSV on first use).
#[inline(always)]
pub fn tables() -> &'static CieTables {
    static TABLES: OnceLock<CieTables> = OnceLock::new();
    TABLES.get_or_init(CieTables::load)
}

/// Cells of equal probability in [`CieTables::sample_wavelength`]'s table.
pub const SAMPLING_CELLS: usize = 1024;

/// A density over 360–830 nm tabulated for drawing by inversion: cells of
/// equal probability, the density constant within each.
pub(crate) struct WavelengthCells {
    /// Cell edges, nm ([`SAMPLING_CELLS`] + 1, from 360 to 830).
    edges_nm: Vec<f32>,
    /// The density, per nm, within each cell.
    pdf: Vec<f32>,
}

impl WavelengthCells {
    /// The density ∝ `weights` (one per nm of the tables' grid, linear
    /// between) plus a floor of 1/1000 of their peak, so that every
    /// wavelength of 360–830 nm can be drawn.
    pub(crate) fn new(weights: &[f64]) -> Self {
        let floor = 1e-3 * weights.iter().copied().fold(0.0, f64::max);
        let bins: Vec<f64> = weights.windows(2).map(|w| 0.5 * (w[0] + w[1]) + floor).collect();
        let total: f64 = bins.iter().sum();
        // The CDF at the 1 nm bins' edges, then inverted at k / cells.
        let mut cdf = vec![0.0f64];
        for b in &bins {
            cdf.push(cdf[cdf.len() - 1] + b / total);
        }
        let edges_nm: Vec<f32> = (0..=SAMPLING_CELLS)
            .map(|k| {
                let c = k as f64 / SAMPLING_CELLS as f64;
                let i = cdf.partition_point(|&x| x <= c).clamp(1, bins.len()) - 1;
                let t = ((c - cdf[i]) / (cdf[i + 1] - cdf[i])).clamp(0.0, 1.0);
                (f64::from(LAMBDA_MIN_NM) + i as f64 + t) as f32
            })
            .collect();
        let pdf = edges_nm
            .windows(2)
            .map(|e| 1.0 / (SAMPLING_CELLS as f32 * (e[1] - e[0])))
            .collect();
        WavelengthCells { edges_nm, pdf }
    }

    /// A wavelength, nm, for `u` in [0, 1), and its density per nm: a
    /// lookup and a lerp.
    #[inline(always)]
    pub(crate) fn sample(&self, u: f32) -> (f32, f32) {
        let x = u * SAMPLING_CELLS as f32;
        let cell = (x as u32 as usize).min(SAMPLING_CELLS - 1);
        let (a, b) = (self.edges_nm[cell], self.edges_nm[cell + 1]);
        (a + (x - cell as f32) * (b - a), self.pdf[cell])
    }

    /// The density, per nm, of `lambda_nm` (zero outside 360–830 nm).
    fn pdf(&self, lambda_nm: f32) -> f32 {
        if !(LAMBDA_MIN_NM..=LAMBDA_MAX_NM).contains(&lambda_nm) {
            return 0.0;
        }
        let cell = self.edges_nm.partition_point(|&e| e <= lambda_nm);
        self.pdf[cell.clamp(1, SAMPLING_CELLS) - 1]
    }
}

/// Rows of numbers of a CSV with one header line.
fn csv_rows(text: &'static str) -> impl Iterator<Item = Vec<f64>> {
    text.lines().skip(1).filter(|l| !l.trim().is_empty()).map(|line| {
        line.split(',')
            .map(|v| v.trim().parse::<f64>().expect("the embedded CIE tables are numbers"))
            .collect()
    })
}

impl CieTables {
    fn load() -> Self {
        let xyz_bar: Vec<Vec3> = csv_rows(CIE_1931_CSV)
            .map(|r| Vec3::new(r[1] as f32, r[2] as f32, r[3] as f32))
            .collect();
        assert_eq!(xyz_bar.len(), SAMPLES, "the CIE table covers 360–830 nm at 1 nm");
        let d65_5nm: Vec<(f64, f64)> = csv_rows(D65_CSV).map(|r| (r[0], r[1])).collect();
        let d65_raw: Vec<f64> = (0..SAMPLES)
            .map(|i| {
                let lambda = f64::from(LAMBDA_MIN_NM) + i as f64;
                let j = d65_5nm.partition_point(|p| p.0 <= lambda).clamp(1, d65_5nm.len() - 1);
                let ((l0, v0), (l1, v1)) = (d65_5nm[j - 1], d65_5nm[j]);
                v0 + (lambda - l0) / (l1 - l0) * (v1 - v0)
            })
            .collect();
        let integrate = |f: &dyn Fn(usize) -> f64| -> f64 { (0..SAMPLES).map(|i| f(i) * trapezoid_weight(i)).sum() };
        let y_integral = integrate(&|i| f64::from(xyz_bar[i].y));
        let d65_y = integrate(&|i| d65_raw[i] * f64::from(xyz_bar[i].y)) / y_integral;
        let d65: Vec<f32> = d65_raw.iter().map(|v| (v / d65_y) as f32).collect();
        let white = DVec3::new(
            integrate(&|i| f64::from(d65[i]) * f64::from(xyz_bar[i].x)),
            integrate(&|i| f64::from(d65[i]) * f64::from(xyz_bar[i].y)),
            integrate(&|i| f64::from(d65[i]) * f64::from(xyz_bar[i].z)),
        ) / y_integral;
        let rgb_to_xyz = rgb_to_xyz_matrix(SRGB_PRIMARIES, white);
        let xyz_to_rgb = rgb_to_xyz.inverse().as_mat3();
        let rgb_bar: Vec<Vec3> = xyz_bar
            .iter()
            .map(|&bar| xyz_to_rgb * bar / y_integral as f32)
            .collect();
        // The density of `sample_wavelength` (its doc comment says why this one).
        let rgb_bar_norm_sqrt: Vec<f64> = rgb_bar.iter().map(|c| f64::from(c.length()).sqrt()).collect();
        let wavelength_cells = WavelengthCells::new(&rgb_bar_norm_sqrt);
        CieTables {
            xyz_bar,
            rgb_bar,
            wavelength_cells,
            d65,
            y_integral: y_integral as f32,
            white_xyz: white.as_vec3(),
            xyz_to_rgb,
            rgb_to_xyz,
        }
    }

    /// A wavelength, nm, for `u` in [0, 1), drawn with density ∝
    /// √‖(r̄, ḡ, b̄)(λ)‖ (the square root of the length of the matching
    /// functions as linear sRGB), and that density per nm.
    ///
    /// The film estimates each of R, G, B from a sample's four wavelengths,
    /// `u` and its rotations by ¼ ([`super::SampledWavelengths::sample_visible`]).
    /// For one wavelength alone, the density that minimises the sum of the
    /// three variances for a flat spectrum is ∝ ‖(r̄, ḡ, b̄)‖ (the
    /// vector-valued case of importance sampling; Veach 1997, §2.5); the four
    /// rotations already spread the wavelengths over the range, and for them
    /// a flatter density, visiting the blue and red ends more, leaves less:
    /// the square root, the best of the powers tried, for D65 white and for
    /// random smooth reflectances under D65 (`bench/wavelength_density.py`;
    /// the figures and the renders in BENCHMARKS.md). pbrt-v4's luminance-shaped density (∝ 1 / cosh²(0.0072
    /// (λ − 538))) is further off still. The floor of `WavelengthCells`
    /// keeps every wavelength of 360–830 nm possible (a dispersive path
    /// carries what it is given).
    ///
    /// The inverse CDF is tabulated at [`SAMPLING_CELLS`] cells of equal
    /// probability, so drawing is a lookup and a lerp (no search), and the
    /// density is exactly constant within each cell: 1 / (cells × width).
    #[inline(always)]
    pub fn sample_wavelength(&self, u: f32) -> (f32, f32) {
        self.wavelength_cells.sample(u)
    }

    /// The density, per nm, [`CieTables::sample_wavelength`] draws
    /// `lambda_nm` with (zero outside 360–830 nm).
    pub fn wavelength_pdf(&self, lambda_nm: f32) -> f32 {
        self.wavelength_cells.pdf(lambda_nm)
    }

    /// Index and fraction of `lambda_nm` on the 1 nm grid, or `None` outside it.
    #[inline(always)]
    pub(crate) fn locate(lambda_nm: f32) -> Option<(usize, f32)> {
        let x = lambda_nm - LAMBDA_MIN_NM;
        if !(0.0..=(SAMPLES - 1) as f32).contains(&x) {
            return None;
        }
        // Through u32: x is in range, and the saturating cast to usize costs
        // several instructions more on x86-64 (four lookups per sample).
        let i = (x as u32 as usize).min(SAMPLES - 2);
        Some((i, x - i as f32))
    }

    /// x̄, ȳ, z̄ at `lambda_nm` (linear between the 1 nm entries; zero outside 360–830 nm).
    #[inline(always)]
    pub fn xyz_bar(&self, lambda_nm: f32) -> Vec3 {
        Self::interpolate(&self.xyz_bar, lambda_nm)
    }

    /// x̄, ȳ, z̄ at `lambda_nm` as linear sRGB over ∫ȳ (see `rgb_bar`).
    #[inline(always)]
    pub fn rgb_bar(&self, lambda_nm: f32) -> Vec3 {
        Self::interpolate(&self.rgb_bar, lambda_nm)
    }

    /// A table on the 1 nm grid at `lambda_nm`, linear between entries, zero outside.
    #[inline(always)]
    pub(crate) fn interpolate(table: &[Vec3], lambda_nm: f32) -> Vec3 {
        match Self::locate(lambda_nm) {
            Some((i, t)) => table[i].lerp(table[i + 1], t),
            None => Vec3::ZERO,
        }
    }

    /// The luminance-normalised D65 at `lambda_nm` (zero outside 360–830 nm).
    #[inline(always)]
    pub fn d65(&self, lambda_nm: f32) -> f32 {
        match Self::locate(lambda_nm) {
            Some((i, t)) => self.d65[i] + t * (self.d65[i + 1] - self.d65[i]),
            None => 0.0,
        }
    }

    /// [`CieTables::d65`] at four wavelengths.
    #[inline(always)]
    pub fn d65_4(&self, lambda_nm: Vec4) -> Vec4 {
        Vec4::new(
            self.d65(lambda_nm.x),
            self.d65(lambda_nm.y),
            self.d65(lambda_nm.z),
            self.d65(lambda_nm.w),
        )
    }

    /// Linear sRGB of CIE XYZ.
    #[inline(always)]
    pub fn xyz_to_rgb(&self, xyz: Vec3) -> Rgb {
        self.xyz_to_rgb * xyz
    }

    /// CIE XYZ of linear sRGB.
    pub fn rgb_to_xyz(&self, rgb: Rgb) -> Vec3 {
        (self.rgb_to_xyz * rgb.as_dvec3()).as_vec3()
    }

    /// The linear sRGB → XYZ matrix, in double precision (the spectral fit's).
    pub(crate) fn rgb_to_xyz_f64(&self) -> DMat3 {
        self.rgb_to_xyz
    }

    /// CIE XYZ of the spectral radiance `f(λ)`, integrated at 1 nm over
    /// 360–830 nm and divided by ∫ȳ (a unit spectrum has Y = 1).
    pub fn spectrum_to_xyz(&self, f: impl Fn(f32) -> f32) -> Vec3 {
        let mut sum = DVec3::ZERO;
        for (i, bar) in self.xyz_bar.iter().enumerate() {
            sum += bar.as_dvec3() * f64::from(f(LAMBDA_MIN_NM + i as f32)) * trapezoid_weight(i);
        }
        (sum / f64::from(self.y_integral)).as_vec3()
    }

    /// Linear sRGB of the spectral radiance `f(λ)`.
    pub fn spectrum_to_rgb(&self, f: impl Fn(f32) -> f32) -> Rgb {
        self.xyz_to_rgb(self.spectrum_to_xyz(f))
    }

    /// Linear sRGB of a surface of spectral reflectance `f(λ)` lit by D65
    /// (what an RGB reflectance must round-trip to).
    pub fn reflectance_to_rgb(&self, f: impl Fn(f32) -> f32) -> Rgb {
        self.spectrum_to_rgb(|l| f(l) * self.d65(l))
    }
}

/// The matrix from linear RGB with `primaries` (xy chromaticities) and
/// `white` (XYZ) to XYZ: each primary's XYZ scaled so the three sum to the
/// white (SMPTE RP 177-1993).
fn rgb_to_xyz_matrix(primaries: [(f64, f64); 3], white: DVec3) -> DMat3 {
    let xyz_of = |(x, y): (f64, f64)| DVec3::new(x / y, 1.0, (1.0 - x - y) / y);
    let p = DMat3::from_cols(xyz_of(primaries[0]), xyz_of(primaries[1]), xyz_of(primaries[2]));
    let s = p.inverse() * white;
    DMat3::from_cols(p.x_axis * s.x, p.y_axis * s.y, p.z_axis * s.z)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tables read: ∫ȳ is pbrt's CIE_Y_integral, D65's white has the
    /// standard's chromaticity (0.3127, 0.3290) to 4 decimals, and the
    /// matrix is the standard sRGB one to 3e-3 (it differs only by that
    /// rounding of the white).
    #[test]
    fn tables_match_the_standards() {
        let t = tables();
        assert!((t.y_integral - 106.856_895).abs() < 1e-3, "{}", t.y_integral);
        let w = t.white_xyz;
        let (x, y) = (w.x / (w.x + w.y + w.z), w.y / (w.x + w.y + w.z));
        assert!(
            (x - 0.3127).abs() < 1e-4 && (y - 0.3290).abs() < 1e-4,
            "white ({x}, {y})"
        );
        assert!((w.y - 1.0).abs() < 1e-6);
        // IEC 61966-2-1's XYZ → sRGB matrix.
        let standard = Mat3::from_cols_array(&[
            3.2406, -0.9689, 0.0557, -1.5372, 1.8758, -0.2040, -0.4986, 0.0415, 1.0570,
        ]);
        let diff = (t.xyz_to_rgb - standard).to_cols_array();
        assert!(diff.iter().all(|d| d.abs() < 3e-3), "{:?}", t.xyz_to_rgb);
        let white_rgb = t.spectrum_to_rgb(|l| t.d65(l));
        assert!((white_rgb - Vec3::ONE).abs().max_element() < 1e-5, "{white_rgb}");
        assert_eq!(t.xyz_bar(200.0), Vec3::ZERO);
        assert!((t.xyz_bar(555.0).y - 1.0).abs() < 2e-3);
    }
}
