//! The modulation transfer function: the modulus of the optical transfer
//! function, the Fourier transform of the [`PointSpread`] normalised to 1 at
//! zero frequency (Goodman, *Introduction to Fourier Optics*, 3rd ed., §6.3),
//! with the tangential (y) and sagittal (x) sections a lens report draws, and
//! the diffraction limit beside them.

use rustfft::num_complex::Complex32;

use super::psf::{centred, fft2, PointSpread};

/// The MTF on the grid of spatial frequencies the PSF's sampling gives.
#[derive(Clone, Debug)]
pub struct Mtf {
    size: usize,
    /// Frequency step in x and y, cycles per mm.
    spacing_per_mm: [f64; 2],
    /// Modulus per frequency, zero frequency at (size/2, size/2).
    modulus: Vec<f64>,
}

impl PointSpread {
    /// The MTF of this PSF.
    pub fn mtf(&self) -> Mtf {
        let size = self.size();
        let mut spectrum: Vec<Complex32> = self
            .intensity()
            .iter()
            .map(|&v| Complex32::new(v as f32, 0.0))
            .collect();
        fft2(&mut spectrum, size);
        let dc = f64::from(spectrum[0].norm());
        let modulus: Vec<f64> = spectrum.iter().map(|c| f64::from(c.norm()) / dc).collect();
        Mtf {
            size,
            spacing_per_mm: self.spacing_mm().map(|d| 1.0 / (size as f64 * d)),
            modulus: centred(&modulus, size),
        }
    }
}

impl Mtf {
    /// The tangential MTF (frequencies along y, the field's direction) at `frequency_per_mm`.
    pub fn tangential(&self, frequency_per_mm: f64) -> f64 {
        self.section(frequency_per_mm, 1)
    }

    /// The sagittal MTF (frequencies along x) at `frequency_per_mm`.
    pub fn sagittal(&self, frequency_per_mm: f64) -> f64 {
        self.section(frequency_per_mm, 0)
    }

    /// The lowest frequency where the tangential (`axis` 1) or sagittal
    /// (`axis` 0) MTF falls to 0.5, linearly interpolated between samples:
    /// MTF50, the figure ISO 12233 and lens reviews quote. `None` when it
    /// stays above 0.5 over the grid.
    pub fn mtf50_per_mm(&self, axis: usize) -> Option<f64> {
        let step = self.spacing_per_mm[axis];
        let value = |k: usize| self.section(k as f64 * step, axis);
        (1..self.size / 2).find_map(|k| {
            let (above, below) = (value(k - 1), value(k));
            (below <= 0.5).then(|| step * ((k - 1) as f64 + (above - 0.5) / (above - below)))
        })
    }

    /// The highest frequency the grid holds along each axis, cycles per mm.
    pub fn max_frequency_per_mm(&self) -> [f64; 2] {
        self.spacing_per_mm.map(|d| d * (self.size / 2 - 1) as f64)
    }

    /// Linear interpolation along the axis through zero frequency; 0 beyond the grid.
    fn section(&self, frequency_per_mm: f64, axis: usize) -> f64 {
        let position = frequency_per_mm.abs() / self.spacing_per_mm[axis];
        let (below, fraction) = (position.floor() as usize, position.fract());
        let centre = self.size / 2;
        let at = |offset: usize| {
            let k = centre + offset;
            if k >= self.size {
                return 0.0;
            }
            match axis {
                0 => self.modulus[centre * self.size + k],
                _ => self.modulus[k * self.size + centre],
            }
        };
        at(below) * (1.0 - fraction) + at(below + 1) * fraction
    }
}

/// The MTF of a perfect lens with a circular pupil at working f-number
/// `f_number`: 2/π·(φ − cos φ sin φ), φ = arccos(ν/ν_c), cut off at
/// ν_c = 1/(λN) (Goodman §6.3.3).
pub fn diffraction_limited_mtf(frequency_per_mm: f64, wavelength_nm: f64, f_number: f64) -> f64 {
    let cutoff_per_mm = 1.0 / (wavelength_nm * 1e-6 * f_number);
    let ratio = frequency_per_mm.abs() / cutoff_per_mm;
    if ratio >= 1.0 {
        return 0.0;
    }
    let phi = ratio.acos();
    std::f64::consts::FRAC_2_PI * (phi - phi.cos() * phi.sin())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lens::wavefront::Wavefront;

    #[test]
    fn a_perfect_lens_has_the_circular_pupils_mtf() {
        let (f_number, wavelength_nm) = (4.0, 550.0);
        let mtf = Wavefront::diffraction_limited(128, f_number, wavelength_nm)
            .psf(4)
            .unwrap()
            .mtf();
        let cutoff = 1.0 / (wavelength_nm * 1e-6 * f_number);
        for k in 0..=20 {
            let nu = cutoff * k as f64 / 20.0;
            let exact = diffraction_limited_mtf(nu, wavelength_nm, f_number);
            for (name, value) in [("tangential", mtf.tangential(nu)), ("sagittal", mtf.sagittal(nu))] {
                assert!(
                    (value - exact).abs() < 0.01,
                    "{name} MTF at {nu:.0} lp/mm: {value}, exact {exact}"
                );
            }
        }
    }

    #[test]
    fn a_perfect_lens_has_the_published_mtf50() {
        // The circular pupil's MTF is 0.5 at ν = 0.4040 ν_c (solving 2/π·(φ − cos φ sin φ) = ½).
        let (f_number, wavelength_nm) = (8.0, 550.0);
        let mtf = Wavefront::diffraction_limited(128, f_number, wavelength_nm)
            .psf(4)
            .unwrap()
            .mtf();
        let expected = 0.4040 / (wavelength_nm * 1e-6 * f_number);
        for axis in [0, 1] {
            let mtf50 = mtf.mtf50_per_mm(axis).unwrap();
            assert!(
                (mtf50 / expected - 1.0).abs() < 0.01,
                "MTF50 {mtf50} against {expected}"
            );
        }
        assert!((diffraction_limited_mtf(expected, wavelength_nm, f_number) - 0.5).abs() < 1e-3);
    }

    #[test]
    fn a_real_lens_stopped_down_on_axis_is_near_the_diffraction_limit_and_never_above_it() {
        let system = crate::lens::wavefront::tests::singlet().with_f_number(16.0).unwrap();
        let f_number = system.paraxial().unwrap().f_number;
        let focus = system.infinity_focus_z_mm(0.1).unwrap();
        let mtf = system.wavefront(0.0, focus, 64).unwrap().psf(4).unwrap().mtf();
        for nu in [10.0, 25.0, 50.0, 75.0, 100.0] {
            let (real, limit) = (mtf.tangential(nu), diffraction_limited_mtf(nu, 550.0, f_number));
            assert!(
                real <= limit + 0.01 && real > limit - 0.05,
                "MTF at {nu} lp/mm: {real}, limit {limit}"
            );
        }
    }
}
