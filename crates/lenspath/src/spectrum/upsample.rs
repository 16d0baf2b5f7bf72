//! RGB to spectrum: the smooth, bounded spectra of Jakob & Hanika 2019,
//! "A Low-Dimensional Function Space for Efficient Spectral Upsampling"
//! (Computer Graphics Forum 38(2)), as pbrt-v4 and Mitsuba 3 use them.
//!
//! A reflectance is s(λ) = S(c₀x² + c₁x + c₂) with S(y) = ½ + y / (2√(1 + y²))
//! and x = (λ − 360 nm) / 470 nm: always in [0, 1], smooth, and three
//! numbers. The coefficients are found per colour by Gauss–Newton on the
//! CIELAB difference between the colour asked for and the colour of the
//! spectrum under D65, as the paper does; the paper and pbrt precompute
//! them over a 64³ grid for textures, while lenspath, whose colours are
//! per material, fits each colour exactly when the scene is compiled
//! (about 0.1 ms a colour). A path from mid grey to the colour, each step
//! starting at the last one's answer, keeps the fit converging for
//! saturated colours (the paper walks its grid outward for the same reason).

use std::sync::OnceLock;

use glam::{DMat3, DVec3, Vec4};

use super::cie::{tables, trapezoid_weight, SAMPLES};
use super::{LAMBDA_MAX_NM, LAMBDA_MIN_NM};
use crate::math::Rgb;

/// Steps of the path from grey to the target colour.
const CONTINUATION_STEPS: usize = 8;
/// Gauss–Newton iterations per step at most.
const MAX_ITERATIONS: usize = 30;
/// Converged when the CIELAB distance is below this.
const LAB_TOLERANCE: f64 = 1e-7;

/// The smooth spectrum S(c₀x² + c₁x + c₂), x = (λ − 360) / 470, with
/// values in [0, 1]. Coefficients ±∞ in `c2` (with `c0 = c1 = 0`) give the
/// constants 0 and 1.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SigmoidPolynomial {
    /// c₀, c₁, c₂ of the polynomial in the normalised wavelength.
    pub coefficients: [f32; 3],
}

/// S(y) = ½ + y / (2√(1 + y²)), the sigmoid that keeps a spectrum in (0, 1).
#[inline(always)]
fn sigmoid(y: f64) -> f64 {
    if y.is_infinite() {
        return if y > 0.0 { 1.0 } else { 0.0 };
    }
    0.5 + y / (2.0 * (1.0 + y * y).sqrt())
}

/// The y with S(y) = v, for a grey: ±∞ at 0 and 1.
fn inverse_sigmoid(v: f64) -> f64 {
    if v <= 0.0 {
        f64::NEG_INFINITY
    } else if v >= 1.0 {
        f64::INFINITY
    } else {
        (v - 0.5) / (v * (1.0 - v)).sqrt()
    }
}

/// The normalised wavelength of the fit's `i`-th 1 nm sample.
fn sample_x(i: usize) -> f64 {
    i as f64 / f64::from(LAMBDA_MAX_NM - LAMBDA_MIN_NM)
}

/// CIELAB of `xyz` relative to `white` (CIE 15:2004).
fn lab(xyz: DVec3, white: DVec3) -> DVec3 {
    let f = |t: f64| {
        const DELTA: f64 = 6.0 / 29.0;
        if t > DELTA * DELTA * DELTA {
            t.cbrt()
        } else {
            t / (3.0 * DELTA * DELTA) + 4.0 / 29.0
        }
    };
    let (fx, fy, fz) = (f(xyz.x / white.x), f(xyz.y / white.y), f(xyz.z / white.z));
    DVec3::new(116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz))
}

/// What the fit integrates with: per 1 nm sample, D65 x̄ȳz̄ / ∫ȳ, and the white.
struct FitWeights {
    xyz: Vec<DVec3>,
    white: DVec3,
}

fn fit_weights() -> &'static FitWeights {
    static WEIGHTS: OnceLock<FitWeights> = OnceLock::new();
    WEIGHTS.get_or_init(|| {
        let t = tables();
        let xyz = (0..SAMPLES)
            .map(|i| {
                let lambda = LAMBDA_MIN_NM + i as f32;
                let w = trapezoid_weight(i);
                t.xyz_bar(lambda).as_dvec3() * (f64::from(t.d65(lambda)) * w / f64::from(t.y_integral))
            })
            .collect();
        FitWeights {
            xyz,
            white: t.white_xyz.as_dvec3(),
        }
    })
}

/// CIE XYZ under D65 of the spectrum with coefficients `c`.
fn xyz_of(c: DVec3, weights: &FitWeights) -> DVec3 {
    weights
        .xyz
        .iter()
        .enumerate()
        .map(|(i, w)| {
            let x = sample_x(i);
            *w * sigmoid((c.x * x + c.y) * x + c.z)
        })
        .sum()
}

impl SigmoidPolynomial {
    /// The spectrum that is 0 everywhere.
    pub const ZERO: SigmoidPolynomial = SigmoidPolynomial {
        coefficients: [0.0, 0.0, f32::NEG_INFINITY],
    };

    /// The smooth spectrum in [0, 1] whose colour under D65 is the linear
    /// sRGB `rgb` (components clamped to [0, 1]).
    pub fn fit(rgb: Rgb) -> Self {
        let target = rgb.as_dvec3().clamp(DVec3::ZERO, DVec3::ONE);
        let target = if target.is_nan() { DVec3::ZERO } else { target };
        if target.x == target.y && target.y == target.z {
            return SigmoidPolynomial {
                coefficients: [0.0, 0.0, inverse_sigmoid(target.x) as f32],
            };
        }
        let weights = fit_weights();
        let xyz_from_rgb = tables().rgb_to_xyz_f64();
        let start = DVec3::splat(0.5);
        let mut c = DVec3::ZERO;
        for step in 1..=CONTINUATION_STEPS {
            let t = step as f64 / CONTINUATION_STEPS as f64;
            let goal = lab(xyz_from_rgb * start.lerp(target, t), weights.white);
            c = gauss_newton(c, goal, weights);
        }
        SigmoidPolynomial {
            coefficients: c.as_vec3().to_array(),
        }
    }

    /// An unbounded non-negative colour as `(fit of rgb / scale, scale)` with
    /// `scale` twice its largest component, so the fitted colour's largest
    /// component is ½, where the sigmoid has room both ways (pbrt-v4).
    pub fn fit_scaled(rgb: Rgb) -> (Self, f32) {
        let rgb = rgb.max(Rgb::ZERO);
        let m = rgb.max_element();
        if !(m > 0.0 && m.is_finite()) {
            return (SigmoidPolynomial::ZERO, 0.0);
        }
        (SigmoidPolynomial::fit(rgb / (2.0 * m)), 2.0 * m)
    }

    /// True for the spectrum that is zero everywhere.
    pub fn is_zero(&self) -> bool {
        self.coefficients == SigmoidPolynomial::ZERO.coefficients
    }

    /// The spectrum's value at one wavelength, nm.
    pub fn at(&self, lambda_nm: f32) -> f32 {
        self.eval4(Vec4::splat(lambda_nm)).x
    }

    /// The spectrum's values at four wavelengths, nm (the path loop's inner
    /// operation: four lanes at once).
    #[inline(always)]
    pub fn eval4(&self, lambda_nm: Vec4) -> Vec4 {
        let [c0, c1, c2] = self.coefficients;
        if c2.is_infinite() {
            return Vec4::splat(if c2 > 0.0 { 1.0 } else { 0.0 });
        }
        let x = (lambda_nm - Vec4::splat(LAMBDA_MIN_NM)) * (1.0 / (LAMBDA_MAX_NM - LAMBDA_MIN_NM));
        let y = (x * c0 + Vec4::splat(c1)) * x + Vec4::splat(c2);
        Vec4::splat(0.5) + y * 0.5 / (Vec4::ONE + y * y).sqrt()
    }
}

/// Gauss–Newton from `c` toward the coefficients whose CIELAB is `goal`,
/// with a forward-difference Jacobian and step halving when a step does
/// not reduce the error.
fn gauss_newton(mut c: DVec3, goal: DVec3, weights: &FitWeights) -> DVec3 {
    let residual = |c: DVec3| lab(xyz_of(c, weights), weights.white) - goal;
    let mut r = residual(c);
    for _ in 0..MAX_ITERATIONS {
        if r.length() < LAB_TOLERANCE {
            break;
        }
        const H: f64 = 1e-6;
        let jacobian = DMat3::from_cols(
            (residual(c + DVec3::X * H) - r) / H,
            (residual(c + DVec3::Y * H) - r) / H,
            (residual(c + DVec3::Z * H) - r) / H,
        );
        if jacobian.determinant().abs() < 1e-300 {
            break;
        }
        let step = jacobian.inverse() * r;
        let mut scale = 1.0;
        let mut improved = false;
        while scale > 1e-4 {
            let next = c - step * scale;
            let r_next = residual(next);
            if r_next.is_finite() && r_next.length() < r.length() {
                c = next;
                r = r_next;
                improved = true;
                break;
            }
            scale *= 0.5;
        }
        if !improved {
            break;
        }
    }
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    /// Jakob & Hanika's claim and the issue's: every colour of a 16³ grid
    /// over the sRGB cube comes back from its spectrum within 1e-3, and the
    /// spectrum stays in [0, 1].
    #[test]
    fn srgb_grid_round_trips_through_spectra() {
        let t = tables();
        let mut worst = (0.0f32, Vec3::ZERO);
        for r in 0..16 {
            for g in 0..16 {
                for b in 0..16 {
                    let rgb = Vec3::new(r as f32, g as f32, b as f32) / 15.0;
                    let s = SigmoidPolynomial::fit(rgb);
                    let back = t.reflectance_to_rgb(|l| s.at(l));
                    let err = (back - rgb).abs().max_element();
                    if err > worst.0 {
                        worst = (err, rgb);
                    }
                    for l in (360..=830).step_by(10) {
                        let v = s.at(l as f32);
                        assert!((0.0..=1.0).contains(&v), "{rgb}: s({l}) = {v}");
                    }
                }
            }
        }
        assert!(worst.0 < 1e-3, "worst round trip {} at {}", worst.0, worst.1);
    }

    /// Greys are constant spectra, exactly; an emitter's scaled fit keeps
    /// its colour and brightness.
    #[test]
    fn greys_are_flat_and_scaled_fits_keep_the_colour() {
        for v in [0.0, 0.18, 0.5, 1.0] {
            let s = SigmoidPolynomial::fit(Vec3::splat(v));
            for l in [380.0, 555.0, 800.0] {
                assert!((s.at(l) - v).abs() < 1e-6, "{v} at {l}: {}", s.at(l));
            }
        }
        let emission = Vec3::new(17.0, 12.0, 4.0);
        let (s, scale) = SigmoidPolynomial::fit_scaled(emission);
        let t = tables();
        let back = t.reflectance_to_rgb(|l| s.at(l) * scale);
        assert!((back - emission).abs().max_element() < 1e-3 * 17.0, "{back}");
        assert_eq!(SigmoidPolynomial::fit_scaled(Vec3::ZERO).1, 0.0);
    }
}
