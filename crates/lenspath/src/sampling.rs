//! Sample generation and warping: the per-pixel Owen-scrambled Sobol
//! sampler, a small PRNG for tests and tools, the standard warps from the
//! unit square, and a piecewise-constant 1D distribution.

use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_PI_4, PI};

use crate::names::Named;

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

/// The most samples per pixel the Sobol sampler supports: its tables hold
/// 16 bits of the sample index, as `sobol_burley`'s do.
pub const MAX_SAMPLES_PER_PIXEL: u32 = 1 << 16;

/// Which sample sequence a render draws from (pbrt-v4's `Sampler` types
/// `sobol` and `independent`, Mitsuba 3's `independent`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SamplerKind {
    /// Owen-scrambled Sobol points: stratified in every dimension, so less
    /// noise at the same samples per pixel (the default).
    #[default]
    Sobol,
    /// Independent uniform random numbers (PCG32): no stratification, the
    /// cheapest to draw; what Mitsuba's and pbrt's `independent` samplers give.
    Independent,
}

impl Named for SamplerKind {
    const WHAT: &'static str = "sampler";
    const NAMED: &'static [(SamplerKind, &'static str)] =
        &[(SamplerKind::Sobol, "sobol"), (SamplerKind::Independent, "independent")];
}

/// The sample stream of one pixel sample: Owen-scrambled Sobol samples
/// (Burley, "Practical Hash-based Owen Scrambling", JCGT 2020; the points
/// are the `sobol_burley` crate's, bit for bit) or independent PCG32
/// numbers. The stream depends only on the kind, the pixel, the sample
/// index and the seed, never on the thread or tile that draws it, which
/// makes renders bit-identical for any thread count.
///
/// Sobol dimensions are drawn four at a time, padded (Burley 2020, §4):
/// every 4D set is the first four Sobol dimensions, the best stratified,
/// under a seed of its own (the index shuffled and the digits scrambled
/// afresh), so each set is a stratified 4D point set of the pixel's samples
/// and the sets are independent of one another, with no limit on their
/// number. This leaves less error than taking the sets as consecutive
/// dimensions of one 256-dimensional sequence, whose higher dimensions' 2D
/// projections are poorly stratified (BENCHMARKS.md).
pub struct Sampler(Source);

/// Where a [`Sampler`]'s numbers come from.
enum Source {
    Sobol(SobolStream),
    Independent(Pcg32),
}

impl Sampler {
    /// The sampler of sample `index` of pixel `(x, y)` under `seed`.
    // Inlined, as `SobolStream::next`, so its first sets are made in the
    // path loop's AVX2 copy rather than in baseline x86-64 code.
    #[inline(always)]
    pub fn new(kind: SamplerKind, x: u32, y: u32, index: u32, seed: u32) -> Self {
        let pixel_seed = hash_u32(x.wrapping_mul(0x9E3779B1) ^ hash_u32(y ^ hash_u32(seed.wrapping_add(0x85EBCA6B))));
        Sampler(match kind {
            SamplerKind::Sobol => Source::Sobol(SobolStream {
                seed: pixel_seed,
                index,
                next_set: SETS_DRAWN_TOGETHER as u32,
                buffer: [[0.0; 4]; SETS_DRAWN_TOGETHER],
                used: 4 * SETS_DRAWN_TOGETHER,
                ahead: SobolStream::sets(pixel_seed, index, 0),
            }),
            // As Mitsuba's independent sampler: one PCG32 stream per pixel,
            // each sample starting at a hashed state (2^64 of them: runs of
            // a few hundred numbers do not meet). pbrt-v4 jumps 2^16 numbers
            // ahead per sample instead, which costs 3% of a render here.
            SamplerKind::Independent => Source::Independent(Pcg32::new(
                u64::from(pixel_seed),
                mix64((u64::from(seed) << 32) | u64::from(index)),
            )),
        })
    }

    /// The next dimension, in [0, 1).
    #[inline(always)]
    pub fn get_1d(&mut self) -> f32 {
        match &mut self.0 {
            Source::Sobol(sobol) => sobol.next(),
            Source::Independent(rng) => rng.uniform(),
        }
    }

    /// The next two dimensions, in [0, 1)².
    #[inline(always)]
    pub fn get_2d(&mut self) -> Vec2 {
        match &mut self.0 {
            Source::Sobol(sobol) => {
                // Keep pairs inside one 4D set so they stay jointly stratified.
                if sobol.used % 4 == 3 {
                    sobol.used += 1;
                }
                Vec2::new(sobol.next(), sobol.next())
            }
            Source::Independent(rng) => Vec2::new(rng.uniform(), rng.uniform()),
        }
    }
}

/// One pixel sample's Owen-scrambled Sobol dimensions.
struct SobolStream {
    seed: u32,
    index: u32,
    /// The first 4D set of the draw after `ahead`'s.
    next_set: u32,
    /// The sets drawn last, and how many of their dimensions are used.
    buffer: [[f32; 4]; SETS_DRAWN_TOGETHER],
    used: usize,
    /// The sets after them, made one refill before they are used: their
    /// chain of dependent multiplies (some hundred cycles) then runs beside
    /// the path's other work instead of holding up the first dimension
    /// asked of them (BENCHMARKS.md, "the Sobol sets made a refill ahead").
    ahead: [[f32; 4]; SETS_DRAWN_TOGETHER],
}

/// How many 4D sets a Sobol stream draws at once: two fill one AVX2
/// register, so one pass of vector instructions makes both (a path's vertex
/// uses two sets: its light sample, and its scattering and roulette). Four
/// measured no faster (BENCHMARKS.md, issue 34).
const SETS_DRAWN_TOGETHER: usize = 2;

impl SobolStream {
    /// The next dimension.
    // Inlined into every copy of the path loop (see `render::render_tile`):
    // out of line it is compiled for baseline x86-64 only, where a lane
    // multiply and a bit reverse take several instructions each.
    #[inline(always)]
    fn next(&mut self) -> f32 {
        if self.used == 4 * SETS_DRAWN_TOGETHER {
            self.buffer = self.ahead;
            self.ahead = Self::sets(self.seed, self.index, self.next_set);
            self.next_set += SETS_DRAWN_TOGETHER as u32;
            self.used = 0;
        }
        let v = self.buffer[self.used / 4][self.used % 4];
        self.used += 1;
        v
    }

    /// The [`SETS_DRAWN_TOGETHER`] sets from set `first` on, of sample
    /// `index` of the pixel seeded `seed`.
    #[inline(always)]
    fn sets(seed: u32, index: u32, first: u32) -> [[f32; 4]; SETS_DRAWN_TOGETHER] {
        let seeds = std::array::from_fn(|k| hash_u32(seed ^ (first + k as u32).wrapping_mul(0x632B_E5AB)));
        sobol_4d_sets(index, seeds)
    }
}

/// The first four Sobol dimensions' direction vectors (Joe & Kuo 2008), in
/// the bit-reversed form `sobol_burley` computes with: row `p` is added for
/// bit `p`, counted from the top, of the reversed (shuffled) sample index.
const SOBOL_REV_VECTORS: [[u32; 4]; 16] = [
    [0x0001, 0x0001, 0x0001, 0x0001],
    [0x0002, 0x0003, 0x0003, 0x0003],
    [0x0004, 0x0005, 0x0006, 0x0004],
    [0x0008, 0x000f, 0x0009, 0x000a],
    [0x0010, 0x0011, 0x0017, 0x001f],
    [0x0020, 0x0033, 0x003a, 0x002e],
    [0x0040, 0x0055, 0x0071, 0x0045],
    [0x0080, 0x00ff, 0x00a3, 0x00c9],
    [0x0100, 0x0101, 0x0116, 0x011b],
    [0x0200, 0x0303, 0x0339, 0x02a4],
    [0x0400, 0x0505, 0x0677, 0x079a],
    [0x0800, 0x0f0f, 0x09aa, 0x0b67],
    [0x1000, 0x1111, 0x1601, 0x101e],
    [0x2000, 0x3333, 0x3903, 0x302d],
    [0x4000, 0x5555, 0x7706, 0x4041],
    [0x8000, 0xffff, 0xaa09, 0xa0c3],
];

/// For each of the reversed index's top two bytes, the sum (XOR) of the
/// direction vectors of every byte value's set bits: a point of the first
/// four dimensions is two lookups instead of a loop over up to 16 bits.
static SOBOL_BYTE_SUMS: [[[u32; 4]; 256]; 2] = sobol_byte_sums();

/// [`SOBOL_BYTE_SUMS`], computed by the compiler.
const fn sobol_byte_sums() -> [[[u32; 4]; 256]; 2] {
    let mut sums = [[[0u32; 4]; 256]; 2];
    let mut byte = 0;
    while byte < 2 {
        let mut value = 0;
        while value < 256 {
            let mut bit = 0;
            while bit < 8 {
                // Bit 7 of the byte is the top one: row 8 × byte + 0.
                if value & (0x80 >> bit) != 0 {
                    let row = SOBOL_REV_VECTORS[8 * byte + bit];
                    let mut lane = 0;
                    while lane < 4 {
                        sums[byte][value][lane] ^= row[lane];
                        lane += 1;
                    }
                }
                bit += 1;
            }
            value += 1;
        }
        byte += 1;
    }
    sums
}

/// The first four Owen-scrambled Sobol dimensions of sample `index` under
/// each of `seeds`: for each, bit for bit `sobol_burley::sample_4d(index,
/// 0, seed)` (Burley 2020: the index shuffled by a nested uniform scramble,
/// each dimension scrambled after), with its loop over the index's bits
/// replaced by [`SOBOL_BYTE_SUMS`]. The padded stream draws its sets here,
/// several at once.
///
/// Written over plain `[u32; 4]` lanes rather than the crate's `Int4`: the
/// crate is compiled for baseline x86-64, where its lane multiply is a
/// six-instruction SSE2 emulation even inside the path loop's AVX2 copy;
/// plain lanes let that copy use `vpmulld` and a byte-shuffle bit reverse.
#[inline(always)]
fn sobol_4d_sets<const SETS: usize>(index: u32, seeds: [u32; SETS]) -> [[f32; 4]; SETS] {
    let index_rev = index.reverse_bits();
    // The per-dimension scrambles, as the crate makes them for dimension set 0.
    let salts = [0x912f_69ba, 0x174f_18ab, 0x691e_72ca, 0xb40c_c1b8];
    let mut sobol_rev = [[0u32; 4]; SETS];
    let mut scrambles = [[0u32; 4]; SETS];
    for (set, seed) in seeds.into_iter().enumerate() {
        let shuffled_rev = owen_scramble_rev(index_rev, burley_hash(seed ^ 0x79c6_8e4a));
        let high = &SOBOL_BYTE_SUMS[0][(shuffled_rev >> 24) as usize];
        let low = &SOBOL_BYTE_SUMS[1][((shuffled_rev >> 16) & 0xff) as usize];
        let seed = seed.wrapping_mul(0x9c8f_2d3b);
        for d in 0..4 {
            sobol_rev[set][d] = high[d] ^ low[d];
            scrambles[set][d] = burley_hash(seed ^ salts[d]);
        }
    }
    let mut points = [[0.0; 4]; SETS];
    for set in 0..SETS {
        for d in 0..4 {
            let scrambled_rev = owen_scramble_rev(sobol_rev[set][d], scrambles[set][d]);
            points[set][d] = u32_to_unit_f32(scrambled_rev.reverse_bits());
        }
    }
    points
}

/// Burley's (2020) hash-based nested uniform scramble of a bit-reversed
/// integer: one of the Owen scrambles, picked by `scramble` (which must be
/// well mixed already). The constants are his, from
/// <https://psychopath.io/post/2021_01_30_building_a_better_lk_hash>.
#[inline(always)]
fn owen_scramble_rev(mut n_rev: u32, scramble: u32) -> u32 {
    n_rev ^= n_rev.wrapping_mul(0x3d20_adea);
    n_rev = n_rev.wrapping_add(scramble);
    n_rev = n_rev.wrapping_mul((scramble >> 16) | 1);
    n_rev ^= n_rev.wrapping_mul(0x0552_6c56);
    n_rev ^= n_rev.wrapping_mul(0x53a2_2864);
    n_rev
}

/// The hash Burley's sampler makes its scrambles with: [`hash_u32`] with
/// its input offset, so that 0 does not map to 0.
#[inline(always)]
fn burley_hash(n: u32) -> u32 {
    hash_u32(n ^ 0xe6fe_3beb)
}

/// The top 23 bits of `n` as a float in [0, 1), exactly (as the crate's
/// `u32_to_f32_norm`): they become the mantissa of a number in [1, 2).
#[inline(always)]
fn u32_to_unit_f32(n: u32) -> f32 {
    f32::from_bits((n >> 9) | 0x3f80_0000) - 1.0
}

/// SplitMix64's finalizer (Steele et al. 2014): a bijective 64-bit hash.
#[inline]
pub(crate) fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58476D1CE4E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D049BB133111EB);
    z ^ (z >> 31)
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
        mix64(self.0)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
    }
}

/// PCG32 (O'Neill, "PCG: A Family of Simple Fast Space-Efficient
/// Statistically Good Algorithms for Random Number Generation", 2014;
/// the XSH-RR variant pbrt-v4's `RNG` and Mitsuba's `PCG32` use): 2^63 streams of
/// period 2^64.
#[derive(Clone, Debug)]
struct Pcg32 {
    state: u64,
    increment: u64,
}

const PCG32_MULTIPLIER: u64 = 0x5851_F42D_4C95_7F2D;

impl Pcg32 {
    /// Stream `sequence`, started from `seed` (pbrt's `SetSequence`).
    fn new(sequence: u64, seed: u64) -> Self {
        let mut rng = Pcg32 {
            state: 0,
            increment: (sequence << 1) | 1,
        };
        rng.next_u32();
        rng.state = rng.state.wrapping_add(seed);
        rng.next_u32();
        rng
    }

    /// The next 32 random bits.
    #[inline]
    fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old.wrapping_mul(PCG32_MULTIPLIER).wrapping_add(self.increment);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        xorshifted.rotate_right((old >> 59) as u32)
    }

    /// Uniform in [0, 1): the top 24 bits, so every value is exact in f32
    /// and 1 cannot come out by rounding.
    #[inline]
    fn uniform(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
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
    // The angle from the major axis is π/4 · minor/major, within ±π/4, where
    // two short polynomials give its sine and cosine (no libm call, which
    // showed in render profiles).
    // Selects, not branches: which axis is major is a coin toss per sample,
    // and a mispredicted branch costs more than the selects.
    let x_major = o.x.abs() > o.y.abs();
    let (major, minor) = if x_major { (o.x, o.y) } else { (o.y, o.x) };
    let (sin, cos) = sin_cos_quarter_turn(FRAC_PI_4 * (minor / major));
    // With y major, θ = π/2 − φ: cos θ = sin φ and sin θ = cos φ.
    let direction = if x_major {
        Vec2::new(cos, sin)
    } else {
        Vec2::new(sin, cos)
    };
    major * direction
}

/// `(sin x, cos x)` for |x| ≤ π/4, without range reduction: the minimax
/// polynomials of Moshier's Cephes `sinf` and `cosf` (relative error
/// 1.7·10⁻⁸ in exact arithmetic; within 2·10⁻⁷ in `f32`, see the test).
#[inline]
fn sin_cos_quarter_turn(x: f32) -> (f32, f32) {
    let z = x * x;
    let sin = ((-1.951_529_6e-4 * z + 8.332_161e-3) * z - 1.666_665_5e-1) * z * x + x;
    let cos = ((2.443_315_7e-5 * z - 1.388_731_6e-3) * z + 4.166_664_6e-2) * z * z - 0.5 * z + 1.0;
    (sin, cos)
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
    #[inline]
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
        for kind in [SamplerKind::Sobol, SamplerKind::Independent] {
            let mut a = Sampler::new(kind, 3, 4, 5, 6);
            let mut b = Sampler::new(kind, 3, 4, 5, 6);
            let mut c = Sampler::new(kind, 4, 3, 5, 6);
            let mut d = Sampler::new(kind, 3, 4, 6, 6);
            let (mut differs, mut differs_by_index) = (false, false);
            for _ in 0..600 {
                let (x, y, z, w) = (a.get_1d(), b.get_1d(), c.get_1d(), d.get_1d());
                assert_eq!(x, y);
                assert!((0.0..1.0).contains(&x));
                differs |= x != z;
                differs_by_index |= x != w;
            }
            assert!(differs, "{kind:?}: different pixels must get different sequences");
            assert!(
                differs_by_index,
                "{kind:?}: different samples must get different sequences"
            );
        }
    }

    /// PCG32's reference output (pcg32-demo's `pcg32_srandom(42, 54)`, the
    /// first six numbers): the generator is the published one.
    #[test]
    fn pcg32_matches_the_reference_stream() {
        let mut rng = Pcg32::new(54, 42);
        let first: Vec<u32> = (0..6).map(|_| rng.next_u32()).collect();
        assert_eq!(
            first,
            [0xa15c02b7, 0x7b47f409, 0xba1d3330, 0x83d2f293, 0xbfa4784b, 0xcbed606e]
        );
    }

    /// Independent samples are uniform: the mean and the variance of many
    /// draws match those of U[0, 1) within five standard errors, and
    /// consecutive draws are uncorrelated.
    #[test]
    fn independent_samples_are_uniform_and_uncorrelated() {
        let n = 100_000;
        let mut values = Vec::with_capacity(n);
        for index in 0..(n / 10) as u32 {
            let mut s = Sampler::new(SamplerKind::Independent, 1, 2, index, 3);
            values.extend((0..10).map(|_| f64::from(s.get_1d())));
        }
        let mean = values.iter().sum::<f64>() / n as f64;
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n as f64;
        let lag1 = values.windows(2).map(|w| (w[0] - mean) * (w[1] - mean)).sum::<f64>() / (n - 1) as f64 / var;
        let se = (1.0 / 12.0 / n as f64).sqrt();
        assert!((mean - 0.5).abs() < 5.0 * se, "mean {mean}");
        assert!((var - 1.0 / 12.0).abs() < 0.002, "variance {var}");
        assert!(lag1.abs() < 5.0 / (n as f64).sqrt(), "lag-1 correlation {lag1}");
    }

    /// The first dimensions of 256 samples are stratified: each of 256
    /// intervals of [0, 1) holds exactly one sample (a (0,1)-sequence property).
    #[test]
    fn sobol_dimension_is_stratified() {
        let mut seen = [0u32; 256];
        for i in 0..256 {
            let u = Sampler::new(SamplerKind::Sobol, 10, 20, i, 1).get_1d();
            seen[(u * 256.0) as usize] += 1;
        }
        assert!(seen.iter().all(|&n| n == 1));
    }

    /// The table-driven points are the crate's, bit for bit, over every
    /// index the sampler allows and several seeds, drawn as the stream draws
    /// them ([`SETS_DRAWN_TOGETHER`] seeds at once).
    #[test]
    fn table_sobol_matches_the_crate() {
        for first_seed in [0, 1, 0x1234_5678, u32::MAX, hash_u32(7), hash_u32(8)] {
            let seeds: [u32; SETS_DRAWN_TOGETHER] = std::array::from_fn(|k| first_seed ^ hash_u32(k as u32));
            for index in 0..MAX_SAMPLES_PER_PIXEL {
                let sets = sobol_4d_sets(index, seeds);
                for (set, seed) in sets.into_iter().zip(seeds) {
                    assert_eq!(
                        set.map(f32::to_bits),
                        sobol_burley::sample_4d(index, 0, seed).map(f32::to_bits),
                        "index {index}, seed {seed}"
                    );
                }
            }
        }
    }

    /// Padding: every 4D set, however far along the stream, is stratified
    /// as the sequence's first dimensions are: the pair opening set k of a
    /// pixel's 256 samples puts one point in each cell of a 16 × 16 grid
    /// (and of 256 × 1 and 1 × 256), and two sets are not the same points.
    #[test]
    fn every_sobol_set_is_a_stratified_net() {
        for set in [1usize, 7, 63, 64, 65, 300] {
            let pairs: Vec<Vec2> = (0..256)
                .map(|i| {
                    let mut sampler = Sampler::new(SamplerKind::Sobol, 3, 5, i, 9);
                    (0..set).for_each(|_| {
                        sampler.get_2d();
                        sampler.get_2d();
                    });
                    sampler.get_2d()
                })
                .collect();
            for (nx, ny) in [(16, 16), (256, 1), (1, 256), (2, 128), (128, 2)] {
                let mut cells = vec![0u32; 256];
                for p in &pairs {
                    cells[(p.y * ny as f32) as usize * nx + (p.x * nx as f32) as usize] += 1;
                }
                assert!(
                    cells.iter().all(|&n| n == 1),
                    "set {set}: not stratified in {nx} × {ny} cells"
                );
            }
        }
        let first = |set: usize| {
            let mut sampler = Sampler::new(SamplerKind::Sobol, 3, 5, 0, 9);
            (0..4 * set).for_each(|_| {
                sampler.get_1d();
            });
            sampler.get_1d()
        };
        assert_ne!(first(1), first(2));
    }

    /// The polynomials agree with the exact sine and cosine over ±π/4 to
    /// float precision, and the disk map with its textbook form (the angle
    /// measured from +x, through libm in f64).
    #[test]
    fn quarter_turn_sin_cos_and_disk_are_exact_to_float_precision() {
        let n = 200_000;
        let worst = (0..=n)
            .map(|k| {
                let x = FRAC_PI_4 * (2.0 * k as f32 / n as f32 - 1.0);
                let (sin, cos) = sin_cos_quarter_turn(x);
                let exact = f64::from(x).sin_cos();
                (f64::from(sin) - exact.0).abs().max((f64::from(cos) - exact.1).abs())
            })
            .fold(0.0, f64::max);
        assert!(worst < 2e-7, "largest error {worst:e}");
        let mut rng = Rng::new(7);
        for _ in 0..100_000 {
            let u = Vec2::new(rng.uniform(), rng.uniform());
            let o = (2.0 * u - Vec2::ONE).as_dvec2();
            let (r, theta) = if o.x.abs() > o.y.abs() {
                (o.x, std::f64::consts::FRAC_PI_4 * (o.y / o.x))
            } else {
                (
                    o.y,
                    std::f64::consts::FRAC_PI_2 - std::f64::consts::FRAC_PI_4 * (o.x / o.y),
                )
            };
            let exact = r * glam::DVec2::new(theta.cos(), theta.sin());
            let error = (concentric_disk(u).as_dvec2() - exact).length();
            assert!(error < 3e-7, "u {u}: {error:e}");
        }
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
