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
//! - the chief ray is aimed through the stop's centre; the grid spans the
//!   real entrance pupil in the pupil's plane, the ellipse through the four
//!   points whose rays graze the stop's rim above, below and beside the chief
//!   ray (aimed as OpticStudio's ray aiming aims them, other apertures
//!   ignored), so pupil distortion and pupil coma size it as they size the
//!   real beam; samples whose rays the lens blocks are outside the pupil, so
//!   vignetting shapes it;
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

        let pupil = self
            .real_pupil(&launch, chief_y_mm)
            .unwrap_or_else(|| PupilEllipse::paraxial(&paraxial, chief_y_mm));
        let unit = |i: usize| (i as f64 - 0.5 * (grid as f64 - 1.0)) * 2.0 / grid as f64;
        let mut opd_waves = vec![f64::NAN; grid * grid];
        let mut fit = [SlopeFit::default(), SlopeFit::default()];
        for j in 0..grid {
            for i in 0..grid {
                let (u, v) = (unit(i), unit(j));
                if u * u + v * v > 1.0 {
                    continue;
                }
                let (x, y) = (u * pupil.half_x_mm, pupil.centre_y_mm + v * pupil.half_y_mm);
                let Some((out, path_mm)) = self.trace_optical_path(&launch.ray(x, y), Direction::ToSensor) else {
                    continue;
                };
                let Some(total_mm) = to_sphere(&out, path_mm + launch.start_path_mm(x, y)) else {
                    continue;
                };
                opd_waves[j * grid + i] = (chief_total_mm - total_mm) / wavelength_mm;
                fit[0].add(u, out.direction.x);
                fit[1].add(v, out.direction.y);
            }
        }
        let (Some(slope_x), Some(slope_y)) = (fit[0].slope(), fit[1].slope()) else {
            return Err(Error::InvalidArgument(format!(
                "{}: no ray passes the pupil at {field_deg}°",
                self.prescription.name
            )));
        };
        // Slopes are per unit of the normalised pupil; a grid step is 2/grid of it.
        let per_step = 2.0 / grid as f64;
        Ok(Wavefront {
            grid,
            opd_waves,
            direction_cosine_steps: [slope_x * per_step, slope_y * per_step],
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

/// The entrance pupil on the pupil's plane: an ellipse with its axes along x and y.
struct PupilEllipse {
    centre_y_mm: f64,
    half_x_mm: f64,
    half_y_mm: f64,
}

impl PupilEllipse {
    /// The paraxial entrance pupil's circle about the chief ray.
    fn paraxial(paraxial: &super::ParaxialData, chief_y_mm: f64) -> PupilEllipse {
        let radius_mm = 0.5 * paraxial.entrance_pupil_diameter_mm;
        PupilEllipse {
            centre_y_mm: chief_y_mm,
            half_x_mm: radius_mm,
            half_y_mm: radius_mm,
        }
    }
}

/// A least-squares line's slope through (u, b) points.
#[derive(Default)]
struct SlopeFit {
    count: f64,
    sum_u: f64,
    sum_b: f64,
    sum_uu: f64,
    sum_ub: f64,
}

impl SlopeFit {
    fn add(&mut self, u: f64, b: f64) {
        self.count += 1.0;
        self.sum_u += u;
        self.sum_b += b;
        self.sum_uu += u * u;
        self.sum_ub += u * b;
    }

    fn slope(&self) -> Option<f64> {
        let spread = self.count * self.sum_uu - self.sum_u * self.sum_u;
        (self.count >= 2.0 && spread > 0.0).then(|| (self.count * self.sum_ub - self.sum_u * self.sum_b) / spread)
    }
}

impl LensSystem {
    /// The real entrance pupil at `launch`'s field (see the module's
    /// conventions); None where a rim ray cannot be aimed (the caller then
    /// takes the paraxial pupil).
    fn real_pupil(&self, launch: &Launch, chief_y_mm: f64) -> Option<PupilEllipse> {
        let mut unclipped = self.clone();
        unclipped
            .surfaces
            .iter_mut()
            .for_each(|s| s.aperture_radius = f64::INFINITY);
        let stop_radius_mm = self.stop_radius_mm();
        let guess_mm = 0.5 * self.paraxial().ok()?.entrance_pupil_diameter_mm;
        // How far from the chief ray, along (dx, dy) in the pupil's plane, a ray meets the stop's rim.
        let rim = |dx: f64, dy: f64| {
            let miss = |s: f64| {
                unclipped
                    .trace_via_stop(&launch.ray(s * dx, chief_y_mm + s * dy), Direction::ToSensor)
                    .map(|(_, at_stop)| at_stop.x.hypot(at_stop.y) - stop_radius_mm)
            };
            let (mut s0, mut s1) = (0.0, guess_mm);
            let (mut f0, mut f1) = (miss(s0)?, miss(s1)?);
            for _ in 0..40 {
                if f1.abs() < 1e-10 * stop_radius_mm || f1 == f0 {
                    break;
                }
                let s2 = s1 - f1 * (s1 - s0) / (f1 - f0);
                (s0, f0) = (s1, f1);
                s1 = s2;
                f1 = miss(s1)?;
            }
            (f1.abs() < 1e-6 * stop_radius_mm.max(1.0) && s1 > 0.0).then_some(s1)
        };
        let (above, below, beside) = (rim(0.0, 1.0)?, rim(0.0, -1.0)?, rim(1.0, 0.0)?);
        Some(PupilEllipse {
            centre_y_mm: chief_y_mm + 0.5 * (above - below),
            half_x_mm: beside,
            half_y_mm: 0.5 * (above + below),
        })
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
