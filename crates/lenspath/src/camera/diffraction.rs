//! Diffraction at the camera's pupil, as a displacement of the film point.
//!
//! Through a lens free of aberrations, a point's image at wavelength λ is the
//! Fraunhofer pattern |𝓕{P}|² of its pupil P, scaled so that the pupil's unit
//! radius maps to film distances x = 2λN·ν (ν in cycles per pupil radius, N
//! the working f-number; Goodman, *Introduction to Fourier Optics*, 3rd ed.,
//! §6.2). By reciprocity a film point that gathers light from a point
//! displaced by a draw from that pattern sees the geometric image convolved
//! with it: diffraction-limited where the lens is sharp, aberration-dominated
//! where its geometric blur is wide, and between the two the convolution,
//! not the full wave PSF (`lens::psf`), whose aberrated wavefront interferes
//! with itself. The pattern depends only on the aperture's shape, so it is
//! tabulated once per shape, in units of ν, for every wavelength and f-number.

use std::sync::{Arc, Mutex};

use glam::{DVec2, Vec2};
use rustfft::num_complex::Complex32;

use super::{Aperture, ApertureShape};
use crate::lens::psf::{centred, fft2};
use crate::sampling::Distribution1D;

/// Pupil samples across the unit disk's bounding square: blade edges are
/// anti-aliased by [`Aperture::rasterize`]'s 4×4 points per sample.
const PUPIL_SAMPLES: usize = 64;
/// Patterns kept for reuse: autofocus builds a camera for every sensor
/// position it tries, with the same aperture.
const CACHED_PATTERNS: usize = 4;

/// Zero padding of the pupil before the FFT: the pattern's cells are
/// 1/(2·PADDING) cycles per radius wide, λN/PADDING on the film (the Airy
/// disc's first dark ring, 1.22 λN, is ten cells out), and the table spans
/// ±PUPIL_SAMPLES/4 cycles per radius, ±PUPIL_SAMPLES/2 · λN on the film.
const PADDING: usize = 8;

/// The pupil's Fraunhofer intensity, normalised to a density over ν and
/// tabulated piecewise constant, ready to be sampled and evaluated.
#[derive(Clone, Debug)]
pub struct DiffractionPattern {
    /// Cells a side.
    size: usize,
    /// A cell's width, cycles per pupil radius.
    step: f64,
    /// The rows' shares.
    rows: Distribution1D,
    /// Each row's cells.
    columns: Vec<Distribution1D>,
    /// Each cell's density, per (cycle per radius)², row-major, row 0 the lowest ν_y.
    density: Vec<f32>,
}

impl DiffractionPattern {
    /// The pattern of `aperture`'s transmission over the unit disk.
    pub fn new(aperture: &Aperture) -> DiffractionPattern {
        let size = PUPIL_SAMPLES * PADDING;
        let pupil = aperture.rasterize(PUPIL_SAMPLES, PUPIL_SAMPLES, 1.0);
        let mut field = vec![Complex32::new(0.0, 0.0); size * size];
        for (k, value) in pupil.iter().enumerate() {
            field[(k / PUPIL_SAMPLES) * size + k % PUPIL_SAMPLES] = Complex32::new(*value, 0.0);
        }
        fft2(&mut field, size);
        // |F(ν)|² = |F(−ν)|² for a real pupil: which way the raster's rows run does not matter.
        let intensity = centred(&field.iter().map(|c| f64::from(c.norm_sqr())).collect::<Vec<_>>(), size);
        let total: f64 = intensity.iter().sum();
        // Pupil spacing 2/PUPIL_SAMPLES radii: the FFT's frequency step is its inverse over `size`.
        let step = PUPIL_SAMPLES as f64 / (2.0 * size as f64);
        let density: Vec<f32> = intensity.iter().map(|v| (v / (total * step * step)) as f32).collect();
        let row_weights: Vec<f32> = intensity
            .chunks(size)
            .map(|row| row.iter().sum::<f64>() as f32)
            .collect();
        let columns = density.chunks(size).map(Distribution1D::new).collect();
        DiffractionPattern {
            size,
            step,
            rows: Distribution1D::new(&row_weights),
            columns,
            density,
        }
    }

    /// [`DiffractionPattern::new`] of `aperture`, shared with the cameras
    /// built before it with the same shape.
    pub fn shared(aperture: &Aperture) -> Arc<DiffractionPattern> {
        static CACHE: Mutex<Vec<(ApertureShape, Arc<DiffractionPattern>)>> = Mutex::new(Vec::new());
        let shape = aperture.shape();
        if let Some((_, pattern)) = CACHE.lock().unwrap().iter().find(|(s, _)| s == shape) {
            return pattern.clone();
        }
        // Made outside the lock: two cameras built at once may both make it, and neither waits.
        let pattern = Arc::new(DiffractionPattern::new(aperture));
        let mut cache = CACHE.lock().unwrap();
        if cache.len() == CACHED_PATTERNS {
            cache.remove(0);
        }
        cache.push((shape.clone(), pattern.clone()));
        pattern
    }

    /// A displacement in cycles per pupil radius for `u` in [0, 1)², drawn
    /// in proportion to the pattern.
    pub fn sample(&self, u: Vec2) -> DVec2 {
        let (row, _, v) = self.rows.sample(u.y);
        let (column, _, w) = self.columns[row].sample(u.x);
        let origin = self.lower_edge_cells();
        DVec2::new(
            (column as f64 + f64::from(w) - origin) * self.step,
            (row as f64 + f64::from(v) - origin) * self.step,
        )
    }

    /// How many cells the table's lower edge lies below ν = 0, which is
    /// the centre of cell `size / 2` (the FFT's zero frequency, centred).
    fn lower_edge_cells(&self) -> f64 {
        self.size as f64 / 2.0 + 0.5
    }

    /// The density of [`DiffractionPattern::sample`] at `nu` (cycles per
    /// pupil radius), per (cycle per radius)²; 0 outside the table.
    pub fn density(&self, nu: DVec2) -> f64 {
        let origin = self.lower_edge_cells();
        let (column, row) = ((nu.x / self.step + origin).floor(), (nu.y / self.step + origin).floor());
        let inside = |k: f64| k >= 0.0 && k < self.size as f64;
        if inside(column) && inside(row) {
            f64::from(self.density[row as usize * self.size + column as usize])
        } else {
            0.0
        }
    }
}

/// Diffraction as a camera applies it: the pattern and its scale on the film.
#[derive(Clone, Debug)]
pub struct PupilDiffraction {
    pattern: Arc<DiffractionPattern>,
    /// Film distance per cycle per radius per nanometre, mm: 2N·10⁻⁶.
    mm_per_cycle_nm: f64,
}

impl PupilDiffraction {
    /// An aperture's `pattern` through a lens of working f-number `working_f_number`.
    pub fn new(pattern: Arc<DiffractionPattern>, working_f_number: f64) -> PupilDiffraction {
        PupilDiffraction {
            pattern,
            mm_per_cycle_nm: 2.0 * working_f_number * 1e-6,
        }
    }

    /// The working f-number the pattern is scaled by.
    pub fn working_f_number(&self) -> f64 {
        self.mm_per_cycle_nm / 2e-6
    }

    /// A film displacement, mm, for `u` in [0, 1)² at `wavelength_nm`.
    pub fn displacement_mm(&self, u: Vec2, wavelength_nm: f32) -> DVec2 {
        self.pattern.sample(u) * (self.mm_per_cycle_nm * f64::from(wavelength_nm))
    }

    /// The density, per mm², with which [`PupilDiffraction::displacement_mm`]
    /// draws `displacement_mm` at `wavelength_nm`: the point-spread function.
    pub fn density_per_mm2(&self, displacement_mm: DVec2, wavelength_nm: f32) -> f64 {
        let scale = self.mm_per_cycle_nm * f64::from(wavelength_nm);
        self.pattern.density(displacement_mm / scale) / (scale * scale)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Rng;

    fn pattern(shape: &str) -> DiffractionPattern {
        DiffractionPattern::new(&Aperture::new(&ApertureShape::parse(shape).unwrap()).unwrap())
    }

    #[test]
    fn the_circle_makes_the_airy_pattern() {
        // 83.8 % of the energy within the first dark ring, ν = 1.2197/2 cycles per radius (Born & Wolf §8.5.2).
        let airy = pattern("circle");
        let first_zero = 1.2197 / 2.0;
        let mut rng = Rng::new(7);
        let n = 200_000;
        let inside = (0..n)
            .filter(|_| airy.sample(Vec2::new(rng.uniform(), rng.uniform())).length() < first_zero)
            .count();
        let energy = inside as f64 / n as f64;
        assert!((energy - 0.838).abs() < 0.01, "encircled energy {energy}");
        // The density is zero-ish on the ring and highest at the centre.
        let ring = airy.density(DVec2::new(first_zero, 0.0));
        let centre = airy.density(DVec2::ZERO);
        assert!(ring < 0.01 * centre, "ring {ring}, centre {centre}");
    }

    #[test]
    fn density_is_the_sampled_distribution_and_integrates_to_one() {
        let blades = pattern("blades:6");
        let step = blades.step;
        let total: f64 = blades.density.iter().map(|d| f64::from(*d) * step * step).sum();
        assert!((total - 1.0).abs() < 1e-3, "{total}");
        // A histogram of draws over 5×5 cells off the centre matches the density there.
        let mut rng = Rng::new(3);
        let n = 400_000;
        let centre = DVec2::new(5.0, -3.0) * step;
        let hits = (0..n)
            .filter(|_| {
                let nu = blades.sample(Vec2::new(rng.uniform(), rng.uniform()));
                ((nu - centre) / step).abs().max_element() < 2.5
            })
            .count();
        let expected = (-2..=2)
            .flat_map(|i| (-2..=2).map(move |j| DVec2::new(f64::from(i), f64::from(j))))
            .map(|offset| blades.density(centre + offset * step))
            .sum::<f64>()
            * step
            * step;
        let measured = hits as f64 / n as f64;
        assert!((measured / expected - 1.0).abs() < 0.05, "{measured} vs {expected}");
    }

    /// The pattern's angular spectrum between 2 and 12 cycles per radius: its
    /// strongest harmonic in azimuth (how many spikes) and that harmonic's
    /// amplitude over the mean.
    fn spikes(pattern: &DiffractionPattern) -> (usize, f64) {
        let bins = 360;
        let mut share = vec![0.0f64; bins];
        let origin = pattern.size as f64 / 2.0;
        for (k, density) in pattern.density.iter().enumerate() {
            let nu = DVec2::new((k % pattern.size) as f64 - origin, (k / pattern.size) as f64 - origin) * pattern.step;
            if (2.0..12.0).contains(&nu.length()) {
                let turn = nu.y.atan2(nu.x).rem_euclid(std::f64::consts::TAU) / std::f64::consts::TAU;
                share[((turn * bins as f64) as usize).min(bins - 1)] += f64::from(*density);
            }
        }
        let mean = share.iter().sum::<f64>() / bins as f64;
        let amplitude = |m: usize| {
            let (c, s) = share.iter().enumerate().fold((0.0, 0.0), |(c, s), (b, v)| {
                let phase = std::f64::consts::TAU * (m * b) as f64 / bins as f64;
                (c + v * phase.cos(), s + v * phase.sin())
            });
            2.0 * c.hypot(s) / bins as f64 / mean
        };
        (1..=40)
            .map(|m| (m, amplitude(m)))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap()
    }

    #[test]
    fn an_iris_makes_a_spike_per_blade_edge_direction() {
        // Each straight edge diffracts across itself: an even count's opposite edges share
        // their spikes (6 blades, 6 spikes), an odd count's do not (7 blades, 14); an 8-point
        // star has 16 edges in 8 directions, 16 spikes.
        for (shape, count) in [
            ("blades:6", 6),
            ("blades:7", 14),
            ("blades:5:10", 10),
            ("star:8:0.5", 16),
        ] {
            let (harmonic, amplitude) = spikes(&pattern(shape));
            assert_eq!(harmonic, count, "{shape}");
            assert!(amplitude > 0.5, "{shape}: {amplitude}");
        }
        // The circle's pattern is round, but for the pupil raster's square grid (fourfold, 2.6 %).
        let (harmonic, amplitude) = spikes(&pattern("circle"));
        assert!(amplitude < 0.04, "circle: harmonic {harmonic} at {amplitude}");
    }
}
