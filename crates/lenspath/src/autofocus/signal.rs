//! The numerics of a focus search: the band-pass a patch is scored through
//! ([`Detail`]), independent seeds for sample streams, and finding a focus
//! curve's peak (the best sample, or a least-squares parabola through the
//! log-scores around it).

use crate::color::luminance;

/// The scale of detail a patch render is scored at: the band-pass applied
/// before the focus measure, a Gaussian minus a Gaussian four times wider. It
/// keeps detail a few pixels across (edges, texture) and drops both the
/// pixel-scale Monte Carlo noise and the smooth glow of bright things far out
/// of focus, which gradient measures would otherwise score as detail.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Detail {
    /// σ = 1 and 4 pixels: where the sharpest focus shows; for locating the peak.
    Fine,
    /// σ = 2 and 8 pixels: for scanning. A peak stays visible several DoF
    /// away, and white noise's gradient energy, which falls as σ⁻⁴, is about
    /// a sixteenth of the fine scale's while an edge's falls as σ⁻¹.
    Coarse,
}

impl Detail {
    /// The narrow and wide standard deviations of the band-pass, pixels.
    pub fn band_pass_sigmas_px(self) -> (f64, f64) {
        match self {
            Detail::Fine => (1.0, 4.0),
            Detail::Coarse => (2.0, 8.0),
        }
    }

    /// The luminance of `rgb` (`width` pixels wide) band-passed at this
    /// scale, in all three channels. Focus is judged on luminance, as a
    /// camera's contrast autofocus does: a lens with longitudinal colour
    /// focuses each colour at its own depth, and the sharpest image is the
    /// one whose luminance is sharpest; and a sample's few wavelengths give
    /// a noisier colour than luminance (wavelengths are drawn about as the
    /// eye's sensitivity goes).
    pub(super) fn band_pass(self, rgb: &[f32], width: usize) -> Vec<f32> {
        let (narrow_sigma, wide_sigma) = self.band_pass_sigmas_px();
        let grey: Vec<f32> = rgb.chunks_exact(3).map(|c| luminance([c[0], c[1], c[2]])).collect();
        let narrow = gaussian_blur(&grey, width, narrow_sigma);
        let wide = gaussian_blur(&grey, width, wide_sigma);
        // The focus measures take three channels: each is the luminance's.
        narrow.iter().zip(&wide).flat_map(|(n, w)| [n - w; 3]).collect()
    }
}

/// The seed of the `stream`-th of several renders that must be independent:
/// seeds far apart (the golden-ratio increment), so their sample sequences
/// do not overlap.
pub(super) fn stream_seed(seed: u32, stream: usize) -> u32 {
    seed.wrapping_add(0x9E37_79B9u32.wrapping_mul(stream as u32))
}

/// `grey` (`width` pixels wide, one float each) blurred by a separable
/// Gaussian of standard deviation `sigma` pixels, renormalised at the borders.
pub(super) fn gaussian_blur(grey: &[f32], width: usize, sigma: f64) -> Vec<f32> {
    let height = grey.len() / width.max(1);
    let radius = (3.0 * sigma).ceil() as isize;
    let weights: Vec<f64> = (-radius..=radius)
        .map(|k| (-((k * k) as f64) / (2.0 * sigma * sigma)).exp())
        .collect();
    // Taps past the patch's edge are left out and the rest renormalised; the
    // valid taps of a pixel are a contiguous range, summed in order.
    let pass = |src: &[f32], horizontal: bool| -> Vec<f32> {
        let mut out = vec![0.0f32; src.len()];
        let (along, stride) = if horizontal { (width, 1) } else { (height, width) };
        for y in 0..height {
            for x in 0..width {
                let at = if horizontal { x } else { y } as isize;
                let first = (-radius).max(-at);
                let last = radius.min(along as isize - 1 - at);
                let pixel = y * width + x;
                let (mut sum, mut total) = (0.0f64, 0.0f64);
                for k in first..=last {
                    let w = weights[(k + radius) as usize];
                    sum += w * f64::from(src[(pixel as isize + k * stride as isize) as usize]);
                    total += w;
                }
                out[pixel] = (sum / total) as f32;
            }
        }
        out
    };
    pass(&pass(grey, true), false)
}

/// The index of the highest-scoring `(z, score)` point (the last of equal
/// ones; 0 for none).
pub(super) fn peak_index(points: &[(f64, f64)]) -> usize {
    points
        .iter()
        .enumerate()
        .max_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
        .map_or(0, |(i, _)| i)
}

/// The index of the highest interior local maximum of a `(z, score)` curve
/// (a point above both neighbours); the highest point when there is none.
pub(super) fn interior_peak_index(points: &[(f64, f64)]) -> usize {
    (1..points.len().saturating_sub(1))
        .filter(|&i| points[i].1 > points[i - 1].1 && points[i].1 > points[i + 1].1)
        .max_by(|&a, &b| points[a].1.total_cmp(&points[b].1))
        .unwrap_or_else(|| peak_index(points))
}

/// The vertex of the least-squares parabola through the log-scores of the
/// `(z, score)` points within `window` of `z` (a Gaussian fit of a focus
/// curve's peak), kept within their span; `z` itself when fewer than three
/// positive scores are there or they make no peak.
pub(super) fn log_parabola_peak(points: &[(f64, f64)], z: f64, window: f64) -> f64 {
    let near: Vec<(f64, f64)> = points
        .iter()
        .filter(|&&(x, score)| score > 0.0 && (x - z).abs() <= window)
        .map(|&(x, score)| (x - z, score.ln()))
        .collect();
    if near.len() < 3 {
        return z;
    }
    let lo = near.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let hi = near.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
    match least_squares_parabola(&near) {
        Some((_, b, c)) if c < 0.0 => z + (-b / (2.0 * c)).clamp(lo, hi),
        _ => z,
    }
}

/// Coefficients (a, b, c) of the least-squares parabola y = a + b·x + c·x²
/// through `points`, from the 3×3 normal equations (Cramer's rule).
pub(super) fn least_squares_parabola(points: &[(f64, f64)]) -> Option<(f64, f64, f64)> {
    let mut s = [0.0f64; 5]; // Σ x^k, k = 0..4
    let mut t = [0.0f64; 3]; // Σ y·x^k, k = 0..2
    for &(x, y) in points {
        let mut xk = 1.0;
        for k in 0..5 {
            s[k] += xk;
            if k < 3 {
                t[k] += y * xk;
            }
            xk *= x;
        }
    }
    let det3 = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let m = [[s[0], s[1], s[2]], [s[1], s[2], s[3]], [s[2], s[3], s[4]]];
    let d = det3(m);
    if d.abs() < 1e-300 || !d.is_finite() {
        return None;
    }
    let column = |k: usize| {
        let mut mk = m;
        for (row, &tv) in mk.iter_mut().zip(&t) {
            row[k] = tv;
        }
        det3(mk) / d
    };
    Some((column(0), column(1), column(2)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn least_squares_parabola_recovers_an_exact_one() {
        let f = |x: f64| 0.5 - 0.3 * x - 1.7 * x * x;
        let points: Vec<(f64, f64)> = [-2.0, -0.5, 0.0, 1.0, 3.0].iter().map(|&x| (x, f(x))).collect();
        let (a, b, c) = least_squares_parabola(&points).unwrap();
        assert!((a - 0.5).abs() < 1e-9 && (b + 0.3).abs() < 1e-9 && (c + 1.7).abs() < 1e-9);
    }
}
