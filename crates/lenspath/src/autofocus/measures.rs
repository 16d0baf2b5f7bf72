//! Focus measures: how sharp an image patch is, higher is sharper.
//!
//! Names and formulas follow Pertuz, Puig & Garcia, "Analysis of focus
//! measure operators for shape-from-focus", Pattern Recognition 46 (2013),
//! whose operator codes are given in brackets. Measures of colour patches
//! are computed per channel; the variance adds the channels' values, every
//! other measure combines them as √(Σ_c F_c²). Sums run over the pixels
//! where the operator's whole stencil lies inside the patch.

use crate::error::{Error, Result};
use crate::names::Named;

/// A linear RGB image patch, row-major, three floats per pixel.
#[derive(Clone, Copy, Debug)]
pub struct Patch<'a> {
    width: usize,
    height: usize,
    rgb: &'a [f32],
}

impl<'a> Patch<'a> {
    /// A `width` × `height` patch over `rgb`, which must hold `3 · width · height` values.
    pub fn new(width: usize, height: usize, rgb: &'a [f32]) -> Result<Patch<'a>> {
        if width.checked_mul(height).and_then(|n| n.checked_mul(3)) != Some(rgb.len()) {
            return Err(Error::InvalidArgument(format!(
                "a {width}x{height} RGB patch needs {} values, got {}",
                3u128 * width as u128 * height as u128,
                rgb.len()
            )));
        }
        Ok(Patch { width, height, rgb })
    }

    /// Channel `c` of pixel (x, y), widened to f64.
    #[inline]
    fn at(&self, x: usize, y: usize, c: usize) -> f64 {
        f64::from(self.rgb[3 * (y * self.width + x) + c])
    }
}

/// A focus measure.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FocusMeasure {
    /// Grey-level variance \[GLVA\]: Σ_c (1/N) Σ (I − μ_c)².
    Variance,
    /// Normalised variance \[GLVN\]: the variance of each channel over its mean, σ_c² / μ_c,
    /// so a brighter patch does not look sharper.
    NormalizedVariance,
    /// Sum-modified Laplacian \[LAPM\] (Nayar & Nakagawa 1994):
    /// ML = |2I(x,y) − I(x−s,y) − I(x+s,y)| + |2I(x,y) − I(x,y−s) − I(x,y+s)|,
    /// summed over the 3×3 window around each pixel, then over the patch; `step` is s.
    SumModifiedLaplacian {
        /// Distance s, in pixels, of the Laplacian's neighbours.
        step: usize,
    },
    /// Tenengrad \[TENG\]: Σ (Gx² + Gy²) with the 3×3 Sobel operators. The default.
    #[default]
    Tenengrad,
    /// Brenner's gradient \[BREN\]: Σ max(I(x+2,y) − I(x,y), I(x,y+2) − I(x,y))².
    Brenner,
    /// Energy of Laplacian \[LAPE\]: Σ (ΔI)², Δ the 3×3 kernel [0 1 0; 1 −4 1; 0 1 0].
    EnergyOfLaplacian,
    /// Vollath's F4 autocorrelation \[VOLA\]: Σ I(x,y)·I(x+1,y) − Σ I(x,y)·I(x+2,y).
    Vollath,
}

impl Named for FocusMeasure {
    const WHAT: &'static str = "focus measure";
    const NAMED: &'static [(FocusMeasure, &'static str)] = &[
        (FocusMeasure::Variance, "variance"),
        (FocusMeasure::NormalizedVariance, "normalized-variance"),
        (FocusMeasure::SumModifiedLaplacian { step: 1 }, "sml"),
        (FocusMeasure::Tenengrad, "tenengrad"),
        (FocusMeasure::Brenner, "brenner"),
        (FocusMeasure::EnergyOfLaplacian, "laplacian-energy"),
        (FocusMeasure::Vollath, "vollath"),
    ];
}

impl FocusMeasure {
    /// The measure's value on `patch`; 0 for a patch too small for its stencil.
    pub fn evaluate(&self, patch: &Patch) -> f64 {
        self.evaluate_groups(std::slice::from_ref(patch))
    }

    /// The measure of the noise-free image, estimated from two renders of it
    /// with independent samples ([`FocusMeasure::evaluate_groups`] of the
    /// two). `evaluate_pair(p, p)` is `evaluate(p)`.
    pub fn evaluate_pair(&self, a: &Patch, b: &Patch) -> f64 {
        self.evaluate_groups(&[*a, *b])
    }

    /// The measure of the noise-free image, estimated from `groups`, images
    /// of it with independent samples. Every measure but the sum-modified
    /// Laplacian is a sum of products of linear filters of the image (a
    /// variance, a gradient energy); taking the two factors from different
    /// images removes the noise's own contribution, which is what makes a
    /// noisy render look sharp, since E[f(A)·f(B)] = f(S)² when A = S + N₁
    /// and B = S + N₂ with independent zero-mean noise. The estimate is the
    /// mean over every pair of groups (a U-statistic, Hoeffding 1948): with
    /// the same samples split into G groups, the variance of the noise-times-
    /// noise term falls from 4 to 2G/(G − 1) times that of the full image's
    /// noise squared (2.3 at G = 8), which matters where the noise is as
    /// strong as the detail. The sum-modified Laplacian (absolute values) is
    /// taken on the mean of the groups. One group is [`FocusMeasure::evaluate`].
    ///
    /// Where the pair sum is a symmetric bilinear form B of the two images
    /// (`FocusMeasure::is_bilinear`) the mean over pairs takes G + 1 pair
    /// sums instead of G(G − 1)/2: Σ_{a<b} B(a, b) = (B(S, S) − Σ_a B(a, a)) / 2
    /// with S = Σ_a a, the sum of the groups.
    pub fn evaluate_groups(&self, groups: &[Patch]) -> f64 {
        let Some(first) = groups.first() else {
            return 0.0;
        };
        assert!(
            groups
                .iter()
                .all(|g| (g.width, g.height) == (first.width, first.height)),
            "patches of one size"
        );
        let g = groups.len() as f64;
        let sum_of_groups = (groups.len() > 1 && self.is_bilinear()).then(|| weighted_sum(groups, 1.0));
        // The channel's pair sum averaged over every pair of distinct groups
        // (the one group with itself when there is only one).
        let over_pairs = |c: usize| {
            if groups.len() == 1 {
                return self.pair_sum(first, first, c);
            }
            if let Some(rgb) = &sum_of_groups {
                let total = Patch { rgb, ..*first };
                let own: f64 = groups.iter().map(|p| self.pair_sum(p, p, c)).sum();
                return (self.pair_sum(&total, &total, c) - own) / (g * (g - 1.0));
            }
            let (mut sum, mut pairs) = (0.0, 0.0);
            for (i, a) in groups.iter().enumerate() {
                for b in &groups[i + 1..] {
                    sum += self.pair_sum(a, b, c);
                    pairs += 1.0;
                }
            }
            sum / pairs
        };
        match *self {
            FocusMeasure::Variance => (0..3).map(over_pairs).sum(),
            FocusMeasure::SumModifiedLaplacian { step } => {
                let step = step.max(1);
                if groups.len() == 1 {
                    return combine(|c| sum_modified_laplacian(first, c, step));
                }
                let mean = weighted_sum(groups, 1.0 / groups.len() as f32);
                let m = Patch { rgb: &mean, ..*first };
                combine(|c| sum_modified_laplacian(&m, c, step))
            }
            _ => combine(over_pairs),
        }
    }

    /// Whether [`FocusMeasure::pair_sum`] is a symmetric bilinear form of its
    /// two images (a variance, a gradient or Laplacian energy, Vollath's
    /// symmetrised autocorrelation); not the normalised variance (divided by
    /// the pair's mean) nor Brenner's gradient (its direction chosen on both).
    fn is_bilinear(&self) -> bool {
        matches!(
            self,
            FocusMeasure::Variance | FocusMeasure::Tenengrad | FocusMeasure::EnergyOfLaplacian | FocusMeasure::Vollath
        )
    }

    /// Channel `c`'s sum of products of the measure's linear filters, one
    /// factor from `a` and one from `b`: the measure of that channel when `a`
    /// and `b` are one image (before the channels are combined). Not defined
    /// for the sum-modified Laplacian, which is not such a sum.
    fn pair_sum(&self, a: &Patch, b: &Patch, c: usize) -> f64 {
        match *self {
            FocusMeasure::Variance => covariance_and_mean(a, b, c).0,
            FocusMeasure::NormalizedVariance => {
                let (covariance, mean) = covariance_and_mean(a, b, c);
                if mean > 0.0 {
                    covariance / mean
                } else {
                    0.0
                }
            }
            FocusMeasure::SumModifiedLaplacian { .. } => unreachable!("the sum-modified Laplacian is not a pair sum"),
            FocusMeasure::Tenengrad => {
                let sobel = |p: &Patch, x: usize, y: usize| {
                    let i = |dx: isize, dy: isize| p.at(x.wrapping_add_signed(dx), y.wrapping_add_signed(dy), c);
                    let gx = i(1, -1) + 2.0 * i(1, 0) + i(1, 1) - i(-1, -1) - 2.0 * i(-1, 0) - i(-1, 1);
                    let gy = i(-1, 1) + 2.0 * i(0, 1) + i(1, 1) - i(-1, -1) - 2.0 * i(0, -1) - i(1, -1);
                    (gx, gy)
                };
                sum_interior(a, 1, |x, y| {
                    let ((ax, ay), (bx, by)) = (sobel(a, x, y), sobel(b, x, y));
                    ax * bx + ay * by
                })
            }
            FocusMeasure::Brenner => {
                let (w, h) = (a.width, a.height);
                let mut sum = 0.0;
                for y in 0..h.saturating_sub(2) {
                    for x in 0..w.saturating_sub(2) {
                        let along = |p: &Patch, dx: usize, dy: usize| p.at(x + dx, y + dy, c) - p.at(x, y, c);
                        // The direction of the larger difference, as judged on both renders.
                        let (dx, dy) = if along(a, 2, 0) + along(b, 2, 0) >= along(a, 0, 2) + along(b, 0, 2) {
                            (2, 0)
                        } else {
                            (0, 2)
                        };
                        sum += along(a, dx, dy) * along(b, dx, dy);
                    }
                }
                sum
            }
            FocusMeasure::EnergyOfLaplacian => {
                let laplacian = |p: &Patch, x: usize, y: usize| {
                    p.at(x - 1, y, c) + p.at(x + 1, y, c) + p.at(x, y - 1, c) + p.at(x, y + 1, c) - 4.0 * p.at(x, y, c)
                };
                sum_interior(a, 1, |x, y| laplacian(a, x, y) * laplacian(b, x, y))
            }
            FocusMeasure::Vollath => {
                let mut sum = 0.0;
                for y in 0..a.height {
                    for x in 0..a.width.saturating_sub(2) {
                        let half = |p: &Patch, q: &Patch| p.at(x, y, c) * (q.at(x + 1, y, c) - q.at(x + 2, y, c));
                        sum += 0.5 * (half(a, b) + half(b, a));
                    }
                }
                sum
            }
        }
    }
}

/// Σ_g weight·g over `groups` (patches of one size), pixel by pixel, the
/// groups added in order: their sum, or with weight 1/G their mean.
fn weighted_sum(groups: &[Patch], weight: f32) -> Vec<f32> {
    let mut sum = vec![0f32; groups.first().map_or(0, |g| g.rgb.len())];
    for g in groups {
        for (s, v) in sum.iter_mut().zip(g.rgb) {
            *s += weight * v;
        }
    }
    sum
}

/// √(Σ_c F_c²) over the three channels; a channel whose estimate came out
/// negative (noise, in a pair estimate) subtracts instead of adding.
fn combine(per_channel: impl Fn(usize) -> f64) -> f64 {
    (0..3)
        .map(|c| {
            let f = per_channel(c);
            f * f.abs()
        })
        .sum::<f64>()
        .max(0.0)
        .sqrt()
}

/// Population covariance of channel `c` between two patches, and the mean of their means.
fn covariance_and_mean(a: &Patch, b: &Patch, c: usize) -> (f64, f64) {
    let n = (a.width * a.height) as f64;
    if n == 0.0 {
        return (0.0, 0.0);
    }
    let channel = |p: &Patch| {
        p.rgb
            .iter()
            .skip(c)
            .step_by(3)
            .map(|&v| f64::from(v))
            .collect::<Vec<f64>>()
    };
    let (va, vb) = (channel(a), channel(b));
    let (mean_a, mean_b) = (va.iter().sum::<f64>() / n, vb.iter().sum::<f64>() / n);
    let covariance = va
        .iter()
        .zip(&vb)
        .map(|(x, y)| (x - mean_a) * (y - mean_b))
        .sum::<f64>()
        / n;
    (covariance, 0.5 * (mean_a + mean_b))
}

/// Σ f(x, y) over the pixels at least `margin` pixels inside the patch.
fn sum_interior(patch: &Patch, margin: usize, f: impl Fn(usize, usize) -> f64) -> f64 {
    let mut sum = 0.0;
    for y in margin..patch.height.saturating_sub(margin) {
        for x in margin..patch.width.saturating_sub(margin) {
            sum += f(x, y);
        }
    }
    sum
}

/// Nayar's sum-modified Laplacian of channel `c` with neighbour distance `step`.
fn sum_modified_laplacian(patch: &Patch, c: usize, step: usize) -> f64 {
    let (w, h) = (patch.width, patch.height);
    // The modified Laplacian where its stencil fits...
    let mut ml = vec![0.0; w * h];
    for y in step..h.saturating_sub(step) {
        for x in step..w.saturating_sub(step) {
            let i2 = 2.0 * patch.at(x, y, c);
            ml[y * w + x] = (i2 - patch.at(x - step, y, c) - patch.at(x + step, y, c)).abs()
                + (i2 - patch.at(x, y - step, c) - patch.at(x, y + step, c)).abs();
        }
    }
    // ...summed over the 3×3 window of every pixel whose window fits too.
    let margin = step + 1;
    let mut sum = 0.0;
    for y in margin..h.saturating_sub(margin) {
        for x in margin..w.saturating_sub(margin) {
            for wy in y - 1..=y + 1 {
                sum += ml[wy * w + x - 1] + ml[wy * w + x] + ml[wy * w + x + 1];
            }
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    /// A 48×48 texture with detail everywhere, band-limited like a focused
    /// render through a pixel filter (random values blurred by σ = 0.7 px;
    /// white noise would defeat autocorrelation measures such as Vollath's,
    /// which assume neighbouring pixels are correlated).
    fn texture() -> Vec<f32> {
        let mut rng = Rng::new(5);
        let noise: Vec<f32> = (0..48 * 48 * 3).map(|_| 0.2 + 0.6 * rng.uniform()).collect();
        blur(&noise, 48, 0.7)
    }

    /// Separable Gaussian blur of standard deviation `sigma` pixels (clamped edges).
    fn blur(rgb: &[f32], size: usize, sigma: f64) -> Vec<f32> {
        let radius = (3.0 * sigma).ceil() as isize;
        let weights: Vec<f64> = (-radius..=radius)
            .map(|k| (-(k * k) as f64 / (2.0 * sigma * sigma)).exp())
            .collect();
        let total: f64 = weights.iter().sum();
        let pass = |src: &[f32], horizontal: bool| -> Vec<f32> {
            let mut out = vec![0.0; src.len()];
            for y in 0..size {
                for x in 0..size {
                    for c in 0..3 {
                        let mut v = 0.0;
                        for (k, w) in (-radius..=radius).zip(&weights) {
                            let (sx, sy) = if horizontal {
                                ((x as isize + k).clamp(0, size as isize - 1) as usize, y)
                            } else {
                                (x, (y as isize + k).clamp(0, size as isize - 1) as usize)
                            };
                            v += w * f64::from(src[3 * (sy * size + sx) + c]);
                        }
                        out[3 * (y * size + x) + c] = (v / total) as f32;
                    }
                }
            }
            out
        };
        pass(&pass(rgb, true), false)
    }

    #[test]
    fn every_measure_falls_as_the_patch_is_blurred_more() {
        let sharp = texture();
        let images: Vec<Vec<f32>> = std::iter::once(sharp.clone())
            .chain([0.5, 1.0, 1.5, 2.5, 4.0].iter().map(|&s| blur(&sharp, 48, s)))
            .collect();
        let measures = FocusMeasure::NAMED
            .iter()
            .map(|(m, n)| (n.to_string(), *m))
            .chain([("sml step 2".to_string(), FocusMeasure::SumModifiedLaplacian { step: 2 })]);
        for (name, measure) in measures {
            let values: Vec<f64> = images
                .iter()
                .map(|rgb| measure.evaluate(&Patch::new(48, 48, rgb).unwrap()))
                .collect();
            // Strictly, until it reaches 0 (Vollath's F4 of a very blurred patch is ≤ 0, read as 0).
            for pair in values.windows(2) {
                assert!(
                    pair[1] < pair[0] || pair == [0.0, 0.0],
                    "{name}: {values:?} must fall with blur"
                );
            }
            assert!(values[2] > 0.0, "{name}: {values:?}");
        }
    }

    /// Hand-computed values on a 5×5 grey patch with one bright pixel in the middle.
    #[test]
    fn measures_match_hand_computed_values_on_a_spike() {
        let mut rgb = vec![0.0f32; 5 * 5 * 3];
        for c in 0..3 {
            rgb[3 * 12 + c] = 1.0;
        }
        let patch = Patch::new(5, 5, &rgb).unwrap();
        let value = |m: FocusMeasure| m.evaluate(&patch);
        let grey = |per_channel: f64| (3.0 * per_channel * per_channel).sqrt();
        // Variance of one 1 among 25 values: 1/25 − 1/625, per channel.
        assert!((value(FocusMeasure::Variance) - 3.0 * (1.0 / 25.0 - 1.0 / 625.0)).abs() < 1e-12);
        // ML is 4 at the spike and 1 at its 4 neighbours; the only 3×3 window that fits
        // (margin 2 in a 5×5 patch) is the centre's, holding all five: 8.
        let sml = value(FocusMeasure::SumModifiedLaplacian { step: 1 });
        assert!((sml - grey(8.0)).abs() < 1e-12, "{sml}");
        // Laplacian −4 at the spike, 1 at its 4 neighbours (all interior): 16 + 4.
        assert!((value(FocusMeasure::EnergyOfLaplacian) - grey(20.0)).abs() < 1e-12);
        // Brenner: pixels two left of or two above the spike see +1 (max of the two differences);
        // the spike itself sees −1 both ways (squared: 1); the others are 0 or out of range.
        assert!((value(FocusMeasure::Brenner) - grey(3.0)).abs() < 1e-12);
    }

    /// Noise makes a patch look sharper to every measure; the pair estimate
    /// from two independently noisy copies sees through it (within 10% of the
    /// clean value here, where noise alone adds 40–900%), except the sum-modified
    /// Laplacian, which is not a sum of products and only gets the mean's
    /// halved noise.
    #[test]
    fn pair_estimates_remove_the_noise_bias() {
        let clean = texture();
        let mut rng = Rng::new(11);
        let mut noisy = || -> Vec<f32> { clean.iter().map(|v| v + 0.15 * (rng.uniform() - 0.5) * 2.0).collect() };
        let (a, b) = (noisy(), noisy());
        fn patch(v: &[f32]) -> Patch<'_> {
            Patch::new(48, 48, v).unwrap()
        }
        for &(m, name) in FocusMeasure::NAMED {
            let truth = m.evaluate(&patch(&clean));
            let single = m.evaluate(&patch(&a));
            let pair = m.evaluate_pair(&patch(&a), &patch(&b));
            if matches!(m, FocusMeasure::SumModifiedLaplacian { .. }) {
                assert!(pair < single, "{name}: the mean of two is less noisy than one");
                continue;
            }
            // Vollath's F4 (lag-1 minus lag-2 autocorrelation) cancels white noise by design.
            if m != FocusMeasure::Vollath {
                assert!(
                    single > 1.3 * truth,
                    "{name}: noise should inflate it: {single} vs {truth}"
                );
            }
            assert!((pair / truth - 1.0).abs() < 0.1, "{name}: pair {pair} vs clean {truth}");
        }
    }

    /// Split into 8 groups, the same samples give an estimate that scatters
    /// less than the pair of halves' where the noise is as strong as the
    /// detail (the U-statistic's noise-times-noise variance is 2G/(G − 1) =
    /// 2.3 times the mean image's noise squared, the pair's 4 times; measured
    /// here: 0.62–0.78 of the pair's variance), and is no more biased.
    #[test]
    fn group_estimates_scatter_less_than_pair_estimates_of_the_same_samples() {
        let clean = texture();
        let mut rng = Rng::new(23);
        fn patch(v: &[f32]) -> Patch<'_> {
            Patch::new(48, 48, v).unwrap()
        }
        for &(m, name) in FocusMeasure::NAMED {
            if matches!(m, FocusMeasure::SumModifiedLaplacian { .. }) {
                continue;
            }
            let truth = m.evaluate(&patch(&clean));
            let (mut pairs, mut groups) = (Vec::new(), Vec::new());
            for _ in 0..40 {
                // Eight images each with √8 times the noise of their mean.
                let eights: Vec<Vec<f32>> = (0..8)
                    .map(|_| clean.iter().map(|v| v + 1.5 * (rng.uniform() - 0.5)).collect())
                    .collect();
                let half = |k: usize| -> Vec<f32> {
                    (0..clean.len())
                        .map(|i| eights[4 * k..4 * k + 4].iter().map(|g| g[i]).sum::<f32>() / 4.0)
                        .collect()
                };
                let (a, b) = (half(0), half(1));
                pairs.push(m.evaluate_pair(&patch(&a), &patch(&b)) / truth);
                let all: Vec<Patch> = eights.iter().map(|g| patch(g)).collect();
                groups.push(m.evaluate_groups(&all) / truth);
            }
            let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
            let variance = |v: &[f64]| {
                let m = mean(v);
                v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (v.len() - 1) as f64
            };
            // At this much noise the channels' combination (a square root)
            // biases both a little; the groups no more than the pair.
            let (bias_groups, bias_pairs) = ((mean(&groups) - 1.0).abs(), (mean(&pairs) - 1.0).abs());
            assert!(
                bias_groups <= bias_pairs + 0.05,
                "{name}: groups' mean {bias_groups:.3} off, pairs' {bias_pairs:.3}"
            );
            assert!(
                variance(&groups) < 0.85 * variance(&pairs),
                "{name}: groups scatter {:.2e}, pairs {:.2e}",
                variance(&groups),
                variance(&pairs)
            );
        }
    }

    /// The bilinear measures' shortcut (G + 1 pair sums) gives the mean over
    /// every pair of groups, as the other measures compute it.
    #[test]
    fn bilinear_group_estimates_are_the_mean_over_pairs() {
        let clean = texture();
        let mut rng = Rng::new(5);
        let groups: Vec<Vec<f32>> = (0..8)
            .map(|_| clean.iter().map(|v| v + 0.8 * (rng.uniform() - 0.5)).collect())
            .collect();
        let patches: Vec<Patch> = groups.iter().map(|g| Patch::new(48, 48, g).unwrap()).collect();
        let mut bilinear = 0;
        for &(m, name) in FocusMeasure::NAMED {
            if !m.is_bilinear() {
                continue;
            }
            bilinear += 1;
            let over_pairs = |c: usize| {
                let mut sum = 0.0;
                for (i, a) in patches.iter().enumerate() {
                    for b in &patches[i + 1..] {
                        sum += m.pair_sum(a, b, c);
                    }
                }
                sum / 28.0
            };
            let reference = if m == FocusMeasure::Variance {
                (0..3).map(over_pairs).sum()
            } else {
                combine(over_pairs)
            };
            let shortcut = m.evaluate_groups(&patches);
            assert!(
                (shortcut - reference).abs() <= 1e-5 * reference.abs(),
                "{name}: {shortcut} against {reference}"
            );
        }
        assert_eq!(bilinear, 4);
    }

    #[test]
    fn a_patch_must_hold_its_pixels() {
        let err = Patch::new(4, 4, &[0.0; 47]).unwrap_err().to_string();
        assert!(err.contains("a 4x4 RGB patch needs 48 values, got 47"), "{err}");
        assert!(Patch::new(usize::MAX, 3, &[]).is_err());
    }

    #[test]
    fn unknown_measure_names_the_known_ones() {
        assert_eq!(
            FocusMeasure::parse("sml").unwrap(),
            FocusMeasure::SumModifiedLaplacian { step: 1 }
        );
        let err = FocusMeasure::parse("sharpness").unwrap_err().to_string();
        assert!(
            err.contains("unknown focus measure 'sharpness'") && err.contains("tenengrad"),
            "{err}"
        );
    }
}
