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

//!
//! The parts: [`path`] is the loop (a vertex at a time, splitting at the
//! first glass, Russian roulette), [`direct`] the light sampling at each
//! vertex with its shadow packets, [`guided`] the guide's share of it,
//! [`caches`] what a path evaluates once and reuses.

mod caches;
mod context;
mod direct;
mod guided;
mod path;
mod settings;

use crate::guiding::{Guide, PathRecorder};
use crate::math::Rgb;
use crate::ray::Ray;
use crate::sampling::Sampler;
use crate::scene::CompiledScene;
use crate::spectrum::{SampledSpectrum, SampledWavelengths};
use context::PathContext;
pub use guided::guiding_can_help;
pub(crate) use guided::material_is_guided;
use path::trace_path;
pub use settings::{
    GuidedSettings, Integrator, IntegratorKind, PathSettings, DEFAULT_GUIDE_TRAINING_SPP, DEFAULT_LIGHT_SAMPLES,
    DEFAULT_MAX_DEPTH,
};

impl Integrator {
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
        let (settings, guide) = match self {
            Integrator::Path(settings) => (settings, None),
            Integrator::Guided(settings) => (&settings.path, guide),
        };
        let mut path = PathContext {
            scene,
            lambda: &mut lambda,
            sampler,
            settings,
            guide,
            rays,
        };
        let l = trace_path(&mut path, camera_ray, None);
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
        let mut path = PathContext {
            scene,
            lambda: &mut lambda,
            sampler,
            settings: &settings,
            guide: Some(guide),
            rays: &mut rays,
        };
        trace_path(&mut path, camera_ray, Some(&mut recorder));
        recorder.finish();
        rays
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::BvhSettings;
    use crate::guiding::directional::to_square;
    use crate::io::load_scene;
    use crate::sampling::{uniform_sphere, SamplerKind};
    use glam::{Vec2, Vec3};

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
