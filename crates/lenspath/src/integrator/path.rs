//! The path loop: a vertex at a time from the camera's ray, emission met
//! along the way weighted by MIS, a light sample at each non-specular
//! vertex, the BSDF's (or the guide's) continuation, one split at the first
//! smooth glass, and Russian roulette.

use super::caches::{BsdfCache, EmissionCache, LightRef};
use super::context::PathContext;
use super::direct::direct_lighting;
use super::guided::{is_guidable, sample_guided, GuideAt};
use crate::guiding::PathRecorder;
use crate::math::Frame;
use crate::ray::{offset_origin, Ray};
use crate::sampling::power_heuristic;
use crate::spectrum::SampledSpectrum;

/// Russian roulette spares a path's first this many scattering events:
/// the light of the first bounces carries most of an image, and ending those
/// paths early costs more variance than the rays it saves. pbrt-v4 starts
/// after the first (`depth > 1`), Mitsuba 3 at its fifth vertex (`rr_depth`
/// 5); after the fourth, with the cap below, leaves less error at equal
/// time than pbrt-v4's rule (BENCHMARKS.md, issue 34).
const ROULETTE_MIN_DEPTH: u32 = 4;

/// The most likely a roulette survives, whatever the throughput (Mitsuba 3's
/// cap): a path through bright glass or mirrors keeps a throughput of 1 and
/// would otherwise never be ended before `max_depth`.
const ROULETTE_MAX_SURVIVAL: f32 = 0.95;

/// Where a path goes on from, with what throughput: the camera's ray, or
/// the reflected half of a path split at glass.
struct Branch {
    ray: Ray,
    beta: SampledSpectrum,
    eta_scale: f32,
    depth: u32,
}

/// The path tracer's loop, inlined into [`super::Integrator::li`].
/// With `guide`, it is the guided path tracer; with `recorder` too, a
/// training path.
///
/// A camera path that meets smooth glass through delta lobes only (the
/// camera's own ray, or after mirrors) splits there once: it follows the
/// refraction, then the reflection, each weighted by what it carries,
/// instead of picking one by its Fresnel weight (splitting, as in Vorba &
/// Křivánek 2016, at the one vertex where it always pays). The glass's
/// mirror image of a lamp is then in every sample rather than in the 4–10%
/// that would pick the reflection (for less squared error at equal time:
/// BENCHMARKS.md, issue 33).
#[inline(always)]
pub(super) fn trace_path(
    path: &mut PathContext<'_>,
    camera_ray: Ray,
    recorder: Option<&mut PathRecorder<'_>>,
) -> SampledSpectrum {
    let start = Branch {
        ray: camera_ray,
        beta: SampledSpectrum::ONE,
        eta_scale: 1.0,
        depth: 0,
    };
    // Training paths do not split: a recorder follows one path.
    let may_split = recorder.is_none();
    trace_from(path, start, may_split, recorder)
}

/// The reflected half of a split path, traced to its end: [`trace_from`]
/// without a split of its own. Out of line, so that the loop of scenes
/// without glass stays as small as it was (BENCHMARKS.md, issue 33).
#[inline(never)]
fn trace_reflected(path: &mut PathContext<'_>, branch: Branch) -> SampledSpectrum {
    trace_from(path, branch, false, None)
}

/// The path loop from `start` (the camera's ray, or the reflected half of
/// a split, both seen through delta lobes only); with `may_split`, the
/// path splits at its first smooth glass (see [`trace_path`]).
#[inline(always)]
fn trace_from(
    path: &mut PathContext<'_>,
    start: Branch,
    mut may_split: bool,
    mut recorder: Option<&mut PathRecorder<'_>>,
) -> SampledSpectrum {
    let (scene, settings, guide) = (path.scene, path.settings, path.guide);
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
        *path.rays += 1;
        let Some(hit) = scene.intersect(&ray) else {
            for (i, (light, emission)) in scene.lights_with_emission().enumerate() {
                if let Some(light_pdf) = light.escaped_pdf() {
                    let w = if specular_bounce {
                        1.0
                    } else {
                        power_heuristic(1.0, scatter_pdf, n_light, light_pdf)
                    };
                    let c = beta * emitted.get(LightRef::Other(i), emission, path.lambda) * w;
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
                let c = beta * emitted.get(LightRef::Area(index as usize), &light.emission, path.lambda) * w;
                add_light(&mut l, &mut recorder, c);
            }
        }
        if depth == settings.max_depth {
            break;
        }
        depth += 1;

        let bsdf = bsdfs.get(scene, hit.material, path.lambda);
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
            let direct = direct_lighting(path, &hit, &bsdf, &frame, wo, guide_at, &mut emitted);
            add_light(&mut l, &mut recorder, beta * direct);
        }

        // Continue the path by sampling the BSDF, or the guide beside it.
        let (wi, pdf) = match guide_at {
            Some(at) => {
                let Some((wi, f, pdf)) = sample_guided(&bsdf, &frame, wo, at, path.sampler) else {
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
                        let uc = path.sampler.get_1d();
                        let u = path.sampler.get_2d();
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
            if path.sampler.get_1d() >= survival {
                break;
            }
            beta /= survival;
        }
    }
    if let Some(branch) = reflected {
        l += trace_reflected(path, branch);
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

#[cfg(test)]
mod tests {
    use super::super::settings::PathSettings;
    use super::*;
    use crate::accel::BvhSettings;
    use crate::sampling::{Sampler, SamplerKind};
    use crate::spectrum::SampledWavelengths;
    use glam::Vec3;

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
            let mut path = PathContext {
                scene: &scene,
                lambda: &mut lambda,
                sampler: &mut sampler,
                settings: &settings,
                guide: None,
                rays,
            };
            trace_path(&mut path, Ray::new(eye, direction), None)
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
}
