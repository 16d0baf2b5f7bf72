//! The depth channel: per pixel, the distance along the view axis to what
//! its centre sees, through the first lens position the optics let through.

use glam::Vec2;
use rayon::prelude::*;

use super::settings::{region, RenderSettings};
use crate::camera::{Camera, CameraRay, CameraSample};
use crate::error::Result;
use crate::parallel::worker_pool;
use crate::scene::CompiledScene;

/// Lens samples tried for a pixel's depth: the middle of the lens first,
/// then a 5×5 grid, for lenses that block some of their pupil.
fn depth_lens_samples() -> impl Iterator<Item = Vec2> {
    std::iter::once(Vec2::splat(0.5))
        .chain((0..25).map(|k| Vec2::new((k % 5) as f32 + 0.5, (k / 5) as f32 + 0.5) / 5.0))
}

/// A camera ray through the centre of pixel `(px, py)`, along the first lens
/// position the optics let through.
#[inline(always)]
pub(super) fn centre_ray(camera: &dyn Camera, px: u32, py: u32) -> Option<CameraRay> {
    let film = Vec2::new(px as f32 + 0.5, py as f32 + 0.5);
    depth_lens_samples().find_map(|lens| camera.generate_ray(CameraSample::new(film, lens)))
}

/// The depth of pixel `(px, py)` along the view `axis` (origin, direction),
/// along the first lens position the optics let through (infinite when
/// nothing is hit), and the camera rays that took (0 or 1).
#[inline(always)]
pub(super) fn pixel_depth(
    scene: &CompiledScene,
    camera: &dyn Camera,
    axis: (glam::Vec3, glam::Vec3),
    px: u32,
    py: u32,
) -> (f32, u64) {
    let ray = centre_ray(camera, px, py);
    let depth = ray
        .and_then(|cr| scene.intersect(&cr.ray))
        .map_or(f32::INFINITY, |hit| (hit.p - axis.0).dot(axis.1));
    (depth, u64::from(ray.is_some()))
}

/// The depth channel alone, row by row over the image (or its crop): what a
/// render with `settings.depth` computes in its first pass, bit for bit. For
/// renders made without it (`lenspath view` leaves it to the EXR download,
/// so its first preview comes sooner).
pub fn render_depth(scene: &CompiledScene, camera: &dyn Camera, settings: &RenderSettings) -> Result<Vec<f32>> {
    settings.validate()?;
    let region = region(settings);
    let axis = camera.view_axis();
    let mut depth = vec![f32::INFINITY; region.width as usize * region.height as usize];
    worker_pool(settings.threads)?.install(|| {
        depth
            .par_chunks_mut(region.width as usize)
            .enumerate()
            .for_each(|(row, line)| {
                for (x, d) in line.iter_mut().enumerate() {
                    *d = pixel_depth(scene, camera, axis, region.x0 + x as u32, region.y0 + row as u32).0;
                }
            });
    });
    Ok(depth)
}
