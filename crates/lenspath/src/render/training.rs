//! A guided render's guide: trained over the whole image before the
//! render, in iterations of doubling samples, deterministically; and a look
//! at what it learned at one pixel.

use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

use super::depth::centre_ray;
use super::settings::RenderSettings;
use crate::camera::{pixel_sample, Camera};
use crate::error::{Error, Result};
use crate::guiding::map::DensityMap;
use crate::guiding::{Guide, GuideRecord, PathRecorder};
use crate::integrator::material_is_guided;
use crate::parallel::worker_pool;
use crate::sampling::hash_u32;
use crate::scene::CompiledScene;

/// Trains the guide of a guided render of `scene` through `camera` with
/// `settings` (`None` when its integrator is not guided, when guiding cannot
/// help in `scene` ([`crate::integrator::guiding_can_help`]), or when
/// `cancel` stopped the training): iterations of 1, 2, 4, ... samples per pixel over
/// the whole image (whatever its crop, so a crop's pixels are the full
/// render's), as many as fit in the integrator's training samples, each with
/// its own sample sequence and guided by what the ones before it learned.
/// Those samples train the guide only; the image is rendered after, with
/// the guide fixed. Deterministic: the same guide for any thread count.
pub fn train_guide(
    scene: &CompiledScene,
    camera: &dyn Camera,
    settings: &RenderSettings,
    cancel: &AtomicBool,
) -> Result<Option<Guide>> {
    settings.validate()?;
    let Some(spp) = settings.integrator.guide_training_spp(scene) else {
        return Ok(None);
    };
    let (guide, _) = worker_pool(settings.threads)?.install(|| train_in_pool(scene, camera, settings, spp, cancel));
    Ok((!cancel.load(Ordering::Relaxed)).then_some(guide))
}

/// The samples per pixel of each training iteration within `training_spp`:
/// 1, 2, 4, ... while their sum fits (one iteration at least).
pub fn guide_training_iterations(training_spp: u32) -> Vec<u32> {
    let mut iterations = vec![1u32];
    let mut used = 1u32;
    loop {
        let next = 2 * iterations[iterations.len() - 1];
        if used + next > training_spp {
            return iterations;
        }
        iterations.push(next);
        used += next;
    }
}

/// Paths a training batch traces before its records are learned: bounds
/// the records held at once.
const TRAINING_BATCH_PATHS: u32 = 1 << 19;

/// [`train_guide`] inside the worker pool; also returns the rays traced.
/// Stops early (with what it learned) when `cancel` is set.
pub(super) fn train_in_pool(
    scene: &CompiledScene,
    camera: &dyn Camera,
    settings: &RenderSettings,
    training_spp: u32,
    cancel: &AtomicBool,
) -> (Guide, u64) {
    let mut guide = Guide::new(scene.bounds());
    let mut rays = 0u64;
    for (iteration, spp) in guide_training_iterations(training_spp).into_iter().enumerate() {
        // A sequence of its own: the render's samples stay independent of the guide's.
        let seed = hash_u32(settings.seed ^ hash_u32(0x6775_6964 + iteration as u32));
        let rows_per_batch = (TRAINING_BATCH_PATHS / (settings.width * spp)).max(1);
        for y0 in (0..settings.height).step_by(rows_per_batch as usize) {
            if cancel.load(Ordering::Relaxed) {
                return (guide, rays);
            }
            let rows: Vec<(Vec<GuideRecord>, u64)> = (y0..(y0 + rows_per_batch).min(settings.height))
                .into_par_iter()
                .map(|py| train_row(scene, camera, settings, &guide, py, spp, seed))
                .collect();
            let records: Vec<GuideRecord> = rows.iter().flat_map(|(r, _)| r.iter().copied()).collect();
            rays += rows.iter().map(|(_, n)| n).sum::<u64>();
            guide.learn(&records);
        }
        guide.end_iteration(spp);
    }
    (guide, rays)
}

/// Training paths of row `py` of the image, `spp` per pixel with sample
/// sequence `seed`: their records in pixel then sample order, and the rays
/// they traced. Compiled for the baseline CPU only (unlike the tiles): the
/// training is a small part of a guided render, and each copy of the
/// inlined path loop costs the build time.
fn train_row(
    scene: &CompiledScene,
    camera: &dyn Camera,
    settings: &RenderSettings,
    guide: &Guide,
    py: u32,
    spp: u32,
    seed: u32,
) -> (Vec<GuideRecord>, u64) {
    let mut records = Vec::new();
    let mut rays = 0u64;
    for px in 0..settings.width {
        for index in 0..spp {
            let (mut sampler, mut sample) = pixel_sample(
                settings.sampler,
                px as i32,
                py as i32,
                index,
                seed,
                settings.filter,
                camera.diffracts(),
            );
            sample.wavelengths = settings.film.wavelengths(sample.wavelengths);
            rays += 1;
            if let Some(cr) = camera.generate_ray(sample) {
                let pixel = u64::from(py * settings.width + px);
                let path_seed = (u64::from(seed) << 32 ^ pixel).wrapping_mul(0x9e37_79b9) + u64::from(index);
                let recorder = PathRecorder::new(&mut records, guide, path_seed);
                rays += settings
                    .integrator
                    .train(scene, guide, cr.ray, cr.wavelengths, &mut sampler, recorder);
            }
        }
    }
    (records, rays)
}

/// What `guide` learned at the surface seen through the centre of pixel
/// `(px, py)` of a `settings`-sized image through `camera`: its density
/// over the sphere of directions there, `size` pixels square
/// ([`DensityMap`]). For a look at the guide when a guided render
/// misbehaves. Fails for a size outside [`DensityMap::SIZES`], a pixel
/// outside the image, one that sees nothing, and one that sees a surface
/// the guide does not steer (glass, a mirror, nearly smooth metal).
pub fn guide_map_at_pixel(
    scene: &CompiledScene,
    camera: &dyn Camera,
    settings: &RenderSettings,
    guide: &Guide,
    (px, py): (u32, u32),
    size: u32,
) -> Result<DensityMap> {
    DensityMap::check_size(size)?;
    if px >= settings.width || py >= settings.height {
        return Err(Error::InvalidArgument(format!(
            "pixel ({px}, {py}) is outside the {}x{} image",
            settings.width, settings.height
        )));
    }
    let ray = centre_ray(camera, px, py).map(|cr| cr.ray);
    let Some((ray, hit)) = ray.and_then(|r| scene.intersect(&r).map(|hit| (r, hit))) else {
        return Err(Error::InvalidArgument(format!(
            "pixel ({px}, {py}) sees no surface: nothing for the guide to show"
        )));
    };
    if !material_is_guided(scene.spectral_material(hit.material)) {
        return Err(Error::InvalidArgument(format!(
            "pixel ({px}, {py}) sees glass, a mirror or smooth metal, which the guide does not steer; \
             pick a pixel on a diffuse or rough surface"
        )));
    }
    let toward_viewer = -ray.direction;
    let n = hit.shading_normal;
    let facing = if n.dot(toward_viewer) < 0.0 { -n } else { n };
    Ok(DensityMap::at(guide, hit.p, facing, toward_viewer, size))
}
