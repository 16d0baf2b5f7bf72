//! What a path reads and advances from its camera ray to its end, handed
//! from the path loop to the light sampling at each vertex.

use super::settings::PathSettings;
use crate::guiding::Guide;
use crate::sampling::Sampler;
use crate::scene::CompiledScene;
use crate::spectrum::SampledWavelengths;

/// What a path reads and advances from its camera ray to its end.
pub(super) struct PathContext<'a> {
    pub(super) scene: &'a CompiledScene,
    /// The path's wavelengths (a dispersive interface keeps only the hero).
    pub(super) lambda: &'a mut SampledWavelengths,
    pub(super) sampler: &'a mut Sampler,
    pub(super) settings: &'a PathSettings,
    /// The trained guide, for a guided path.
    pub(super) guide: Option<&'a Guide>,
    /// Rays traced so far.
    pub(super) rays: &'a mut u64,
}
