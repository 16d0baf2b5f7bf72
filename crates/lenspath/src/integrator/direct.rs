//! Direct lighting at a path's vertex: every light's shadow rays, weighed
//! against BSDF (or guided) sampling by the power heuristic, the unblocked
//! ones found first and their shadow rays traced together as a packet.

use glam::Vec3;

use super::caches::{EmissionCache, LightRef};
use super::context::PathContext;
use super::guided::GuideAt;
use crate::accel::SHADOW_PACKET;
use crate::lights::SampleLight;
use crate::materials::Bsdf;
use crate::math::Frame;
use crate::ray::{offset_origin, Ray};
use crate::sampling::{power_heuristic, Sampler};
use crate::scene::{CompiledScene, SurfaceHit};
use crate::spectrum::{SampledSpectrum, SampledWavelengths, Spectrum};

/// Shadow rays stop this fraction short of a sampled light point.
const SHADOW_EPSILON: f32 = 1e-4;

/// Light arriving directly from every light, `light_samples` shadow rays
/// each, weighted against BSDF sampling (or the guided mixture's) with the
/// power heuristic (Veach's multi-sample model: n_light light samples, one
/// BSDF sample).
#[inline(always)]
pub(super) fn direct_lighting(
    path: &mut PathContext<'_>,
    hit: &SurfaceHit,
    bsdf: &Bsdf,
    frame: &Frame,
    wo: Vec3,
    guide_at: Option<GuideAt<'_>>,
    emitted: &mut EmissionCache,
) -> SampledSpectrum {
    let scene = path.scene;
    let mut shading = Shading {
        scene,
        hit,
        bsdf,
        frame,
        wo,
        lambda: path.lambda,
        emitted,
        sampler: path.sampler,
        guide_at,
        rays: path.rays,
    };
    // Two loops, not one over `dyn` lights: each light's sampling inlines.
    let mut sum = SampledSpectrum::ZERO;
    let samples = path.settings.light_samples;
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
/// rays cross many nodes and costs where the tree is shallow (BENCHMARKS.md).
const PACKET_MIN_RAYS: usize = 8;

#[cfg(test)]
mod tests {
    use super::super::Integrator;
    use crate::accel::BvhSettings;
    use crate::math::Rgb;
    use crate::ray::Ray;
    use crate::sampling::{uniform_sphere, Sampler, SamplerKind};
    use crate::scene::CompiledScene;
    use crate::spectrum::SampledWavelengths;
    use glam::Vec3;

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
}
