//! What a path evaluates once and reuses at every vertex: each material's
//! BSDF and each light's emission at the path's wavelengths.

use crate::materials::Bsdf;
use crate::scene::CompiledScene;
use crate::shapes::MaterialId;
use crate::spectrum::{SampledSpectrum, SampledWavelengths, Spectrum};

/// Each material's BSDF at the path's wavelengths, made once per path
/// (materials have no textures, so a BSDF depends on the wavelengths
/// alone), for the first [`BsdfCache::MATERIALS`] materials. A dispersive
/// glass is made at every hit: making it keeps the hero wavelength alone.
#[derive(Default)]
pub(super) struct BsdfCache {
    bsdfs: [Option<Bsdf>; BsdfCache::MATERIALS],
}

impl BsdfCache {
    const MATERIALS: usize = 8;

    /// Material `id`'s BSDF at `lambda`.
    #[inline(always)]
    pub(super) fn get(&mut self, scene: &CompiledScene, id: MaterialId, lambda: &mut SampledWavelengths) -> Bsdf {
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
pub(super) enum LightRef {
    /// `scene.area_lights()[i]`.
    Area(usize),
    /// The `i`-th of `scene.lights_with_emission()`.
    Other(usize),
}

/// Each light's emission at the path's wavelengths, evaluated once per
/// path: the wavelengths never change along a path (a dispersive surface
/// changes only their densities). The first [`EmissionCache::LIGHTS`]
/// lights are kept, area lights first.
pub(super) struct EmissionCache {
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
    pub(super) fn new(scene: &CompiledScene) -> Self {
        EmissionCache {
            values: [SampledSpectrum::ZERO; Self::LIGHTS],
            known: 0,
            area_lights: scene.area_lights().len(),
        }
    }

    /// What `light` emits (`emission`) at `lambda`.
    #[inline(always)]
    pub(super) fn get(&mut self, light: LightRef, emission: &Spectrum, lambda: &SampledWavelengths) -> SampledSpectrum {
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
