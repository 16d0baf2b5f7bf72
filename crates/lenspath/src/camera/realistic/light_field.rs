//! The camera as a recorder of the light field inside it: a sample with its
//! line from the film to the rear plane, so that it can be moved to another
//! sensor position (what autofocus refocuses with).

use glam::{Vec2, Vec3};

use super::*;
use crate::camera::{CameraRay, CameraSample};
use crate::lens::LensRay;
use crate::spectrum::SampledWavelengths;

/// A camera sample as a record of the light field inside the camera: the
/// line it follows from the film to the rear plane, and the ray it becomes
/// in the scene. The line is what lets the sample be moved to another sensor
/// position ([`RealisticCamera::refocused_raster`]).
#[derive(Clone, Copy, Debug)]
pub struct LensSample {
    /// Where the sample's line crosses the rear plane, in raster coordinates
    /// (the film's pixels, extended past its edges).
    pub rear_raster: Vec2,
    /// The ray into the scene with its weight; `None` when the lens blocks it.
    pub ray: Option<CameraRay>,
}

impl RealisticCamera {
    /// [`Camera::generate_ray`] with the line the sample follows inside the
    /// camera, for recording a light field. A film point with no open pupil
    /// gives a blocked sample whose line stays where it is.
    pub fn generate_lens_sample(&self, sample: CameraSample) -> LensSample {
        let Some((start, out)) = self.traced_sample(sample) else {
            return LensSample {
                rear_raster: sample.film,
                ray: None,
            };
        };
        let t = (self.rear_z_mm - start.origin.z) / start.direction.z;
        let rear = start.origin + start.direction * t;
        let rear_raster = self.raster_point(rear);
        // Through a dispersive lens the wavelengths are weighted for the
        // pixel recorded; refocused, the record follows the hero's line
        // (another wavelength's line moves by up to a pixel more).
        LensSample {
            rear_raster,
            ray: out.map(|(out, weight)| {
                let wavelengths = self.weighted_wavelengths(&sample, &start, &out);
                self.scene_ray(&out, weight, wavelengths)
            }),
        }
    }

    /// Where a sample recorded at raster position `film` with its line
    /// through `rear_raster` ([`RealisticCamera::generate_lens_sample`])
    /// crosses the sensor when the sensor is at `sensor_depth_mm` instead: the
    /// line is the same (the image-space ray between the film and the lens),
    /// only the plane it is cut by moves. Exact for the lens's image space;
    /// it neglects that the lens, which moves to focus, sees the scene from
    /// the difference of the two sensor positions nearer or farther (at 1 m and 50 mm focal
    /// length, a hundredth of a DoF per tenth of a mm).
    pub fn refocused_raster(&self, film: Vec2, rear_raster: Vec2, sensor_depth_mm: f64) -> Vec2 {
        rear_raster + (film - rear_raster) * self.refocus_scale(sensor_depth_mm) as f32
    }

    /// How much farther from the rear plane the sensor at `sensor_depth_mm` is
    /// than this camera's: the factor lines from the rear plane spread by.
    pub fn refocus_scale(&self, sensor_depth_mm: f64) -> f64 {
        (sensor_depth_mm - self.rear_z_mm) / (self.sensor_depth_mm - self.rear_z_mm)
    }

    /// The bounding box of the rear element's aperture in raster
    /// coordinates: every sample's line crosses the rear plane in it.
    pub fn rear_aperture_raster_bounds(&self) -> (Vec2, Vec2) {
        let (w, h) = self.resolution;
        let (sw, sh) = self.sensor_mm;
        let radius = self.system.rear_aperture_radius_mm();
        let half = Vec2::new((radius / sw * w) as f32, (radius / sh * h) as f32);
        let centre = Vec2::new((0.5 * w) as f32, (0.5 * h) as f32);
        (centre - half, centre + half)
    }

    /// The scene ray of a ray leaving the lens, with its weight and wavelengths.
    pub(super) fn scene_ray(&self, out: &LensRay, weight: f64, wavelengths: SampledWavelengths) -> CameraRay {
        // Lens coordinates → camera space: the sensor centre is the origin,
        // +z looks into the scene (lens z runs the other way), mm → scene units.
        let origin = Vec3::new(
            out.origin.x as f32,
            out.origin.y as f32,
            (self.sensor_depth_mm - out.origin.z) as f32,
        ) * self.scene_per_mm as f32;
        let direction = Vec3::new(out.direction.x as f32, out.direction.y as f32, -out.direction.z as f32);
        let m = &self.pose.render_from_camera;
        CameraRay {
            ray: Ray::new(m.transform_point3(origin), m.transform_vector3(direction).normalize()),
            weight: (weight * self.weight_scale) as f32,
            wavelengths,
        }
    }
}
