//! The render driver: splits the image into tiles, renders them in parallel
//! in progressive passes ([`tiles`]), reports progress, saves checkpoints
//! and stops early when asked; trains a guided render's guide first
//! ([`training`]) and computes the depth channel ([`depth`]).

mod depth;
mod output;
mod settings;
mod tiles;
mod training;

use std::sync::atomic::AtomicBool;
use std::time::Instant;

use crate::camera::Camera;
use crate::error::Result;
pub use crate::film::{NormalizedRect, PixelRect};
use crate::guiding::Guide;
use crate::parallel::worker_pool;
use crate::scene::CompiledScene;
pub use depth::render_depth;
pub use output::{
    check_checkpoint_interval, Accumulation, Checkpoints, RenderOutput, RenderStats, MIN_CHECKPOINT_INTERVAL,
};
pub use settings::{
    FilmResponse, RenderSettings, DEFAULT_IMAGE_SIZE, DEFAULT_SEED, DEFAULT_SPP, DEFAULT_TILE_SIZE, MAX_LIGHT_SAMPLES,
    MAX_PATH_DEPTH,
};
use tiles::{render_in_pool, tiles, Shot};
use training::train_in_pool;
pub use training::{guide_map_at_pixel, guide_training_iterations, train_guide};

/// Where a render starts and what it is handed besides its scene, camera
/// and settings; the default starts afresh and trains its own guide.
#[derive(Default)]
pub struct Continuation<'a> {
    /// A saved state of the same scene, camera and settings to continue
    /// from, with at most `settings.spp` samples.
    pub start: Option<Accumulation>,
    /// A guide trained beforehand by [`train_guide`] for the same scene,
    /// camera and settings (the viewer trains one for all its steps);
    /// `None` trains one when the integrator is guided.
    pub guide: Option<&'a Guide>,
    /// Periodic saving of the render's state.
    pub checkpoints: Option<Checkpoints<'a>>,
}

/// Renders `scene` through `camera`. `progress(done, total)` is called with
/// sample counts as tiles finish; setting `cancel` stops the render within
/// one tile per thread and returns what was accumulated, every pixel the
/// mean of the samples it got.
pub fn render(
    scene: &CompiledScene,
    camera: &dyn Camera,
    settings: &RenderSettings,
    progress: &(dyn Fn(u64, u64) + Sync),
    cancel: &AtomicBool,
) -> Result<RenderOutput> {
    render_from(scene, camera, settings, Continuation::default(), progress, cancel)
}

/// [`render`], continuing as `from` says. The image is bit-identical to an
/// uninterrupted render's: a guided render continued without its guide
/// trains it again ([`train_guide`] is deterministic), which a checkpoint
/// does not hold, and one given its guide renders as if it had trained it.
pub fn render_from(
    scene: &CompiledScene,
    camera: &dyn Camera,
    settings: &RenderSettings,
    from: Continuation<'_>,
    progress: &(dyn Fn(u64, u64) + Sync),
    cancel: &AtomicBool,
) -> Result<RenderOutput> {
    settings.validate()?;
    let tiles = tiles(settings, from.start)?;
    worker_pool(settings.threads)?.install(|| {
        let started = Instant::now();
        let trained = match from.guide {
            Some(_) => None,
            None => settings
                .integrator
                .guide_training_spp(scene)
                .map(|spp| train_in_pool(scene, camera, settings, spp, cancel)),
        };
        let guide = from.guide.or(trained.as_ref().map(|(guide, _)| guide));
        let shot = Shot {
            scene,
            camera,
            settings,
            guide,
        };
        let mut output = render_in_pool(&shot, tiles, from.checkpoints, progress, cancel)?;
        if let Some((_, rays)) = &trained {
            output.stats.rays += rays;
            output.stats.seconds = started.elapsed().as_secs_f64();
        }
        Ok(output)
    })
}
