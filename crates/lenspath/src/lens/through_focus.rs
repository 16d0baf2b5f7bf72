//! Through-focus analysis of a point's image: the bundle of real rays from an
//! object point through the lens ([`SpotBundle`]), its geometric modulation
//! transfer at a sensor position, and the sensor position of best contrast.
//!
//! A wide-open lens does not image a point best at its paraxial (or
//! near-axis real-ray) conjugate: spherical aberration and field curvature
//! move the plane of best contrast by a depth of focus or more (for
//! `dgauss50` at f/2, 1 to 2.5 DoF at 640×480). Lens designers read it off
//! the through-focus MTF; this is its geometric-optics form (Smith, *Modern
//! Optical Engineering*, 4th ed., §11.7: the MTF of a spot diagram is the
//! magnitude of the mean of exp(2πi·ν·x) over its ray intercepts).
//!
use glam::DVec3;

use super::system::{Direction, LensRay, LensSystem};

/// The real rays from one object point that pass the lens, as they leave its rear surface.
#[derive(Clone, Debug)]
pub struct SpotBundle {
    rays: Vec<LensRay>,
}

impl LensSystem {
    /// Rays from `object` (lens coordinates, in front of the lens) toward a
    /// `grid` × `grid` square of points over the front element's clear
    /// aperture, traced to the sensor side; the blocked ones are dropped, so
    /// vignetting shapes the bundle as it shapes the image.
    pub fn spot_bundle(&self, object: DVec3, grid: usize) -> SpotBundle {
        let radius = self.front_aperture_radius_mm();
        let front_z_mm = self.front_z_mm();
        let mut rays = Vec::with_capacity(grid * grid);
        for j in 0..grid {
            for i in 0..grid {
                let u = 2.0 * (i as f64 + 0.5) / grid as f64 - 1.0;
                let v = 2.0 * (j as f64 + 0.5) / grid as f64 - 1.0;
                if u * u + v * v > 1.0 {
                    continue;
                }
                let target = DVec3::new(u * radius, v * radius, front_z_mm);
                let out = self.trace(&LensRay::between(object, target), Direction::ToSensor);
                if let Some(out) = out.filter(|o| o.direction.z > 0.0) {
                    rays.push(out);
                }
            }
        }
        SpotBundle { rays }
    }
}

impl SpotBundle {
    /// How many rays passed the lens.
    pub fn len(&self) -> usize {
        self.rays.len()
    }

    /// True when no ray passed.
    pub fn is_empty(&self) -> bool {
        self.rays.is_empty()
    }

    /// The modulation energy of the spot at sensor position `sensor_depth_mm`
    /// (mm behind the stop) for a sinusoid of `frequency_per_mm` cycles per
    /// mm: the mean of the squared geometric MTF across x and across y. Squared,
    /// because gradient-energy focus measures (Tenengrad) grow with the
    /// square of the contrast; 1 for a perfect point image, toward 0 when blurred.
    pub fn modulation_energy(&self, sensor_depth_mm: f64, frequency_per_mm: f64) -> f64 {
        if self.rays.is_empty() {
            return 0.0;
        }
        let omega = std::f64::consts::TAU * frequency_per_mm;
        let (mut cx, mut sx, mut cy, mut sy) = (0.0, 0.0, 0.0, 0.0);
        for ray in &self.rays {
            let t = (sensor_depth_mm - ray.origin.z) / ray.direction.z;
            let (x, y) = (ray.origin.x + ray.direction.x * t, ray.origin.y + ray.direction.y * t);
            let (s, c) = (omega * x).sin_cos();
            (sx, cx) = (sx + s, cx + c);
            let (s, c) = (omega * y).sin_cos();
            (sy, cy) = (sy + s, cy + c);
        }
        let n2 = (self.rays.len() * self.rays.len()) as f64;
        0.5 * ((cx * cx + sx * sx) + (cy * cy + sy * sy)) / n2
    }

    /// The sensor position in [`lo`, `hi`] (mm behind the stop) where
    /// [`SpotBundle::modulation_energy`] at `frequency_per_mm` is highest:
    /// the best of `steps` + 1 evenly spaced positions, then the vertex of the
    /// parabola through it and its neighbours. `None` for an empty bundle.
    pub fn best_focus_z(&self, lo: f64, hi: f64, steps: usize, frequency_per_mm: f64) -> Option<f64> {
        if self.rays.is_empty() || steps < 2 || hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
            return None;
        }
        let z = |k: usize| lo + (hi - lo) * k as f64 / steps as f64;
        let energy: Vec<f64> = (0..=steps)
            .map(|k| self.modulation_energy(z(k), frequency_per_mm))
            .collect();
        let best = (0..=steps).max_by(|&a, &b| energy[a].total_cmp(&energy[b]))?;
        if best == 0 || best == steps {
            return Some(z(best));
        }
        let (a, b, c) = (energy[best - 1], energy[best], energy[best + 1]);
        let curvature = a - 2.0 * b + c;
        let offset = if curvature < 0.0 {
            0.5 * (a - c) / curvature
        } else {
            0.0
        };
        Some(z(best) + offset.clamp(-1.0, 1.0) * (hi - lo) / steps as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lens::LensPrescription;

    fn dgauss50() -> LensSystem {
        LensSystem::new(&LensPrescription::load("dgauss50").unwrap())
    }

    #[test]
    fn modulation_of_a_square_blur_is_a_sinc() {
        // Rays converging on (0, 0, 10) from a uniform square pupil, half-width
        // 1 mm at z = 0: at z = 10 + δ the spot is a uniform square of side
        // w = 2δ/10, whose MTF across x (and y) is |sin(πνw) / (πνw)|.
        let n = 200;
        let rays: Vec<LensRay> = (0..n * n)
            .map(|k| {
                let (i, j) = (k % n, k / n);
                let origin = DVec3::new(
                    2.0 * (i as f64 + 0.5) / n as f64 - 1.0,
                    2.0 * (j as f64 + 0.5) / n as f64 - 1.0,
                    0.0,
                );
                LensRay::between(origin, DVec3::new(0.0, 0.0, 10.0))
            })
            .collect();
        let bundle = SpotBundle { rays };
        for (delta, nu) in [(0.5, 3.0), (1.0, 2.0), (2.0, 1.3)] {
            let w = 2.0 * delta / 10.0;
            let x = std::f64::consts::PI * nu * w;
            let expected = (x.sin() / x).powi(2);
            let got = bundle.modulation_energy(10.0 + delta, nu);
            assert!((got - expected).abs() < 1e-3, "δ {delta} ν {nu}: {got} vs {expected}");
        }
        assert!((bundle.modulation_energy(10.0, 5.0) - 1.0).abs() < 1e-12);
        let best = bundle.best_focus_z(8.0, 13.0, 500, 2.0).unwrap();
        assert!((best - 10.0).abs() < 1e-3, "{best}");
    }

    #[test]
    fn a_stopped_down_lens_focuses_best_at_its_real_ray_conjugate() {
        // At f/16 the aberrations are negligible: the best-contrast plane of an
        // on-axis point is its near-axis real-ray conjugate.
        let lens = dgauss50().with_f_number(16.0).unwrap();
        let object = DVec3::new(0.0, 0.0, -2000.0);
        let conjugate = lens.real_image_z_mm(object.z, 0.1).unwrap();
        let bundle = lens.spot_bundle(object, 96);
        assert!(bundle.len() > 20, "{} rays", bundle.len());
        let best = bundle
            .best_focus_z(conjugate - 1.0, conjugate + 1.0, 400, 10.0)
            .unwrap();
        assert!((best - conjugate).abs() < 0.01, "best {best} conjugate {conjugate}");
        // In focus the modulation is nearly perfect; 0.5 mm away (a blur
        // circle of about 30 µm against a 100 µm period) it has dropped.
        let peak = bundle.modulation_energy(best, 10.0);
        assert!(peak > 0.99, "{peak}");
        assert!(bundle.modulation_energy(best + 0.5, 10.0) < 0.85 * peak);
    }

    #[test]
    fn wide_open_field_curvature_moves_the_best_focus_back_off_axis() {
        // dgauss50 at f/2, object 2 m away: on the axis the best focus is the
        // conjugate (within 10 µm); off the axis the best-contrast surface
        // curves away from the lens, the further the more (0.15 mm at 15°,
        // about one depth of focus at 640×480).
        let lens = dgauss50();
        let conjugate = lens.real_image_z_mm(-2000.0, 0.1).unwrap();
        let shifts: Vec<f64> = [0.0f64, 5.0, 10.0, 15.0]
            .iter()
            .map(|angle: &f64| {
                let object = DVec3::new(2000.0 * angle.to_radians().tan(), 0.0, -2000.0);
                let bundle = lens.spot_bundle(object, 64);
                bundle.best_focus_z(conjugate - 1.0, conjugate + 1.0, 400, 2.0).unwrap() - conjugate
            })
            .collect();
        assert!(shifts[0].abs() < 0.01, "{shifts:?}");
        assert!(shifts.windows(2).all(|w| w[1] > w[0] + 0.02), "{shifts:?}");
        assert!(shifts[3] > 0.1 && shifts[3] < 0.25, "{shifts:?}");
    }
}
