//! The tile loop: the image (or its crop) cut into tiles, rendered in
//! progressive passes in parallel, each pixel's samples summed in sample
//! order whatever the passes, and the sums saved as checkpoints.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;

use glam::DVec3;
use rayon::prelude::*;

use super::depth::pixel_depth;
use super::output::{Accumulation, Checkpoints, RenderOutput, RenderStats};
use super::settings::{region, RenderSettings};
use crate::camera::{pixel_sample, Camera, CameraRay};
use crate::error::{Error, Result};
use crate::film::{Image, PixelRect};
use crate::guiding::Guide;
use crate::math::Rgb;
use crate::sampling::Sampler;
use crate::scene::CompiledScene;

/// What a render's passes draw on: the scene through a camera with its
/// settings, and a guided render's guide.
#[derive(Clone, Copy)]
pub(super) struct Shot<'a> {
    pub(super) scene: &'a CompiledScene,
    pub(super) camera: &'a dyn Camera,
    pub(super) settings: &'a RenderSettings,
    pub(super) guide: Option<&'a Guide>,
}

pub(super) struct Tile {
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

/// The region cut into tiles, empty or filled from `start`.
pub(super) fn tiles(settings: &RenderSettings, start: Option<Accumulation>) -> Result<Vec<Tile>> {
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

/// Renders the samples `tile.spp_done..pass_end` of every pixel of `tile`
/// (and its depth, when it has no samples yet); returns (rays, invalid samples).
// With the `x86-64-v3` feature, compiled twice, for the baseline and for
// x86-64-v3 (AVX2, FMA: Haswell, Zen and later), and run in the copy the CPU
// can: the path tracer is inlined into both, the v3 copy the faster. No
// fused multiply-adds are written or contracted, so both give bit-identical images.
// Not in the library's own unit-test build: its x86-64-v3 test has a copy of its
// own (`integrator`), and the integration tests and the wheel run this one.
#[cfg_attr(
    all(feature = "x86-64-v3", not(test)),
    multiversion::multiversion(targets("x86_64+avx+avx2+fma+bmi1+bmi2+lzcnt+movbe+f16c"))
)]
fn render_tile(shot: &Shot<'_>, tile: &mut Tile, pass_end: u32) -> (u64, u64) {
    let Shot {
        scene,
        camera,
        settings,
        guide,
    } = *shot;
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
                        camera.diffracts(),
                    );
                    sample.wavelengths = settings.film.wavelengths(sample.wavelengths);
                    (sampler, sample)
                };
                let mut trace = |ray: Option<CameraRay>, sampler: &mut Sampler, slot: usize| {
                    let l = ray.map_or(Rgb::ZERO, |cr| {
                        let integrator = &settings.integrator;
                        cr.weight
                            * settings.film.reading(
                                integrator,
                                scene,
                                guide,
                                cr.ray,
                                cr.wavelengths,
                                sampler,
                                &mut tile_rays,
                            )
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

/// The render's passes over `tiles` inside the worker pool, then the image.
pub(super) fn render_in_pool(
    shot: &Shot<'_>,
    mut tiles: Vec<Tile>,
    mut checkpoints: Option<Checkpoints<'_>>,
    progress: &(dyn Fn(u64, u64) + Sync),
    cancel: &AtomicBool,
) -> Result<RenderOutput> {
    let started = Instant::now();
    let settings = shot.settings;
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
            let (tile_rays, tile_invalid) = render_tile(shot, tile, pass_end);
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
            depth: state.depth.clone(),
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
        accumulation: state,
    })
}
