//! Convolution of an image with a blur kernel: shift-and-add (the
//! reference) or by FFT with zero padding.
//!
//! Both compute, for every pixel, out(x, y) = Σᵢⱼ K(i, j) · I(x − (i − cx), y − (j − cy))
//! with (cx, cy) the kernel's centre and I = 0 outside the image: each open
//! kernel pixel adds a copy of the image shifted by its offset, so a point
//! of light spreads into the kernel as it looks (a true convolution; OpenCV's
//! `filter2D` correlates, so it matches with the kernel flipped).

use std::sync::Arc;

use rayon::prelude::*;
use realfft::num_complex::Complex32;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};

use super::kernel::Kernel;
use crate::names::Named;

/// How the convolution is computed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Method {
    /// Shift-and-add over the open kernel pixels: the reference.
    Direct,
    /// Products of spectra (realfft), zero-padded so nothing wraps around.
    Fft,
    /// Whichever the cost model says is faster (the default).
    #[default]
    Auto,
}

impl Named for Method {
    const WHAT: &'static str = "convolution method";
    const NAMED: &'static [(Method, &'static str)] =
        &[(Method::Auto, "auto"), (Method::Direct, "direct"), (Method::Fft, "fft")];
}

/// What lies beyond the image's edges.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Edges {
    /// Black: edges darken where the kernel reaches past them (OpenCV's
    /// `BORDER_CONSTANT` with 0).
    Black,
    /// Each pixel divided by the share of the kernel that fell inside the
    /// image, so a uniform image stays uniform up to its edges (the default).
    #[default]
    Renormalize,
}

impl Named for Edges {
    const WHAT: &'static str = "edge treatment";
    const NAMED: &'static [(Edges, &'static str)] = &[(Edges::Renormalize, "renormalize"), (Edges::Black, "black")];
}

/// Operations of one multiply-add, relative to one butterfly-point of the
/// FFT (n log₂ n); measured with `lenspath bench bokeh` (BENCHMARKS.md).
const DIRECT_COST_PER_TAP: f64 = 0.12;

/// The method [`Method::Auto`] picks for a `width`×`height` image and `kernel`.
pub fn choose_method(width: usize, height: usize, kernel: &Kernel) -> Method {
    let direct = DIRECT_COST_PER_TAP * (kernel.open_pixels() * width * height) as f64;
    let (pw, ph) = padded_size(width, height, kernel);
    let n = (pw * ph) as f64;
    // Forward and inverse transforms of the image (the kernel's is shared).
    let fft = 2.0 * n * n.log2();
    if direct <= fft {
        Method::Direct
    } else {
        Method::Fft
    }
}

/// `method`, with [`Method::Auto`] made the one [`choose_method`] picks.
fn resolved(method: Method, width: usize, height: usize, kernel: &Kernel) -> Method {
    match method {
        Method::Auto => choose_method(width, height, kernel),
        m => m,
    }
}

/// The three channel planes of an interleaved RGB image (3 floats a pixel).
pub fn rgb_planes(rgb: &[f32]) -> Vec<Vec<f32>> {
    (0..3).map(|c| rgb.chunks_exact(3).map(|px| px[c]).collect()).collect()
}

/// Writes three channel planes back into an interleaved RGB image.
pub fn interleave_planes(planes: &[Vec<f32>], rgb: &mut [f32]) {
    for (c, plane) in planes.iter().enumerate() {
        for (px, &v) in rgb.chunks_exact_mut(3).zip(plane) {
            px[c] = v;
        }
    }
}

/// Convolves an interleaved RGB image (`width`×`height`, 3 floats a pixel,
/// row-major) with `kernel`, channel by channel, in place.
pub fn convolve_rgb(rgb: &mut [f32], width: usize, height: usize, kernel: &Kernel, method: Method, edges: Edges) {
    let blurred = convolve_planes(&rgb_planes(rgb), width, height, kernel, method, edges);
    interleave_planes(&blurred, rgb);
}

/// Fails when blurring a `width`×`height` image with `kernel` by `method`
/// would need more memory than [`crate::memory::budget_bytes`] allows.
pub fn check_blur_memory(width: usize, height: usize, kernel: &Kernel, method: Method) -> crate::error::Result<()> {
    let bytes = match resolved(method, width, height, kernel) {
        // Three planes in, three out.
        Method::Direct => (width * height) as u64 * 24,
        _ => {
            let (w, h) = padded_size(width, height, kernel);
            (w * h) as u64 * crate::memory::FFT_BYTES_PER_PADDED_PIXEL
        }
    };
    crate::memory::check_fits(
        &|| {
            format!(
                "blurring a {width}x{height} image with a {}x{} kernel",
                kernel.width, kernel.height
            )
        },
        bytes,
    )
}

/// Convolves `channels` planes (each `width`×`height`, row-major) with `kernel`.
pub fn convolve_planes(
    planes: &[Vec<f32>],
    width: usize,
    height: usize,
    kernel: &Kernel,
    method: Method,
    edges: Edges,
) -> Vec<Vec<f32>> {
    // An empty image blurs to itself (and its rows cannot be cut into chunks).
    if width == 0 || height == 0 {
        return planes.to_vec();
    }
    let method = resolved(method, width, height, kernel);
    let mut out: Vec<Vec<f32>> = match method {
        Method::Direct => planes.iter().map(|p| direct(p, width, height, kernel)).collect(),
        _ => {
            let fft = Fft2d::new(padded_size(width, height, kernel));
            let kernel_spectrum = fft.forward(&kernel.weights, kernel.width, kernel.height);
            planes
                .iter()
                .map(|p| {
                    let mut spectrum = fft.forward(p, width, height);
                    let scale = 1.0 / (fft.width * fft.height) as f32;
                    spectrum
                        .par_iter_mut()
                        .zip(kernel_spectrum.par_iter())
                        .for_each(|(a, b)| *a = *a * *b * scale);
                    let (cx, cy) = kernel.centre();
                    fft.inverse(spectrum, (cx, cy), width, height)
                })
                .collect()
        }
    };
    if edges == Edges::Renormalize {
        let share = kernel_share_inside(width, height, kernel);
        for plane in &mut out {
            plane.par_iter_mut().zip(share.par_iter()).for_each(|(v, &s)| {
                if s > 1e-6 {
                    *v /= s;
                }
            });
        }
    }
    out
}

/// Shift-and-add, rows in parallel; each output row sums the kernel's rows
/// in order, so the result does not depend on the thread count.
pub fn direct(plane: &[f32], width: usize, height: usize, kernel: &Kernel) -> Vec<f32> {
    let (cx, cy) = kernel.centre();
    let mut out = vec![0f32; width * height];
    out.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        for j in 0..kernel.height {
            // The source row: y − (j − cy).
            let Some(sy) = (y + cy).checked_sub(j).filter(|&sy| sy < height) else {
                continue;
            };
            let source = &plane[sy * width..(sy + 1) * width];
            for i in 0..kernel.width {
                let k = kernel.weights[j * kernel.width + i];
                if k == 0.0 {
                    continue;
                }
                // x − (i − cx) must lie in [0, width).
                let shift = i as isize - cx as isize;
                let (x0, x1) = (shift.max(0) as usize, (width as isize + shift).min(width as isize));
                if x0 as isize >= x1 {
                    continue;
                }
                let x1 = x1 as usize;
                let s0 = (x0 as isize - shift) as usize;
                for (o, s) in row[x0..x1].iter_mut().zip(&source[s0..s0 + (x1 - x0)]) {
                    *o += k * s;
                }
            }
        }
    });
    out
}

/// For every pixel, the sum of the kernel weights whose source pixel lies
/// inside the image (a summed-area table of the kernel makes it O(1) each).
fn kernel_share_inside(width: usize, height: usize, kernel: &Kernel) -> Vec<f32> {
    let (kw, kh) = (kernel.width, kernel.height);
    let mut table = vec![0f64; (kw + 1) * (kh + 1)];
    for j in 0..kh {
        for i in 0..kw {
            table[(j + 1) * (kw + 1) + i + 1] =
                f64::from(kernel.weights[j * kw + i]) + table[j * (kw + 1) + i + 1] + table[(j + 1) * (kw + 1) + i]
                    - table[j * (kw + 1) + i];
        }
    }
    let (cx, cy) = kernel.centre();
    // Kernel index i reaches inside when x − (i − cx) ∈ [0, n): i ∈ [x + cx + 1 − n, x + cx].
    let range = |x: usize, c: usize, n: usize, k: usize| ((x + c + 1).saturating_sub(n), (x + c + 1).min(k));
    let mut share = vec![0f32; width * height];
    share.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
        let (j0, j1) = range(y, cy, height, kh);
        for (x, s) in row.iter_mut().enumerate() {
            let (i0, i1) = range(x, cx, width, kw);
            let at = |i: usize, j: usize| table[j * (kw + 1) + i];
            *s = (at(i1, j1) - at(i0, j1) - at(i1, j0) + at(i0, j0)) as f32;
        }
    });
    share
}

/// The FFT size for a linear convolution without wrap-around: at least the
/// image plus the kernel less one, rounded up to a product of 2, 3, 5 and 7.
fn padded_size(width: usize, height: usize, kernel: &Kernel) -> (usize, usize) {
    (
        fast_size(width + kernel.width - 1),
        fast_size(height + kernel.height - 1),
    )
}

fn fast_size(n: usize) -> usize {
    (n..)
        .find(|&m| {
            let mut r = m;
            for p in [2, 3, 5, 7] {
                while r % p == 0 {
                    r /= p;
                }
            }
            r == 1
        })
        .expect("a 7-smooth number exists above any n")
}

/// A 2-D real FFT of a fixed padded size: real-to-complex transforms of the
/// rows, then complex transforms of the columns. Spectra are stored column
/// by column (`width / 2 + 1` columns of `height`).
struct Fft2d {
    width: usize,
    height: usize,
    rows_forward: Arc<dyn RealToComplex<f32>>,
    rows_inverse: Arc<dyn ComplexToReal<f32>>,
    columns_forward: Arc<dyn Fft<f32>>,
    columns_inverse: Arc<dyn Fft<f32>>,
}

impl Fft2d {
    fn new((width, height): (usize, usize)) -> Fft2d {
        let mut real = RealFftPlanner::<f32>::new();
        let mut complex = FftPlanner::<f32>::new();
        Fft2d {
            width,
            height,
            rows_forward: real.plan_fft_forward(width),
            rows_inverse: real.plan_fft_inverse(width),
            columns_forward: complex.plan_fft_forward(height),
            columns_inverse: complex.plan_fft_inverse(height),
        }
    }

    fn columns(&self) -> usize {
        self.width / 2 + 1
    }

    /// The spectrum of a `w`×`h` plane zero-padded to the transform's size.
    fn forward(&self, plane: &[f32], w: usize, h: usize) -> Vec<Complex32> {
        let n = self.columns();
        // Rows: only the first h hold data; the others transform to zero.
        let mut rows = vec![Complex32::default(); h * n];
        rows.par_chunks_mut(n).enumerate().for_each_init(
            || (vec![0f32; self.width], self.rows_forward.make_scratch_vec()),
            |(input, scratch), (y, out)| {
                input[..w].copy_from_slice(&plane[y * w..(y + 1) * w]);
                input[w..].fill(0.0);
                self.rows_forward
                    .process_with_scratch(input, out, scratch)
                    .expect("buffer sizes match the plan");
            },
        );
        // Columns: transpose, then transform each.
        let mut spectrum = vec![Complex32::default(); n * self.height];
        spectrum.par_chunks_mut(self.height).enumerate().for_each_init(
            || vec![Complex32::default(); self.columns_forward.get_inplace_scratch_len()],
            |scratch, (x, column)| {
                for y in 0..h {
                    column[y] = rows[y * n + x];
                }
                self.columns_forward.process_with_scratch(column, scratch);
            },
        );
        spectrum
    }

    /// The `w`×`h` window starting at `offset` of the real plane whose
    /// spectrum this is (consumed: the column transforms work in place).
    fn inverse(&self, mut spectrum: Vec<Complex32>, offset: (usize, usize), w: usize, h: usize) -> Vec<f32> {
        let n = self.columns();
        spectrum.par_chunks_mut(self.height).for_each_init(
            || vec![Complex32::default(); self.columns_inverse.get_inplace_scratch_len()],
            |scratch, column| self.columns_inverse.process_with_scratch(column, scratch),
        );
        let mut out = vec![0f32; w * h];
        out.par_chunks_mut(w).enumerate().for_each_init(
            || {
                (
                    vec![Complex32::default(); n],
                    vec![0f32; self.width],
                    self.rows_inverse.make_scratch_vec(),
                )
            },
            |(row, real, scratch), (y, out_row)| {
                for (x, v) in row.iter_mut().enumerate() {
                    *v = spectrum[x * self.height + y + offset.1];
                }
                // A real signal's spectrum: the DC and Nyquist bins are real
                // (rounding leaves tiny imaginary parts, which realfft refuses).
                row[0].im = 0.0;
                if self.width % 2 == 0 {
                    row[n - 1].im = 0.0;
                }
                self.rows_inverse
                    .process_with_scratch(row, real, scratch)
                    .expect("buffer sizes match the plan");
                out_row.copy_from_slice(&real[offset.0..offset.0 + w]);
            },
        );
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    fn random_plane(width: usize, height: usize, seed: u64) -> Vec<f32> {
        let mut rng = Rng::new(seed);
        (0..width * height).map(|_| rng.uniform()).collect()
    }

    fn random_kernel(width: usize, height: usize, seed: u64) -> Kernel {
        let mut rng = Rng::new(seed);
        // Some closed pixels, as in a real mask.
        let values: Vec<f32> = (0..width * height)
            .map(|_| if rng.uniform() < 0.3 { 0.0 } else { rng.uniform() })
            .collect();
        Kernel::from_mask(width, height, &values, super::super::KernelSize::Native).unwrap()
    }

    /// A single lit pixel spreads into the kernel as it looks, centred on it.
    #[test]
    fn a_point_spreads_into_the_kernel_upright() {
        let (w, h) = (9, 7);
        let kernel = random_kernel(3, 4, 1);
        let mut plane = vec![0f32; w * h];
        plane[3 * w + 4] = 1.0;
        for method in [Method::Direct, Method::Fft] {
            let out = &convolve_planes(&[plane.clone()], w, h, &kernel, method, Edges::Black)[0];
            let (cx, cy) = kernel.centre();
            for j in 0..kernel.height {
                for i in 0..kernel.width {
                    let (x, y) = (4 + i - cx, 3 + j - cy);
                    let expected = kernel.weights[j * kernel.width + i];
                    assert!((out[y * w + x] - expected).abs() < 1e-6, "{method:?} ({i}, {j})");
                }
            }
            let total: f32 = out.iter().sum();
            assert!((total - 1.0).abs() < 1e-5, "{method:?}: {total}");
        }
    }

    /// FFT and shift-and-add agree within 1e-5 of the largest value, for odd
    /// and even kernels, kernels larger than the image, both edge rules.
    #[test]
    fn fft_agrees_with_shift_and_add() {
        for (w, h, kw, kh) in [(40, 30, 5, 5), (37, 23, 8, 3), (20, 16, 31, 40), (64, 48, 64, 48)] {
            let planes = [random_plane(w, h, 2), random_plane(w, h, 3)];
            let kernel = random_kernel(kw, kh, 4);
            for edges in [Edges::Black, Edges::Renormalize] {
                let direct = convolve_planes(&planes, w, h, &kernel, Method::Direct, edges);
                let fft = convolve_planes(&planes, w, h, &kernel, Method::Fft, edges);
                for (a, b) in direct.iter().zip(&fft) {
                    let peak = a.iter().fold(0f32, |m, v| m.max(v.abs()));
                    let worst = a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0f32, f32::max);
                    assert!(worst <= 1e-5 * peak, "{w}x{h} * {kw}x{kh} {edges:?}: {worst} of {peak}");
                }
            }
        }
    }

    /// Renormalised edges keep a uniform image uniform; black edges darken it
    /// by the share of the kernel that falls outside.
    #[test]
    fn edges_renormalise_or_darken() {
        let (w, h) = (24, 18);
        let kernel = random_kernel(7, 9, 5);
        let plane = vec![0.7f32; w * h];
        let kept = &convolve_planes(
            std::slice::from_ref(&plane),
            w,
            h,
            &kernel,
            Method::Auto,
            Edges::Renormalize,
        )[0];
        assert!(kept.iter().all(|v| (v - 0.7).abs() < 1e-5));
        let black = &convolve_planes(&[plane], w, h, &kernel, Method::Direct, Edges::Black)[0];
        assert!(black[0] < 0.6 && (black[9 * w + 12] - 0.7).abs() < 1e-5);
    }

    #[test]
    fn auto_picks_direct_for_small_kernels_and_fft_for_large() {
        let small = random_kernel(3, 3, 6);
        let large = random_kernel(101, 101, 7);
        assert_eq!(choose_method(1920, 1080, &small), Method::Direct);
        assert_eq!(choose_method(1920, 1080, &large), Method::Fft);
    }

    #[test]
    fn fft_sizes_are_7_smooth_and_large_enough() {
        for n in [1, 7, 11, 13, 97, 1000, 2021] {
            let m = fast_size(n);
            assert!(m >= n && m < n + n / 4 + 2, "{n} -> {m}");
        }
        assert_eq!(fast_size(11), 12);
    }
}
