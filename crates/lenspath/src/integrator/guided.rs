//! The guide's share of a guided vertex: which BSDFs it steers, its
//! continuation mixed one-sample with the BSDF's, and that mixture's density.

use glam::Vec3;

use crate::guiding::directional::{to_square, DirectionalTree};
use crate::guiding::BSDF_SAMPLING_FRACTION;
use crate::materials::{Bsdf, SpectralMaterial};
use crate::math::Frame;
use crate::sampling::Sampler;
use crate::scene::CompiledScene;
use crate::spectrum::{SampledSpectrum, SampledWavelengths};

/// What the guide offers at one guided vertex: once the vertex's region
/// has learned light, its distribution.
#[derive(Clone, Copy)]
pub(super) struct GuideAt<'g> {
    pub(super) distribution: Option<&'g DirectionalTree>,
}

impl GuideAt<'_> {
    /// The density of the guided mixture for world direction `wi`, given
    /// the BSDF's density `bsdf_pdf` for it.
    #[inline(always)]
    pub(super) fn mixture_pdf(&self, bsdf_pdf: f32, wi: Vec3) -> f32 {
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
pub(super) fn is_guidable(bsdf: &Bsdf) -> bool {
    match bsdf {
        Bsdf::Diffuse { .. } => true,
        Bsdf::Conductor { alpha, .. } => *alpha >= GUIDED_MIN_ALPHA,
        Bsdf::Mirror { .. } | Bsdf::Dielectric { .. } => false,
    }
}

/// Conductors at least this rough are guided.
const GUIDED_MIN_ALPHA: f32 = 0.3;

/// A continuation at a guided vertex: from the guide's distribution with
/// probability 1 − [`BSDF_SAMPLING_FRACTION`], else from the BSDF; returns
/// the world direction, the BSDF's value for it and the mixture's density.
#[inline(always)]
pub(super) fn sample_guided(
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
