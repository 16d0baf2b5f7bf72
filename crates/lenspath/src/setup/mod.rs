//! Setting up a render: what the caller asks ([`RenderOverrides`], every
//! field optional) over what the scene file says ([`SceneOptions`]) over the
//! library's defaults ([`crate::defaults`]), resolved into the
//! [`RenderSettings`] and the [`CameraSettings`] of one render. The CLI, the
//! Python binding, the viewer and `lenspath.distributed` map their own
//! spelling of options onto [`RenderOverrides`] and call [`resolve`]; none of
//! them applies a default or builds a camera itself, so the same request
//! gives the same image from every front end.
//!
//! Autofocus is set up the same way ([`AutofocusOverrides`],
//! [`resolve_autofocus`], in `autofocus.rs`): its patch renders have
//! defaults of their own, since the scene file's integrator settings are for
//! the final image. What an image records of its setup is
//! [`RenderSetup::image_header`] (`header.rs`).

use std::sync::Arc;

use crate::camera::{
    sensor_for_image, Aperture, ApertureShape, Camera, CameraPose, LensFocus, PerspectiveCamera, Radiometry,
    RealisticCamera, RealisticCameraSettings,
};
use crate::defaults;
use crate::error::{Error, Result};
use crate::film::{Filter, Image, PixelRect};
use crate::integrator::{Integrator, IntegratorKind, PathSettings};
use crate::lens::{LensPrescription, LensSystem};
use crate::names::Named;
use crate::options::SceneOptions;
use crate::render::{FilmResponse, RenderSettings};
use crate::sampling::SamplerKind;
use crate::scene::SceneView;
use crate::sensor::{capture_through, needs_a_lens, Development, RawFrame, SensorDescription, SensorSettings};

mod autofocus;
mod fingerprint;
mod header;
pub use autofocus::{autofocus_before_render, autofocus_setup, resolve_autofocus, AutofocusOverrides, AutofocusSetup};
pub use fingerprint::SceneHash;

// ---------------------------------------------------------------------------
// What a caller asks for

/// What a caller asks of a render; `None` means "the scene file's, else the
/// library's default".
#[derive(Clone, Debug, Default)]
pub struct RenderOverrides {
    /// Image size in pixels, (width, height).
    pub resolution: Option<(u32, u32)>,
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// The integrator (path or guided).
    pub integrator: Option<IntegratorKind>,
    /// Maximum path depth.
    pub max_depth: Option<u32>,
    /// Shadow rays per area or environment light at each non-specular hit.
    pub light_samples: Option<u32>,
    /// Seed of the sample sequences.
    pub seed: Option<u32>,
    /// The sample sequence.
    pub sampler: Option<SamplerKind>,
    /// Pixel reconstruction filter (default: box).
    pub filter: Option<Filter>,
    /// Worker threads (`None`: every core).
    pub threads: Option<usize>,
    /// Render only this rectangle of the image.
    pub crop: Option<PixelRect>,
    /// Compute the depth channel (default: yes).
    pub depth: Option<bool>,
    /// Render at one wavelength, nm (default: colour across the visible).
    pub wavelength_nm: Option<f32>,
    /// The camera (default: the realistic camera with the scene's lens settings).
    pub camera: CameraDescription,
    /// Record the light through an image sensor, these settings over the
    /// scene file's `[sensor]` (`None` and no `[sensor]`: linear sRGB
    /// radiance).
    pub sensor: Option<SensorDescription>,
}

/// The kinds of camera, as every front end names them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CameraKind {
    /// An ideal pinhole: everything in focus.
    Pinhole,
    /// An ideal thin lens: depth of field from its aperture and focus distance.
    ThinLens,
    /// A real lens prescription, traced surface by surface.
    #[default]
    Realistic,
}

impl Named for CameraKind {
    const WHAT: &'static str = "camera";
    const NAMED: &'static [(CameraKind, &'static str)] = &[
        (CameraKind::Pinhole, "pinhole"),
        (CameraKind::ThinLens, "thin-lens"),
        (CameraKind::Realistic, "realistic"),
    ];
}

/// A camera as a caller describes it; what it leaves out comes from the
/// scene (its view and its file's `[camera]` settings) or the defaults.
#[derive(Clone, Debug, PartialEq)]
pub enum CameraDescription {
    /// An ideal pinhole: everything in focus.
    Pinhole {
        /// Vertical field of view, degrees (default: the scene view's).
        fov_y_deg: Option<f32>,
    },
    /// An ideal thin lens.
    ThinLens {
        /// Vertical field of view, degrees (default: the scene view's).
        fov_y_deg: Option<f32>,
        /// Aperture radius, scene units (default [`defaults::THIN_LENS_APERTURE_RADIUS`]).
        aperture_radius: Option<f32>,
        /// Focus distance from the lens, scene units (default: the view's subject distance).
        focus_distance: Option<f32>,
        /// The aperture's shape (default: the scene file's, else the circle).
        aperture: Option<ApertureShape>,
    },
    /// A real lens prescription, traced surface by surface.
    Realistic(RealisticDescription),
}

impl Default for CameraDescription {
    /// The realistic camera with the scene's settings.
    fn default() -> Self {
        CameraDescription::Realistic(RealisticDescription::default())
    }
}

/// The realistic camera as a caller describes it: each field overrides the
/// scene file's `[camera]` setting, which overrides the default.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RealisticDescription {
    /// The lens (default: the scene file's, else [`defaults::LENS`]).
    pub lens: Option<LensPrescription>,
    /// Sensor width, mm; its height follows the image's aspect (default: the
    /// scene file's, else [`defaults::SENSOR_WIDTH_MM`]).
    pub sensor_width_mm: Option<f64>,
    /// Focus (default: the scene file's focus distance or sensor depth, else
    /// the view's subject distance).
    pub focus: Option<LensFocus>,
    /// f-number to stop down to (default: the scene file's, else wide open).
    pub f_number: Option<f64>,
    /// Metres per scene unit (default: the scene file's, else 1).
    pub scene_unit_m: Option<f64>,
    /// Exposure normalisation (default: normalised).
    pub radiometry: Option<Radiometry>,
    /// The aperture's shape (default: the scene file's, else the circle).
    pub aperture: Option<ApertureShape>,
    /// Whether the lens's glasses disperse (default: the scene file's, else
    /// [`defaults::LENS_DISPERSION`]).
    pub dispersion: Option<bool>,
    /// Whether the pupil diffracts (default: the scene file's, else
    /// [`defaults::LENS_DIFFRACTION`]).
    pub diffraction: Option<bool>,
    /// Whether an anamorphic lens's image is desqueezed (default: the scene
    /// file's, else [`defaults::LENS_DESQUEEZE`]): the sensor keeps its
    /// width, and its height grows by the lens's squeeze, so each pixel
    /// covers that many times more of it in height than in width.
    pub desqueeze: Option<bool>,
}

// ---------------------------------------------------------------------------
// What a render is

/// A camera with every setting decided, ready to build.
#[derive(Clone, Debug, PartialEq)]
pub enum CameraSettings {
    /// An ideal pinhole.
    Pinhole {
        /// Vertical field of view, degrees.
        fov_y_deg: f32,
    },
    /// An ideal thin lens.
    ThinLens {
        /// Vertical field of view, degrees.
        fov_y_deg: f32,
        /// Aperture radius, scene units.
        aperture_radius: f32,
        /// Focus distance, scene units.
        focus_distance: f32,
        /// The aperture's shape.
        aperture: ApertureShape,
    },
    /// A real lens.
    Realistic(RealisticCameraSettings),
}

impl CameraSettings {
    /// Which kind of camera it is.
    pub fn kind(&self) -> CameraKind {
        match self {
            CameraSettings::Pinhole { .. } => CameraKind::Pinhole,
            CameraSettings::ThinLens { .. } => CameraKind::ThinLens,
            CameraSettings::Realistic(_) => CameraKind::Realistic,
        }
    }

    /// The camera at `pose` for a `width` × `height` image.
    pub fn build(&self, pose: CameraPose, width: u32, height: u32) -> Result<Arc<dyn Camera>> {
        Ok(match self {
            CameraSettings::Pinhole { fov_y_deg } => {
                Arc::new(PerspectiveCamera::pinhole(pose, *fov_y_deg, width, height))
            }
            CameraSettings::ThinLens {
                fov_y_deg,
                aperture_radius,
                focus_distance,
                aperture,
            } => Arc::new(
                PerspectiveCamera::thin_lens(pose, *fov_y_deg, width, height, *aperture_radius, *focus_distance)
                    .with_aperture(Arc::new(Aperture::new(aperture)?)),
            ),
            CameraSettings::Realistic(settings) => Arc::new(RealisticCamera::new(pose, width, height, settings)?),
        })
    }

    /// The aperture's shape (the circle for the pinhole, which has none).
    pub fn aperture(&self) -> &ApertureShape {
        match self {
            CameraSettings::Pinhole { .. } => &ApertureShape::Circle,
            CameraSettings::ThinLens { aperture, .. } => aperture,
            CameraSettings::Realistic(s) => &s.aperture,
        }
    }
}

/// One render, resolved: its settings, its camera and where the camera is.
#[derive(Clone, Debug)]
pub struct RenderSetup {
    /// Image size, samples, integrator, sampler, ...
    pub settings: RenderSettings,
    /// The camera's settings.
    pub camera: CameraSettings,
    /// Where the camera is (the scene's view).
    pub pose: CameraPose,
    /// The image sensor the film is read out by, if any (the film then
    /// records its channels).
    pub sensor: Option<SensorSettings>,
}

impl RenderSetup {
    /// Builds the camera.
    pub fn build_camera(&self) -> Result<Arc<dyn Camera>> {
        self.camera.build(self.pose, self.settings.width, self.settings.height)
    }

    /// The raw frame the sensor reads out of `image`, this setup's render
    /// through `camera`, and how the setup develops it (`None` without a
    /// sensor).
    pub fn capture(&self, camera: &dyn Camera, image: &Image) -> Result<Option<(RawFrame, Development)>> {
        let Some(sensor) = &self.sensor else {
            return Ok(None);
        };
        let origin = self.settings.crop.map_or((0, 0), |c| (c.x0, c.y0));
        let frame = capture_through(camera, image, origin, sensor)?;
        Ok(Some((frame, sensor.development)))
    }
}

// ---------------------------------------------------------------------------
// Resolution: caller > scene file > default

/// The render `overrides` asks for, of a scene whose file says `options` and
/// whose view is `view`: every field is the caller's, else the file's, else
/// the default; the settings are validated.
pub fn resolve(options: &SceneOptions, view: &SceneView, overrides: &RenderOverrides) -> Result<RenderSetup> {
    let mut settings = resolve_settings(options, overrides)?;
    let camera = resolve_camera(options, view, &overrides.camera, settings.width, settings.height)?;
    let sensor = over_file_sensor(overrides.sensor.as_ref(), options)
        .as_ref()
        .map(SensorDescription::resolve)
        .transpose()?;
    if let Some(sensor) = &sensor {
        if !matches!(camera, CameraSettings::Realistic(_)) {
            return Err(needs_a_lens());
        }
        settings.film = settings.film.read_by(sensor.response)?;
        settings.validate()?;
    }
    Ok(RenderSetup {
        settings,
        camera,
        pose: view.pose,
        sensor,
    })
}

/// The caller's sensor description over the scene file's, field by field.
pub(super) fn over_file_sensor(asked: Option<&SensorDescription>, options: &SceneOptions) -> Option<SensorDescription> {
    match (asked, &options.sensor) {
        (Some(asked), Some(file)) => Some(asked.over(file)),
        (asked, file) => asked.cloned().or_else(|| file.clone()),
    }
}

/// The render settings alone (no camera), validated.
pub fn resolve_settings(options: &SceneOptions, overrides: &RenderOverrides) -> Result<RenderSettings> {
    let (width, height) = image_size(overrides.resolution, options);
    // What no caller and no scene file sets: the library's own (box filter, 16-pixel tiles, the depth channel).
    let library = RenderSettings::default();
    let settings = RenderSettings {
        width,
        height,
        spp: overrides.spp.or(options.spp).unwrap_or(defaults::SPP),
        integrator: Integrator::new(
            overrides.integrator.or(options.integrator).unwrap_or_default(),
            PathSettings {
                max_depth: overrides.max_depth.or(options.max_depth).unwrap_or(defaults::MAX_DEPTH),
                light_samples: overrides
                    .light_samples
                    .or(options.light_samples)
                    .unwrap_or(defaults::LIGHT_SAMPLES),
            },
            defaults::GUIDE_TRAINING_SPP,
        ),
        seed: overrides.seed.or(options.seed).unwrap_or(defaults::SEED),
        sampler: overrides.sampler.or(options.sampler).unwrap_or_default(),
        filter: overrides.filter.unwrap_or(library.filter),
        threads: overrides.threads,
        crop: overrides.crop,
        depth: overrides.depth.unwrap_or(library.depth),
        film: FilmResponse::radiance(overrides.wavelength_nm),
        ..library
    };
    settings.validate()?;
    Ok(settings)
}

/// The image size the caller asks for, else the scene file's, else the default.
pub(super) fn image_size(asked: Option<(u32, u32)>, options: &SceneOptions) -> (u32, u32) {
    asked.or(options.resolution).unwrap_or(defaults::IMAGE_SIZE)
}

/// The camera `description` asks for, for a `width` × `height` image of a
/// scene whose file says `options` and whose view is `view`.
pub fn resolve_camera(
    options: &SceneOptions,
    view: &SceneView,
    description: &CameraDescription,
    width: u32,
    height: u32,
) -> Result<CameraSettings> {
    let fov = |asked: Option<f32>| {
        let fov = asked.unwrap_or(view.fov_y_deg);
        crate::camera::check_fov_deg(fov).map_err(Error::InvalidArgument)?;
        Ok(fov)
    };
    Ok(match description {
        CameraDescription::Pinhole { fov_y_deg } => CameraSettings::Pinhole {
            fov_y_deg: fov(*fov_y_deg)?,
        },
        CameraDescription::ThinLens {
            fov_y_deg,
            aperture_radius,
            focus_distance,
            aperture,
        } => {
            let aperture_radius = aperture_radius.unwrap_or(defaults::THIN_LENS_APERTURE_RADIUS);
            if !(aperture_radius >= 0.0 && aperture_radius.is_finite()) {
                return Err(Error::InvalidArgument(format!(
                    "the aperture radius must be zero or positive, got {aperture_radius}"
                )));
            }
            let focus_distance = focus_distance.unwrap_or(view.focus_distance);
            if !(focus_distance > 0.0 && focus_distance.is_finite()) {
                return Err(Error::InvalidArgument(format!(
                    "the focus distance must be positive, got {focus_distance}"
                )));
            }
            let aperture = aperture.clone().unwrap_or_else(|| file_aperture(options));
            // Checks the shape's values (blade count, curvature, ratio) before any rendering.
            Aperture::new(&aperture)?;
            CameraSettings::ThinLens {
                fov_y_deg: fov(*fov_y_deg)?,
                aperture_radius,
                focus_distance,
                aperture,
            }
        }
        CameraDescription::Realistic(realistic) => {
            CameraSettings::Realistic(realistic_settings(options, view, realistic, width, height)?)
        }
    })
}

/// The realistic camera `description` asks for, for a `width` × `height`
/// image: the caller's settings over the scene file's `[camera]` (lens,
/// sensor, f-number, aperture, focus distance or sensor depth, scene unit)
/// over the defaults. The sensor's height follows the image's aspect (times
/// an anamorphic lens's squeeze when the image is desqueezed).
pub fn realistic_settings(
    options: &SceneOptions,
    view: &SceneView,
    description: &RealisticDescription,
    width: u32,
    height: u32,
) -> Result<RealisticCameraSettings> {
    let file = options.lens.clone().unwrap_or_default();
    let lens = match &description.lens {
        Some(lens) => lens.clone(),
        None => LensPrescription::load(file.lens.as_deref().unwrap_or(defaults::LENS))?,
    };
    let sensor_width_mm = description
        .sensor_width_mm
        .or(file.sensor_mm.map(|(w, _)| w))
        .unwrap_or(defaults::SENSOR_WIDTH_MM);
    if !(sensor_width_mm > 0.0 && sensor_width_mm.is_finite()) {
        return Err(Error::InvalidArgument(format!(
            "the sensor width must be a positive number of mm, got {sensor_width_mm}"
        )));
    }
    let focus = description.focus.unwrap_or(match file.sensor_depth_mm {
        Some(mm) => LensFocus::SensorDepthMm(mm),
        None => LensFocus::Distance(file.focus_distance.unwrap_or(f64::from(view.focus_distance))),
    });
    let scene_unit_m = description
        .scene_unit_m
        .or(options.scene_unit_m)
        .unwrap_or(defaults::SCENE_UNIT_M);
    if !(scene_unit_m > 0.0 && scene_unit_m.is_finite()) {
        return Err(Error::InvalidArgument(format!(
            "the scene unit must be a positive number of metres, got {scene_unit_m}"
        )));
    }
    // Desqueezed, the image is the sensor's record stretched in width by the
    // squeeze: the same pixels over a sensor that much taller.
    let (sensor_w, mut sensor_h) = sensor_for_image(sensor_width_mm, width, height);
    if description
        .desqueeze
        .or(file.desqueeze)
        .unwrap_or(defaults::LENS_DESQUEEZE)
    {
        sensor_h *= LensSystem::new(&lens).squeeze()?;
    }
    // Radiometry has no scene-file key: the caller's, else `RealisticCameraSettings::new`'s.
    let library = RealisticCameraSettings::new(lens, (sensor_w, sensor_h), focus);
    Ok(RealisticCameraSettings {
        f_number: description.f_number.or(file.f_number),
        scene_unit_m,
        radiometry: description.radiometry.unwrap_or(library.radiometry),
        aperture: description.aperture.clone().unwrap_or_else(|| file_aperture(options)),
        dispersion: description.dispersion.or(file.dispersion).unwrap_or(library.dispersion),
        diffraction: description
            .diffraction
            .or(file.diffraction)
            .unwrap_or(library.diffraction),
        ..library
    })
}

/// The aperture shape the scene file gives, else the circle.
fn file_aperture(options: &SceneOptions) -> ApertureShape {
    options
        .lens
        .as_ref()
        .and_then(|l| l.aperture.clone())
        .unwrap_or(ApertureShape::Circle)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtin::builtin_scene;
    use crate::options::LensOptions;

    /// Every field: the caller's when given, else the scene file's, else the default.
    #[test]
    fn the_caller_wins_over_the_scene_file_which_wins_over_the_defaults() {
        let view = builtin_scene("cornell-spheres", 0).unwrap().view.unwrap();
        let file = SceneOptions {
            resolution: Some((40, 30)),
            spp: Some(5),
            max_depth: Some(7),
            seed: Some(11),
            scene_unit_m: Some(0.5),
            lens: Some(LensOptions {
                lens: Some("wide22".into()),
                f_number: Some(4.0),
                sensor_depth_mm: Some(30.0),
                ..LensOptions::default()
            }),
            ..SceneOptions::default()
        };
        let asked = RenderOverrides {
            spp: Some(9),
            sampler: Some(SamplerKind::Independent),
            camera: CameraDescription::Realistic(RealisticDescription {
                f_number: Some(8.0),
                ..RealisticDescription::default()
            }),
            ..RenderOverrides::default()
        };
        let setup = resolve(&file, &view, &asked).unwrap();
        let s = &setup.settings;
        assert_eq!((s.width, s.height, s.spp, s.seed), (40, 30, 9, 11));
        assert_eq!(s.integrator, Integrator::path(7, defaults::LIGHT_SAMPLES));
        assert_eq!(s.sampler, SamplerKind::Independent);
        let CameraSettings::Realistic(camera) = &setup.camera else {
            panic!("the default camera is the realistic one");
        };
        assert_eq!(camera.lens.name(), "wide22");
        assert_eq!(camera.f_number, Some(8.0));
        assert_eq!(camera.focus, LensFocus::SensorDepthMm(30.0));
        assert_eq!(camera.scene_unit_m, 0.5);
        assert_eq!(
            camera.sensor_mm,
            (defaults::SENSOR_WIDTH_MM, defaults::SENSOR_WIDTH_MM * 30.0 / 40.0)
        );
        assert_eq!(camera.dispersion, defaults::LENS_DISPERSION);

        // The realistic camera that a file's lens settings and a caller's
        // description resolve to, for a 40x30 image.
        let realistic = |file: LensOptions, asked: RealisticDescription| {
            let file = SceneOptions {
                lens: Some(file),
                ..SceneOptions::default()
            };
            let asked = RenderOverrides {
                resolution: Some((40, 30)),
                camera: CameraDescription::Realistic(asked),
                ..RenderOverrides::default()
            };
            match resolve(&file, &view, &asked).unwrap().camera {
                CameraSettings::Realistic(camera) => camera,
                _ => unreachable!(),
            }
        };

        // The lens's dispersion: the caller's, else the file's, else on.
        let dispersion = |file_says: Option<bool>, caller_says: Option<bool>| {
            let file = LensOptions {
                dispersion: file_says,
                ..LensOptions::default()
            };
            let asked = RealisticDescription {
                dispersion: caller_says,
                ..RealisticDescription::default()
            };
            realistic(file, asked).dispersion
        };
        assert!(dispersion(None, None));
        assert!(!dispersion(Some(false), None));
        assert!(dispersion(Some(false), Some(true)));
        assert!(!dispersion(None, Some(false)));

        // Desqueezing (the caller's, else the file's, else off) keeps the
        // sensor's width and makes it the lens's squeeze times taller than
        // the image's aspect says; a rotationally symmetric lens has none.
        let sensor_mm = |lens: &str, file_says: Option<bool>, caller_says: Option<bool>| {
            let file = LensOptions {
                lens: Some(lens.into()),
                desqueeze: file_says,
                ..LensOptions::default()
            };
            let asked = RealisticDescription {
                desqueeze: caller_says,
                ..RealisticDescription::default()
            };
            realistic(file, asked).sensor_mm
        };
        let squeeze = LensSystem::new(&LensPrescription::load("lentil:2004").unwrap())
            .squeeze()
            .unwrap();
        let (w, h) = (defaults::SENSOR_WIDTH_MM, defaults::SENSOR_WIDTH_MM * 30.0 / 40.0);
        assert_eq!(sensor_mm("lentil:2004", None, None), (w, h));
        assert_eq!(sensor_mm("lentil:2004", Some(true), None), (w, h * squeeze));
        assert_eq!(sensor_mm("lentil:2004", Some(true), Some(false)), (w, h));
        assert_eq!(sensor_mm("lentil:2004", None, Some(true)), (w, h * squeeze));
        assert_eq!(sensor_mm("dgauss50", None, Some(true)), (w, h));

        // Nothing asked, nothing in the file: the defaults.
        let bare = resolve(&SceneOptions::default(), &view, &RenderOverrides::default()).unwrap();
        let s = &bare.settings;
        assert_eq!((s.width, s.height), defaults::IMAGE_SIZE);
        assert_eq!(
            (s.spp, s.seed, s.sampler),
            (defaults::SPP, defaults::SEED, SamplerKind::default())
        );
        assert_eq!(
            s.integrator,
            Integrator::path(defaults::MAX_DEPTH, defaults::LIGHT_SAMPLES)
        );
        let CameraSettings::Realistic(camera) = &bare.camera else {
            panic!("the default camera is the realistic one");
        };
        assert_eq!(camera.lens.name(), defaults::LENS);
        assert_eq!(camera.focus, LensFocus::Distance(f64::from(view.focus_distance)));
    }

    #[test]
    fn bad_requests_are_refused_with_what_is_wrong() {
        let view = builtin_scene("cornell-spheres", 0).unwrap().view.unwrap();
        let file = SceneOptions::default();
        let with = |camera: CameraDescription| RenderOverrides {
            camera,
            ..RenderOverrides::default()
        };
        let pinhole = with(CameraDescription::Pinhole { fov_y_deg: Some(190.0) });
        let err = resolve(&file, &view, &pinhole).unwrap_err().to_string();
        assert!(err.contains("field of view must be between 0 and 180"), "{err}");
        let thin = with(CameraDescription::ThinLens {
            fov_y_deg: None,
            aperture_radius: Some(-1.0),
            focus_distance: None,
            aperture: None,
        });
        let err = resolve(&file, &view, &thin).unwrap_err().to_string();
        assert!(err.contains("aperture radius must be zero or positive"), "{err}");
        let zero_spp = RenderOverrides {
            spp: Some(0),
            ..RenderOverrides::default()
        };
        assert!(resolve(&file, &view, &zero_spp).is_err());
    }
}
