//! Sample generation and warping: the per-pixel Owen-scrambled Sobol
//! sampler, a small PRNG for tests and tools, the standard warps from the
//! unit square, and a piecewise-constant 1D distribution.

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4, PI};

/// Hash of 32 bits (Wellons' "lowbias32", a well-mixed integer hash).
#[inline]
pub fn hash_u32(mut x: u32) -> u32 {
    x ^= x >> 16;
    x = x.wrapping_mul(0x7feb352d);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846ca68b);
    x ^= x >> 16;
    x
}

/// The most samples per pixel the Sobol sampler supports (a sobol_burley limit).
pub const MAX_SAMPLES_PER_PIXEL: u32 = 1 << 16;

/// Owen-scrambled Sobol samples (Burley, "Practical Hash-based Owen
/// Scrambling", JCGT 2020, via the `sobol_burley` crate) for one pixel
/// sample. The stream depends only on the pixel, the sample index and the
/// seed, never on the thread or tile that draws it, which makes renders
/// bit-identical for any thread count.
///
/// Dimensions are drawn four at a time; past the crate's 256 dimensions
/// the sequence continues with a re-hashed seed (decorrelated, no longer
/// stratified against the first dimensions).
pub struct Sampler {
    seed: u32,
    index: u32,
    next_set: u32,
    buffer: [f32; 4],
    used: usize,
}

impl Sampler {
    /// The sampler of sample `index` of pixel `(x, y)` under `seed`.
    pub fn new(x: u32, y: u32, index: u32, seed: u32) -> Self {
        let pixel_seed = hash_u32(x.wrapping_mul(0x9E3779B1) ^ hash_u32(y ^ hash_u32(seed.wrapping_add(0x85EBCA6B))));
        Sampler {
            seed: pixel_seed,
            index,
            next_set: 0,
            buffer: [0.0; 4],
            used: 4,
        }
    }

    /// The next dimension, in [0, 1).
    #[inline]
    pub fn get_1d(&mut self) -> f32 {
        if self.used == 4 {
            let set = self.next_set % sobol_burley::NUM_DIMENSION_SETS_4D;
            let round = self.next_set / sobol_burley::NUM_DIMENSION_SETS_4D;
            let seed = if round == 0 {
                self.seed
            } else {
                hash_u32(self.seed ^ round.wrapping_mul(0x632BE5AB))
            };
            self.buffer = sobol_burley::sample_4d(self.index, set, seed);
            self.next_set += 1;
            self.used = 0;
        }
        let v = self.buffer[self.used];
        self.used += 1;
        v
    }

    /// The next two dimensions, in [0, 1)².
    #[inline]
    pub fn get_2d(&mut self) -> Vec2 {
        // Keep pairs inside one 4D set so they stay jointly stratified.
        if self.used == 3 {
            self.used = 4;
        }
        Vec2::new(self.get_1d(), self.get_1d())
    }
}

/// A small, fast PRNG (SplitMix64) for tests, benchmarks and tools: not for rendering.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Rng(seed ^ 0x9E3779B97F4A7C15)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E3779B97F4A7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }
}

/// Uniform direction on the unit sphere; pdf 1/(4π).
#[inline]
pub fn uniform_sphere(u0: f32, u1: f32) -> Vec3 {
    let z = 1.0 - 2.0 * u0;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = 2.0 * PI * u1;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// Density of [`uniform_sphere`] per solid angle.
pub const UNIFORM_SPHERE_PDF: f32 = 1.0 / (4.0 * PI);

/// Point on the unit disk by Shirley–Chiu's concentric map (area-preserving).
#[inline]
pub fn concentric_disk(u: Vec2) -> Vec2 {
    let o = 2.0 * u - Vec2::ONE;
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    let (r, theta) = if o.x.abs() > o.y.abs() {
        (o.x, FRAC_PI_4 * (o.y / o.x))
    } else {
        (o.y, FRAC_PI_2 - FRAC_PI_4 * (o.x / o.y))
    };
    r * Vec2::new(theta.cos(), theta.sin())
}

/// Cosine-weighted direction in the +z hemisphere (Malley's method); pdf cosθ/π.
#[inline]
pub fn cosine_hemisphere(u: Vec2) -> Vec3 {
    let d = concentric_disk(u);
    let z = (1.0 - d.length_squared()).max(0.0).sqrt();
    Vec3::new(d.x, d.y, z)
}

/// Uniform barycentrics `(b0, b1, b2)` on a triangle (Heitz, "A Low-Distortion
/// Map Between Triangle and Square", 2019, as pbrt-v4 `SampleUniformTriangle`).
#[inline]
pub fn uniform_triangle(u: Vec2) -> [f32; 3] {
    let (b0, b1) = if u.x < u.y {
        let b0 = u.x / 2.0;
        (b0, u.y - b0)
    } else {
        let b1 = u.y / 2.0;
        (u.x - b1, b1)
    };
    [b0, b1, 1.0 - b0 - b1]
}

/// Veach's power heuristic (β = 2) for a sample from strategy `f` with
/// `nf` samples, against strategy `g` with `ng` samples.
#[inline]
pub fn power_heuristic(nf: f32, f_pdf: f32, ng: f32, g_pdf: f32) -> f32 {
    let f = nf * f_pdf;
    let g = ng * g_pdf;
    if f.is_infinite() {
        return 1.0;
    }
    if f == 0.0 && g == 0.0 {
        return 0.0;
    }
    (f * f) / (f * f + g * g)
}

/// A piecewise-constant distribution over `n` items, sampled by inverting its CDF.
#[derive(Clone, Debug)]
pub struct Distribution1D {
    cdf: Vec<f32>,
}

impl Distribution1D {
    /// A distribution proportional to `weights` (non-negative, not all zero).
    pub fn new(weights: &[f32]) -> Self {
        let mut cdf = Vec::with_capacity(weights.len() + 1);
        let mut acc = 0.0f64;
        cdf.push(0.0);
        for w in weights {
            acc += f64::from(w.max(0.0));
            cdf.push(acc as f32);
        }
        let total = acc as f32;
        for c in &mut cdf {
            *c /= total;
        }
        Distribution1D { cdf }
    }

    /// Picks an item for `u` in [0, 1): returns it, its probability, and `u`
    /// remapped to [0, 1) within the item (so it can be reused).
    pub fn sample(&self, u: f32) -> (usize, f32, f32) {
        let n = self.cdf.len() - 1;
        let i = self.cdf.partition_point(|&c| c <= u).clamp(1, n) - 1;
        let width = self.cdf[i + 1] - self.cdf[i];
        let remapped = if width > 0.0 {
            ((u - self.cdf[i]) / width).min(1.0 - f32::EPSILON)
        } else {
            0.0
        };
        (i, width, remapped)
    }
}

/// Inverse error function, single precision (Giles, "Approximating the erfinv
/// function", GPU Computing Gems, 2011), as used by pbrt-v4 `ErfInv`.
// The published coefficients are kept exactly as printed.
#[allow(clippy::excessive_precision)]
pub fn erf_inv(a: f32) -> f32 {
    let mut w = -((1.0 - a) * (1.0 + a)).max(f32::MIN_POSITIVE).ln();
    let p;
    if w < 5.0 {
        w -= 2.5;
        let mut q = 2.81022636e-08f32;
        q = 3.43273939e-07 + q * w;
        q = -3.5233877e-06 + q * w;
        q = -4.39150654e-06 + q * w;
        q = 0.00021858087 + q * w;
        q = -0.00125372503 + q * w;
        q = -0.00417768164 + q * w;
        q = 0.246640727 + q * w;
        p = 1.50140941 + q * w;
    } else {
        w = w.sqrt() - 3.0;
        let mut q = -0.000200214257f32;
        q = 0.000100950558 + q * w;
        q = 0.00134934322 + q * w;
        q = -0.00367342844 + q * w;
        q = 0.00573950773 + q * w;
        q = -0.0076224613 + q * w;
        q = 0.00943887047 + q * w;
        q = 1.00167406 + q * w;
        p = 2.83297682 + q * w;
    }
    p * a
}

/// Error function (Abramowitz and Stegun 7.1.26, |error| < 1.5e-7).
#[allow(clippy::excessive_precision)]
pub fn erf(x: f32) -> f32 {
    let t = 1.0 / (1.0 + 0.3275911 * x.abs());
    let y = 1.0
        - (((((1.061405429 * t - 1.453152027) * t) + 1.421413741) * t - 0.284496736) * t + 0.254829592)
            * t
            * (-x * x).exp();
    y.copysign(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampler_is_deterministic_and_in_range() {
        let mut a = Sampler::new(3, 4, 5, 6);
        let mut b = Sampler::new(3, 4, 5, 6);
        let mut c = Sampler::new(4, 3, 5, 6);
        let mut differs = false;
        for _ in 0..600 {
            let (x, y, z) = (a.get_1d(), b.get_1d(), c.get_1d());
            assert_eq!(x, y);
            assert!((0.0..1.0).contains(&x));
            differs |= x != z;
        }
        assert!(differs, "different pixels must get different sequences");
    }

    /// The first dimensions of 256 samples are stratified: each of 256
    /// intervals of [0, 1) holds exactly one sample (a (0,1)-sequence property).
    #[test]
    fn sobol_dimension_is_stratified() {
        let mut seen = [0u32; 256];
        for i in 0..256 {
            let u = Sampler::new(10, 20, i, 1).get_1d();
            seen[(u * 256.0) as usize] += 1;
        }
        assert!(seen.iter().all(|&n| n == 1));
    }

    #[test]
    fn warps_stay_on_their_domains() {
        let mut rng = Rng::new(1);
        for _ in 0..10_000 {
            let u = Vec2::new(rng.uniform(), rng.uniform());
            assert!((uniform_sphere(u.x, u.y).length() - 1.0).abs() < 1e-5);
            assert!(concentric_disk(u).length() <= 1.0 + 1e-6);
            let h = cosine_hemisphere(u);
            assert!(h.z >= 0.0 && (h.length() - 1.0).abs() < 1e-5);
            let b = uniform_triangle(u);
            assert!(b.iter().all(|&x| x >= -1e-7) && (b.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn distribution_samples_in_proportion() {
        let d = Distribution1D::new(&[1.0, 0.0, 3.0]);
        assert_eq!(d.sample(0.1).0, 0);
        assert_eq!(d.sample(0.3).0, 2);
        assert!((d.sample(0.3).1 - 0.75).abs() < 1e-6);
        let mut rng = Rng::new(2);
        let mut counts = [0; 3];
        for _ in 0..40_000 {
            counts[d.sample(rng.uniform()).0] += 1;
        }
        assert_eq!(counts[1], 0);
        assert!((counts[2] as f32 / 40_000.0 - 0.75).abs() < 0.01);
    }

    #[test]
    fn erf_inv_inverts_erf() {
        for i in -99..100 {
            let x = i as f32 / 100.0;
            assert!((erf(erf_inv(x)) - x).abs() < 2e-5, "x = {x}");
        }
    }

    #[test]
    fn power_heuristic_weights_sum_to_one() {
        let w1 = power_heuristic(4.0, 0.3, 1.0, 0.7);
        let w2 = power_heuristic(1.0, 0.7, 4.0, 0.3);
        assert!((w1 + w2 - 1.0).abs() < 1e-6);
    }
}
