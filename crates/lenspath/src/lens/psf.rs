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
//!
//! The polychromatic PSF is the weighted sum of monochromatic ones, each
//! resampled (bilinearly, its energy kept) onto the first wavelength's grid
//! and placed by its own chief ray's image point, so lateral colour
//! separates the colours' peaks as it does on the sensor.

use rustfft::num_complex::Complex32;
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
    /// The chief ray's image point (x, y) on the sensor, mm: the grid's centre.
    centre_mm: [f64; 2],
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
        let mut field = vec![Complex32::new(0.0, 0.0); size * size];
        let mut amplitude_sum = 0.0;
        for (k, &w) in self.opd_waves().iter().enumerate().filter(|(_, w)| !w.is_nan()) {
            // The phase's fraction of a wave in f64 (W can be many waves), the unit phasor in f32.
            let (sin, cos) = (std::f64::consts::TAU * w.fract()).sin_cos();
            field[(k / grid) * size + k % grid] = Complex32::new(cos as f32, sin as f32);
            amplitude_sum += 1.0;
        }
        fft2(&mut field, size);
        let mut intensity: Vec<f64> = field.iter().map(|c| f64::from(c.norm_sqr())).collect();
        let peak = intensity.iter().copied().fold(0.0, f64::max);
        let total: f64 = intensity.iter().sum();
        intensity.iter_mut().for_each(|v| *v /= total);
        let wavelength_mm = self.wavelength_nm() * 1e-6;
        let steps = self.optical_direction_steps();
        let intensity = centred(&intensity, size);
        // The field at sensor offset x is Σ exp(−2πi·W)·exp(ik·α·x) (the
        // phase lags where the wave leads; Goodman §6.4), whose intensity is
        // that of the forward transform of exp(+2πi·W) read at index m with
        // α·x growing with m: x = m·spacing where α rises across the pupil,
        // and mirrored where it falls, as a converging lens makes it.
        let flip = |c: usize, falling: bool| if falling { (size - c) % size } else { c };
        let intensity = (0..size * size)
            .map(|k| intensity[flip(k / size, steps[1] < 0.0) * size + flip(k % size, steps[0] < 0.0)])
            .collect();
        Ok(PointSpread {
            size,
            spacing_mm: steps.map(|step| wavelength_mm / (size as f64 * step.abs())),
            intensity,
            // A perfect pupil of the same shape peaks at (ΣA)².
            strehl_ratio: peak / (amplitude_sum * amplitude_sum),
            centre_mm: [self.image_point_mm().x, self.image_point_mm().y],
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

    /// The chief ray's image point (x, y) on the sensor, mm, where the grid is centred.
    pub fn centre_mm(&self) -> [f64; 2] {
        self.centre_mm
    }

    /// The spectrum-weighted sum of `parts` (a PSF and its weight each, at
    /// one field and sensor position), on the first part's grid and unit
    /// sum. Its Strehl ratio is the weighted mean of the parts'. Fails for
    /// no parts or weights that do not sum to a positive number.
    pub fn polychromatic(parts: &[(PointSpread, f64)]) -> Result<PointSpread> {
        let total_weight: f64 = parts.iter().map(|(_, w)| w).sum();
        let Some((reference, _)) = parts.first().filter(|_| total_weight > 0.0 && total_weight.is_finite()) else {
            return Err(Error::InvalidArgument(format!(
                "a polychromatic PSF needs wavelengths with positive weights, got {} weighing {total_weight}",
                parts.len()
            )));
        };
        let (size, [dx, dy]) = (reference.size, reference.spacing_mm);
        let centre = (size / 2) as f64;
        let mut intensity = vec![0.0; size * size];
        for (part, weight) in parts {
            let [px, py] = part.spacing_mm;
            let part_centre = (part.size / 2) as f64;
            // Bilinear samples of a density: scaled by the area ratio to keep the energy.
            let scale = weight * (dx * dy) / (px * py);
            for (k, value) in intensity.iter_mut().enumerate() {
                let x_mm = reference.centre_mm[0] + ((k % size) as f64 - centre) * dx;
                let y_mm = reference.centre_mm[1] + ((k / size) as f64 - centre) * dy;
                let u = (x_mm - part.centre_mm[0]) / px + part_centre;
                let v = (y_mm - part.centre_mm[1]) / py + part_centre;
                *value += scale * part.bilinear(u, v);
            }
        }
        let sum: f64 = intensity.iter().sum();
        intensity.iter_mut().for_each(|v| *v /= sum);
        Ok(PointSpread {
            size,
            spacing_mm: reference.spacing_mm,
            intensity,
            strehl_ratio: parts.iter().map(|(p, w)| p.strehl_ratio * w).sum::<f64>() / total_weight,
            centre_mm: reference.centre_mm,
        })
    }

    /// The intensity at fractional grid position (u columns, v rows); 0 outside.
    fn bilinear(&self, u: f64, v: f64) -> f64 {
        let (u0, v0) = (u.floor(), v.floor());
        let (fu, fv) = (u - u0, v - v0);
        let at = |i: f64, j: f64| {
            let inside = i >= 0.0 && j >= 0.0 && i < self.size as f64 && j < self.size as f64;
            if inside {
                self.intensity[j as usize * self.size + i as usize]
            } else {
                0.0
            }
        };
        (at(u0, v0) * (1.0 - fu) + at(u0 + 1.0, v0) * fu) * (1.0 - fv)
            + (at(u0, v0 + 1.0) * (1.0 - fu) + at(u0 + 1.0, v0 + 1.0) * fu) * fv
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
pub(crate) fn centred(values: &[f64], size: usize) -> Vec<f64> {
    let half = size / 2;
    (0..size * size)
        .map(|k| values[((k / size + half) % size) * size + (k % size + half) % size])
        .collect()
}

/// An in-place 2-D forward FFT of a `size` × `size` row-major array: rows, then columns.
/// Single precision, as the bokeh's convolution: one float type keeps rustfft's
/// kernels compiled once, and its round-off (about 1e-7 of the peak) is far
/// below what a PSF or MTF is read to.
pub(crate) fn fft2(data: &mut [Complex32], size: usize) {
    let fft = FftPlanner::new().plan_fft_forward(size);
    fft.process(data);
    let mut transposed = transpose(data, size);
    fft.process(&mut transposed);
    data.copy_from_slice(&transpose(&transposed, size));
}

fn transpose(data: &[Complex32], size: usize) -> Vec<Complex32> {
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
    fn a_polychromatic_perfect_psf_has_the_mean_airy_radius_and_keeps_its_energy() {
        // Equal weights at 450 and 650 nm: the encircled energy at each wavelength's first zero
        // is the mean of the two Airy patterns' there (Born & Wolf §8.5.2, L(v) = 1 − J0² − J1²).
        let f_number = 8.0;
        let part = |nm: f64| (Wavefront::diffraction_limited(128, f_number, nm).psf(8).unwrap(), 1.0);
        let (blue, red) = (part(450.0), part(650.0));
        let mixed = PointSpread::polychromatic(&[blue.clone(), red.clone()]).unwrap();
        assert!((mixed.intensity().iter().sum::<f64>() - 1.0).abs() < 1e-12);
        assert_eq!(mixed.spacing_mm(), blue.0.spacing_mm());
        for radius_mm in [1.22e-6 * 450.0 * f_number, 1.22e-6 * 650.0 * f_number, 0.02] {
            let expected = 0.5 * (blue.0.encircled_energy(radius_mm) + red.0.encircled_energy(radius_mm));
            let got = mixed.encircled_energy(radius_mm);
            assert!(
                (got - expected).abs() < 0.01,
                "at {radius_mm} mm: {got}, expected {expected}"
            );
        }
        assert!(PointSpread::polychromatic(&[(blue.0, 0.0)]).is_err());
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

    /// The PSF's centroid lies at the rays' mean intercept on the sensor
    /// (a theorem for a uniformly lit pupil: the centroid follows the mean
    /// wavefront slope, Welford §8.4), on the same side of the chief ray's
    /// image point: the PSF is in the sensor's orientation, not mirrored.
    #[test]
    fn the_psfs_centroid_is_the_rays_mean_intercept_off_axis() {
        use crate::lens::{Direction, LensPrescription, LensRay, LensSystem};
        use glam::DVec3;
        let system = LensSystem::new(&LensPrescription::load("dgauss50").unwrap())
            .with_f_number(2.8)
            .unwrap();
        let (field_deg, sensor_depth_mm) = (15.0f64, system.infinity_focus_z_mm(0.1).unwrap());
        let wavefront = system.wavefront(field_deg, sensor_depth_mm, 128).unwrap();
        let psf = wavefront.psf(4).unwrap();
        let (size, [dx, dy]) = (psf.size(), psf.spacing_mm());
        let centre = (size / 2) as f64;
        let (mut psf_x, mut psf_y) = (0.0, 0.0);
        for (k, v) in psf.intensity().iter().enumerate() {
            psf_x += v * ((k % size) as f64 - centre) * dx;
            psf_y += v * ((k / size) as f64 - centre) * dy;
        }
        // Parallel rays on a fine square wide enough for the whole beam; the lens picks the pupil.
        let direction = DVec3::new(0.0, field_deg.to_radians().sin(), field_deg.to_radians().cos());
        let (side, half_mm) = (600, 2.0 * system.front_aperture_radius_mm());
        let start_z = system.front_z_mm() - 5.0;
        let image = wavefront.image_point_mm();
        let (mut count, mut ray_x, mut ray_y) = (0.0, 0.0, 0.0);
        for j in 0..side {
            for i in 0..side {
                let at = |k: usize| (k as f64 / (side - 1) as f64 * 2.0 - 1.0) * half_mm;
                let ray = LensRay {
                    origin: DVec3::new(at(i), at(j) + start_z * direction.y / direction.z, start_z),
                    direction,
                };
                if let Some(hit) = system
                    .trace(&ray, Direction::ToSensor)
                    .and_then(|out| out.at_z(sensor_depth_mm))
                {
                    (count, ray_x, ray_y) = (count + 1.0, ray_x + hit.x - image.x, ray_y + hit.y - image.y);
                }
            }
        }
        let (ray_x, ray_y) = (ray_x / count, ray_y / count);
        assert!(
            ray_y.abs() > 2e-3,
            "coma and astigmatism displace the spot ({ray_y} mm)"
        );
        assert!(
            (psf_y - ray_y).abs() < 0.1 * ray_y.abs() && psf_x.abs() < 1e-4 && ray_x.abs() < 1e-4,
            "PSF centroid ({psf_x}, {psf_y}) mm, rays' ({ray_x}, {ray_y}) mm"
        );
    }
}
