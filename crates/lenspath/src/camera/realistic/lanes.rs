//! A sample's four wavelengths through a dispersive lens.
//!
//! A lens whose glasses disperse sends each wavelength from a film point out
//! along its own ray, so the ray traced at the hero wavelength left, for each
//! other wavelength, from another film point. pbrt-v4 keeps the hero alone
//! (`TerminateSecondary`), which turns every camera ray into one wavelength:
//! on `cornell-spheres` through `dgauss50` that is 5–8× the error at equal
//! time (BENCHMARKS.md, "Lens colour noise"). Here all wavelengths stay on
//! the hero's ray, each weighted by multiple importance sampling over which
//! wavelength led it (Wilkie et al. 2014, §4, "hero wavelength MIS"; the
//! balance heuristic, Veach 1997 §9.2, over n techniques "λ_k led", each
//! chosen with probability 1/n by the rotation of the wavelengths):
//!
//! ```text
//! w_i = W(x_i) T_i / ((1/n) Σ_k p_k(r)),   p_k(r) = p_film(x_k) p_pupil(q_k | x_k) / g(x_k, q_k)
//! ```
//!
//! The ray `r` is traced back through the lens at λ_k to its film point x_k
//! and rear-plane point q_k. W is the pixel filter (the film's measurement),
//! T the aperture's transmission where the ray crosses the stop, and p_k(r)
//! the density with which the camera draws r when λ_k leads: the film and
//! pupil densities over the geometric factor g = cos⁴θ / d². No Jacobian
//! between wavelengths is needed: a lens conserves étendue (Liouville's
//! theorem for refraction between media of index 1 at every wavelength), so
//! a bundle's measure g dA(x) dA(q) on the film side is the same at every
//! wavelength as its dA dω⊥ in the scene (`lane_maps_conserve_etendue`
//! checks this by finite differences).
//!
//! The camera ray carries the hero's own weight W T / p_h; lane i's factor
//! w_i / (W(x_h) T_h / p_h(r)) goes into its density
//! ([`SampledWavelengths::weight_lanes`]). A dispersive interface further
//! along keeps only the hero and restores its own density, which is the
//! hero-alone estimate, as pbrt's, of every path that meets one.
//!
//! Through a diffracting pupil (`camera/diffraction.rs`) the film point x the
//! sample drew is displaced to x + δ before the ray is traced, δ drawn from
//! the point-spread function S_h at the hero's wavelength. Lane i's
//! measurement and density then carry S_i(x_i − x) where they carried W(x_i)
//! (W(x) is every lane's and cancels); through a lens that does not disperse,
//! x_i is the same point for every lane and w_i = S_i(δ) / ((1/n) Σ_k S_k(δ)).

use glam::{DVec2, DVec3, Vec2, Vec4};

use super::RealisticCamera;
use crate::camera::CameraSample;
use crate::lens::{Direction, LensRay, LensSystem};
use crate::spectrum::{SampledWavelengths, WAVELENGTHS_PER_SAMPLE};

/// How far out along a ray leaving the lens its trace back starts, mm: any
/// point in front of the surface it left from will do.
const TRACE_BACK_START_MM: f64 = 1.0;

/// Where a ray leaving the lens came from at one wavelength.
#[derive(Clone, Copy, Debug)]
struct FilmSide {
    /// Film point, raster coordinates.
    raster: Vec2,
    /// Film point, lens coordinates (mm).
    film: DVec3,
    /// Rear-plane point, lens coordinates (mm).
    rear: DVec2,
    /// Cosine of the angle between the line from the film and the axis.
    cos_theta: f64,
    /// The aperture's transmission where the ray crossed the stop.
    transmission: f64,
}

impl RealisticCamera {
    /// The wavelengths of `sample`, each weighted (module notes) for the ray
    /// `out` the camera traced at the hero wavelength from the film along
    /// `start`. Unchanged when the lens does not disperse or the sample
    /// carries one wavelength.
    pub(super) fn weighted_wavelengths(
        &self,
        sample: &CameraSample,
        start: &LensRay,
        out: &LensRay,
    ) -> SampledWavelengths {
        let mut wavelengths = sample.wavelengths;
        let live = wavelengths.live_count();
        if live < 2 {
            return wavelengths;
        }
        // The diffraction, and the film point the sample drew before it was displaced.
        let diffraction = (self.diffraction.as_ref())
            .filter(|_| sample.diffraction.is_some())
            .map(|diffraction| (diffraction, self.film_point(sample.film)));
        if self.spectral.is_none() {
            // One ray for every wavelength: they differ only in how far diffraction spreads them.
            if let Some((diffraction, drawn_film)) = diffraction {
                let displacement = (start.origin - drawn_film).truncate();
                let spread = [0, 1, 2, 3].map(|lane| {
                    if wavelengths.pdf[lane] > 0.0 {
                        diffraction.density_per_mm2(displacement, wavelengths.lambda_nm[lane])
                    } else {
                        0.0
                    }
                });
                let mean = spread.iter().sum::<f64>() / f64::from(live);
                if mean > 0.0 && spread[0] > 0.0 {
                    wavelengths.weight_lanes(Vec4::from_array(spread.map(|s| (s / mean) as f32)));
                }
            }
            return wavelengths;
        }
        let mut weight = [0.0f64; WAVELENGTHS_PER_SAMPLE];
        let mut density = [0.0f64; WAVELENGTHS_PER_SAMPLE];
        for (lane, side) in self.film_sides(sample, start, out).into_iter().enumerate() {
            if let Some(side) = side.filter(|_| wavelengths.pdf[lane] > 0.0) {
                // The film's measurement: the pixel filter at the film point, or, through a
                // diffracting pupil, the spread from the drawn point (the filter there is every lane's).
                let film_density = match diffraction {
                    Some((diffraction, drawn_film)) => {
                        diffraction.density_per_mm2((side.film - drawn_film).truncate(), wavelengths.lambda_nm[lane])
                    }
                    None => f64::from(sample.film_density(side.raster)),
                };
                weight[lane] = film_density * side.transmission;
                density[lane] = film_density * self.pupil_density(&side, lane == 0) / side.cos_theta.powi(4);
            }
        }
        let mean_density = density.iter().sum::<f64>() / f64::from(live);
        // Relative to the hero's own weight W(x_h) T_h / p_h.
        let scale = density[0] / (weight[0] * mean_density);
        if !(scale.is_finite() && scale > 0.0) {
            return wavelengths;
        }
        wavelengths.weight_lanes(Vec4::from_array(weight.map(|w| (w * scale) as f32)));
        wavelengths
    }

    /// Where `out` came from at each of the sample's wavelengths: for the
    /// hero, the film point the camera drew; for the others, traced back.
    fn film_sides(
        &self,
        sample: &CameraSample,
        start: &LensRay,
        out: &LensRay,
    ) -> [Option<FilmSide>; WAVELENGTHS_PER_SAMPLE] {
        let systems = [0, 1, 2, 3].map(|lane| self.system_at(sample.wavelengths.lambda_nm[lane]));
        match &self.shaped {
            // The plain circle: the three others traced back together.
            None => {
                let back = [trace_back_start(out); 3];
                let [a, b, c] =
                    LensSystem::trace_each([systems[1], systems[2], systems[3]], &back, Direction::ToSensor);
                let drawn = FilmSide {
                    raster: sample.film,
                    film: start.origin,
                    rear: start.at_z(self.rear_z_mm).unwrap_or(start.origin).truncate(),
                    cos_theta: -start.direction.z,
                    transmission: 1.0,
                };
                [
                    Some(drawn),
                    a.and_then(|inside| self.film_side_of(&inside, 1.0)),
                    b.and_then(|inside| self.film_side_of(&inside, 1.0)),
                    c.and_then(|inside| self.film_side_of(&inside, 1.0)),
                ]
            }
            // A shaped aperture: each one by itself, the hero too, for where
            // it crossed the stop (its transmission).
            Some(_) => {
                let mut sides = systems.map(|system| self.film_side(system, out));
                sides[0] = sides[0].map(|side| FilmSide {
                    raster: sample.film,
                    ..side
                });
                sides
            }
        }
    }

    /// Where the ray `out` leaving the lens came from when traced back
    /// through `system` (the lens at one wavelength); `None` when the lens
    /// or the aperture's shape blocks it there.
    fn film_side(&self, system: &LensSystem, out: &LensRay) -> Option<FilmSide> {
        let back = trace_back_start(out);
        match &self.shaped {
            None => self.film_side_of(&system.trace(&back, Direction::ToSensor)?, 1.0),
            Some((aperture, _)) => {
                let (inside, at_stop) = system.trace_via_stop(&back, Direction::ToSensor)?;
                self.film_side_of(
                    &inside,
                    aperture.transmission(at_stop.truncate() / system.stop_radius_mm()),
                )
            }
        }
    }

    /// The film side of `inside`, a ray traced back out of the rear element.
    fn film_side_of(&self, inside: &LensRay, transmission: f64) -> Option<FilmSide> {
        if inside.direction.z <= 0.0 || transmission <= 0.0 {
            return None;
        }
        let film = inside.at_z(self.sensor_depth_mm)?;
        Some(FilmSide {
            raster: self.raster_point(film),
            film,
            rear: inside.at_z(self.rear_z_mm)?.truncate(),
            cos_theta: inside.direction.z,
            transmission,
        })
    }

    /// The density, per mm² of the rear plane, with which the camera draws
    /// `side`'s rear-plane point for its film point. `drawn`: the camera
    /// drew it (the hero's), so it lies in its grid, which testing it again
    /// could miss by a rounding at a cell's edge.
    fn pupil_density(&self, side: &FilmSide, drawn: bool) -> f64 {
        let (patch, local, frame) = self.film_place(side.film);
        let grid = &self.pupils[patch];
        if grid.cells.is_empty() {
            return 0.0;
        }
        let q = frame.grid_from_film(side.rear);
        match &self.shaped {
            None => {
                if drawn || grid.contains(q, local) {
                    1.0 / grid.area()
                } else {
                    0.0
                }
            }
            Some((aperture, maps)) => maps[patch]
                .as_ref()
                .map_or(0.0, |map| self.shaped_density(aperture, grid, map, local, frame, q)),
        }
    }
}

/// The ray `out` leaving the lens, turned round to be traced back into it.
fn trace_back_start(out: &LensRay) -> LensRay {
    LensRay {
        origin: out.origin + out.direction * TRACE_BACK_START_MM,
        direction: -out.direction,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{pixel_sample, Camera, CameraPose, LensFocus, RealisticCameraSettings};
    use crate::film::Filter;
    use crate::lens::{LensPrescription, TableConvention};
    use crate::sampling::SamplerKind;
    use glam::{DMat4, DVec4, Vec3};

    fn dgauss_camera() -> RealisticCamera {
        let lens = LensPrescription::load("dgauss50").unwrap();
        let settings = RealisticCameraSettings::new(lens, (36.0, 24.0), LensFocus::Distance(1.0));
        let pose = CameraPose::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y);
        RealisticCamera::new(pose, 320, 240, &settings).unwrap()
    }

    /// Étendue: the map from a film point and rear-plane point traced out at
    /// one wavelength and back at another has Jacobian determinant
    /// g(x, q) / g(x′, q′), measured by central differences.
    #[test]
    fn lane_maps_conserve_etendue() {
        let camera = dgauss_camera();
        let (blue, red) = (camera.system.at_wavelength(420.0), camera.system.at_wavelength(680.0));
        let map = |v: DVec4| -> Option<(DVec4, f64)> {
            let film = DVec3::new(v.x, v.y, camera.sensor_depth_mm);
            let start = LensRay::between(film, DVec3::new(v.z, v.w, camera.rear_z_mm));
            let out = blue.trace(&start, Direction::ToScene)?;
            let side = camera.film_side(&red, &out)?;
            Some((
                DVec4::new(side.film.x, side.film.y, side.rear.x, side.rear.y),
                side.cos_theta,
            ))
        };
        let g = |cos: f64| cos.powi(4);
        let mut checked = 0;
        for (film, rear) in [
            (DVec2::new(0.0, 0.0), DVec2::new(3.0, 1.0)),
            (DVec2::new(8.0, -5.0), DVec2::new(-2.0, 4.0)),
            (DVec2::new(-14.0, 2.0), DVec2::new(1.5, -6.0)),
        ] {
            let v = DVec4::new(film.x, film.y, rear.x, rear.y);
            let Some((_, cos_red)) = map(v) else { continue };
            let cos_blue = {
                let d = DVec3::new(
                    rear.x - film.x,
                    rear.y - film.y,
                    camera.rear_z_mm - camera.sensor_depth_mm,
                );
                -d.normalize().z
            };
            let h = 1e-4;
            let columns: Vec<DVec4> = (0..4)
                .map(|k| {
                    let mut e = DVec4::ZERO;
                    e[k] = h;
                    (map(v + e).unwrap().0 - map(v - e).unwrap().0) / (2.0 * h)
                })
                .collect();
            let jacobian = DMat4::from_cols(columns[0], columns[1], columns[2], columns[3]).determinant();
            let expected = g(cos_blue) / g(cos_red);
            assert!(
                (jacobian - expected).abs() < 1e-7 * expected,
                "at {film:?}: |J| {jacobian} against g ratio {expected}"
            );
            assert!(
                (jacobian - 1.0).abs() > 1e-6 || film == DVec2::ZERO,
                "the map should not be trivial"
            );
            checked += 1;
        }
        assert!(checked >= 2, "only {checked} rays passed");
    }

    /// The weighted lanes estimate what the hero alone estimates, with less
    /// noise: a pixel of an out-of-focus edge through an N-BK7 singlet at
    /// f/2.8 (its wavelengths land pixels apart), Gaussian filter, a
    /// radiance that depends on the wavelength and the ray. Measured: the
    /// means agree to 2e-4 relative; variance 0.30, 0.37 and 0.58 of the
    /// hero alone's in X, Y and Z (the blue spreads farthest, and lanes
    /// landing outside the pixel's filter add nothing).
    #[test]
    fn weighted_lanes_agree_with_the_hero_alone() {
        let table = "0 2 0 17.9\n51.68 5 1.5168 24 N-BK7\n-51.68 45 1 24\n";
        let lens = LensPrescription::parse(table, "singlet", TableConvention::ThicknessToNext).unwrap();
        // 3 mm in front of the infinity focus (56.16 mm): a blur 15 pixels across.
        let settings = RealisticCameraSettings::new(lens, (4.8, 4.8), LensFocus::SensorDepthMm(53.0));
        let pose = CameraPose::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y);
        let camera = RealisticCamera::new(pose, 64, 64, &settings).unwrap();
        // A bright half-plane of the view (x > 0) whose spectrum rises to the red.
        let radiance = |ray: &crate::ray::Ray, lambda: Vec4| {
            let spectral = Vec4::ONE + (lambda - Vec4::splat(550.0)) / 300.0;
            if ray.direction.x > 0.02 {
                spectral
            } else {
                0.1 * spectral
            }
        };
        let n = 60_000;
        let (mut weighted, mut alone) = ([DVec3::ZERO; 2], [DVec3::ZERO; 2]);
        let mut reweighted_lanes = 0;
        for index in 0..n {
            let (_, sample) = pixel_sample(SamplerKind::Sobol, 33, 31, index, 7, Filter::GAUSSIAN, false);
            let Some(ray) = camera.generate_ray(sample) else {
                continue;
            };
            let l = radiance(&ray.ray, ray.wavelengths.lambda_nm);
            let mut hero = ray.wavelengths;
            hero.terminate_secondary();
            reweighted_lanes += usize::from(ray.wavelengths.pdf != sample.wavelengths.pdf);
            for (sums, wavelengths) in [(&mut weighted, ray.wavelengths), (&mut alone, hero)] {
                let xyz = (wavelengths.to_xyz(l) * ray.weight).as_dvec3();
                sums[0] += xyz;
                sums[1] += xyz * xyz;
            }
        }
        assert!(
            reweighted_lanes > n as usize / 2,
            "only {reweighted_lanes} samples had their lanes weighed"
        );
        let stats = |sums: [DVec3; 2]| {
            let mean = sums[0] / f64::from(n);
            (mean, (sums[1] / f64::from(n) - mean * mean) / f64::from(n))
        };
        let ((mean_w, var_w), (mean_h, var_h)) = (stats(weighted), stats(alone));
        for c in 0..3 {
            let bound = 4.0 * (var_w[c] + var_h[c]).sqrt();
            assert!(
                (mean_w[c] - mean_h[c]).abs() < bound,
                "channel {c}: weighted {} against hero alone {} (4σ {bound})",
                mean_w[c],
                mean_h[c]
            );
            assert!(
                var_w[c] < 0.7 * var_h[c],
                "channel {c}: variance {} against {}",
                var_w[c],
                var_h[c]
            );
        }
    }
}
