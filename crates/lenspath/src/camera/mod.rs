//! Cameras turn a film position and a lens sample into a ray and a weight.
//!
//! Camera space follows pbrt: x right, y up, looking down +z.
//! `render_from_camera` places it in the scene. A new camera (the
//! compound-lens camera, say) implements [`Camera`] and may return `None`
//! for rays its optics block.

use std::f64::consts::PI;
use std::sync::Arc;

use glam::{Affine3A, Mat3A, Vec2, Vec3, Vec3A};

use crate::film::Filter;
use crate::ray::Ray;
use crate::sampling::{concentric_disk, Sampler, SamplerKind};
use crate::spectrum::SampledWavelengths;

mod aperture;
mod diffraction;
mod realistic;
pub use crate::film::FilmRadiometry;
pub use aperture::{Aperture, ApertureMask, ApertureShape};
pub use diffraction::{DiffractionPattern, PupilDiffraction};
pub use realistic::{
    sensor_for_image, LensFocus, LensSample, Radiometry, RealisticCamera, RealisticCameraSettings, DEFAULT_DESQUEEZE,
    DEFAULT_DIFFRACTION, DEFAULT_DISPERSION, DEFAULT_LENS, DEFAULT_SCENE_UNIT_M, DEFAULT_SENSOR_WIDTH_MM,
};

/// Where on the film and where on the lens a camera ray starts.
#[derive(Clone, Copy, Debug)]
pub struct CameraSample {
    /// Raster position in pixels: (0, 0) is the top-left corner of the image,
    /// (width, height) the bottom-right.
    pub film: Vec2,
    /// Lens (aperture) sample in [0, 1)².
    pub lens: Vec2,
    /// The wavelengths the sample carries (a dispersive lens traces its hero).
    pub wavelengths: SampledWavelengths,
    /// Centre of the pixel the sample is for, raster coordinates.
    pub pixel_centre: Vec2,
    /// The filter `film` was drawn from around `pixel_centre`.
    pub filter: Filter,
    /// The sample in [0, 1)² a diffracting camera draws the film point's
    /// displacement with (`None`: not displaced, for questions of geometry).
    pub diffraction: Option<Vec2>,
}

impl CameraSample {
    /// A sample at `film` and `lens` carrying only the d line (587.6 nm), the
    /// wavelength lens prescriptions give their indices at: for questions of
    /// geometry (where a ray goes, what it hits), not radiometry.
    /// Its pixel is the one `film` lies in, with the box filter.
    pub fn new(film: Vec2, lens: Vec2) -> Self {
        CameraSample {
            film,
            lens,
            wavelengths: SampledWavelengths::single(crate::spectrum::D_LINE_NM),
            pixel_centre: film.floor() + Vec2::splat(0.5),
            filter: Filter::Box,
            diffraction: None,
        }
    }

    /// The density, per pixel², with which film position `raster` would have
    /// been drawn for this sample's pixel: also that position's weight
    /// toward the pixel.
    #[inline(always)]
    pub fn film_density(&self, raster: Vec2) -> f32 {
        self.filter.pdf(raster - self.pixel_centre)
    }
}

/// A generated camera ray and its radiometric weight.
#[derive(Clone, Copy, Debug)]
pub struct CameraRay {
    /// The ray, in scene space, with a unit direction.
    pub ray: Ray,
    /// Factor applied to the radiance the ray brings back.
    pub weight: f32,
    /// The wavelengths the ray carries: the sample's, with only the hero
    /// left when the camera's optics disperse.
    pub wavelengths: SampledWavelengths,
}

/// The interface every camera implements.
pub trait Camera: Send + Sync {
    /// The ray for `sample`, or `None` when the optics block it.
    fn generate_ray(&self, sample: CameraSample) -> Option<CameraRay>;

    /// Rays for two samples at once, for cameras that trace faster in pairs.
    fn generate_ray_pair(&self, samples: [CameraSample; 2]) -> [Option<CameraRay>; 2] {
        samples.map(|s| self.generate_ray(s))
    }

    /// Camera position and unit viewing direction in scene space, which
    /// define the depth (Z) output: the distance along this axis.
    fn view_axis(&self) -> (Vec3, Vec3);

    /// What a film reading means in light on the sensor, for a sensor model
    /// to count photons; `None` for the ideal cameras, whose reading is the
    /// scene's radiance with no optics behind it.
    fn film_radiometry(&self) -> Option<FilmRadiometry> {
        None
    }

    /// Whether its samples need [`CameraSample::diffraction`] (the pupil diffracts).
    fn diffracts(&self) -> bool {
        false
    }
}

/// A camera's placement in the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraPose {
    /// Camera space → scene space.
    pub render_from_camera: Affine3A,
    /// The eye, target and up it was made from: written back to a scene
    /// file they give this pose again bit for bit, which a target derived
    /// from the matrix would not (a rounding of the view direction).
    look_at: [Vec3; 3],
}

impl CameraPose {
    /// A camera at `eye` looking at `target`, with `up` roughly up.
    pub fn look_at(eye: Vec3, target: Vec3, up: Vec3) -> Self {
        let forward = (target - eye).normalize();
        let right = forward.cross(up).normalize();
        let true_up = right.cross(forward);
        CameraPose {
            render_from_camera: Affine3A::from_mat3_translation(
                Mat3A::from_cols(Vec3A::from(right), Vec3A::from(true_up), Vec3A::from(forward)).into(),
                eye,
            ),
            look_at: [eye, target, up],
        }
    }

    /// [`CameraPose::look_at`], or why the three give no camera: a point not
    /// finite or beyond ±[`crate::math::MAX_SCENE_COORDINATE`], `eye` on
    /// `target`, or `up` along the view. Every front end and loader asks
    /// this, so a camera is refused for the same reasons everywhere.
    pub fn try_look_at(eye: Vec3, target: Vec3, up: Vec3) -> std::result::Result<Self, String> {
        use crate::math::{within_scene_range, MAX_SCENE_COORDINATE};
        if !(within_scene_range(eye) && within_scene_range(target) && up.is_finite()) {
            return Err(format!(
                "eye {eye} and target {target} must be finite and within ±{MAX_SCENE_COORDINATE:e} scene units, up {up} finite"
            ));
        }
        let pose = Self::look_at(eye, target, up);
        let frame = pose.render_from_camera.matrix3;
        let orthonormal = [frame.x_axis, frame.y_axis, frame.z_axis]
            .iter()
            .all(|a| a.is_finite() && (a.length() - 1.0).abs() < 1e-3);
        if !orthonormal {
            return Err(format!(
                "eye {eye} and target {target} must differ, and up {up} must not lie along the view"
            ));
        }
        Ok(pose)
    }

    /// The eye, target and up [`CameraPose::look_at`] made it from.
    pub fn look_at_arguments(&self) -> (Vec3, Vec3, Vec3) {
        let [eye, target, up] = self.look_at;
        (eye, target, up)
    }
}

/// Fails unless `fov_deg` is a perspective camera's field of view: above 0
/// and below 180 degrees (not NaN).
pub fn check_fov_deg(fov_deg: f32) -> std::result::Result<(), String> {
    if fov_deg > 0.0 && fov_deg < 180.0 {
        Ok(())
    } else {
        Err(format!(
            "the field of view must be between 0 and 180 degrees, got {fov_deg}"
        ))
    }
}

/// The thin-lens camera's aperture radius when the scene file gives none, scene units.
pub const DEFAULT_THIN_LENS_APERTURE_RADIUS: f32 = 0.05;

/// A perspective camera: a pinhole when `aperture_radius` is 0, otherwise
/// an ideal thin lens focused at `focus_distance` (pbrt-v4 `PerspectiveCamera`),
/// with a round aperture or any [`ApertureShape`].
#[derive(Clone, Debug)]
pub struct PerspectiveCamera {
    pose: CameraPose,
    /// Raster position → point on the camera-space plane z = 1: `scale · film + offset`
    /// (precomputed: no division per ray).
    plane_from_raster_scale: Vec2,
    plane_from_raster_offset: Vec2,
    aperture_radius: f32,
    focus_distance: f32,
    /// `None`: the full circle.
    aperture: Option<Arc<Aperture>>,
}

impl PerspectiveCamera {
    /// A pinhole camera with vertical field of view `fov_y_deg` for a `width`×`height` image.
    pub fn pinhole(pose: CameraPose, fov_y_deg: f32, width: u32, height: u32) -> Self {
        Self::thin_lens(pose, fov_y_deg, width, height, 0.0, 1.0)
    }

    /// A thin-lens camera; `aperture_radius` and `focus_distance` in scene units.
    pub fn thin_lens(
        pose: CameraPose,
        fov_y_deg: f32,
        width: u32,
        height: u32,
        aperture_radius: f32,
        focus_distance: f32,
    ) -> Self {
        let tan_half_fov_y = (0.5 * fov_y_deg.to_radians()).tan();
        let tan_half_fov_x = tan_half_fov_y * (width as f32 / height as f32);
        PerspectiveCamera {
            pose,
            // x from −tan(fov_x/2) at the left edge to +tan at the right; y from +tan at the top down.
            plane_from_raster_scale: Vec2::new(
                2.0 * tan_half_fov_x / width as f32,
                -2.0 * tan_half_fov_y / height as f32,
            ),
            plane_from_raster_offset: Vec2::new(-tan_half_fov_x, tan_half_fov_y),
            aperture_radius,
            focus_distance,
            aperture: None,
        }
    }

    /// The same camera with its aperture (of radius `aperture_radius`) shaped
    /// like `aperture`. The image darkens with the open area, as a real iris does.
    pub fn with_aperture(mut self, aperture: Arc<Aperture>) -> Self {
        self.aperture = (!aperture.is_circle()).then_some(aperture);
        self
    }

    /// Camera-space direction (not normalised, z = 1) through a raster position.
    fn direction_through(&self, film: Vec2) -> Vec3 {
        let p = self.plane_from_raster_scale * film + self.plane_from_raster_offset;
        Vec3::new(p.x, p.y, 1.0)
    }
}

impl Camera for PerspectiveCamera {
    fn generate_ray(&self, sample: CameraSample) -> Option<CameraRay> {
        let dir = self.direction_through(sample.film);
        let (origin, dir, weight) = if self.aperture_radius > 0.0 {
            // A point of the aperture and its weight: the shape's transmission
            // over its sampling density, relative to the full circle's 1/π.
            let (lens, weight) = match &self.aperture {
                None => (concentric_disk(sample.lens), 1.0),
                Some(aperture) => {
                    let (p, pdf) = aperture.sample(sample.lens);
                    let transmission = aperture.transmission(p);
                    if transmission <= 0.0 {
                        return None;
                    }
                    (p.as_vec2(), (transmission / (PI * pdf)) as f32)
                }
            };
            // Every ray through the lens meets the others on the plane of focus.
            let lens = self.aperture_radius * lens;
            let origin = Vec3::new(lens.x, lens.y, 0.0);
            let focus = dir * self.focus_distance;
            (origin, focus - origin, weight)
        } else {
            (Vec3::ZERO, dir, 1.0)
        };
        let m = &self.pose.render_from_camera;
        Some(CameraRay {
            ray: Ray::new(m.transform_point3(origin), m.transform_vector3(dir).normalize()),
            weight,
            wavelengths: sample.wavelengths,
        })
    }

    fn view_axis(&self) -> (Vec3, Vec3) {
        let m = &self.pose.render_from_camera;
        (m.transform_point3(Vec3::ZERO), m.transform_vector3(Vec3::Z).normalize())
    }
}

/// Mixed into the seed of the sampler that draws diffraction's displacements.
const DIFFRACTION_STREAM: u32 = 0x9e37_79b9;

/// Sample `index` of pixel `(px, py)` of the `kind` sequence under `seed`: its camera sample (the
/// film position, the pixel centre moved by `filter`'s offset, the lens
/// position and the wavelengths: the sampler's first five dimensions) and the sampler, which the
/// path goes on with. Every render and light field draws its samples here,
/// so the same seed gives the same samples. Pixels past the image's left or
/// top edge (a light field's margin) get samplers of their own, seeded with
/// their wrapped coordinates. `diffracts`: also the draw for the film
/// point's displacement ([`CameraSample::diffraction`]).
// Inlined into the tile and light-field loops (see `render_tile`): the
// sampler then stays in registers instead of coming back through memory.
#[inline(always)]
pub fn pixel_sample(
    kind: SamplerKind,
    px: i32,
    py: i32,
    index: u32,
    seed: u32,
    filter: Filter,
    diffracts: bool,
) -> (Sampler, CameraSample) {
    let mut sampler = Sampler::new(kind, px as u32, py as u32, index, seed);
    let centre = Vec2::new(px as f32 + 0.5, py as f32 + 0.5);
    let film = centre + filter.sample_offset(sampler.get_2d());
    let lens = sampler.get_2d();
    let wavelengths = SampledWavelengths::sample_visible(sampler.get_1d());
    // From a stream of its own, so that the path's dimensions are the same
    // whether the camera diffracts or not.
    let diffraction =
        diffracts.then(|| Sampler::new(kind, px as u32, py as u32, index, seed ^ DIFFRACTION_STREAM).get_2d());
    (
        sampler,
        CameraSample {
            film,
            lens,
            wavelengths,
            pixel_centre: centre,
            filter,
            diffraction,
        },
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pinhole_centre_ray_looks_at_the_target_and_corners_span_the_fov() {
        let pose = CameraPose::look_at(Vec3::new(1.0, 2.0, 3.0), Vec3::new(1.0, 2.0, -7.0), Vec3::Y);
        let cam = PerspectiveCamera::pinhole(pose, 60.0, 200, 100);
        let centre = cam
            .generate_ray(CameraSample::new(Vec2::new(100.0, 50.0), Vec2::splat(0.5)))
            .unwrap();
        assert!((centre.ray.direction - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6);
        // The top edge's centre is 30° above the axis; image right is scene +x here.
        let top = cam
            .generate_ray(CameraSample::new(Vec2::new(100.0, 0.0), Vec2::ZERO))
            .unwrap();
        assert!((top.ray.direction.y.asin().to_degrees() - 30.0).abs() < 1e-4);
        let right = cam
            .generate_ray(CameraSample::new(Vec2::new(200.0, 50.0), Vec2::ZERO))
            .unwrap();
        assert!(right.ray.direction.x > 0.0);
    }

    #[test]
    fn thin_lens_rays_converge_on_the_focus_plane() {
        let pose = CameraPose::look_at(Vec3::ZERO, Vec3::new(0.0, 0.0, 1.0), Vec3::Y);
        let cam = PerspectiveCamera::thin_lens(pose, 40.0, 64, 64, 0.5, 4.0);
        let film = Vec2::new(10.0, 50.0);
        let points: Vec<Vec3> = [Vec2::new(0.1, 0.2), Vec2::new(0.9, 0.5), Vec2::new(0.4, 0.95)]
            .iter()
            .map(|&lens| {
                let r = cam.generate_ray(CameraSample::new(film, lens)).unwrap().ray;
                r.at((4.0 - r.origin.z) / r.direction.z)
            })
            .collect();
        assert!((points[0] - points[1]).length() < 1e-5 && (points[0] - points[2]).length() < 1e-5);
        let r = cam
            .generate_ray(CameraSample::new(film, Vec2::new(0.1, 0.2)))
            .unwrap()
            .ray;
        assert!(r.origin.length() > 0.1, "lens samples must spread over the aperture");
    }
}
