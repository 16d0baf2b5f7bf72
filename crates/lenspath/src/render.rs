//! The render driver: splits the image into tiles, renders them in parallel
//! in progressive passes, reports progress and stops early when asked.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use glam::{DVec3, Vec2};
use rayon::prelude::*;

use crate::camera::{pixel_sample, Camera, CameraRay, CameraSample};
use crate::defaults;
use crate::error::{Error, Result};
use crate::film::{Filter, Image};
pub use crate::film::{NormalizedRect, PixelRect};
use crate::guiding::map::DensityMap;
use crate::guiding::{Guide, GuideRecord, PathRecorder};
use crate::integrator::{material_is_guided, Integrator};
use crate::math::Rgb;
use crate::parallel::worker_pool;
use crate::ray::Ray;
use crate::sampling::{hash_u32, Sampler, SamplerKind, MAX_SAMPLES_PER_PIXEL};
use crate::scene::CompiledScene;
use crate::sensor::SpectralResponse;
use crate::spectrum::{SampledWavelengths, LAMBDA_MAX_NM, LAMBDA_MIN_NM};

/// Lens samples tried for a pixel's depth: the middle of the lens first,
/// then a 5×5 grid, for lenses that block some of their pupil.
fn depth_lens_samples() -> impl Iterator<Item = Vec2> {
    std::iter::once(Vec2::splat(0.5))
        .chain((0..25).map(|k| Vec2::new((k % 5) as f32 + 0.5, (k / 5) as f32 + 0.5) / 5.0))
}

/// Everything that controls one render.
#[derive(Clone, Copy, Debug)]
pub struct RenderSettings {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// The integrator and its settings (path depth, light sampling).
    pub integrator: Integrator,
    /// Seed of the sample sequences: the same seed gives the same image.
    pub seed: u32,
    /// The sample sequence: Sobol (the default) or independent.
    pub sampler: SamplerKind,
    /// Pixel reconstruction filter.
    pub filter: Filter,
    /// Worker threads; `None` uses every core.
    pub threads: Option<usize>,
    /// Edge of the square tiles, in pixels.
    pub tile_size: u32,
    /// Render only this rectangle of the image (pbrt's crop window): the
    /// output is the rectangle, each pixel exactly as in the full render.
    /// For patches rendered many times, as autofocus does.
    pub crop: Option<PixelRect>,
    /// Compute the depth (Z) channel: one extra camera ray per pixel, in the
    /// first pass. Off for renders only their colour is wanted from, such as
    /// autofocus patches.
    pub depth: bool,
    /// Render at this one wavelength, nm, instead of across the visible:
    /// every sample carries it alone and the image is the spectral radiance
    /// there, the same in all three channels (a lens designer's
    /// monochromatic image; `None`, the default, renders colour).
    pub wavelength_nm: Option<f32>,
    /// What the film records of the light: linear sRGB (the default) or a
    /// sensor's channels ([`FilmResponse`]).
    pub film: FilmResponse,
}

/// What a pixel's three numbers are.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum FilmResponse {
    /// Linear sRGB radiance, from the CIE matching functions.
    #[default]
    Srgb,
    /// Each channel's photoelectron rate through this sensor response per
    /// unit étendue ([`SpectralResponse::electron_rate`]), for
    /// [`crate::sensor::capture`].
    Sensor(&'static SpectralResponse),
}

impl FilmResponse {
    /// What the film records of the light arriving along a camera ray at
    /// the wavelengths `lambda` ([`Integrator::radiance`]'s arguments).
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn reading(
        self,
        integrator: &Integrator,
        scene: &CompiledScene,
        guide: Option<&Guide>,
        camera_ray: Ray,
        lambda: SampledWavelengths,
        sampler: &mut Sampler,
        rays: &mut u64,
    ) -> Rgb {
        match self {
            FilmResponse::Srgb => integrator.li(scene, guide, camera_ray, lambda, sampler, rays),
            FilmResponse::Sensor(response) => {
                let (l, lambda) = integrator.li_spectrum(scene, guide, camera_ray, lambda, sampler, rays);
                response.electron_rate(&lambda, l)
            }
        }
    }
}

impl Default for RenderSettings {
    /// The library's defaults ([`crate::defaults`]): box filter, every core, the depth channel.
    fn default() -> Self {
        RenderSettings {
            width: defaults::IMAGE_SIZE.0,
            height: defaults::IMAGE_SIZE.1,
            spp: defaults::SPP,
            integrator: Integrator::path(defaults::MAX_DEPTH, defaults::LIGHT_SAMPLES),
            seed: defaults::SEED,
            sampler: defaults::SAMPLER,
            filter: Filter::Box,
            threads: None,
            tile_size: defaults::TILE_SIZE,
            crop: None,
            depth: true,
            wavelength_nm: None,
            film: FilmResponse::Srgb,
        }
    }
}

impl RenderSettings {
    /// The pixel that point `(x, y)` of the image lies in, the point given
    /// as fractions of the image's width and height from its top left (0 to
    /// 1; a point on the right or bottom edge is in the last pixel). Fails
    /// for a point outside the image.
    pub fn pixel_at(&self, (x, y): (f64, f64)) -> Result<(u32, u32)> {
        if !((0.0..=1.0).contains(&x) && (0.0..=1.0).contains(&y)) {
            return Err(Error::InvalidArgument(format!(
                "a point of the image is given as fractions of its width and height from its top left \
                 (0 to 1), got ({x}, {y})"
            )));
        }
        let at = |f: f64, size: u32| ((f * f64::from(size)) as u32).min(size.saturating_sub(1));
        Ok((at(x, self.width), at(y, self.height)))
    }

    /// Rejects settings that cannot make an image.
    pub fn validate(&self) -> Result<()> {
        let fail = |m: String| Err(Error::InvalidArgument(m));
        if self.width == 0 || self.height == 0 {
            return fail(format!(
                "image size must be positive, got {}x{}",
                self.width, self.height
            ));
        }
        if self.width > 65_536 || self.height > 65_536 {
            return fail(format!(
                "image size {}x{} exceeds 65536 pixels on a side",
                self.width, self.height
            ));
        }
        if self.spp == 0 || self.spp > MAX_SAMPLES_PER_PIXEL {
            return fail(format!(
                "samples per pixel must be in 1..={MAX_SAMPLES_PER_PIXEL}, got {}",
                self.spp
            ));
        }
        check_max_depth(self.integrator.max_depth())?;
        if self.integrator.light_samples() > 1024 {
            return fail(format!(
                "light samples must be at most 1024, got {}",
                self.integrator.light_samples()
            ));
        }
        crate::parallel::check_threads(self.threads)?;
        let (width, height) = self.crop.map_or((self.width, self.height), |c| (c.width, c.height));
        crate::memory::check_fits(
            &|| format!("a {width}x{height} render"),
            u64::from(width) * u64::from(height) * crate::memory::RENDER_BYTES_PER_PIXEL,
        )?;
        if self.tile_size == 0 {
            return fail("tile size must be positive".into());
        }
        if let Some(c) = self.crop {
            let inside =
                |start: u32, len: u32, size: u32| len > 0 && start.checked_add(len).is_some_and(|end| end <= size);
            if !inside(c.x0, c.width, self.width) || !inside(c.y0, c.height, self.height) {
                return fail(format!(
                    "crop {}x{} at ({}, {}) is empty or leaves the {}x{} image",
                    c.width, c.height, c.x0, c.y0, self.width, self.height
                ));
            }
        }
        if let Some(nm) = self.wavelength_nm {
            if !(LAMBDA_MIN_NM..=LAMBDA_MAX_NM).contains(&nm) {
                return fail(format!(
                    "wavelength must be in {LAMBDA_MIN_NM}..={LAMBDA_MAX_NM} nm, got {nm}"
                ));
            }
            if self.film != FilmResponse::Srgb {
                return fail("a sensor records colour: render it across the visible, not at one wavelength".into());
            }
        }
        if let Filter::Gaussian { sigma, radius } = self.filter {
            if !(sigma > 0.0 && radius > 0.0 && sigma.is_finite() && radius.is_finite()) {
                return fail(format!(
                    "Gaussian filter needs positive sigma and radius, got {sigma} and {radius}"
                ));
            }
        }
        Ok(())
    }
}

/// Counters of a finished (or stopped) render.
#[derive(Clone, Copy, Debug, Default)]
pub struct RenderStats {
    /// Wall time in seconds.
    pub seconds: f64,
    /// Camera samples taken (by this run, when it continued a saved one).
    pub samples: u64,
    /// Rays traced: camera, bounce and shadow rays.
    pub rays: u64,
    /// Samples whose radiance was NaN or infinite (dropped as zero).
    pub invalid_samples: u64,
    /// True when the render was stopped before all samples were taken.
    pub cancelled: bool,
}

/// What a render produced.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// The image.
    pub image: Image,
    /// How it went.
    pub stats: RenderStats,
}

/// The state of a render between two samples, enough to continue it: for
/// each pixel of the rendered region (row-major), the sum of its samples'
/// radiance, how many samples it has, and its depth. A pixel's sum is added to
/// in sample order whatever the passes, so a render continued from this state
/// ends bit-identical to one that never stopped.
#[derive(Clone, Debug, PartialEq)]
pub struct Accumulation {
    /// The pixels it covers: the whole image, or the crop.
    pub region: PixelRect,
    /// Sum of each pixel's sample radiance.
    pub sum: Vec<DVec3>,
    /// Samples each pixel has (its sample indices `0..count`).
    pub count: Vec<u32>,
    /// Depth along the view axis (infinite: nothing hit, or not yet computed).
    pub depth: Vec<f32>,
}

impl Accumulation {
    /// Samples every pixel has.
    pub fn spp_min(&self) -> u32 {
        self.count.iter().copied().min().unwrap_or(0)
    }
}

/// Least time between two checkpoint saves a front end accepts
/// ([`check_checkpoint_interval`]): a save writes the whole image's sums,
/// so saving after every pass spends the render writing them. (The library
/// itself saves as often as [`Checkpoints::every`] says: 0 is after every
/// pass, which its tests use.)
pub const MIN_CHECKPOINT_INTERVAL: Duration = Duration::from_millis(100);

/// Periodic saving of a render's [`Accumulation`], so a stopped or killed
/// render can continue ([`render_from`]).
pub struct Checkpoints<'a> {
    /// Least time between two saves. Passes are kept short enough (about
    /// half of it) that a save is seldom late.
    pub every: Duration,
    /// Saves the state; called at most every `every`, and once more when the
    /// render finishes or is stopped. An error stops the render.
    pub save: &'a mut (dyn FnMut(&Accumulation) -> Result<()> + Send),
}

struct Tile {
    x0: u32,
    y0: u32,
    width: u32,
    height: u32,
    /// Samples each of its pixels has: a pass renders a tile whole or not at all.
    spp_done: u32,
    sum: Vec<DVec3>,
    depth: Vec<f32>,
}

impl Tile {
    /// Each of its pixels as (index in the tile, index in `region`), row by row.
    fn pixels_in(&self, region: PixelRect) -> impl Iterator<Item = (usize, usize)> + '_ {
        (0..self.height).flat_map(move |ty| {
            (0..self.width).map(move |tx| {
                let o =
                    (self.y0 + ty - region.y0) as usize * region.width as usize + (self.x0 + tx - region.x0) as usize;
                ((ty * self.width + tx) as usize, o)
            })
        })
    }
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
    render_from(scene, camera, settings, None, None, progress, cancel)
}

/// [`render`], continuing from `start` (a saved [`Accumulation`] of the same
/// scene, camera and settings, with at most `settings.spp` samples) and
/// saving its state through `checkpoints`. The image is bit-identical to an
/// uninterrupted render's: a guided render trains its guide again
/// ([`train_guide`] is deterministic), which a checkpoint does not hold.
pub fn render_from(
    scene: &CompiledScene,
    camera: &dyn Camera,
    settings: &RenderSettings,
    start: Option<Accumulation>,
    checkpoints: Option<Checkpoints<'_>>,
    progress: &(dyn Fn(u64, u64) + Sync),
    cancel: &AtomicBool,
) -> Result<RenderOutput> {
    settings.validate()?;
    let tiles = tiles(settings, start)?;
    worker_pool(settings.threads)?.install(|| {
        let started = Instant::now();
        let trained = settings
            .integrator
            .guide_training_spp(scene)
            .map(|spp| train_in_pool(scene, camera, settings, spp, cancel));
        let guide = trained.as_ref().map(|(guide, _)| guide);
        let mut output = render_in_pool(scene, camera, settings, guide, tiles, checkpoints, progress, cancel)?;
        output.stats.rays += trained.as_ref().map_or(0, |(_, rays)| *rays);
        output.stats.seconds = started.elapsed().as_secs_f64();
        Ok(output)
    })
}

/// [`render_from`] with a guide trained beforehand by [`train_guide`] for
/// the same scene, camera and settings (the viewer trains one for all its
/// steps); the image is [`render_from`]'s, bit for bit.
#[allow(clippy::too_many_arguments)]
pub fn render_guided_from(
    scene: &CompiledScene,
    camera: &dyn Camera,
    settings: &RenderSettings,
    guide: &Guide,
    start: Option<Accumulation>,
    checkpoints: Option<Checkpoints<'_>>,
    progress: &(dyn Fn(u64, u64) + Sync),
    cancel: &AtomicBool,
) -> Result<RenderOutput> {
    settings.validate()?;
    let tiles = tiles(settings, start)?;
    worker_pool(settings.threads)?.install(|| {
        render_in_pool(
            scene,
            camera,
            settings,
            Some(guide),
            tiles,
            checkpoints,
            progress,
            cancel,
        )
    })
}

/// The deepest path a render may ask for (scattering events): deeper paths
/// carry nothing Russian roulette would not have ended long before.
pub const MAX_PATH_DEPTH: u32 = 1024;

/// Fails for a maximum path depth over [`MAX_PATH_DEPTH`] (0, emitters
/// only, is a depth).
pub fn check_max_depth(max_depth: u32) -> Result<()> {
    if max_depth > MAX_PATH_DEPTH {
        return Err(Error::InvalidArgument(format!(
            "max depth must be at most {MAX_PATH_DEPTH}, got {max_depth}"
        )));
    }
    Ok(())
}

/// Fails for a checkpoint interval under [`MIN_CHECKPOINT_INTERVAL`].
pub fn check_checkpoint_interval(every: Duration) -> Result<()> {
    if every < MIN_CHECKPOINT_INTERVAL {
        return Err(Error::InvalidArgument(format!(
            "checkpoints at most every {} s, asked for every {} s",
            MIN_CHECKPOINT_INTERVAL.as_secs_f64(),
            every.as_secs_f64()
        )));
    }
    Ok(())
}

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
fn train_in_pool(
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
            let (mut sampler, mut sample) =
                pixel_sample(settings.sampler, px as i32, py as i32, index, seed, settings.filter);
            if let Some(nm) = settings.wavelength_nm {
                sample.wavelengths = SampledWavelengths::single(nm);
            }
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

/// The region a render covers: its crop, else the whole image.
fn region(settings: &RenderSettings) -> PixelRect {
    settings.crop.unwrap_or(PixelRect {
        x0: 0,
        y0: 0,
        width: settings.width,
        height: settings.height,
    })
}

/// The region cut into tiles, empty or filled from `start`.
fn tiles(settings: &RenderSettings, start: Option<Accumulation>) -> Result<Vec<Tile>> {
    let ts = settings.tile_size;
    let region = region(settings);
    if let Some(a) = &start {
        let n = region.width as usize * region.height as usize;
        if a.region != region || a.sum.len() != n || a.count.len() != n || a.depth.len() != n {
            return Err(Error::InvalidArgument(format!(
                "the saved render covers {}x{} pixels at ({}, {}), this one {}x{} at ({}, {})",
                a.region.width,
                a.region.height,
                a.region.x0,
                a.region.y0,
                region.width,
                region.height,
                region.x0,
                region.y0
            )));
        }
        let most = a.count.iter().copied().max().unwrap_or(0);
        if most > settings.spp {
            return Err(Error::InvalidArgument(format!(
                "the saved render already has {most} samples per pixel, more than the {} asked for",
                settings.spp
            )));
        }
    }
    let (region_x1, region_y1) = (region.x0 + region.width, region.y0 + region.height);
    let mut tiles: Vec<Tile> = Vec::new();
    for y0 in (region.y0..region_y1).step_by(ts as usize) {
        for x0 in (region.x0..region_x1).step_by(ts as usize) {
            let (width, height) = (ts.min(region_x1 - x0), ts.min(region_y1 - y0));
            let n = (width * height) as usize;
            let mut tile = Tile {
                x0,
                y0,
                width,
                height,
                spp_done: 0,
                sum: vec![DVec3::ZERO; n],
                depth: vec![f32::INFINITY; n],
            };
            if let Some(a) = &start {
                let pixels: Vec<(usize, usize)> = tile.pixels_in(region).collect();
                tile.spp_done = a.count[pixels[0].1];
                for &(i, o) in &pixels {
                    tile.sum[i] = a.sum[o];
                    tile.depth[i] = a.depth[o];
                }
                if pixels.iter().any(|&(_, o)| a.count[o] != tile.spp_done) {
                    return Err(Error::InvalidArgument(format!(
                        "the saved render's pixels in the tile at ({x0}, {y0}) have different sample counts; \
                         it was not made with {ts}-pixel tiles"
                    )));
                }
            }
            tiles.push(tile);
        }
    }
    Ok(tiles)
}

/// The state held by `tiles`, as one [`Accumulation`] over `region`.
fn accumulation(tiles: &[Tile], region: PixelRect) -> Accumulation {
    let n = region.width as usize * region.height as usize;
    let mut a = Accumulation {
        region,
        sum: vec![DVec3::ZERO; n],
        count: vec![0; n],
        depth: vec![f32::INFINITY; n],
    };
    for tile in tiles {
        for (i, o) in tile.pixels_in(region) {
            a.sum[o] = tile.sum[i];
            a.count[o] = tile.spp_done;
            a.depth[o] = tile.depth[i];
        }
    }
    a
}

/// A camera ray through the centre of pixel `(px, py)`, along the first lens
/// position the optics let through.
#[inline(always)]
fn centre_ray(camera: &dyn Camera, px: u32, py: u32) -> Option<CameraRay> {
    let film = Vec2::new(px as f32 + 0.5, py as f32 + 0.5);
    depth_lens_samples().find_map(|lens| camera.generate_ray(CameraSample::new(film, lens)))
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

/// The depth of pixel `(px, py)` along the view `axis` (origin, direction),
/// along the first lens position the optics let through (infinite when
/// nothing is hit), and the camera rays that took (0 or 1).
#[inline(always)]
fn pixel_depth(
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

/// Renders the samples `tile.spp_done..pass_end` of every pixel of `tile`
/// (and its depth, when it has no samples yet); returns (rays, invalid samples).
// Compiled twice, for the baseline and for x86-64-v3 (AVX2, FMA: Haswell,
// Zen and later), and run in the copy the CPU can: the path tracer is
// inlined into both, and the v3 copy is 5% faster (BENCHMARKS.md). No
// fused multiply-adds are written or contracted, so both give bit-identical images.
#[multiversion::multiversion(targets("x86_64+avx+avx2+fma+bmi1+bmi2+lzcnt+movbe+f16c"))]
fn render_tile(
    scene: &CompiledScene,
    camera: &dyn Camera,
    settings: &RenderSettings,
    guide: Option<&Guide>,
    tile: &mut Tile,
    pass_end: u32,
) -> (u64, u64) {
    let (axis_origin, axis_dir) = camera.view_axis();
    let first = tile.spp_done;
    let mut tile_rays = 0u64;
    let mut tile_invalid = 0u64;
    for ty in 0..tile.height {
        // Depth, in the first pass.
        for tx in (0..tile.width).filter(|_| first == 0 && settings.depth) {
            let (depth, rays) = pixel_depth(scene, camera, (axis_origin, axis_dir), tile.x0 + tx, tile.y0 + ty);
            tile_rays += rays;
            tile.depth[(ty * tile.width + tx) as usize] = depth;
        }
        // Pixels in pairs, so a camera can trace two rays at once
        // (the realistic camera does); every pixel keeps its own
        // samplers and its sum's order, so the image does not change.
        // The two samplers are named, not in arrays: moving arrays of
        // samplers through `map` and `zip` cost 3% of a render.
        for tx in (0..tile.width).step_by(2) {
            let (px, py) = (tile.x0 + tx, tile.y0 + ty);
            let slot = (ty * tile.width + tx) as usize;
            let paired = tx + 1 < tile.width;
            for index in first..pass_end {
                let sample = |px: u32| {
                    let (sampler, mut sample) = pixel_sample(
                        settings.sampler,
                        px as i32,
                        py as i32,
                        index,
                        settings.seed,
                        settings.filter,
                    );
                    if let Some(nm) = settings.wavelength_nm {
                        sample.wavelengths = SampledWavelengths::single(nm);
                    }
                    (sampler, sample)
                };
                let mut trace = |ray: Option<CameraRay>, sampler: &mut Sampler, slot: usize| {
                    let l = ray.map_or(Rgb::ZERO, |cr| {
                        let integrator = &settings.integrator;
                        cr.weight
                            * match settings.wavelength_nm {
                                None => settings.film.reading(
                                    integrator,
                                    scene,
                                    guide,
                                    cr.ray,
                                    cr.wavelengths,
                                    sampler,
                                    &mut tile_rays,
                                ),
                                // One wavelength at density 1: the estimate is the radiance itself.
                                Some(_) => Rgb::splat(
                                    integrator
                                        .li_spectrum(scene, guide, cr.ray, cr.wavelengths, sampler, &mut tile_rays)
                                        .0
                                        .x,
                                ),
                            }
                    });
                    if l.is_finite() {
                        tile.sum[slot] += l.as_dvec3();
                    } else {
                        tile_invalid += 1;
                    }
                };
                let (mut sampler_a, sample_a) = sample(px);
                if paired {
                    let (mut sampler_b, sample_b) = sample(px + 1);
                    let [ray_a, ray_b] = camera.generate_ray_pair([sample_a, sample_b]);
                    trace(ray_a, &mut sampler_a, slot);
                    trace(ray_b, &mut sampler_b, slot + 1);
                } else {
                    trace(camera.generate_ray(sample_a), &mut sampler_a, slot);
                }
            }
        }
    }
    tile.spp_done = pass_end;
    (tile_rays, tile_invalid)
}

/// Samples per pixel of the pass after one of `last` samples: passes double
/// up to 64, so a stopped render is still even; with checkpoints, a pass
/// takes at most about half their interval (at `seconds_per_spp`).
fn next_pass_size(last: u32, checkpoints: Option<&Checkpoints<'_>>, seconds_per_spp: f64) -> u32 {
    let doubled = (last * 2).min(64);
    match checkpoints {
        Some(c) if seconds_per_spp > 0.0 => {
            let fits = (0.5 * c.every.as_secs_f64() / seconds_per_spp).floor();
            doubled.min(fits.clamp(1.0, 64.0) as u32)
        }
        _ => doubled,
    }
}

#[allow(clippy::too_many_arguments)]
fn render_in_pool(
    scene: &CompiledScene,
    camera: &dyn Camera,
    settings: &RenderSettings,
    guide: Option<&Guide>,
    mut tiles: Vec<Tile>,
    mut checkpoints: Option<Checkpoints<'_>>,
    progress: &(dyn Fn(u64, u64) + Sync),
    cancel: &AtomicBool,
) -> Result<RenderOutput> {
    let started = Instant::now();
    let region = region(settings);
    let total = u64::from(region.width) * u64::from(region.height) * u64::from(settings.spp);
    let tile_samples = |t: &Tile| u64::from(t.width * t.height) * u64::from(t.spp_done);
    let resumed: u64 = tiles.iter().map(tile_samples).sum();
    let done = AtomicU64::new(resumed);
    let rays = AtomicU64::new(0);
    let invalid = AtomicU64::new(0);

    // Progressive passes of growing size, so a stopped render is still even.
    let mut pass_start = tiles.iter().map(|t| t.spp_done).min().unwrap_or(settings.spp);
    let mut pass_size = 1u32;
    let mut last_save = Instant::now();
    let mut unsaved = false;
    while pass_start < settings.spp && !cancel.load(Ordering::Relaxed) {
        let pass_end = (pass_start + pass_size).min(settings.spp);
        tiles.par_iter_mut().for_each(|tile| {
            if cancel.load(Ordering::Relaxed) || tile.spp_done >= pass_end {
                return;
            }
            let before = tile_samples(tile);
            let (tile_rays, tile_invalid) = render_tile(scene, camera, settings, guide, tile, pass_end);
            rays.fetch_add(tile_rays, Ordering::Relaxed);
            invalid.fetch_add(tile_invalid, Ordering::Relaxed);
            let n = tile_samples(tile) - before;
            progress(done.fetch_add(n, Ordering::Relaxed) + n, total);
        });
        unsaved = true;
        if let Some(c) = checkpoints.as_mut().filter(|c| last_save.elapsed() >= c.every) {
            (c.save)(&accumulation(&tiles, region))?;
            (last_save, unsaved) = (Instant::now(), false);
        }
        let taken = done.load(Ordering::Relaxed) - resumed;
        let pixels = f64::from(region.width) * f64::from(region.height);
        let seconds_per_spp = started.elapsed().as_secs_f64() * pixels / taken.max(1) as f64;
        pass_start = pass_end;
        pass_size = next_pass_size(pass_size, checkpoints.as_ref(), seconds_per_spp);
    }
    let state = accumulation(&tiles, region);
    if let Some(c) = checkpoints.as_mut().filter(|_| unsaved) {
        (c.save)(&state)?;
    }

    // Resolve: each pixel is the mean of its samples.
    let mut rgb = vec![0f32; 3 * state.sum.len()];
    for ((out, sum), &n) in rgb.chunks_exact_mut(3).zip(&state.sum).zip(&state.count) {
        let mean = if n > 0 { *sum / f64::from(n) } else { DVec3::ZERO };
        out.copy_from_slice(&mean.as_vec3().to_array());
    }
    let spp_min = state.spp_min();
    let samples = done.into_inner();
    Ok(RenderOutput {
        image: Image {
            width: region.width,
            height: region.height,
            rgb,
            depth: state.depth,
            spp_min,
            spp_requested: settings.spp,
        },
        stats: RenderStats {
            seconds: started.elapsed().as_secs_f64(),
            samples: samples - resumed,
            rays: rays.into_inner(),
            invalid_samples: invalid.into_inner(),
            cancelled: samples < total,
        },
    })
}
