//! Setting up an autofocus search: what the caller asks
//! ([`AutofocusOverrides`]) over the scene file over the defaults. Its patch
//! renders have defaults of their own, since the scene file's integrator
//! settings are for the final image.

use super::{image_size, over_file_sensor, realistic_settings, CameraSettings, RealisticDescription, RenderSetup};
use crate::autofocus::{AutofocusSettings, FocusMeasure, FocusSensor, SensorSignal, Strategy};
use crate::camera::{CameraPose, RealisticCameraSettings};
use crate::defaults;
use crate::error::{Error, Result};
use crate::film::NormalizedRect;
use crate::integrator::Integrator;
use crate::options::SceneOptions;
use crate::scene::SceneView;
use crate::sensor::{SensorDescription, SensorSettings};

/// What a caller asks of an autofocus search; `None` means the default.
#[derive(Clone, Debug, Default)]
pub struct AutofocusOverrides {
    /// Image size the patch is a part of (default: the scene file's, else [`defaults::IMAGE_SIZE`]).
    pub resolution: Option<(u32, u32)>,
    /// Samples per pixel of each patch render (default [`defaults::AUTOFOCUS_PATCH_SPP`]).
    pub spp: Option<u32>,
    /// Maximum path depth of the patch renders (default [`defaults::AUTOFOCUS_PATCH_MAX_DEPTH`]).
    pub max_depth: Option<u32>,
    /// Seed of the patch renders (default [`defaults::AUTOFOCUS_SEED`]).
    pub seed: Option<u32>,
    /// Worker threads (`None`: every core).
    pub threads: Option<usize>,
    /// The focus measure (default: [`FocusMeasure`]'s).
    pub metric: Option<FocusMeasure>,
    /// The strategy (default: [`Strategy`]'s).
    pub strategy: Option<Strategy>,
    /// The early-exit strategy's patience, over the strategy's own.
    pub patience: Option<usize>,
    /// The realistic camera; its focus is what the search sets, and is ignored.
    pub camera: RealisticDescription,
    /// Contrast autofocus through this sensor (over the scene file's
    /// `[sensor]`, field by field); without either, on the noiseless film.
    pub sensor: Option<SensorDescription>,
    /// What the measure reads of the sensor's frames (default:
    /// [`SensorSignal`]'s).
    pub sensor_signal: Option<SensorSignal>,
}

/// An autofocus search, resolved: what to search with and how.
#[derive(Clone, Debug)]
pub struct AutofocusSetup {
    /// The search's settings (camera, patch, measure, patch renders).
    pub settings: AutofocusSettings,
    /// The strategy.
    pub strategy: Strategy,
    /// Where the camera is.
    pub pose: CameraPose,
}

/// The search of `patch` that `overrides` asks for, of a scene whose file
/// says `options` and whose view is `view`; patch renders trace one shadow
/// ray per light.
pub fn resolve_autofocus(
    options: &SceneOptions,
    view: &SceneView,
    patch: NormalizedRect,
    overrides: &AutofocusOverrides,
) -> Result<AutofocusSetup> {
    let size = image_size(overrides.resolution, options);
    let camera = realistic_settings(options, view, &overrides.camera, size.0, size.1)?;
    let overrides = AutofocusOverrides {
        sensor: over_file_sensor(overrides.sensor.as_ref(), options),
        ..overrides.clone()
    };
    autofocus_setup(camera, size, patch, &overrides, view.pose)
}

/// The search of `patch` of a `width` × `height` image through `camera` (a
/// camera already resolved, as the viewer's) at `pose`; `overrides.camera`
/// and `overrides.resolution` are not read, nor a scene file's sensor.
pub fn autofocus_setup(
    camera: RealisticCameraSettings,
    (width, height): (u32, u32),
    patch: NormalizedRect,
    overrides: &AutofocusOverrides,
    pose: CameraPose,
) -> Result<AutofocusSetup> {
    let strategy = overrides.strategy.unwrap_or_default();
    let strategy = overrides.patience.map_or(strategy, |p| strategy.with_patience(p));
    // Checked by `Focuser::new`, with the rest of the search's settings.
    let settings = AutofocusSettings {
        camera,
        width,
        height,
        patch: patch.to_pixels(width, height),
        measure: overrides.metric.unwrap_or_default(),
        spp: overrides.spp.unwrap_or(defaults::AUTOFOCUS_PATCH_SPP),
        integrator: Integrator::path(overrides.max_depth.unwrap_or(defaults::AUTOFOCUS_PATCH_MAX_DEPTH), 1),
        seed: overrides.seed.unwrap_or(defaults::AUTOFOCUS_SEED),
        threads: overrides.threads,
        sensor: overrides
            .sensor
            .as_ref()
            .map(|described| -> Result<FocusSensor> {
                Ok(FocusSensor {
                    sensor: described.resolve()?,
                    signal: overrides.sensor_signal.unwrap_or_default(),
                })
            })
            .transpose()?,
    };
    Ok(AutofocusSetup {
        settings,
        strategy,
        pose,
    })
}

/// The autofocus of `lenspath render --autofocus`: the default strategy and
/// measure on `patch` through the render's camera, its patch renders with the
/// render's seed and threads and its depth capped at
/// [`defaults::AUTOFOCUS_PATCH_MAX_DEPTH`]; through the render's sensor,
/// when it has one (the frame a camera focuses on is its sensor's).
pub fn autofocus_before_render(setup: &RenderSetup, patch: NormalizedRect) -> Result<AutofocusSetup> {
    let CameraSettings::Realistic(camera) = &setup.camera else {
        return Err(Error::InvalidArgument("autofocus needs the realistic camera".into()));
    };
    let s = &setup.settings;
    let overrides = AutofocusOverrides {
        max_depth: Some(s.integrator.max_depth().min(defaults::AUTOFOCUS_PATCH_MAX_DEPTH)),
        seed: Some(s.seed),
        threads: s.threads,
        sensor: setup.sensor.as_ref().map(SensorSettings::description),
        ..AutofocusOverrides::default()
    };
    autofocus_setup(camera.clone(), (s.width, s.height), patch, &overrides, setup.pose)
}
