//! Light as spectra: the wavelengths a camera sample carries, spectral
//! values at those wavelengths, and the spectra a scene's colours and
//! lights become.
//!
//! lenspath's transport is spectral (after pbrt-v4, Pharr et al. 4th ed.
//! §4.5–4.6): every camera sample carries [`WAVELENGTHS_PER_SAMPLE`]
//! wavelengths chosen by hero-wavelength sampling (Wilkie et al. 2014,
//! "Hero Wavelength Spectral Sampling"), importance-sampled toward the
//! visible wavelengths the film's R, G and B weigh
//! ([`SampledWavelengths::sample_visible`]); a path carries their
//! [`SampledSpectrum`] and the film turns it into CIE XYZ and linear sRGB
//! ([`cie`]). Scene colours stay RGB: reflectances become smooth spectra in
//! [0, 1] and emission becomes a spectrum times the D65 illuminant
//! ([`upsample`], Jakob & Hanika 2019).

pub mod cie;
pub mod metals;
pub mod upsample;

use std::sync::Arc;

use glam::{Vec3, Vec4};

use crate::error::{Error, Result};
use crate::math::Rgb;
pub use upsample::SigmoidPolynomial;

/// Shortest wavelength transported, nm (the CIE tables' first entry).
pub const LAMBDA_MIN_NM: f32 = 360.0;
/// Longest wavelength transported, nm (the CIE tables' last entry).
pub const LAMBDA_MAX_NM: f32 = 830.0;
/// The helium d line, nm: the wavelength at which lens prescriptions give
/// their indices (n_d) and the Abbe number V_d is defined.
pub const D_LINE_NM: f32 = 587.5618;
/// Wavelengths each camera sample carries (pbrt-v4's `NSpectrumSamples`).
pub const WAVELENGTHS_PER_SAMPLE: usize = 4;

/// Values of a spectral quantity at a sample's [`SampledWavelengths`], one
/// per lane (a SIMD vector: the path loop multiplies these as it did RGB).
pub type SampledSpectrum = Vec4;

/// The wavelengths one camera sample carries and their densities.
///
/// The first is the hero; the others are its rotations through the sampled
/// range, so one uniform number stratifies all four (Wilkie et al. 2014).
/// An interface whose direction depends on the wavelength (a dispersive
/// glass) keeps only the hero: [`SampledWavelengths::terminate_secondary`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledWavelengths {
    /// Wavelengths, nm.
    pub lambda_nm: Vec4,
    /// Density of each, per nm (zero for a terminated wavelength), divided
    /// by any weight the camera gave its lane
    /// ([`SampledWavelengths::weight_lanes`]).
    pub pdf: Vec4,
    /// The hero's density once it is left alone
    /// ([`SampledWavelengths::terminate_secondary`]): its own density over
    /// the number of wavelengths it was drawn with.
    hero_alone_pdf: f32,
}

impl SampledWavelengths {
    /// Wavelengths for the uniform number `u` in [0, 1): the hero drawn with
    /// the density of [`cie::CieTables::sample_wavelength`] (toward the
    /// wavelengths the film's R, G and B weigh most), the others at `u`
    /// rotated by ¼, ½ and ¾ (Wilkie et al. 2014).
    #[inline(always)]
    pub fn sample_visible(u: f32) -> Self {
        let tables = cie::tables();
        let mut lambda_nm = [0.0f32; WAVELENGTHS_PER_SAMPLE];
        let mut pdf = [0.0f32; WAVELENGTHS_PER_SAMPLE];
        for lane in 0..WAVELENGTHS_PER_SAMPLE {
            let ui = u + lane as f32 / WAVELENGTHS_PER_SAMPLE as f32;
            let ui = if ui >= 1.0 { ui - 1.0 } else { ui };
            (lambda_nm[lane], pdf[lane]) = tables.sample_wavelength(ui);
        }
        SampledWavelengths {
            lambda_nm: Vec4::from_array(lambda_nm),
            pdf: Vec4::from_array(pdf),
            hero_alone_pdf: pdf[0] / WAVELENGTHS_PER_SAMPLE as f32,
        }
    }

    /// Wavelengths `lambda_nm` with density `pdf` each, those of density 0
    /// absent (tests, analysis tools).
    pub fn new(lambda_nm: Vec4, pdf: Vec4) -> Self {
        let present = pdf.cmpgt(Vec4::ZERO).bitmask().count_ones().max(1);
        SampledWavelengths {
            lambda_nm,
            pdf,
            hero_alone_pdf: pdf.x / present as f32,
        }
    }

    /// One wavelength alone, density 1 (geometric questions and analysis).
    pub fn single(lambda_nm: f32) -> Self {
        Self::new(Vec4::splat(lambda_nm), Vec4::new(1.0, 0.0, 0.0, 0.0))
    }

    /// How many wavelengths are still carried (density above 0).
    pub fn live_count(&self) -> u32 {
        self.pdf.cmpgt(Vec4::ZERO).bitmask().count_ones()
    }

    /// The hero wavelength, nm: the one a dispersive interface follows.
    pub fn hero_nm(&self) -> f32 {
        self.lambda_nm.x
    }

    /// Keeps only the hero wavelength (a path that just split by wavelength):
    /// the others get density 0, so they add nothing, and the hero's density
    /// is divided by their count, so the estimate stays unbiased (pbrt-v4
    /// `TerminateSecondary`). Any lane weights are dropped with them: the
    /// hero alone is the estimate of the one wavelength that chose the path.
    pub fn terminate_secondary(&mut self) {
        self.pdf = Vec4::new(self.hero_alone_pdf, 0.0, 0.0, 0.0);
    }

    /// Scales each wavelength's contribution by its `weights` entry by
    /// dividing its density; a weight of 0 drops the wavelength. A
    /// dispersive lens's camera weighs the lanes so (see
    /// `camera::RealisticCamera`'s lane weights); terminating the
    /// secondaries later returns the hero to its own density.
    #[inline(always)]
    pub fn weight_lanes(&mut self, weights: Vec4) {
        self.pdf = Vec4::select(weights.cmpgt(Vec4::ZERO), self.pdf / weights, Vec4::ZERO);
    }

    /// True once only the hero wavelength is left.
    pub fn secondary_terminated(&self) -> bool {
        self.pdf.y == 0.0 && self.pdf.z == 0.0 && self.pdf.w == 0.0
    }

    /// Linear sRGB (D65) of the spectral radiance `l` carried at these
    /// wavelengths: its CIE XYZ estimate, then the sRGB primaries.
    #[inline(always)]
    pub fn to_rgb(&self, l: SampledSpectrum) -> Rgb {
        let tables = cie::tables();
        self.estimate(l, |lambda| tables.rgb_bar(lambda))
    }

    /// The Monte Carlo estimate of CIE XYZ from `l` at these wavelengths:
    /// the mean over lanes of L(λ) x̄ȳz̄(λ) / p(λ), over ∫ȳ (so a spectrum
    /// equal to 1 everywhere has Y ≈ 1).
    #[inline(always)]
    pub fn to_xyz(&self, l: SampledSpectrum) -> Vec3 {
        let tables = cie::tables();
        self.estimate(l, |lambda| tables.xyz_bar(lambda)) / tables.y_integral
    }

    /// The mean over lanes of L(λ) · `weight`(λ) / p(λ): the Monte Carlo
    /// estimate of ∫ L(λ) weight(λ) dλ, terminated lanes left out.
    #[inline(always)]
    pub(crate) fn estimate(&self, l: SampledSpectrum, weight: impl Fn(f32) -> Vec3) -> Vec3 {
        // Most samples of a dark pixel carry nothing: skip the table lookups.
        if l == SampledSpectrum::ZERO {
            return Vec3::ZERO;
        }
        let l_over_pdf = Vec4::select(self.pdf.cmpgt(Vec4::ZERO), l / self.pdf, Vec4::ZERO);
        let mut sum = Vec3::ZERO;
        for i in 0..WAVELENGTHS_PER_SAMPLE {
            if l_over_pdf[i] != 0.0 {
                sum += weight(self.lambda_nm[i]) * l_over_pdf[i];
            }
        }
        sum / WAVELENGTHS_PER_SAMPLE as f32
    }
}

/// A spectral distribution as a scene gives it: what a reflectance,
/// emission or index of refraction is, evaluated at a sample's wavelengths
/// by [`Spectrum::sample`].
#[derive(Clone, Debug, PartialEq)]
pub enum Spectrum {
    /// The same value at every wavelength.
    Constant(f32),
    /// A smooth spectrum fitted to an RGB colour (Jakob & Hanika 2019),
    /// times `scale`: reflectances (scale 1, values in [0, 1]) and other
    /// unbounded RGB quantities (scale twice the largest component).
    Rgb {
        /// The fitted sigmoid polynomial, values in [0, 1].
        polynomial: SigmoidPolynomial,
        /// Factor applied to it.
        scale: f32,
    },
    /// An emitter's RGB colour: a fitted spectrum times the D65 illuminant,
    /// so RGB white (1, 1, 1) emits D65 with luminance 1 and renders as
    /// sRGB (1, 1, 1) (pbrt-v4 `RGBIlluminantSpectrum`).
    RgbIlluminant {
        /// The fitted sigmoid polynomial, values in [0, 1].
        polynomial: SigmoidPolynomial,
        /// Factor applied to it.
        scale: f32,
    },
    /// Planck's black body at `temperature_k` times `scale`, made by
    /// [`Spectrum::blackbody`] so its luminance Y is the one asked for (1
    /// renders as bright as RGB white).
    Blackbody {
        /// Temperature, kelvin.
        temperature_k: f32,
        /// Factor on Planck's law (W·m⁻²·sr⁻¹·nm⁻¹) giving the luminance asked for.
        scale: f32,
    },
    /// Values given at wavelengths, linear between them and constant beyond
    /// the ends (measured data: lamps, metals).
    Tabulated(Arc<Tabulated>),
}

/// A spectrum given at increasing wavelengths, linear between them.
#[derive(Clone, Debug, PartialEq)]
pub struct Tabulated {
    lambda_nm: Vec<f32>,
    values: Vec<f32>,
}

impl Tabulated {
    /// A table of `(wavelength_nm, value)` pairs; wavelengths must increase
    /// strictly and every number be finite, values non-negative.
    pub fn new(pairs: &[(f32, f32)]) -> Result<Self> {
        let fail = |m: String| Err(Error::InvalidArgument(format!("spectrum table: {m}")));
        if pairs.len() < 2 {
            return fail(format!(
                "needs at least two (wavelength_nm, value) pairs, got {}",
                pairs.len()
            ));
        }
        for (i, &(lambda, value)) in pairs.iter().enumerate() {
            if !(lambda.is_finite() && value.is_finite() && value >= 0.0) {
                return fail(format!(
                    "pair {i} ({lambda}, {value}) must be finite with a non-negative value"
                ));
            }
            if i > 0 && lambda <= pairs[i - 1].0 {
                return fail(format!(
                    "wavelengths must increase, but pair {i} has {lambda} nm after {} nm",
                    pairs[i - 1].0
                ));
            }
        }
        Ok(Tabulated {
            lambda_nm: pairs.iter().map(|p| p.0).collect(),
            values: pairs.iter().map(|p| p.1).collect(),
        })
    }

    /// The value at `lambda_nm`.
    pub fn at(&self, lambda_nm: f32) -> f32 {
        let n = self.lambda_nm.len();
        if lambda_nm <= self.lambda_nm[0] {
            return self.values[0];
        }
        if lambda_nm >= self.lambda_nm[n - 1] {
            return self.values[n - 1];
        }
        let i = self.lambda_nm.partition_point(|&l| l <= lambda_nm) - 1;
        let t = (lambda_nm - self.lambda_nm[i]) / (self.lambda_nm[i + 1] - self.lambda_nm[i]);
        self.values[i] + t * (self.values[i + 1] - self.values[i])
    }
}

impl Spectrum {
    /// A reflectance or transmittance colour in [0, 1]³ as a spectrum in [0, 1].
    pub fn reflectance(rgb: Rgb) -> Self {
        Spectrum::Rgb {
            polynomial: SigmoidPolynomial::fit(rgb.clamp(Vec3::ZERO, Vec3::ONE)),
            scale: 1.0,
        }
    }

    /// A non-negative RGB quantity that is not a reflectance (a conductor's
    /// η or k): the fit of `rgb / (2 max)` times `2 max` (pbrt-v4
    /// `RGBUnboundedSpectrum`).
    pub fn unbounded(rgb: Rgb) -> Self {
        let (polynomial, scale) = SigmoidPolynomial::fit_scaled(rgb);
        Spectrum::Rgb { polynomial, scale }
    }

    /// An emitter's RGB colour as a spectrum times D65.
    pub fn illuminant(rgb: Rgb) -> Self {
        let (polynomial, scale) = SigmoidPolynomial::fit_scaled(rgb);
        Spectrum::RgbIlluminant { polynomial, scale }
    }

    /// A black body at `temperature_k` with luminance `luminance`.
    pub fn blackbody(temperature_k: f32, luminance: f32) -> Result<Self> {
        if !(temperature_k > 0.0 && temperature_k.is_finite()) {
            return Err(Error::InvalidArgument(format!(
                "a black body's temperature must be positive kelvin, got {temperature_k}"
            )));
        }
        if !(luminance >= 0.0 && luminance.is_finite()) {
            return Err(Error::InvalidArgument(format!(
                "a black body's luminance must be 0 or more, got {luminance}"
            )));
        }
        let planck_luminance = cie::tables().spectrum_to_xyz(|l| planck(l, temperature_k)).y;
        let scale = luminance / planck_luminance;
        if !scale.is_finite() {
            return Err(Error::InvalidArgument(format!(
                "a black body at {temperature_k} K gives no visible light; give a temperature of 500 K or more"
            )));
        }
        Ok(Spectrum::Blackbody { temperature_k, scale })
    }

    /// The spectrum's values at `lambda`.
    #[inline(always)]
    pub fn sample(&self, lambda: &SampledWavelengths) -> SampledSpectrum {
        match self {
            Spectrum::Constant(c) => Vec4::splat(*c),
            Spectrum::Rgb { polynomial, scale } => polynomial.eval4(lambda.lambda_nm) * *scale,
            Spectrum::RgbIlluminant { polynomial, scale } => {
                polynomial.eval4(lambda.lambda_nm) * *scale * cie::tables().d65_4(lambda.lambda_nm)
            }
            Spectrum::Blackbody { temperature_k, scale } => {
                Vec4::from_array(lambda.lambda_nm.to_array().map(|l| planck(l, *temperature_k) * scale))
            }
            Spectrum::Tabulated(table) => Vec4::from_array(lambda.lambda_nm.to_array().map(|l| table.at(l))),
        }
    }

    /// The value at one wavelength.
    pub fn at(&self, lambda_nm: f32) -> f32 {
        self.sample(&SampledWavelengths::new(Vec4::splat(lambda_nm), Vec4::ONE))
            .x
    }

    /// True when every value is zero (a black emitter, a zero tint).
    pub fn is_black(&self) -> bool {
        match self {
            Spectrum::Constant(c) => *c == 0.0,
            Spectrum::Rgb { scale, polynomial } | Spectrum::RgbIlluminant { scale, polynomial } => {
                *scale == 0.0 || polynomial.is_zero()
            }
            Spectrum::Blackbody { scale, .. } => *scale == 0.0,
            Spectrum::Tabulated(t) => t.values.iter().all(|&v| v == 0.0),
        }
    }

    /// Linear sRGB of this spectrum: as an emitter's radiance when it is an
    /// illuminant or a light's own spectrum, integrated against the CIE
    /// matching functions at 1 nm.
    pub fn to_rgb(&self) -> Rgb {
        cie::tables().spectrum_to_rgb(|l| self.at(l))
    }
}

/// What an emitter gives off, as a scene describes it: an RGB colour, as
/// every scene format writes it, or a spectrum of its own (pbrt-v4's
/// `blackbody` and tabulated light spectra). A spectrum is scaled to a
/// luminance: 1 is as bright as RGB white (1, 1, 1).
#[derive(Clone, Debug, PartialEq)]
pub enum Emission {
    /// Linear sRGB radiance, intensity or irradiance, emitted as its fitted
    /// spectrum times D65 ([`Spectrum::illuminant`]).
    Rgb(Rgb),
    /// A spectrum of its own ([`Emission::blackbody`], [`Emission::tabulated`]).
    Spectral(Spectrum),
}

impl From<Rgb> for Emission {
    fn from(rgb: Rgb) -> Self {
        Emission::Rgb(rgb)
    }
}

impl Emission {
    /// A black body at `temperature_k` with luminance `luminance`.
    pub fn blackbody(temperature_k: f32, luminance: f32) -> Result<Self> {
        Spectrum::blackbody(temperature_k, luminance).map(Emission::Spectral)
    }

    /// A spectrum given at wavelengths (`(wavelength_nm, value)` pairs,
    /// linear between them, zero beyond the ends, as pbrt-v4's piecewise
    /// linear spectra), scaled to luminance `luminance`: only its shape matters.
    pub fn tabulated(pairs: &[(f32, f32)], luminance: f32) -> Result<Self> {
        if !(luminance >= 0.0 && luminance.is_finite()) {
            return Err(Error::InvalidArgument(format!(
                "a spectrum's luminance must be 0 or more, got {luminance}"
            )));
        }
        // Checked as given, so a refusal names the caller's pairs.
        Tabulated::new(pairs)?;
        // Zero beyond the ends: a step of a thousandth of a nanometre down to 0.
        let (first, last) = (pairs[0].0, pairs[pairs.len() - 1].0);
        let padded: Vec<(f32, f32)> = std::iter::once((first - 1e-3, 0.0))
            .chain(pairs.iter().copied())
            .chain(std::iter::once((last + 1e-3, 0.0)))
            .collect();
        let mut table = Tabulated::new(&padded)?;
        let y = cie::tables().spectrum_to_xyz(|l| table.at(l)).y;
        if y.is_nan() || y <= 0.0 {
            return Err(Error::InvalidArgument(
                "spectrum table: it has no visible light (its luminance is 0), so it cannot be scaled to a luminance"
                    .into(),
            ));
        }
        let scale = luminance / y;
        table.values.iter_mut().for_each(|v| *v *= scale);
        Ok(Emission::Spectral(Spectrum::Tabulated(Arc::new(table))))
    }

    /// The spectrum emitted.
    pub fn spectrum(&self) -> Spectrum {
        match self {
            Emission::Rgb(rgb) => Spectrum::illuminant(*rgb),
            Emission::Spectral(spectrum) => spectrum.clone(),
        }
    }

    /// True when nothing is emitted.
    pub fn is_black(&self) -> bool {
        match self {
            Emission::Rgb(rgb) => rgb.max_element() <= 0.0,
            Emission::Spectral(spectrum) => spectrum.is_black(),
        }
    }

    /// Its colour as linear sRGB: the RGB given, or the spectrum's.
    pub fn to_rgb(&self) -> Rgb {
        match self {
            Emission::Rgb(rgb) => *rgb,
            Emission::Spectral(spectrum) => spectrum.to_rgb(),
        }
    }
}

/// Planck's law: spectral radiance of a black body at `temperature_k`, in
/// W·m⁻²·sr⁻¹·nm⁻¹, at `lambda_nm` (CODATA 2018 constants).
pub fn planck(lambda_nm: f32, temperature_k: f32) -> f32 {
    const C: f64 = 299_792_458.0;
    const H: f64 = 6.626_070_15e-34;
    const KB: f64 = 1.380_649e-23;
    let l = f64::from(lambda_nm) * 1e-9;
    let t = f64::from(temperature_k);
    let radiance_per_m = 2.0 * H * C * C / (l.powi(5) * ((H * C / (l * KB * t)).exp_m1()));
    (radiance_per_m * 1e-9) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sampling density integrates to 1 over [360, 830] nm and the
    /// sampler inverts its CDF: the fraction of samples below a wavelength
    /// equals the density's integral up to it, and each sample carries the
    /// density of where it landed.
    #[test]
    fn wavelength_sampling_matches_its_density() {
        let tables = cie::tables();
        let pdf = |lambda: f32| f64::from(tables.wavelength_pdf(lambda));
        let integral: f64 = (0..47_000).map(|i| pdf(360.0 + (i as f32 + 0.5) * 0.01) * 0.01).sum();
        assert!((integral - 1.0).abs() < 1e-4, "∫pdf = {integral}");
        let n = 100_000;
        let draws: Vec<(f32, f32)> = (0..n)
            .map(|i| tables.sample_wavelength((i as f32 + 0.5) / n as f32))
            .collect();
        for cut in [420.0f32, 500.0, 560.0, 650.0, 780.0] {
            let below = draws.iter().filter(|d| d.0 < cut).count();
            let cdf: f64 = (0..((cut - 360.0) * 100.0) as usize)
                .map(|i| pdf(360.0 + (i as f32 + 0.5) * 0.01) * 0.01)
                .sum();
            assert!(
                (below as f64 / n as f64 - cdf).abs() < 1e-3,
                "{cut} nm: {below} vs {cdf}"
            );
        }
        for &(lambda, p) in draws.iter().step_by(97) {
            // Away from a bin's edge, where rounding may put λ in the next bin.
            if (lambda - lambda.round()).abs() > 1e-3 {
                assert_eq!(p, tables.wavelength_pdf(lambda), "{lambda} nm");
            }
        }
        assert!((tables.sample_wavelength(0.0).0 - 360.0).abs() < 1e-3);
        assert!((tables.sample_wavelength(0.999_999_9).0 - 830.0).abs() < 0.1);
        let w = SampledWavelengths::sample_visible(0.9);
        let rotated = [0.0f32, 0.25, 0.5, 0.75].map(|r| {
            let u = 0.9 + r;
            tables.sample_wavelength(if u >= 1.0 { u - 1.0 } else { u })
        });
        assert_eq!(w.lambda_nm.to_array(), rotated.map(|d| d.0));
        assert_eq!(w.pdf.to_array(), rotated.map(|d| d.1));
    }

    /// The density samples where R and B need it, not only where luminance
    /// does: the colour noise of D65's sRGB estimate (four hero-rotated
    /// wavelengths, u stratified) is under 0.3× what the density ∝
    /// ‖(r̄, ḡ, b̄)‖ gives, which is itself under half of
    /// pbrt-v4's luminance-shaped density's; all three are unbiased.
    #[test]
    fn wavelength_sampling_lowers_colour_noise() {
        let tables = cie::tables();
        // pbrt-v4's SampleVisibleWavelengths and VisibleWavelengthsPDF.
        let pbrt = |u: f32| {
            let t = 0.856_910_6 - 1.827_502 * u;
            (538.0 - 138.888_89 * t.atanh(), 0.003_939_804 * (1.0 - t * t))
        };
        // The density ∝ ‖(r̄, ḡ, b̄)‖ itself, optimal for one wavelength alone.
        let norm_weights: Vec<f64> = (0..cie::SAMPLES)
            .map(|i| f64::from(tables.rgb_bar(LAMBDA_MIN_NM + i as f32).length()))
            .collect();
        let norm_cells = cie::WavelengthCells::new(&norm_weights);
        let norm = |u: f32| norm_cells.sample(u);
        let ours = |u: f32| tables.sample_wavelength(u);
        let variance = |sample: &dyn Fn(f32) -> (f32, f32)| {
            let n = 20_000;
            let estimates: Vec<Vec3> = (0..n)
                .map(|i| {
                    let u = (i as f32 + 0.5) / n as f32;
                    let lanes = [0.0, 0.25, 0.5, 0.75].map(|r| sample((u + r) % 1.0));
                    let w = SampledWavelengths::new(
                        Vec4::from_array(lanes.map(|l| l.0)),
                        Vec4::from_array(lanes.map(|l| l.1)),
                    );
                    w.to_rgb(tables.d65_4(w.lambda_nm))
                })
                .collect();
            let mean = estimates.iter().sum::<Vec3>() / n as f32;
            assert!((mean - Vec3::ONE).abs().max_element() < 2e-3, "D65 is white: {mean}");
            estimates.iter().map(|e| (*e - mean).length_squared()).sum::<f32>() / n as f32
        };
        let (ours, norm, pbrt) = (variance(&ours), variance(&norm), variance(&pbrt));
        assert!(ours < 0.3 * norm, "variance {ours} against the norm's density's {norm}");
        assert!(
            norm < 0.5 * pbrt,
            "variance {norm} of the norm's density against pbrt's {pbrt}"
        );
    }

    /// Terminating the secondaries leaves an estimate with the same mean: the
    /// XYZ of a constant spectrum averaged over many hero wavelengths.
    #[test]
    fn terminating_secondary_wavelengths_keeps_the_mean() {
        let n = 20_000;
        let (mut all, mut hero) = (Vec3::ZERO, Vec3::ZERO);
        for i in 0..n {
            let mut w = SampledWavelengths::sample_visible((i as f32 + 0.5) / n as f32);
            all += w.to_xyz(Vec4::ONE);
            w.terminate_secondary();
            assert!(w.secondary_terminated());
            hero += w.to_xyz(Vec4::ONE);
        }
        let (all, hero) = (all / n as f32, hero / n as f32);
        assert!((all.y - 1.0).abs() < 1e-3, "Y of a unit spectrum {}", all.y);
        assert!((all - hero).abs().max_element() < 2e-3, "{all} vs {hero}");
    }

    /// Planck's law: the peak sits at Wien's b / T and the radiance at the
    /// peak of a 5778 K body is the tabulated 2.6e13 W·m⁻²·sr⁻¹·m⁻¹.
    #[test]
    fn planck_peaks_at_wien() {
        let t = 5778.0;
        let peak = (3000..9000)
            .map(|i| i as f32 * 0.1)
            .max_by(|a, b| planck(*a, t).total_cmp(&planck(*b, t)))
            .unwrap();
        assert!((peak - 2.897_772e6 / t).abs() < 0.2, "peak at {peak} nm");
        let radiance = planck(peak, t) * 1e9;
        assert!((radiance / 2.63e13 - 1.0).abs() < 0.01, "{radiance}");
    }

    /// A 6504 K black body is near D65's white, a 2700 K lamp is warm, and
    /// the luminance asked for is the luminance given.
    #[test]
    fn blackbody_colours() {
        let d65ish = Spectrum::blackbody(6504.0, 1.0).unwrap();
        let xyz = cie::tables().spectrum_to_xyz(|l| d65ish.at(l));
        assert!((xyz.y - 1.0).abs() < 1e-4, "Y = {}", xyz.y);
        let rgb = d65ish.to_rgb();
        assert!((rgb - Vec3::ONE).abs().max_element() < 0.1, "{rgb}");
        let warm = Spectrum::blackbody(2700.0, 2.0).unwrap().to_rgb();
        assert!(warm.x > 1.4 * warm.z, "{warm}");
        assert!(Spectrum::blackbody(-3.0, 1.0).is_err());
        assert!(Spectrum::blackbody(100.0, 1.0).is_err());
    }

    /// Emission spectra: a black body and a table take the luminance asked
    /// for, whatever their own scale; RGB stays as given; dark ones are refused.
    #[test]
    fn emission_spectra_have_the_luminance_asked_for() {
        let y = |e: &Emission| cie::tables().spectrum_to_xyz(|l| e.spectrum().at(l)).y;
        let lamp = Emission::blackbody(2856.0, 3.0).unwrap();
        assert!((y(&lamp) / 3.0 - 1.0).abs() < 1e-4, "{}", y(&lamp));
        let sodium = Emission::tabulated(&[(585.0, 0.0), (589.0, 1000.0), (593.0, 0.0)], 2.0).unwrap();
        assert!((y(&sodium) / 2.0 - 1.0).abs() < 1e-3, "{}", y(&sodium));
        // A sodium lamp is orange-yellow: much more red than blue.
        let rgb = sodium.to_rgb();
        assert!(rgb.x > 5.0 * rgb.z.abs() && rgb.x > rgb.y, "{rgb}");
        assert_eq!(Emission::from(Rgb::ONE).to_rgb(), Rgb::ONE);
        assert!(Emission::blackbody(100.0, 1.0).is_err());
        // Zero beyond its ends: a table in the infrared emits nothing visible.
        assert!(Emission::tabulated(&[(900.0, 1.0), (1000.0, 1.0)], 1.0).is_err());
        let green = Emission::tabulated(&[(500.0, 1.0), (560.0, 1.0)], 1.0)
            .unwrap()
            .spectrum();
        assert_eq!(
            (green.at(499.0), green.at(530.0) > 0.0, green.at(561.0)),
            (0.0, true, 0.0)
        );
        assert!(Emission::tabulated(&[(400.0, 0.0), (500.0, 0.0)], 1.0).is_err());
        assert!(Emission::tabulated(&[(400.0, 1.0), (500.0, 1.0)], -1.0).is_err());
    }

    #[test]
    fn tabulated_interpolates_and_refuses_bad_tables() {
        let t = Tabulated::new(&[(400.0, 1.0), (500.0, 3.0), (600.0, 0.0)]).unwrap();
        assert_eq!(t.at(450.0), 2.0);
        assert_eq!(t.at(300.0), 1.0);
        assert_eq!(t.at(700.0), 0.0);
        assert!(Tabulated::new(&[(400.0, 1.0), (400.0, 2.0)]).is_err());
        assert!(Tabulated::new(&[(400.0, -1.0), (500.0, 2.0)]).is_err());
        assert!(Tabulated::new(&[(400.0, 1.0)]).is_err());
    }
}
