//! A patch's light field inside the camera: every sample of a patch render
//! kept with the line it follows between the film and the lens, so that the
//! patch can be imaged at any nearby sensor position without tracing a ray
//! again (synthetic refocusing, as a plenoptic camera does it: Ng et al.
//! 2005, "Light Field Photography with a Hand-held Plenoptic Camera").
//!
//! A sample recorded with the sensor at `z₀` starts at film point `x` and
//! aims at rear-plane point `q`; with the sensor at `z` it lands at
//! `q + (x − q)·s`, `s = (z − z_rear) / (z₀ − z_rear)`. Its weight needs no
//! change: the shear scales film area by `s²` and the `1/d²` of the camera's
//! `cos⁴θ·A/d²` weight by `1/s²`. Each pixel of the refocused image is the
//! mean of the samples that land in it (pbrt's film estimate: the ratio of
//! their sum to their count), so at `z₀` it is exactly the render, or their
//! bilinearly weighted mean, which changes smoothly with `z` ([`Splat`]).
//!
//! Samples land up to a blur radius away and the image breathes (grows as
//! the sensor moves back), so the patch is recorded with a margin that
//! covers the sensor positions asked for; [`LightField::refocus`] refuses
//! positions whose samples could come from outside it.

use glam::{DVec3, Vec2, Vec3};
use rayon::prelude::*;

use crate::camera::{pixel_sample, Camera, CameraPose, RealisticCamera, RealisticCameraSettings};
use crate::error::{Error, Result};
use crate::film::Filter;
use crate::film::PixelRect;
use crate::integrator::Integrator;
use crate::parallel::worker_pool;
use crate::render::FilmResponse;
use crate::sampling::SamplerKind;
use crate::scene::CompiledScene;

/// One sample of the light field.
#[derive(Clone, Copy, Debug)]
struct Record {
    /// Raster position on the film where it was recorded.
    film: Vec2,
    /// Raster position of the rear-plane point its line aims at.
    rear: Vec2,
    /// Weighted radiance (zero when the lens blocks it).
    radiance: Vec3,
}

/// A rectangle of film pixels that may reach past the image's edges (the
/// light that would land inside it from there is recorded all the same).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FilmRegion {
    /// First column (negative: left of the image).
    pub x0: i32,
    /// First row (negative: above the image).
    pub y0: i32,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
}

impl FilmRegion {
    /// The region as a crop of a `width`×`height` image, when it lies inside it.
    pub fn inside(&self, width: u32, height: u32) -> Option<PixelRect> {
        let fits = self.x0 >= 0
            && self.y0 >= 0
            && self.x0 as u32 + self.width <= width
            && self.y0 as u32 + self.height <= height;
        fits.then_some(PixelRect {
            x0: self.x0 as u32,
            y0: self.y0 as u32,
            width: self.width,
            height: self.height,
        })
    }

    fn contains(&self, p: Vec2) -> bool {
        p.x >= self.x0 as f32
            && p.y >= self.y0 as f32
            && p.x <= (self.x0 + self.width as i32) as f32
            && p.y <= (self.y0 + self.height as i32) as f32
    }
}

/// The bounding box of where the lines through the rear-plane box
/// `rear_bounds` (raster coordinates) that land in `patch` with the sensor
/// `scale` times as far from the rear plane crossed the recording's sensor.
fn preimage_bounds(patch: PixelRect, rear_bounds: (Vec2, Vec2), scale: f32) -> (Vec2, Vec2) {
    let patch_lo = Vec2::new(patch.x0 as f32, patch.y0 as f32);
    let patch_hi = patch_lo + Vec2::new(patch.width as f32, patch.height as f32);
    let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
    for c in corners_of(patch_lo, patch_hi) {
        for rear in corners_of(rear_bounds.0, rear_bounds.1) {
            let p = rear + (c - rear) / scale;
            (lo, hi) = (lo.min(p), hi.max(p));
        }
    }
    (lo, hi)
}

/// The samples of a region rendered with the sensor at one position.
pub struct LightField {
    camera: RealisticCamera,
    region: FilmRegion,
    records: Vec<Record>,
    /// Bounding box of the records' rear-plane points, raster coordinates.
    rear_bounds: (Vec2, Vec2),
}

/// How a light field is recorded.
#[derive(Clone, Copy, Debug)]
pub struct Recording {
    /// Samples per pixel.
    pub spp: u32,
    /// Seed of the sample sequences (a render with it and the default Sobol
    /// sampler has the same samples).
    pub seed: u32,
    /// The integrator of the recorded paths.
    pub integrator: Integrator,
    /// Worker threads (`None`: all cores).
    pub threads: Option<usize>,
    /// What a sample's value is: sRGB radiance or a sensor's electron rates.
    pub film: FilmResponse,
}

impl LightField {
    /// The film region to record so that `patch` can be refocused anywhere
    /// from `sensor_depth_mm.0` to `sensor_depth_mm.1` through `camera`: the patch's
    /// corners carried back to the camera's sensor position along lines
    /// through the rear aperture's bounding box, plus a pixel.
    pub fn region_for(camera: &RealisticCamera, patch: PixelRect, sensor_depth_mm: (f64, f64)) -> FilmRegion {
        let rear_bounds = camera.rear_aperture_raster_bounds();
        let bounds = |z: f64| preimage_bounds(patch, rear_bounds, camera.refocus_scale(z) as f32);
        let ((lo_near, hi_near), (lo_far, hi_far)) = (bounds(sensor_depth_mm.0), bounds(sensor_depth_mm.1));
        let (lo, hi) = (lo_near.min(lo_far), hi_near.max(hi_far));
        let (lo, hi) = (lo.floor() - Vec2::ONE, hi.ceil() + Vec2::ONE);
        let (x0, y0) = ((lo.x as i32).min(patch.x0 as i32), (lo.y as i32).min(patch.y0 as i32));
        let x1 = (hi.x as i32).max((patch.x0 + patch.width) as i32);
        let y1 = (hi.y as i32).max((patch.y0 + patch.height) as i32);
        FilmRegion {
            x0,
            y0,
            width: (x1 - x0) as u32,
            height: (y1 - y0) as u32,
        }
    }

    /// The camera to record `region` of a `width`×`height` image through
    /// with `settings`: cropped to the region when it lies inside the image;
    /// past the image's edges, the whole camera, whose pupil bands cover film
    /// points off the sensor.
    pub fn recording_camera(
        pose: CameraPose,
        width: u32,
        height: u32,
        settings: &RealisticCameraSettings,
        region: FilmRegion,
    ) -> Result<RealisticCamera> {
        match region.inside(width, height) {
            Some(crop) => RealisticCamera::for_region(pose, width, height, settings, crop),
            None => RealisticCamera::new(pose, width, height, settings),
        }
    }

    /// Renders `region` through `camera` keeping every sample; inside the
    /// image the samples are those of [`crate::render::render`] with the same
    /// seed, the Sobol sampler and a box filter. The camera must cover the region
    /// ([`LightField::recording_camera`] makes one that does).
    pub fn record(
        scene: &CompiledScene,
        camera: RealisticCamera,
        region: FilmRegion,
        recording: &Recording,
    ) -> Result<LightField> {
        if recording.spp == 0 {
            return Err(Error::InvalidArgument(
                "a light field needs at least 1 sample per pixel".into(),
            ));
        }
        let rows: Vec<Vec<Record>> = worker_pool(recording.threads)?.install(|| {
            (region.y0..region.y0 + region.height as i32)
                .into_par_iter()
                .map(|py| record_row(scene, &camera, region, py, recording))
                .collect()
        });
        let records: Vec<Record> = rows.into_iter().flatten().collect();
        let rear_bounds = records.iter().fold(
            (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)),
            |(lo, hi), r| (lo.min(r.rear), hi.max(r.rear)),
        );
        Ok(LightField {
            camera,
            region,
            records,
            rear_bounds,
        })
    }

    /// The camera it was recorded through (its film radiometry is the
    /// refocused images').
    pub fn camera(&self) -> &RealisticCamera {
        &self.camera
    }

    /// Samples recorded (camera rays).
    pub fn samples(&self) -> u64 {
        self.records.len() as u64
    }

    /// Whether every sample that lands in `patch` with the sensor at
    /// `sensor_depth_mm` was recorded: each line through the recorded rear-plane
    /// points that reaches the patch crossed the recording inside the region.
    pub fn reaches(&self, sensor_depth_mm: f64, patch: PixelRect) -> bool {
        let scale = self.camera.refocus_scale(sensor_depth_mm) as f32;
        let (lo, hi) = preimage_bounds(patch, self.rear_bounds, scale);
        self.region.contains(lo) && self.region.contains(hi)
    }

    /// The image of `patch` (RGB, row by row) with the sensor at
    /// `sensor_depth_mm`, its samples gathered into pixels as `splat` says (none
    /// in a pixel: black). `None` when the patch is out of reach
    /// ([`LightField::reaches`]).
    pub fn refocus(&self, sensor_depth_mm: f64, patch: PixelRect, splat: Splat) -> Option<Vec<f32>> {
        if !self.reaches(sensor_depth_mm, patch) {
            return None;
        }
        let (w, h) = (patch.width as usize, patch.height as usize);
        let mut sum = vec![DVec3::ZERO; w * h];
        let mut weight = vec![0f64; w * h];
        let mut add = |x: i64, y: i64, radiance: Vec3, share: f64| {
            if x >= 0 && y >= 0 && (x as usize) < w && (y as usize) < h {
                let k = y as usize * w + x as usize;
                sum[k] += radiance.as_dvec3() * share;
                weight[k] += share;
            }
        };
        let recorded_here = sensor_depth_mm == self.camera.sensor_depth_mm();
        let origin = Vec2::new(patch.x0 as f32, patch.y0 as f32);
        for r in &self.records {
            let film = if recorded_here {
                r.film
            } else {
                self.camera.refocused_raster(r.film, r.rear, sensor_depth_mm)
            };
            let p = film - origin;
            match splat {
                Splat::Box => add(p.x.floor() as i64, p.y.floor() as i64, r.radiance, 1.0),
                Splat::Bilinear => {
                    // Pixel centres are at half-integers.
                    let c = p - Vec2::splat(0.5);
                    let (x, y) = (c.x.floor(), c.y.floor());
                    let (tx, ty) = (f64::from(c.x - x), f64::from(c.y - y));
                    let (x, y) = (x as i64, y as i64);
                    add(x, y, r.radiance, (1.0 - tx) * (1.0 - ty));
                    add(x + 1, y, r.radiance, tx * (1.0 - ty));
                    add(x, y + 1, r.radiance, (1.0 - tx) * ty);
                    add(x + 1, y + 1, r.radiance, tx * ty);
                }
            }
        }
        let mut rgb = vec![0f32; 3 * w * h];
        for ((out, s), &total) in rgb.chunks_exact_mut(3).zip(&sum).zip(&weight) {
            let mean = if total > 0.0 { *s / total } else { DVec3::ZERO };
            out.copy_from_slice(&mean.as_vec3().to_array());
        }
        Some(rgb)
    }
}

/// How [`LightField::refocus`] gathers samples into pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Splat {
    /// Each pixel the mean of the samples landing in it (pbrt's film estimate
    /// with a box filter: at the recorded position, exactly the render).
    Box,
    /// Each sample shared among the four nearest pixel centres by bilinear
    /// weights, each pixel the weighted mean. The image then changes
    /// continuously with the sensor position (a box pixel's samples jump in
    /// and out of it, which makes a quarter-DoF step's focus curve jitter by
    /// several percent), for a slight blur (a tent pixel filter).
    Bilinear,
}

/// The four corners of the box from `lo` to `hi`.
fn corners_of(lo: Vec2, hi: Vec2) -> [Vec2; 4] {
    [lo, Vec2::new(hi.x, lo.y), Vec2::new(lo.x, hi.y), hi]
}

/// Row `py` of `region`'s samples, in pixel then sample order. Compiled for
/// x86-64-v3 too with that feature, like [`crate::render`]'s tiles (the path tracer inlines).
#[cfg_attr(
    all(feature = "x86-64-v3", not(test)),
    multiversion::multiversion(targets("x86_64+avx+avx2+fma+bmi1+bmi2+lzcnt+movbe+f16c"))
)]
fn record_row(
    scene: &CompiledScene,
    camera: &RealisticCamera,
    region: FilmRegion,
    py: i32,
    recording: &Recording,
) -> Vec<Record> {
    let Recording {
        spp,
        seed,
        integrator,
        film: response,
        ..
    } = *recording;
    let mut row = Vec::with_capacity((region.width * spp) as usize);
    let mut rays = 0u64;
    for px in region.x0..region.x0 + region.width as i32 {
        for index in 0..spp {
            let (mut sampler, camera_sample) =
                pixel_sample(SamplerKind::Sobol, px, py, index, seed, Filter::Box, camera.diffracts());
            let film = camera_sample.film;
            let sample = camera.generate_lens_sample(camera_sample);
            let l = sample.ray.map_or(Vec3::ZERO, |cr| {
                cr.weight
                    * response.reading(
                        &integrator,
                        scene,
                        None,
                        cr.ray,
                        cr.wavelengths,
                        &mut sampler,
                        &mut rays,
                    )
            });
            row.push(Record {
                film,
                rear: sample.rear_raster,
                // A non-finite sample counts as black, as in a render.
                radiance: if l.is_finite() { l } else { Vec3::ZERO },
            });
        }
    }
    row
}
