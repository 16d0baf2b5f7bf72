//! The unidirectional path tracer: next-event estimation with several
//! shadow rays per light, multiple importance sampling with the power
//! heuristic, and Russian roulette (after pbrt-v4 `PathIntegrator`).
//!
//! Transport is spectral: a path carries the four wavelengths its camera
//! sample drew ([`SampledWavelengths`]) and its throughput at each; the
//! estimate becomes linear sRGB at the end ([`SampledWavelengths::to_rgb`]).
//!
//! The guided path tracer is the same loop with a trained [`Guide`]: at a
//! diffuse or rough vertex it samples the guide or the BSDF (one-sample MIS,
//! [`crate::guiding::BSDF_SAMPLING_FRACTION`]) and weighs light samples
//! against that mixture's density.

use glam::Vec3;

use crate::accel::SHADOW_PACKET;
use crate::guiding::directional::{to_square, DirectionalTree};
use crate::guiding::{Guide, PathRecorder, BSDF_SAMPLING_FRACTION};
use crate::lights::SampleLight;
use crate::materials::{Bsdf, SpectralMaterial};
use crate::math::{Frame, Rgb};
use crate::ray::{offset_origin, Ray};
use crate::sampling::{power_heuristic, Sampler};
use crate::scene::{CompiledScene, SurfaceHit};
use crate::shapes::MaterialId;
use crate::spectrum::{SampledSpectrum, SampledWavelengths, Spectrum};

/// How far and how carefully paths are traced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PathSettings {
    /// Maximum number of scattering events; 0 shows only emitters,
    /// 1 direct lighting (pbrt's `maxdepth`).
    pub max_depth: u32,
    /// Shadow rays per area or environment light at each non-specular hit
    /// (the CS184 `-l`); a point, spot or directional light takes one.
    pub light_samples: u32,
}

/// Which integrator estimates the radiance along camera rays, with its
/// settings: the seam where another integrator (spectral transport, path
/// guiding) goes beside the path tracer. An enum, not a trait object, so
/// each variant's loop inlines into the render's tile loop and the light
/// field's row loop, which are compiled for two CPU targets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// The unidirectional path tracer with next-event estimation and MIS.
    Path(PathSettings),
    /// The path tracer guided by a [`Guide`] trained on the scene first
    /// (`crate::render` trains it): for caustics and light that arrives
    /// through glass or off metal, which light sampling cannot find.
    Guided(GuidedSettings),
}

/// The guided path tracer's settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GuidedSettings {
    /// Its paths' depth and light samples.
    pub path: PathSettings,
    /// Samples per pixel spent training the guide before the render, in
    /// iterations of 1, 2, 4, ... (as many as fit); they train the guide and
    /// are not part of the image.
    pub training_spp: u32,
}

/// Which integrator, without its settings: what callers and scene files
/// choose by name.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum IntegratorKind {
    /// [`Integrator::Path`].
    #[default]
    Path,
    /// [`Integrator::Guided`].
    Guided,
}

impl IntegratorKind {
    /// Every kind's name, as every front end spells it.
    pub const NAMES: [&'static str; 2] = ["path", "guided"];

    /// The kind called `name` ([`IntegratorKind::NAMES`]).
    pub fn from_name(name: &str) -> Option<Self> {
        match name {
            "path" => Some(IntegratorKind::Path),
            "guided" => Some(IntegratorKind::Guided),
            _ => None,
        }
    }

    /// Its name in [`IntegratorKind::NAMES`].
    pub fn name(self) -> &'static str {
        match self {
            IntegratorKind::Path => "path",
            IntegratorKind::Guided => "guided",
        }
    }
}

impl Integrator {
    /// The integrator of kind `kind` with `settings`; a guided one trains
    /// its guide with `training_spp` samples per pixel.
    pub fn new(kind: IntegratorKind, settings: PathSettings, training_spp: u32) -> Self {
        match kind {
            IntegratorKind::Path => Integrator::Path(settings),
            IntegratorKind::Guided => Integrator::Guided(GuidedSettings {
                path: settings,
                training_spp,
            }),
        }
    }

    /// Which integrator it is.
    pub fn kind(&self) -> IntegratorKind {
        match self {
            Integrator::Path(_) => IntegratorKind::Path,
            Integrator::Guided(_) => IntegratorKind::Guided,
        }
    }

    /// Its path settings (depth, light samples).
    pub fn path_settings(&self) -> PathSettings {
        match *self {
            Integrator::Path(s) | Integrator::Guided(GuidedSettings { path: s, .. }) => s,
        }
    }

    /// The guide's training samples per pixel for a render of `scene`:
    /// `None` for the path tracer, and for a guided one where a guide cannot
    /// help ([`guiding_can_help`]), which then renders as the path tracer,
    /// image for image, without the cost of training.
    pub fn guide_training_spp(&self, scene: &CompiledScene) -> Option<u32> {
        match self {
            Integrator::Path(_) => None,
            Integrator::Guided(g) => guiding_can_help(scene).then_some(g.training_spp),
        }
    }
}

/// True when `scene` has light that a guide can find and next-event
/// estimation cannot: light that reaches a diffuse or rough surface through
/// glass, off a mirror or off nearly smooth metal (a caustic path), which
/// only a surface the guide does not steer makes. Where every surface is
/// diffuse or rough, light samples reach every light a path can see and a
/// guide only reshapes the indirect bounces: on the Cornell box with diffuse
/// spheres that cost its training and 3% a sample for no gain in error at
/// equal samples (BENCHMARKS.md, issue 33), so a guided render switches
/// itself off there.
pub fn guiding_can_help(scene: &CompiledScene) -> bool {
    !scene.spectral_materials().iter().all(material_is_guided)
}

/// True for a material whose BSDF the guide steers ([`is_guidable`]), at
/// any wavelength: a material's kind of lobes does not depend on it.
pub(crate) fn material_is_guided(material: &SpectralMaterial) -> bool {
    is_guidable(&material.bsdf(&mut SampledWavelengths::single(crate::spectrum::D_LINE_NM)))
}

impl Integrator {
    /// The path tracer with `max_depth` and `light_samples`.
    pub const fn path(max_depth: u32, light_samples: u32) -> Self {
        Integrator::Path(PathSettings {
            max_depth,
            light_samples,
        })
    }

    /// Maximum number of scattering events.
    pub fn max_depth(&self) -> u32 {
        self.path_settings().max_depth
    }

    /// Shadow rays per area or environment light at each non-specular hit.
    pub fn light_samples(&self) -> u32 {
        self.path_settings().light_samples
    }

    /// Radiance arriving along a camera ray at the wavelengths `lambda`, as
    /// linear sRGB, guided by `guide` if the integrator is guided and one is
    /// given. `rays` counts traced rays.
    pub fn radiance(
        &self,
        scene: &CompiledScene,
        guide: Option<&Guide>,
        camera_ray: Ray,
        lambda: SampledWavelengths,
        sampler: &mut Sampler,
        rays: &mut u64,
    ) -> Rgb {
        self.li(scene, guide, camera_ray, lambda, sampler, rays)
    }

    /// [`Integrator::radiance`], inlined into its caller: the loops over a
    /// render's tiles and a light field's rows, compiled for two CPU
    /// targets, each get a copy.
    #[inline(always)]
    pub(crate) fn li(
        &self,
        scene: &CompiledScene,
        guide: Option<&Guide>,
        camera_ray: Ray,
        lambda: SampledWavelengths,
        sampler: &mut Sampler,
        rays: &mut u64,
    ) -> Rgb {
        let (l, lambda) = self.li_spectrum(scene, guide, camera_ray, lambda, sampler, rays);
        lambda.to_rgb(l)
    }

    /// The spectral radiance arriving along a camera ray at `lambda`, one
    /// value per wavelength, with the wavelengths as the path left them (a
    /// dispersive interface keeps only the hero).
    #[inline(always)]
    pub(crate) fn li_spectrum(
        &self,
        scene: &CompiledScene,
        guide: Option<&Guide>,
        camera_ray: Ray,
        mut lambda: SampledWavelengths,
        sampler: &mut Sampler,
        rays: &mut u64,
    ) -> (SampledSpectrum, SampledWavelengths) {
        let l = match self {
            Integrator::Path(settings) => {
                trace_path(scene, camera_ray, &mut lambda, sampler, settings, None, None, rays)
            }
            Integrator::Guided(settings) => trace_path(
                scene,
                camera_ray,
                &mut lambda,
                sampler,
                &settings.path,
                guide,
                None,
                rays,
            ),
        };
        (l, lambda)
    }

    /// A training path of the guided integrator: traced like a render's,
    /// guided by `guide` as trained so far, recording the light it finds
    /// into `recorder`. Returns the rays traced.
    pub(crate) fn train(
        &self,
        scene: &CompiledScene,
        guide: &Guide,
        camera_ray: Ray,
        mut lambda: SampledWavelengths,
        sampler: &mut Sampler,
        mut recorder: PathRecorder<'_>,
    ) -> u64 {
        let mut rays = 0;
        let settings = self.path_settings();
        trace_path(
            scene,
            camera_ray,
            &mut lambda,
            sampler,
            &settings,
            Some(guide),
            Some(&mut recorder),
            &mut rays,
        );
        recorder.finish();
        rays
    }
}

/// What the guide offers at one guided vertex: once the vertex's region
/// has learned light, its distribution.
#[derive(Clone, Copy)]
struct GuideAt<'g> {
    distribution: Option<&'g DirectionalTree>,
}

impl GuideAt<'_> {
    /// The density of the guided mixture for world direction `wi`, given
    /// the BSDF's density `bsdf_pdf` for it.
    #[inline(always)]
    fn mixture_pdf(&self, bsdf_pdf: f32, wi: Vec3) -> f32 {
        match self.distribution {
            Some(d) => BSDF_SAMPLING_FRACTION * bsdf_pdf + (1.0 - BSDF_SAMPLING_FRACTION) * d.pdf(to_square(wi)),
            None => bsdf_pdf,
        }
    }
}

/// True for BSDFs the guide steers: diffuse and rough ones, where the
/// light a path finds depends on where it comes from (not for delta lobes
/// or nearly smooth metal, whose own sampling is better than any guide).
#[inline(always)]
fn is_guidable(bsdf: &Bsdf) -> bool {
    match bsdf {
        Bsdf::Diffuse { .. } => true,
        Bsdf::Conductor { alpha, .. } => *alpha >= GUIDED_MIN_ALPHA,
        Bsdf::Mirror { .. } | Bsdf::Dielectric { .. } => false,
    }
}

/// Conductors at least this rough are guided.
const GUIDED_MIN_ALPHA: f32 = 0.3;

/// Russian roulette spares a path's first this many scattering events:
/// the light of the first bounces carries most of an image, and ending those
/// paths early costs more variance than the rays it saves. pbrt-v4 starts
/// after the first (`depth > 1`), Mitsuba 3 at its fifth vertex (`rr_depth`
/// 5). Measured on `cornell-spheres` and `glass-and-gold` against pbrt-v4's
/// rule (BENCHMARKS.md, issue 34): starting after the fourth, with the cap
/// below, costs 2–51% more time per sample and leaves 0.45–0.81 of the
/// error, 0.64–0.88 of the error × time product.
const ROULETTE_MIN_DEPTH: u32 = 4;

/// The most likely a roulette survives, whatever the throughput (Mitsuba 3's
/// cap): a path through bright glass or mirrors keeps a throughput of 1 and
/// would otherwise never be ended before `max_depth`.
const ROULETTE_MAX_SURVIVAL: f32 = 0.95;

/// Shadow rays stop this fraction short of a sampled light point.
const SHADOW_EPSILON: f32 = 1e-4;

/// Where a path goes on from, with what throughput: the camera's ray, or
/// the reflected half of a path split at glass.
struct Branch {
    ray: Ray,
    beta: SampledSpectrum,
    eta_scale: f32,
    depth: u32,
}

/// The path tracer's loop, inlined into [`Integrator::li`].
/// With `guide`, it is the guided path tracer; with `recorder` too, a
/// training path.
///
/// A camera path that meets smooth glass through delta lobes only (the
/// camera's own ray, or after mirrors) splits there once: it follows the
/// refraction, then the reflection, each weighted by what it carries,
/// instead of picking one by its Fresnel weight (splitting, as in Vorba &
/// Křivánek 2016, at the one vertex where it always pays). The glass's
/// mirror image of a lamp is then in every sample rather than in the 4–10%
/// that would pick the reflection. Measured against picking (BENCHMARKS.md,
/// issue 33; three seeds at 16–128 spp): `glass-and-gold` 0.81–0.88× the
/// squared error for 0–5% more time, `caustics` 0.82–0.99× for 3–7%;
/// splitting at up to four such vertices cut `glass-and-gold`'s error a
/// little more (0.78–0.83×) for 3–14% more time.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn trace_path(
    scene: &CompiledScene,
    camera_ray: Ray,
    lambda: &mut SampledWavelengths,
    sampler: &mut Sampler,
    settings: &PathSettings,
    guide: Option<&Guide>,
    recorder: Option<&mut PathRecorder<'_>>,
    rays: &mut u64,
) -> SampledSpectrum {
    let start = Branch {
        ray: camera_ray,
        beta: SampledSpectrum::ONE,
        eta_scale: 1.0,
        depth: 0,
    };
    // Training paths do not split: a recorder follows one path.
    let may_split = recorder.is_none();
    trace_from(
        scene, start, may_split, lambda, sampler, settings, guide, recorder, rays,
    )
}

/// The reflected half of a split path, traced to its end: [`trace_from`]
/// without a split of its own. Out of line: traced within the same loop
/// (the loop restarting from the branch), the course's dragon render,
/// which has no glass, took 11–13% longer.
#[inline(never)]
fn trace_reflected(
    scene: &CompiledScene,
    branch: Branch,
    lambda: &mut SampledWavelengths,
    sampler: &mut Sampler,
    settings: &PathSettings,
    guide: Option<&Guide>,
    rays: &mut u64,
) -> SampledSpectrum {
    trace_from(scene, branch, false, lambda, sampler, settings, guide, None, rays)
}

/// The path loop from `start` (the camera's ray, or the reflected half of
/// a split, both seen through delta lobes only); with `may_split`, the
/// path splits at its first smooth glass (see [`trace_path`]).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn trace_from(
    scene: &CompiledScene,
    start: Branch,
    mut may_split: bool,
    lambda: &mut SampledWavelengths,
    sampler: &mut Sampler,
    settings: &PathSettings,
    guide: Option<&Guide>,
    mut recorder: Option<&mut PathRecorder<'_>>,
    rays: &mut u64,
) -> SampledSpectrum {
    let n_light = settings.light_samples as f32;
    let mut l = SampledSpectrum::ZERO;
    let Branch {
        mut ray,
        mut beta,
        mut eta_scale,
        mut depth,
    } = start;
    // The camera ray and specular bounces see emitters directly, without MIS.
    let mut specular_bounce = true;
    // The density the last direction was sampled with (BSDF or guided mixture).
    let mut scatter_pdf = 0.0f32;
    let mut emitted = EmissionCache::new(scene);
    let mut bsdfs = BsdfCache::default();
    // The reflected half of a split, traced once this path ends.
    let mut reflected: Option<Branch> = None;
    loop {
        *rays += 1;
        let Some(hit) = scene.intersect(&ray) else {
            for (i, (light, emission)) in scene.lights_with_emission().enumerate() {
                if let Some(light_pdf) = light.escaped_pdf() {
                    let w = if specular_bounce {
                        1.0
                    } else {
                        power_heuristic(1.0, scatter_pdf, n_light, light_pdf)
                    };
                    let c = beta * emitted.get(LightRef::Other(i), emission, lambda) * w;
                    add_light(&mut l, &mut recorder, c);
                }
            }
            break;
        };

        // Emission from the front face of an area light.
        if let Some(index) = hit.area_light {
            let cos_light = hit.geometric_normal.dot(-ray.direction);
            if cos_light > 0.0 {
                let light = &scene.area_lights()[index as usize];
                let w = if specular_bounce {
                    1.0
                } else {
                    power_heuristic(1.0, scatter_pdf, n_light, light.pdf(hit.t, cos_light))
                };
                let c = beta * emitted.get(LightRef::Area(index as usize), &light.emission, lambda) * w;
                add_light(&mut l, &mut recorder, c);
            }
        }
        if depth == settings.max_depth {
            break;
        }
        depth += 1;

        let bsdf = bsdfs.get(scene, hit.material, lambda);
        let frame = Frame::from_normal(hit.shading_normal);
        let wo = frame.to_local(-ray.direction);
        // The side of the surface the path is on: what the guide tells apart.
        let facing = if wo.z < 0.0 {
            -hit.shading_normal
        } else {
            hit.shading_normal
        };
        let guide_at = guide.filter(|_| is_guidable(&bsdf)).map(|g| GuideAt {
            distribution: g.distribution(hit.p, facing),
        });
        if !bsdf.is_specular() && settings.light_samples > 0 {
            let direct = direct_lighting(
                scene,
                &hit,
                &bsdf,
                &frame,
                wo,
                lambda,
                &mut emitted,
                sampler,
                settings,
                guide_at,
                rays,
            );
            add_light(&mut l, &mut recorder, beta * direct);
        }

        // Continue the path by sampling the BSDF, or the guide beside it.
        let (wi, pdf) = match guide_at {
            Some(at) => {
                let Some((wi, f, pdf)) = sample_guided(&bsdf, &frame, wo, at, sampler) else {
                    break;
                };
                beta *= f * (frame.to_local(wi).z.abs() / pdf);
                specular_bounce = false;
                (wi, pdf)
            }
            None => {
                let bs = match bsdf.split(wo).filter(|_| may_split && specular_bounce) {
                    Some([mirrored, transmitted]) => {
                        may_split = false;
                        let wi = frame.from_local(mirrored.wi);
                        reflected = Some(Branch {
                            ray: Ray::new(offset_origin(hit.p, hit.geometric_normal, wi), wi),
                            beta: beta * mirrored.f * mirrored.wi.z.abs(),
                            eta_scale,
                            depth,
                        });
                        transmitted
                    }
                    None => {
                        let uc = sampler.get_1d();
                        let u = sampler.get_2d();
                        let Some(bs) = bsdf.sample(wo, uc, u) else {
                            break;
                        };
                        bs
                    }
                };
                beta *= bs.f * (bs.wi.z.abs() / bs.pdf);
                specular_bounce = bs.specular;
                eta_scale *= bs.eta * bs.eta;
                (frame.from_local(bs.wi), bs.pdf)
            }
        };
        if beta == SampledSpectrum::ZERO || !beta.is_finite() {
            break;
        }
        scatter_pdf = pdf;
        if let (Some(r), Some(_)) = (recorder.as_deref_mut(), guide_at) {
            r.scattered(hit.p, facing, wi, pdf, beta);
        }
        ray = Ray::new(offset_origin(hit.p, hit.geometric_normal, wi), wi);

        // Russian roulette on the throughput without the radiance scaling of refraction.
        // Survival follows the throughput, capped below 1 so that no path
        // lives forever, from the vertex after ROULETTE_MIN_DEPTH on.
        let survival = (beta * eta_scale).max_element().min(ROULETTE_MAX_SURVIVAL);
        if depth > ROULETTE_MIN_DEPTH {
            if sampler.get_1d() >= survival {
                break;
            }
            beta /= survival;
        }
    }
    if let Some(branch) = reflected {
        l += trace_reflected(scene, branch, lambda, sampler, settings, guide, rays);
    }
    l
}

/// Adds `c` to the path's estimate `l`, and, on a training path, to the
/// light its recorded vertices received.
#[inline(always)]
fn add_light(l: &mut SampledSpectrum, recorder: &mut Option<&mut PathRecorder<'_>>, c: SampledSpectrum) {
    *l += c;
    if let Some(r) = recorder.as_deref_mut() {
        r.contribution(c);
    }
}

/// A continuation at a guided vertex: from the guide's distribution with
/// probability 1 − [`BSDF_SAMPLING_FRACTION`], else from the BSDF; returns
/// the world direction, the BSDF's value for it and the mixture's density.
#[inline(always)]
fn sample_guided(
    bsdf: &Bsdf,
    frame: &Frame,
    wo: Vec3,
    at: GuideAt<'_>,
    sampler: &mut Sampler,
) -> Option<(Vec3, SampledSpectrum, f32)> {
    let choose = sampler.get_1d();
    let uc = sampler.get_1d();
    let u = sampler.get_2d();
    let wi_local = match at.distribution {
        Some(d) if choose >= BSDF_SAMPLING_FRACTION => frame.to_local(d.sample(u)?.0),
        _ => bsdf.sample(wo, uc, u)?.wi,
    };
    let wi = frame.from_local(wi_local);
    let pdf = at.mixture_pdf(bsdf.pdf(wo, wi_local), wi);
    let f = bsdf.eval(wo, wi_local);
    (pdf > 0.0 && f != SampledSpectrum::ZERO).then_some((wi, f, pdf))
}

/// Light arriving directly from every light, `light_samples` shadow rays
/// each, weighted against BSDF sampling (or the guided mixture's) with the
/// power heuristic (Veach's multi-sample model: n_light light samples, one
/// BSDF sample).
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn direct_lighting(
    scene: &CompiledScene,
    hit: &SurfaceHit,
    bsdf: &Bsdf,
    frame: &Frame,
    wo: Vec3,
    lambda: &SampledWavelengths,
    emitted: &mut EmissionCache,
    sampler: &mut Sampler,
    settings: &PathSettings,
    guide_at: Option<GuideAt<'_>>,
    rays: &mut u64,
) -> SampledSpectrum {
    let mut shading = Shading {
        scene,
        hit,
        bsdf,
        frame,
        wo,
        lambda,
        emitted,
        sampler,
        guide_at,
        rays,
    };
    // Two loops, not one over `dyn` lights: each light's sampling inlines.
    let mut sum = SampledSpectrum::ZERO;
    let samples = settings.light_samples;
    for (i, light) in scene.area_lights().iter().enumerate() {
        sum += shading.light_sum(LightRef::Area(i), &light.emission, samples, light);
    }
    for (i, (light, emission)) in scene.lights_with_emission().enumerate() {
        // A point, spot or directional light's samples would all be one
        // ray: it takes one, as in the CS184 renderer.
        let samples = if light.is_delta() { 1 } else { samples };
        sum += shading.light_sum(LightRef::Other(i), emission, samples, light);
    }
    sum
}

/// Each material's BSDF at the path's wavelengths, made once per path
/// (materials have no textures, so a BSDF depends on the wavelengths
/// alone), for the first [`BsdfCache::MATERIALS`] materials. A dispersive
/// glass is made at every hit: making it keeps the hero wavelength alone.
#[derive(Default)]
struct BsdfCache {
    bsdfs: [Option<Bsdf>; BsdfCache::MATERIALS],
}

impl BsdfCache {
    const MATERIALS: usize = 8;

    /// Material `id`'s BSDF at `lambda`.
    #[inline(always)]
    fn get(&mut self, scene: &CompiledScene, id: MaterialId, lambda: &mut SampledWavelengths) -> Bsdf {
        let Some(slot) = self.bsdfs.get_mut(id as usize) else {
            return scene.spectral_material(id).bsdf(lambda);
        };
        if let Some(bsdf) = slot {
            return *bsdf;
        }
        let material = scene.spectral_material(id);
        let bsdf = material.bsdf(lambda);
        if !material.disperses() {
            *slot = Some(bsdf);
        }
        bsdf
    }
}

/// One of a scene's lights: an emissive shape's or one of
/// [`CompiledScene::lights`], by its index in that list.
#[derive(Clone, Copy)]
enum LightRef {
    /// `scene.area_lights()[i]`.
    Area(usize),
    /// The `i`-th of `scene.lights_with_emission()`.
    Other(usize),
}

/// Each light's emission at the path's wavelengths, evaluated once per
/// path: the wavelengths never change along a path (a dispersive surface
/// changes only their densities). The first [`EmissionCache::LIGHTS`]
/// lights are kept, area lights first.
struct EmissionCache {
    values: [SampledSpectrum; EmissionCache::LIGHTS],
    /// Bit `i` set: `values[i]` holds light `i`'s emission.
    known: u8,
    /// The scene's area-light count: its other lights are numbered after them.
    area_lights: usize,
}

impl EmissionCache {
    const LIGHTS: usize = 8;

    /// An empty cache for paths through `scene`.
    #[inline(always)]
    fn new(scene: &CompiledScene) -> Self {
        EmissionCache {
            values: [SampledSpectrum::ZERO; Self::LIGHTS],
            known: 0,
            area_lights: scene.area_lights().len(),
        }
    }

    /// What `light` emits (`emission`) at `lambda`.
    #[inline(always)]
    fn get(&mut self, light: LightRef, emission: &Spectrum, lambda: &SampledWavelengths) -> SampledSpectrum {
        let slot = match light {
            LightRef::Area(i) => i,
            LightRef::Other(i) => self.area_lights + i,
        };
        if slot >= Self::LIGHTS {
            return emission.sample(lambda);
        }
        if self.known & (1 << slot) == 0 {
            self.values[slot] = emission.sample(lambda);
            self.known |= 1 << slot;
        }
        self.values[slot]
    }
}

/// What direct lighting at one hit reads and advances.
struct Shading<'a> {
    scene: &'a CompiledScene,
    hit: &'a SurfaceHit,
    bsdf: &'a Bsdf,
    frame: &'a Frame,
    wo: Vec3,
    lambda: &'a SampledWavelengths,
    emitted: &'a mut EmissionCache,
    sampler: &'a mut Sampler,
    guide_at: Option<GuideAt<'a>>,
    rays: &'a mut u64,
}

impl Shading<'_> {
    /// `light`'s `samples` shadow rays, its samples drawn from `source`
    /// (the light itself), what it emits `emission`. From [`PACKET_MIN_RAYS`]
    /// on, the samples' contributions are found first, then their shadow
    /// rays traced together (see [`Shading::blocked`]) and the unblocked
    /// ones summed in order; fewer are traced one by one as they come.
    #[inline(always)]
    fn light_sum(
        &mut self,
        light: LightRef,
        emission: &Spectrum,
        samples: u32,
        source: &impl SampleLight,
    ) -> SampledSpectrum {
        let n_light = samples as f32;
        let mut sum = SampledSpectrum::ZERO;
        if (samples as usize) < PACKET_MIN_RAYS {
            for _ in 0..samples {
                if let Some(sample) = self.unblocked_sample(light, emission, n_light, source) {
                    if !self.blocked_alone(&sample) {
                        sum += sample.contribution;
                    }
                }
            }
            return sum;
        }
        let mut left = samples as usize;
        while left > 0 {
            let batch = left.min(SHADOW_PACKET);
            left -= batch;
            let mut found = [UnblockedSample::NONE; SHADOW_PACKET];
            let mut count = 0;
            for _ in 0..batch {
                if let Some(sample) = self.unblocked_sample(light, emission, n_light, source) {
                    found[count] = sample;
                    count += 1;
                }
            }
            let blocked = self.blocked(&found[..count]);
            for (i, sample) in found[..count].iter().enumerate() {
                if blocked & (1 << i) == 0 {
                    sum += sample.contribution;
                }
            }
        }
        sum
    }

    /// One sample of `light` (one of `n_light`, drawn from `source`) and
    /// what it contributes if nothing blocks it; `None` when it contributes
    /// nothing anyway.
    #[inline(always)]
    fn unblocked_sample(
        &mut self,
        light: LightRef,
        emission: &Spectrum,
        n_light: f32,
        source: &impl SampleLight,
    ) -> Option<UnblockedSample> {
        let (hit, bsdf, wo) = (self.hit, self.bsdf, self.wo);
        let u = self.sampler.get_2d();
        let ls = source.sample(hit.p, u)?;
        if ls.pdf <= 0.0 || ls.scale == 0.0 {
            return None;
        }
        let wi = self.frame.to_local(ls.wi);
        let f = bsdf.eval(wo, wi) * wi.z.abs();
        if f == SampledSpectrum::ZERO {
            return None;
        }
        *self.rays += 1;
        let w = if ls.delta {
            1.0
        } else {
            let bsdf_pdf = bsdf.pdf(wo, wi);
            let scatter_pdf = self.guide_at.map_or(bsdf_pdf, |at| at.mixture_pdf(bsdf_pdf, ls.wi));
            power_heuristic(n_light, ls.pdf, 1.0, scatter_pdf)
        };
        let emitted = self.emitted.get(light, emission, self.lambda);
        Some(UnblockedSample {
            contribution: f * emitted * (ls.scale * w / (ls.pdf * n_light)),
            wi: ls.wi,
            distance: ls.distance,
        })
    }

    /// Which of `samples`' shadow rays are blocked (bit `i` for
    /// `samples[i]`). Rays toward points leave from the side of the surface
    /// they head to; those on one side share an origin and, from
    /// [`PACKET_MIN_RAYS`] on, are traced as one packet, which gives each
    /// the answer it gets alone.
    #[inline(always)]
    fn blocked(&self, samples: &[UnblockedSample]) -> u32 {
        let hit = self.hit;
        let mut blocked = 0;
        if samples.len() >= PACKET_MIN_RAYS && samples.iter().all(|s| s.distance.is_finite()) {
            for front in [true, false] {
                let mut targets = [Vec3::ZERO; SHADOW_PACKET];
                let mut which = [0u8; SHADOW_PACKET];
                let mut count = 0;
                for (i, s) in samples.iter().enumerate() {
                    if (s.wi.dot(hit.geometric_normal) >= 0.0) == front {
                        targets[count] = hit.p + s.wi * s.distance;
                        which[count] = i as u8;
                        count += 1;
                    }
                }
                if count == 0 {
                    continue;
                }
                let side = if front {
                    hit.geometric_normal
                } else {
                    -hit.geometric_normal
                };
                let origin = offset_origin(hit.p, hit.geometric_normal, side);
                let mask = self
                    .scene
                    .occluded_from(origin, &targets[..count], 1.0 - SHADOW_EPSILON);
                for (k, &i) in which[..count].iter().enumerate() {
                    blocked |= ((mask >> k) & 1) << i;
                }
            }
            return blocked;
        }
        for (i, sample) in samples.iter().enumerate() {
            blocked |= u32::from(self.blocked_alone(sample)) << i;
        }
        blocked
    }

    /// Whether `sample`'s shadow ray, traced alone, is blocked.
    #[inline(always)]
    fn blocked_alone(&self, sample: &UnblockedSample) -> bool {
        let hit = self.hit;
        let origin = offset_origin(hit.p, hit.geometric_normal, sample.wi);
        if sample.distance.is_finite() {
            let target = hit.p + sample.wi * sample.distance;
            self.scene
                .occluded(&Ray::new(origin, target - origin), 1.0 - SHADOW_EPSILON)
        } else {
            self.scene.occluded(&Ray::new(origin, sample.wi), f32::INFINITY)
        }
    }
}

/// A light sample's contribution were it unblocked, and where its shadow
/// ray goes.
#[derive(Clone, Copy)]
struct UnblockedSample {
    contribution: SampledSpectrum,
    /// Unit direction to the light.
    wi: Vec3,
    /// Distance to the sampled point (infinite for distant lights).
    distance: f32,
}

impl UnblockedSample {
    const NONE: UnblockedSample = UnblockedSample {
        contribution: SampledSpectrum::ZERO,
        wi: Vec3::ZERO,
        distance: 0.0,
    };
}

/// The fewest shadow rays from one vertex traced as a packet; fewer go one
/// by one. A packet shares the walk through the tree, which pays where the
/// rays cross many nodes: the course's dragon setting (16 light samples)
/// took 0.52–0.62× the time. In the Cornell box of spheres, whose tree is
/// a root and its leaves, packets of four took 1.15× the time of single rays
/// (16 spp, 4 light samples, three interleaved runs).
const PACKET_MIN_RAYS: usize = 8;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::BvhSettings;
    use crate::guiding::Guide;
    use crate::io::load_scene;
    use crate::sampling::{uniform_sphere, SamplerKind};
    use glam::Vec2;

    /// The x86-64-v3 copy of the path loop gives the same radiance, bit for
    /// bit, as the baseline one, on diffuse, glass and rough gold: the
    /// claim behind compiling the render's tiles twice.
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn x86_64_v3_copy_is_bit_identical() {
        let v3 = is_x86_feature_detected!("avx2")
            && is_x86_feature_detected!("fma")
            && is_x86_feature_detected!("bmi1")
            && is_x86_feature_detected!("bmi2")
            && is_x86_feature_detected!("lzcnt")
            && is_x86_feature_detected!("movbe")
            && is_x86_feature_detected!("f16c");
        if !v3 {
            eprintln!("skipped: this CPU is not x86-64-v3");
            return;
        }
        #[target_feature(enable = "avx2,fma,bmi1,bmi2,lzcnt,movbe,f16c")]
        fn trace_path_v3(
            scene: &CompiledScene,
            ray: Ray,
            lambda: SampledWavelengths,
            sampler: &mut Sampler,
            integrator: &Integrator,
            rays: &mut u64,
        ) -> Rgb {
            integrator.li(scene, None, ray, lambda, sampler, rays)
        }
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/glass-and-gold.toml");
        let scene = load_scene(path.as_ref())
            .unwrap()
            .scene
            .compile(&BvhSettings::default())
            .unwrap();
        let integrator = Integrator::path(12, 2);
        let origin = Vec3::new(0.0, 1.0, 1.5);
        let (mut rays_a, mut rays_b) = (0, 0);
        let mut lit = 0;
        for i in 0..20_000u32 {
            let mut setup = Sampler::new(SamplerKind::Independent, i, 0, 0, 3);
            let u = setup.get_2d();
            let ray = Ray::new(origin, uniform_sphere(u.x, u.y));
            let lambda = SampledWavelengths::sample_visible(setup.get_1d());
            let mut sampler_a = Sampler::new(SamplerKind::Sobol, i, 1, 0, 3);
            let mut sampler_b = Sampler::new(SamplerKind::Sobol, i, 1, 0, 3);
            let a = integrator.radiance(&scene, None, ray, lambda, &mut sampler_a, &mut rays_a);
            // SAFETY: the CPU has every feature `trace_path_v3` is compiled for (checked above).
            let b = unsafe { trace_path_v3(&scene, ray, lambda, &mut sampler_b, &integrator, &mut rays_b) };
            assert_eq!(
                a.to_array().map(f32::to_bits),
                b.to_array().map(f32::to_bits),
                "path {i}"
            );
            lit += usize::from(a != Rgb::ZERO);
        }
        assert_eq!(rays_a, rays_b);
        assert!(lit > 10_000, "only {lit} paths carried light");
    }

    /// A camera path splits at the glass it sees first: every sample of a
    /// ray meeting a clear glass sphere head on carries the sphere's mirror
    /// image of the lamp behind the camera, R = F(0) = 4% of the lamp's
    /// radiance at the same wavelengths (picking one lobe would leave it
    /// out of 96% of the samples), and the mean is the light of both lobes
    /// and of every internal reflection, 2R / (1 + R) (a slab's
    /// reflectance at normal incidence; Born & Wolf).
    #[test]
    fn camera_paths_split_at_the_first_glass() {
        let text = r#"
            [materials.glass]
            type = "dielectric"
            eta = 1.5

            [[shapes]]
            type = "sphere"
            center = [0, 0, 0]
            radius = 1
            material = "glass"

            [[shapes]]                    # the lamp behind the camera, facing the sphere
            type = "quad"
            corner = [-10, -10, 10]
            edge_u = [0, 20, 0]
            edge_v = [20, 0, 0]
            emission = 1
        "#;
        let no_files = |p: &std::path::Path| Err(crate::Error::InvalidScene(format!("no file {}", p.display())));
        let scene = crate::io::scene_file::parse_scene_file(text, "split.toml".as_ref(), &no_files)
            .unwrap()
            .scene
            .compile(&BvhSettings::default())
            .unwrap();
        let settings = PathSettings {
            max_depth: 16,
            light_samples: 1,
        };
        let eye = Vec3::new(0.0, 0.0, 5.0);
        let mut rays = 0;
        let trace = |direction: Vec3, lambda: SampledWavelengths, seed: u32, rays: &mut u64| {
            let mut lambda = lambda;
            let mut sampler = Sampler::new(SamplerKind::Independent, seed, 1, 0, 3);
            trace_path(
                &scene,
                Ray::new(eye, direction),
                &mut lambda,
                &mut sampler,
                &settings,
                None,
                None,
                rays,
            )
        };
        let reflectance = crate::materials::fresnel_dielectric(1.0, 1.5);
        let n = 20_000;
        let mut sum = 0.0f64;
        for i in 0..n {
            let lambda =
                SampledWavelengths::sample_visible(Sampler::new(SamplerKind::Independent, i, 0, 0, 3).get_1d());
            let lamp = trace(Vec3::Z, lambda, i, &mut rays);
            let seen = trace(-Vec3::Z, lambda, i, &mut rays);
            assert!(lamp.min_element() > 0.0, "the lamp is not seen directly");
            assert!(
                (seen - lamp * (0.999 * reflectance)).min_element() >= 0.0,
                "sample {i}: {seen} lacks the reflection of {lamp}"
            );
            sum += f64::from((seen / lamp).element_sum() / 4.0);
        }
        let mean = sum / f64::from(n);
        let expected = f64::from(2.0 * reflectance / (1.0 + reflectance));
        assert!((mean - expected).abs() < 0.006, "mean {mean}, expected {expected}");
    }

    /// A point light's samples would all be the same shadow ray, so it takes
    /// one whatever the light samples (as the CS184 renderer does): in a
    /// box lit by a point light alone, 1 and 16 light samples trace the same
    /// rays and give the same radiance bit for bit, while an area light's
    /// samples still multiply its shadow rays.
    #[test]
    fn a_point_light_takes_one_shadow_ray_whatever_the_light_samples() {
        let mut scene = crate::builtin::builtin_scene("cornell-spheres", 0).unwrap();
        let area_lit = scene.clone().compile(&BvhSettings::default()).unwrap();
        for mesh in &mut scene.meshes {
            mesh.emission = None;
        }
        for sphere in &mut scene.spheres {
            sphere.emission = None;
        }
        scene.lights = vec![crate::lights::Light::Point {
            position: Vec3::new(0.0, 1.9, 0.0),
            intensity: Rgb::splat(4.0).into(),
        }];
        let point_lit = scene.compile(&BvhSettings::default()).unwrap();
        let trace = |scene: &CompiledScene, light_samples: u32| {
            let integrator = Integrator::path(8, light_samples);
            let mut rays = 0;
            let radiance: Vec<[u32; 3]> = (0..2000u32)
                .map(|i| {
                    let mut sampler = Sampler::new(SamplerKind::Sobol, i, 0, 0, 9);
                    let u = sampler.get_2d();
                    let ray = Ray::new(Vec3::new(0.0, 1.0, 0.5), uniform_sphere(u.x, u.y));
                    let lambda = SampledWavelengths::sample_visible(sampler.get_1d());
                    let l = integrator.radiance(scene, None, ray, lambda, &mut sampler, &mut rays);
                    l.to_array().map(f32::to_bits)
                })
                .collect();
            (radiance, rays)
        };
        let (one, one_rays) = trace(&point_lit, 1);
        let (sixteen, sixteen_rays) = trace(&point_lit, 16);
        assert_eq!(one_rays, sixteen_rays);
        assert!(one == sixteen, "the radiance changed with the light samples");
        assert!(
            one.iter().filter(|l| **l != [0; 3]).count() > 1000,
            "too few paths were lit"
        );
        let (_, area_one) = trace(&area_lit, 1);
        let (_, area_sixteen) = trace(&area_lit, 16);
        assert!(
            area_sixteen > 4 * area_one,
            "area light rays: {area_one} and {area_sixteen}"
        );
    }

    /// Paths recorded through the guided loop teach the guide where light
    /// comes from: paths that start at a point on the Cornell box's floor,
    /// without light sampling (so only their directions find the lamp),
    /// leave a guide whose density toward the lamp is many times the
    /// cosine's that BSDF sampling has, and whose samples hit the lamp
    /// several times as often.
    #[test]
    fn recorded_paths_teach_the_guide_where_the_lamp_is() {
        let scene = crate::builtin::builtin_scene("cornell-spheres", 0)
            .unwrap()
            .compile(&BvhSettings::default())
            .unwrap();
        let blind = Integrator::new(
            IntegratorKind::Guided,
            PathSettings {
                max_depth: 16,
                light_samples: 0,
            },
            15,
        );
        let mut guide = Guide::new(scene.bounds());
        let p = Vec3::new(0.0, 0.0, 0.9);
        for iteration in 0..4u32 {
            let mut records = Vec::new();
            for i in 0..20_000u32 {
                let mut sampler = Sampler::new(SamplerKind::Independent, i, iteration, 0, 3);
                let ray = Ray::new(p + Vec3::Y, -Vec3::Y);
                let lambda = SampledWavelengths::sample_visible(sampler.get_1d());
                let recorder = PathRecorder::new(&mut records, &guide, u64::from(i));
                blind.train(&scene, &guide, ray, lambda, &mut sampler, recorder);
            }
            guide.learn(&records);
            guide.end_iteration(1 << iteration);
        }
        let learned = guide.distribution(p, Vec3::Y).expect("the guide learned light at p");
        let to_lamp = (Vec3::new(0.0, 1.98, 0.0) - p).normalize();
        let cosine_pdf = to_lamp.y * std::f32::consts::FRAC_1_PI;
        let pdf = learned.pdf(to_square(to_lamp));
        assert!(
            pdf > 10.0 * cosine_pdf,
            "density toward the lamp {pdf}, cosine {cosine_pdf}"
        );
        let mut rng = crate::sampling::Rng::new(1);
        let hits = |sample: &mut dyn FnMut() -> Vec3| {
            (0..10_000)
                .filter(|_| {
                    let w = sample();
                    scene
                        .intersect(&Ray::new(p + Vec3::Y * 1e-3, w))
                        .is_some_and(|h| h.area_light.is_some())
                })
                .count()
        };
        let guided = hits(&mut || learned.sample(Vec2::new(rng.uniform(), rng.uniform())).unwrap().0);
        let mut rng = crate::sampling::Rng::new(2);
        let cosine = hits(&mut || {
            let l = crate::sampling::cosine_hemisphere(Vec2::new(rng.uniform(), rng.uniform()));
            Vec3::new(l.x, l.z, l.y)
        });
        assert!(
            guided > 4 * cosine,
            "lamp hits of 10 000: guided {guided}, cosine {cosine}"
        );
    }
}
