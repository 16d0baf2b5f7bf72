//! The wavefront of the real lens at one field point and wavelength: the
//! optical path difference (OPD) of real rays from a distant object point to
//! the reference sphere centred on the chief ray's image point (Welford,
//! *Aberrations of Optical Systems*, 1986, §6.2–6.4), sampled on a square
//! grid over the entrance pupil, as Zemax OpticStudio's and optiland's FFT
//! PSFs sample it.
//!
//! Conventions, chosen once here:
//! - the object is at infinity, `field_deg` off the axis in the vertical
//!   (y) meridian, so the tangential direction is y and the sagittal x;
//! - the grid spans the paraxial entrance pupil's diameter, centred where the
//!   real chief ray (aimed through the stop's centre) crosses the entrance
//!   pupil's plane; samples whose rays the lens blocks are outside the pupil,
//!   so vignetting shapes it (pupil distortion is not corrected: on a
//!   wide-angle lens the real pupil may reach past the grid's circle);
//! - W = OPL(chief ray) − OPL(ray), in waves: positive where the wave has
//!   run ahead of the reference sphere (a sensor behind the focus gives
//!   positive defocus at the pupil's rim).

use glam::DVec3;

use super::system::{Direction, LensRay, LensSystem};
use crate::error::{Error, Result};

/// The OPD over the pupil at one field point, wavelength and sensor position.
#[derive(Clone, Debug)]
pub struct Wavefront {
    /// Samples per side of the grid.
    grid: usize,
    /// OPD per sample (row-major, y rows, x columns), waves; NaN outside the pupil.
    opd_waves: Vec<f64>,
    /// How far the image-space direction cosines (x, y) move per grid step:
    /// the scale from the pupil's samples to the PSF's.
    direction_cosine_steps: [f64; 2],
    /// Refractive index of image space.
    image_index: f64,
    /// Wavelength, nm.
    wavelength_nm: f64,
    /// The chief ray's image point on the sensor plane, lens coordinates, mm.
    image_point_mm: DVec3,
}

/// How far out of the lens (in front of its front vertex and rim) rays start, mm.
const START_CLEARANCE_MM: f64 = 1.0;

impl LensSystem {
    /// The wavefront for an object at infinity `field_deg` off the axis (in
    /// y), at this system's wavelength, with the sensor `sensor_depth_mm`
    /// behind the stop, on a `grid` × `grid` square over the entrance pupil.
    /// Fails when no chief ray passes at that field or `grid` is below 8.
    pub fn wavefront(&self, field_deg: f64, sensor_depth_mm: f64, grid: usize) -> Result<Wavefront> {
        if grid < 8 {
            return Err(Error::InvalidArgument(format!(
                "a wavefront grid needs at least 8 samples a side, got {grid}"
            )));
        }
        let paraxial = self.paraxial()?;
        let launch = Launch::new(self, field_deg, paraxial.entrance_pupil_z_mm);
        let chief_y_mm = self.aim_chief_ray(&launch).ok_or_else(|| {
            Error::InvalidArgument(format!(
                "{}: no chief ray passes the stop at {field_deg}°",
                self.prescription.name
            ))
        })?;
        let (chief_out, chief_path_mm) = self
            .trace_optical_path(&launch.ray(0.0, chief_y_mm), Direction::ToSensor)
            .ok_or_else(|| {
                Error::InvalidArgument(format!(
                    "{}: the chief ray at {field_deg}° is blocked",
                    self.prescription.name
                ))
            })?;
        let image_point_mm = chief_out.at_z(sensor_depth_mm).ok_or_else(|| {
            Error::InvalidArgument(format!(
                "{}: the chief ray at {field_deg}° never reaches the sensor",
                self.prescription.name
            ))
        })?;
        // The reference sphere passes through the exit pupil's centre on the chief ray.
        let exit_pupil_point = chief_out.at_z(paraxial.exit_pupil_z_mm).unwrap_or(chief_out.origin);
        let sphere = ReferenceSphere {
            centre_mm: image_point_mm,
            radius_mm: image_point_mm.distance(exit_pupil_point),
        };
        let image_index = self.surfaces.last().map_or(1.0, |s| s.ior_back);
        let wavelength_mm = self.wavelength_nm() * 1e-6;
        let to_sphere = |out: &LensRay, path_mm: f64| sphere.meet(out).map(|t| path_mm + image_index * t);
        let chief_total_mm =
            to_sphere(&chief_out, chief_path_mm + launch.start_path_mm(0.0, chief_y_mm)).ok_or_else(|| {
                Error::InvalidArgument(format!(
                    "{}: the chief ray misses its reference sphere",
                    self.prescription.name
                ))
            })?;

        let pupil_radius_mm = 0.5 * paraxial.entrance_pupil_diameter_mm;
        let step_mm = 2.0 * pupil_radius_mm / grid as f64;
        let offset = |i: usize| (i as f64 - 0.5 * (grid as f64 - 1.0)) * step_mm;
        let mut opd_waves = vec![f64::NAN; grid * grid];
        // Least squares of the rays' direction cosines against their pupil offsets.
        let (mut sxx, mut sxa, mut syy, mut syb) = (0.0, 0.0, 0.0, 0.0);
        for j in 0..grid {
            for i in 0..grid {
                let (x, y) = (offset(i), offset(j));
                if x * x + y * y > pupil_radius_mm * pupil_radius_mm {
                    continue;
                }
                let Some((out, path_mm)) = self.trace_optical_path(&launch.ray(x, chief_y_mm + y), Direction::ToSensor)
                else {
                    continue;
                };
                let Some(total_mm) = to_sphere(&out, path_mm + launch.start_path_mm(x, chief_y_mm + y)) else {
                    continue;
                };
                opd_waves[j * grid + i] = (chief_total_mm - total_mm) / wavelength_mm;
                (sxx, sxa) = (sxx + x * x, sxa + x * (out.direction.x - chief_out.direction.x));
                (syy, syb) = (syy + y * y, syb + y * (out.direction.y - chief_out.direction.y));
            }
        }
        if sxx == 0.0 || syy == 0.0 {
            return Err(Error::InvalidArgument(format!(
                "{}: no ray passes the pupil at {field_deg}°",
                self.prescription.name
            )));
        }
        Ok(Wavefront {
            grid,
            opd_waves,
            direction_cosine_steps: [sxa / sxx * step_mm, syb / syy * step_mm],
            image_index,
            wavelength_nm: self.wavelength_nm(),
            image_point_mm,
        })
    }

    /// The entrance-pupil height (y, mm, in the pupil's plane) of the ray at
    /// `launch`'s field that crosses the stop at its centre, by the secant method.
    fn aim_chief_ray(&self, launch: &Launch) -> Option<f64> {
        let stop_height = |y: f64| {
            self.trace_via_stop(&launch.ray(0.0, y), Direction::ToSensor)
                .map(|(_, at_stop)| at_stop.y)
        };
        let scale = 1e-3 * self.stop_radius_mm().max(1e-3);
        let (mut y0, mut y1) = (0.0, scale);
        let (mut f0, mut f1) = (stop_height(y0)?, stop_height(y1)?);
        for _ in 0..40 {
            if f1.abs() < 1e-12 * scale.max(1.0) || f1 == f0 {
                break;
            }
            let y2 = y1 - f1 * (y1 - y0) / (f1 - f0);
            (y0, f0) = (y1, f1);
            y1 = y2;
            f1 = stop_height(y1)?;
        }
        (f1.abs() < 1e-6).then_some(y1)
    }
}

/// Where rays of one field start: a plane wave along `direction`, each ray
/// aimed at a point of the entrance pupil's plane and started in front of the lens.
struct Launch {
    direction: DVec3,
    pupil_z_mm: f64,
    back_off_mm: f64,
}

impl Launch {
    fn new(system: &LensSystem, field_deg: f64, pupil_z_mm: f64) -> Launch {
        let direction = DVec3::new(0.0, field_deg.to_radians().sin(), field_deg.to_radians().cos());
        let start_z = system.front_z_mm() - system.front_aperture_radius_mm() - START_CLEARANCE_MM;
        Launch {
            direction,
            pupil_z_mm,
            back_off_mm: ((pupil_z_mm - start_z) / direction.z).max(START_CLEARANCE_MM),
        }
    }

    /// The ray through (x, y) of the entrance pupil's plane.
    fn ray(&self, x: f64, y: f64) -> LensRay {
        LensRay {
            origin: DVec3::new(x, y, self.pupil_z_mm) - self.direction * self.back_off_mm,
            direction: self.direction,
        }
    }

    /// The optical path (object space is air) from the plane wavefront
    /// through the pupil's axial point to that ray's start.
    fn start_path_mm(&self, x: f64, y: f64) -> f64 {
        DVec3::new(x, y, 0.0).dot(self.direction) - self.back_off_mm
    }
}

/// The sphere the wavefront is measured against.
struct ReferenceSphere {
    centre_mm: DVec3,
    radius_mm: f64,
}

impl ReferenceSphere {
    /// How far along `ray` it meets the sphere on the lens's side of the
    /// centre (negative when the sphere lies behind the ray's start).
    fn meet(&self, ray: &LensRay) -> Option<f64> {
        let to_start = ray.origin - self.centre_mm;
        let b = ray.direction.dot(to_start);
        let c = to_start.length_squared() - self.radius_mm * self.radius_mm;
        let discriminant = b * b - c;
        (discriminant >= 0.0).then(|| -b - discriminant.sqrt())
    }
}

impl Wavefront {
    /// The wavefront of a perfect lens of working f-number `f_number`: a
    /// uniform circular pupil with no path difference, on a `grid` × `grid`
    /// square (what diffraction alone does, drawn beside a real lens).
    pub fn diffraction_limited(grid: usize, f_number: f64, wavelength_nm: f64) -> Wavefront {
        let half = 0.5 * (grid as f64 - 1.0);
        let radius = 0.5 * grid as f64;
        let opd_waves = (0..grid * grid)
            .map(|k| {
                let (x, y) = ((k % grid) as f64 - half, (k / grid) as f64 - half);
                if x * x + y * y <= radius * radius {
                    0.0
                } else {
                    f64::NAN
                }
            })
            .collect();
        // The rim's direction cosine is the numerical aperture, 1 / (2N),
        // toward the axis (the wave converges).
        let step = -1.0 / (2.0 * f_number * radius);
        Wavefront {
            grid,
            opd_waves,
            direction_cosine_steps: [step, step],
            image_index: 1.0,
            wavelength_nm,
            image_point_mm: DVec3::ZERO,
        }
    }

    /// Samples per side of the grid.
    pub fn grid(&self) -> usize {
        self.grid
    }

    /// OPD per sample (row-major: rows run in y, columns in x), waves; NaN outside the pupil.
    pub fn opd_waves(&self) -> &[f64] {
        &self.opd_waves
    }

    /// Wavelength, nm.
    pub fn wavelength_nm(&self) -> f64 {
        self.wavelength_nm
    }

    /// The chief ray's image point on the sensor, lens coordinates, mm.
    pub fn image_point_mm(&self) -> DVec3 {
        self.image_point_mm
    }

    /// Image-space direction-cosine change per grid step in x and y, times
    /// the image space's index: what sets the PSF's scale.
    pub(super) fn optical_direction_steps(&self) -> [f64; 2] {
        self.direction_cosine_steps.map(|s| s * self.image_index)
    }

    /// The fraction of the grid's circle that passes the lens.
    pub fn passing_fraction(&self) -> f64 {
        let inside = self.opd_waves.iter().filter(|w| !w.is_nan()).count();
        inside as f64 / (std::f64::consts::FRAC_PI_4 * (self.grid * self.grid) as f64)
    }

    /// Replaces each OPD sample inside the pupil by `f(index, opd)`.
    #[cfg(test)]
    pub(super) fn map_opd(&mut self, f: impl Fn(usize, f64) -> f64) {
        for (k, w) in self.opd_waves.iter_mut().enumerate().filter(|(_, w)| !w.is_nan()) {
            *w = f(k, *w);
        }
    }

    /// RMS wavefront error about its mean (piston removed), waves.
    pub fn rms_waves(&self) -> f64 {
        let inside: Vec<f64> = self.opd_waves.iter().copied().filter(|w| !w.is_nan()).collect();
        let mean = inside.iter().sum::<f64>() / inside.len() as f64;
        (inside.iter().map(|w| (w - mean) * (w - mean)).sum::<f64>() / inside.len() as f64).sqrt()
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;
    use crate::lens::LensPrescription;

    /// `scenes/lenses/bk7-singlet-50.dat` at 550 nm, wide open (f/2.8).
    pub(in crate::lens) fn singlet() -> LensSystem {
        let text = include_str!("../../../../scenes/lenses/bk7-singlet-50.dat");
        let lens =
            LensPrescription::parse(text, "bk7-singlet-50", crate::lens::TableConvention::ThicknessToNext).unwrap();
        LensSystem::new(&lens).at_wavelength(550.0)
    }

    /// The coefficient b of W ≈ a + b ρ² (ρ the pupil radius fraction), by least squares.
    fn quadratic_coefficient(w: &[f64], grid: usize) -> f64 {
        let half = 0.5 * (grid as f64 - 1.0);
        let r = 0.5 * grid as f64;
        let (mut n, mut s1, mut s2, mut sw, mut s1w) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for (k, &value) in w.iter().enumerate().filter(|(_, v)| !v.is_nan()) {
            let (x, y) = (((k % grid) as f64 - half) / r, ((k / grid) as f64 - half) / r);
            let rho2 = x * x + y * y;
            (n, s1, s2, sw, s1w) = (n + 1.0, s1 + rho2, s2 + rho2 * rho2, sw + value, s1w + rho2 * value);
        }
        (n * s1w - s1 * sw) / (n * s2 - s1 * s1)
    }

    #[test]
    fn moving_the_sensor_adds_the_defocus_that_first_order_optics_predicts() {
        // W₀₂₀ = δz · NA² / 2 (Welford §6.3), NA = 1 / (2N) for an object at infinity.
        let lens = singlet().with_f_number(16.0).unwrap();
        let focus = lens.infinity_focus_z_mm(0.1).unwrap();
        let grid = 64;
        let delta_mm = 0.08;
        let at_focus = lens.wavefront(0.0, focus, grid).unwrap();
        let behind = lens.wavefront(0.0, focus + delta_mm, grid).unwrap();
        let difference: Vec<f64> = at_focus
            .opd_waves()
            .iter()
            .zip(behind.opd_waves())
            .map(|(a, b)| b - a)
            .collect();
        let measured_mm = quadratic_coefficient(&difference, grid) * 550e-6;
        let na = 1.0 / (2.0 * 16.0);
        let expected_mm = delta_mm * na * na / 2.0;
        assert!(
            (measured_mm / expected_mm - 1.0).abs() < 0.02,
            "W020 {measured_mm:e} mm against {expected_mm:e} mm"
        );
    }

    #[test]
    fn the_chief_ray_is_aimed_through_the_stop_centre_off_axis() {
        let lens = singlet();
        let launch = Launch::new(&lens, 10.0, lens.paraxial().unwrap().entrance_pupil_z_mm);
        let y = lens.aim_chief_ray(&launch).unwrap();
        let (_, at_stop) = lens.trace_via_stop(&launch.ray(0.0, y), Direction::ToSensor).unwrap();
        assert!(
            at_stop.y.abs() < 1e-6 && at_stop.x.abs() < 1e-12,
            "crossed the stop at {at_stop}"
        );
    }

    #[test]
    fn a_singlet_wide_open_has_much_more_wavefront_error_than_stopped_down() {
        // Third-order spherical aberration grows as the aperture's fourth power: f/2.8 → f/11 is ×(11/2.8)⁴ ≈ 240.
        let lens = singlet();
        let best = |system: &LensSystem| {
            let focus = system.infinity_focus_z_mm(0.1).unwrap();
            (0..41)
                .map(|k| {
                    system
                        .wavefront(0.0, focus - 2.0 + 0.1 * k as f64, 48)
                        .unwrap()
                        .rms_waves()
                })
                .fold(f64::INFINITY, f64::min)
        };
        let (open, stopped) = (best(&lens), best(&lens.with_f_number(11.0).unwrap()));
        assert!(
            open > 1.0 && stopped < 0.07 && open / stopped > 30.0,
            "RMS {open} waves at f/2.8, {stopped} at f/11"
        );
    }
}
