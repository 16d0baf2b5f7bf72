//! Which integrator, with its settings: the path tracer's depth and light
//! samples, the guided path tracer's training, and their names.

use super::guided::guiding_can_help;
use crate::names::Named;
use crate::scene::CompiledScene;

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

/// Maximum path depth when neither the caller nor the scene file gives one
/// (scattering events; 1 is direct lighting only).
pub const DEFAULT_MAX_DEPTH: u32 = 16;
/// Shadow rays per area or environment light at each non-specular hit when
/// neither the caller nor the scene file gives them (a point, spot or
/// directional light takes one: its samples would all be one ray).
pub const DEFAULT_LIGHT_SAMPLES: u32 = 1;
/// The guided integrator's training when the scene file does not give it:
/// samples per pixel of the whole image spent on iterations of 1, 2, 4 and
/// 8 before the render.
pub const DEFAULT_GUIDE_TRAINING_SPP: u32 = 15;

impl Default for PathSettings {
    /// [`DEFAULT_MAX_DEPTH`] and [`DEFAULT_LIGHT_SAMPLES`].
    fn default() -> Self {
        PathSettings {
            max_depth: DEFAULT_MAX_DEPTH,
            light_samples: DEFAULT_LIGHT_SAMPLES,
        }
    }
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

impl Named for IntegratorKind {
    const WHAT: &'static str = "integrator";
    const NAMED: &'static [(IntegratorKind, &'static str)] =
        &[(IntegratorKind::Path, "path"), (IntegratorKind::Guided, "guided")];
}

impl Default for Integrator {
    /// The default kind with the default path settings (and training).
    fn default() -> Self {
        Integrator::new(
            IntegratorKind::default(),
            PathSettings::default(),
            DEFAULT_GUIDE_TRAINING_SPP,
        )
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
}
