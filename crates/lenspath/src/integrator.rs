//! The unidirectional path tracer: next-event estimation with several
//! shadow rays per light, multiple importance sampling with the power
//! heuristic, and Russian roulette (after pbrt-v4 `PathIntegrator`).
//!
//! Transport is spectral: a path carries the four wavelengths its camera
//! sample drew ([`SampledWavelengths`]) and its throughput at each; the
//! estimate becomes linear sRGB at the end ([`SampledWavelengths::to_rgb`]).

use glam::{Vec2, Vec3};

use crate::lights::LightSample;
use crate::materials::Bsdf;
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
    /// Shadow rays per light at each non-specular hit (the CS184 `-l`).
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
        match self {
            Integrator::Path(s) => s.max_depth,
        }
    }

    /// Shadow rays per light at each non-specular hit.
    pub fn light_samples(&self) -> u32 {
        match self {
            Integrator::Path(s) => s.light_samples,
        }
    }

    /// Radiance arriving along a camera ray at the wavelengths `lambda`, as
    /// linear sRGB. `rays` counts traced rays.
    pub fn radiance(
        &self,
        scene: &CompiledScene,
        camera_ray: Ray,
        lambda: SampledWavelengths,
        sampler: &mut Sampler,
        rays: &mut u64,
    ) -> Rgb {
        self.li(scene, camera_ray, lambda, sampler, rays)
    }

    /// [`Integrator::radiance`], inlined into its caller: the loops over a
    /// render's tiles and a light field's rows, compiled for two CPU
    /// targets, each get a copy.
    #[inline(always)]
    pub(crate) fn li(
        &self,
        scene: &CompiledScene,
        camera_ray: Ray,
        lambda: SampledWavelengths,
        sampler: &mut Sampler,
        rays: &mut u64,
    ) -> Rgb {
        let (l, lambda) = self.li_spectrum(scene, camera_ray, lambda, sampler, rays);
        lambda.to_rgb(l)
    }

    /// The spectral radiance arriving along a camera ray at `lambda`, one
    /// value per wavelength, with the wavelengths as the path left them (a
    /// dispersive interface keeps only the hero).
    #[inline(always)]
    pub(crate) fn li_spectrum(
        &self,
        scene: &CompiledScene,
        camera_ray: Ray,
        mut lambda: SampledWavelengths,
        sampler: &mut Sampler,
        rays: &mut u64,
    ) -> (SampledSpectrum, SampledWavelengths) {
        let l = match self {
            Integrator::Path(settings) => trace_path(scene, camera_ray, &mut lambda, sampler, settings, rays),
        };
        (l, lambda)
    }
}

/// Shadow rays stop this fraction short of a sampled light point.
const SHADOW_EPSILON: f32 = 1e-4;

/// The path tracer's loop, inlined into [`Integrator::li`].
#[inline(always)]
fn trace_path(
    scene: &CompiledScene,
    camera_ray: Ray,
    lambda: &mut SampledWavelengths,
    sampler: &mut Sampler,
    settings: &PathSettings,
    rays: &mut u64,
) -> SampledSpectrum {
    let n_light = settings.light_samples as f32;
    let mut l = SampledSpectrum::ZERO;
    let mut beta = SampledSpectrum::ONE;
    let mut eta_scale = 1.0f32;
    // The camera ray and specular bounces see emitters directly, without MIS.
    let mut specular_bounce = true;
    let mut bsdf_pdf = 0.0f32;
    let mut ray = camera_ray;
    let mut depth = 0;
    let mut emitted = EmissionCache::new(scene);
    let mut bsdfs = BsdfCache::default();
    loop {
        *rays += 1;
        let Some(hit) = scene.intersect(&ray) else {
            for (i, (light, emission)) in scene.lights_with_emission().enumerate() {
                if let Some(light_pdf) = light.escaped_pdf() {
                    let w = if specular_bounce {
                        1.0
                    } else {
                        power_heuristic(1.0, bsdf_pdf, n_light, light_pdf)
                    };
                    l += beta * emitted.get(LightRef::Other(i), emission, lambda) * w;
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
                    power_heuristic(1.0, bsdf_pdf, n_light, light.pdf(hit.t, cos_light))
                };
                l += beta * emitted.get(LightRef::Area(index as usize), &light.emission, lambda) * w;
            }
        }
        if depth == settings.max_depth {
            break;
        }
        depth += 1;

        let bsdf = bsdfs.get(scene, hit.material, lambda);
        let frame = Frame::from_normal(hit.shading_normal);
        let wo = frame.to_local(-ray.direction);
        if !bsdf.is_specular() && settings.light_samples > 0 {
            l += beta
                * direct_lighting(
                    scene,
                    &hit,
                    &bsdf,
                    &frame,
                    wo,
                    lambda,
                    &mut emitted,
                    sampler,
                    settings,
                    rays,
                );
        }

        // Continue the path by sampling the BSDF.
        let uc = sampler.get_1d();
        let u = sampler.get_2d();
        let Some(bs) = bsdf.sample(wo, uc, u) else {
            break;
        };
        beta *= bs.f * (bs.wi.z.abs() / bs.pdf);
        if beta == SampledSpectrum::ZERO || !beta.is_finite() {
            break;
        }
        specular_bounce = bs.specular;
        bsdf_pdf = bs.pdf;
        eta_scale *= bs.eta * bs.eta;
        let wi = frame.from_local(bs.wi);
        ray = Ray::new(offset_origin(hit.p, hit.geometric_normal, wi), wi);

        // Russian roulette on the throughput without the radiance scaling of refraction.
        let rr_beta = (beta * eta_scale).max_element();
        if rr_beta < 1.0 && depth > 1 {
            let q = (1.0 - rr_beta).max(0.0);
            if sampler.get_1d() < q {
                break;
            }
            beta /= 1.0 - q;
        }
    }
    l
}

/// Light arriving directly from every light, `light_samples` shadow rays
/// each, weighted against BSDF sampling with the power heuristic
/// (Veach's multi-sample model: n_light light samples, one BSDF sample).
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
        settings,
        rays,
    };
    // Two loops, not one over `dyn` lights: each light's sampling inlines.
    let mut sum = SampledSpectrum::ZERO;
    for (i, light) in scene.area_lights().iter().enumerate() {
        sum += shading.light_sum(LightRef::Area(i), &light.emission, |p, u| light.sample(p, u));
    }
    for (i, (light, emission)) in scene.lights_with_emission().enumerate() {
        sum += shading.light_sum(LightRef::Other(i), emission, |p, u| light.sample(p, u));
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
    settings: &'a PathSettings,
    rays: &'a mut u64,
}

impl Shading<'_> {
    /// `light`'s `light_samples` shadow rays, its samples drawn by
    /// `sample_light`, what it emits `emission`.
    #[inline(always)]
    fn light_sum(
        &mut self,
        light: LightRef,
        emission: &Spectrum,
        sample_light: impl Fn(Vec3, Vec2) -> Option<LightSample>,
    ) -> SampledSpectrum {
        let (hit, bsdf, wo) = (self.hit, self.bsdf, self.wo);
        let n_light = self.settings.light_samples as f32;
        let mut sum = SampledSpectrum::ZERO;
        for _ in 0..self.settings.light_samples {
            let u = self.sampler.get_2d();
            let Some(ls) = sample_light(hit.p, u) else {
                continue;
            };
            if ls.pdf <= 0.0 || ls.scale == 0.0 {
                continue;
            }
            let wi = self.frame.to_local(ls.wi);
            let f = bsdf.eval(wo, wi) * wi.z.abs();
            if f == SampledSpectrum::ZERO {
                continue;
            }
            *self.rays += 1;
            let origin = offset_origin(hit.p, hit.geometric_normal, ls.wi);
            let blocked = if ls.distance.is_finite() {
                let target = hit.p + ls.wi * ls.distance;
                self.scene
                    .occluded(&Ray::new(origin, target - origin), 1.0 - SHADOW_EPSILON)
            } else {
                self.scene.occluded(&Ray::new(origin, ls.wi), f32::INFINITY)
            };
            if blocked {
                continue;
            }
            let w = if ls.delta {
                1.0
            } else {
                power_heuristic(n_light, ls.pdf, 1.0, bsdf.pdf(wo, wi))
            };
            let emitted = self.emitted.get(light, emission, self.lambda);
            sum += f * emitted * (ls.scale * w / (ls.pdf * n_light));
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::BvhSettings;
    use crate::io::load_scene;
    use crate::sampling::{uniform_sphere, SamplerKind};

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
            integrator.li(scene, ray, lambda, sampler, rays)
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
            let a = integrator.radiance(&scene, ray, lambda, &mut sampler_a, &mut rays_a);
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
}
