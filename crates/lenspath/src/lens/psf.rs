//! The point spread function from a [`Wavefront`]: the squared modulus of
//! the Fourier transform of the pupil function P = A·exp(2πi·W)
//! (Goodman, *Introduction to Fourier Optics*, 3rd ed., §6.4), by FFT.
//!
//! Sampling: the pupil's `grid` samples are zero-padded to `grid × padding`
//! a side, so the PSF's samples are `padding` times finer than λ/(n′·Δα)
//! over the grid (Δα the image-space direction-cosine span of one grid step);
//! for a perfect lens at working f-number N that is λN/padding (a padding of
//! 4 puts five samples inside the Airy disc's first dark ring, at 1.22λN).
//! The PSF is in the sensor's plane, centred on the chief ray's image point.

use rustfft::num_complex::Complex64;
use rustfft::FftPlanner;

use super::wavefront::Wavefront;
use crate::error::{Error, Result};

/// A sampled PSF, normalised to unit sum.
#[derive(Clone, Debug)]
pub struct PointSpread {
    size: usize,
    spacing_mm: [f64; 2],
    intensity: Vec<f64>,
    strehl_ratio: f64,
}

impl Wavefront {
    /// The PSF with the pupil zero-padded `padding` times (2 or more, so
    /// the MTF taken from it does not wrap around).
    pub fn psf(&self, padding: usize) -> Result<PointSpread> {
        if padding < 2 {
            return Err(Error::InvalidArgument(format!(
                "PSF padding must be at least 2, got {padding}"
            )));
        }
        let (grid, size) = (self.grid(), self.grid() * padding);
        let mut field = vec![Complex64::new(0.0, 0.0); size * size];
        let mut amplitude_sum = 0.0;
        for (k, &w) in self.opd_waves().iter().enumerate().filter(|(_, w)| !w.is_nan()) {
            field[(k / grid) * size + k % grid] = Complex64::from_polar(1.0, std::f64::consts::TAU * w);
            amplitude_sum += 1.0;
        }
        fft2(&mut field, size);
        let mut intensity: Vec<f64> = field.iter().map(|c| c.norm_sqr()).collect();
        let peak = intensity.iter().copied().fold(0.0, f64::max);
        let total: f64 = intensity.iter().sum();
        intensity.iter_mut().for_each(|v| *v /= total);
        let wavelength_mm = self.wavelength_nm() * 1e-6;
        let steps = self.optical_direction_steps();
        let intensity = centred(&intensity, size);
        // The field at sensor offset x sums P·exp(ik·α·x); a converging lens
        // turns a pupil offset into the opposite direction cosine (α falls
        // across the pupil), and then the forward transform's index runs with
        // x. Where α rises instead, the axis is flipped back.
        let flip = |c: usize, rising: bool| if rising { (size - c) % size } else { c };
        let intensity = (0..size * size)
            .map(|k| intensity[flip(k / size, steps[1] > 0.0) * size + flip(k % size, steps[0] > 0.0)])
            .collect();
        Ok(PointSpread {
            size,
            spacing_mm: steps.map(|step| wavelength_mm / (size as f64 * step.abs())),
            intensity,
            // A perfect pupil of the same shape peaks at (ΣA)².
            strehl_ratio: peak / (amplitude_sum * amplitude_sum),
        })
    }
}

impl PointSpread {
    /// Samples per side; the image point is at (size/2, size/2).
    pub fn size(&self) -> usize {
        self.size
    }

    /// Distance between samples in x and y on the sensor, mm.
    pub fn spacing_mm(&self) -> [f64; 2] {
        self.spacing_mm
    }

    /// Intensity per sample (row-major, rows in y), summing to 1.
    pub fn intensity(&self) -> &[f64] {
        &self.intensity
    }

    /// The PSF's peak over a perfect lens's of the same pupil (the Strehl ratio).
    pub fn strehl_ratio(&self) -> f64 {
        self.strehl_ratio
    }

    /// The fraction of the energy within `radius_mm` of the image point.
    pub fn encircled_energy(&self, radius_mm: f64) -> f64 {
        let centre = (self.size / 2) as f64;
        let [dx, dy] = self.spacing_mm;
        self.intensity
            .iter()
            .enumerate()
            .filter(|(k, _)| {
                let (x, y) = (
                    ((k % self.size) as f64 - centre) * dx,
                    ((k / self.size) as f64 - centre) * dy,
                );
                x * x + y * y <= radius_mm * radius_mm
            })
            .map(|(_, v)| v)
            .sum()
    }
}

/// The array with its zero frequency moved from the corner to (size/2, size/2).
pub(super) fn centred(values: &[f64], size: usize) -> Vec<f64> {
    let half = size / 2;
    (0..size * size)
        .map(|k| values[((k / size + half) % size) * size + (k % size + half) % size])
        .collect()
}

/// An in-place 2-D forward FFT of a `size` × `size` row-major array: rows, then columns.
pub(super) fn fft2(data: &mut [Complex64], size: usize) {
    let fft = FftPlanner::new().plan_fft_forward(size);
    fft.process(data);
    let mut transposed = transpose(data, size);
    fft.process(&mut transposed);
    data.copy_from_slice(&transpose(&transposed, size));
}

fn transpose(data: &[Complex64], size: usize) -> Vec<Complex64> {
    (0..size * size).map(|k| data[(k % size) * size + k / size]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_perfect_lens_makes_the_airy_pattern() {
        // First dark ring at 1.22 λN with 83.8 % of the energy inside it (Born & Wolf §8.5.2).
        let (f_number, wavelength_nm) = (8.0, 550.0);
        let psf = Wavefront::diffraction_limited(128, f_number, wavelength_nm)
            .psf(8)
            .unwrap();
        let first_zero_mm = 1.2197 * wavelength_nm * 1e-6 * f_number;
        // The radial profile along x: its first minimum, by a parabola through the lowest sample.
        let (size, dx) = (psf.size(), psf.spacing_mm()[0]);
        let row = &psf.intensity()[(size / 2) * size + size / 2..(size / 2 + 1) * size];
        let k = (1..row.len() - 1)
            .find(|&k| row[k] < row[k - 1] && row[k] <= row[k + 1])
            .unwrap();
        let shift = 0.5 * (row[k - 1] - row[k + 1]) / (row[k - 1] - 2.0 * row[k] + row[k + 1]);
        let zero_mm = (k as f64 + shift) * dx;
        assert!(
            (zero_mm / first_zero_mm - 1.0).abs() < 0.02,
            "first zero {zero_mm} mm, Airy {first_zero_mm}"
        );
        let energy = psf.encircled_energy(first_zero_mm);
        assert!((energy - 0.838).abs() < 0.01, "encircled energy {energy}");
        assert!((psf.strehl_ratio() - 1.0).abs() < 1e-9);
    }

    #[test]
    fn a_singlet_stopped_down_has_the_strehl_ratio_marechal_predicts() {
        // Maréchal: S ≈ exp(−(2πσ)²) for small RMS error σ in waves (Born & Wolf §9.1.3).
        let system = crate::lens::wavefront::tests::singlet().with_f_number(11.0).unwrap();
        let focus = system.infinity_focus_z_mm(0.1).unwrap();
        let wavefront = system.wavefront(0.0, focus, 64).unwrap();
        let sigma = wavefront.rms_waves();
        let strehl = wavefront.psf(4).unwrap().strehl_ratio();
        let marechal = (-(std::f64::consts::TAU * sigma).powi(2)).exp();
        assert!(sigma > 0.02 && sigma < 0.1, "RMS {sigma} waves");
        assert!(
            (strehl - marechal).abs() < 0.03,
            "Strehl {strehl}, Maréchal {marechal} (σ = {sigma})"
        );
    }
}
