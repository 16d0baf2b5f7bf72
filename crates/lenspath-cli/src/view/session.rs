//! The viewer's state: the settings the page sets, checked like the CLI's
//! flags, the camera built from them, the render's progress and the last
//! complete image. Shared by the server's handlers and the render thread.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::time::Instant;

use axum::body::Bytes;
use glam::Vec3;
use lenspath::autofocus::{FocusMeasure, Strategy};
use lenspath::camera::{ApertureShape, CameraPose, LensFocus, RealisticCamera, RealisticCameraSettings};
use lenspath::film::Image;
use lenspath::integrator::IntegratorKind;
use lenspath::io::scene_file::{SceneBase, SceneSettingsFile, SensorTable};
use lenspath::lens::{AnalysisSettings, LensAnalysis, LensPrescription, TableConvention};
use lenspath::lens_report::{LensReport, LensReportSettings};
use lenspath::names::Named;
use lenspath::options::SceneOptions;
use lenspath::render::{NormalizedRect, RenderSettings};
use lenspath::sampling::SamplerKind;
use lenspath::sampling::MAX_SAMPLES_PER_PIXEL;
use lenspath::scene::{CompiledScene, SceneView};
use lenspath::sensor::{capture_through, develop::develop, Exposure, SensorSettings};
use lenspath::setup::{
    realistic_settings, resolve, resolve_settings, CameraSettings, RealisticDescription, RenderOverrides,
};
use lenspath::{Error, Result};
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};
use tokio::sync::broadcast;

/// Where the page puts the sensor.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "by", rename_all = "kebab-case", deny_unknown_fields)]
pub enum Focus {
    /// The sensor this many mm behind the aperture stop (the focus ring, read off the lens).
    Sensor {
        /// mm behind the stop.
        depth_mm: f64,
    },
    /// Whatever is this far from the sensor plane in focus (a distance scale).
    Distance {
        /// Metres from the sensor plane.
        distance_m: f64,
    },
}

/// Everything the page can set; a change is sent as a JSON object of the
/// fields that change, merged into these and checked before it applies.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ViewSettings {
    /// Built-in lens, a table dropped on the page, or a table file the command line allows.
    pub lens: String,
    /// f-number to stop down to (`None`: wide open).
    pub f_number: Option<f64>,
    /// Focus.
    pub focus: Focus,
    /// Aperture shape: circle, blades:N[:ROTATION_DEG[:CURVATURE]], star:N[:INNER_RATIO[:ROTATION_DEG]].
    pub aperture: String,
    /// Whether the lens's glasses disperse (off: every glass at its d-line index).
    pub dispersion: bool,
    /// Whether the pupil diffracts (the Airy disc, the starburst).
    pub diffraction: bool,
    /// Camera position, scene units.
    pub eye: [f32; 3],
    /// The point it looks at (what orbiting turns about).
    pub target: [f32; 3],
    /// Up direction.
    pub up: [f32; 3],
    /// Refinement stops at this many samples per pixel.
    pub max_spp: u32,
    /// Maximum path depth.
    pub max_depth: u32,
    /// Shadow rays per area or environment light per hit.
    pub light_samples: u32,
    /// Seed of the sample sequences.
    pub seed: u32,
    /// `sobol` or `independent`.
    pub sampler: String,
    /// `path` or `guided` (the integrator).
    #[serde(default = "default_integrator")]
    pub integrator: String,
    /// Record through an image sensor (`None`: linear radiance): a scene
    /// file's `[sensor]` table, the same names and spellings.
    #[serde(default)]
    pub sensor: Option<SensorTable>,
}

/// The integrator of settings that do not name one: the library's default.
fn default_integrator() -> String {
    IntegratorKind::default().name().into()
}

/// The autofocus request of a click or a dragged rectangle.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AutofocusRequest {
    /// The patch, `[x, y, width, height]` in fractions of the image.
    pub patch: [f64; 4],
    /// The focus measure, by name (as `lenspath autofocus --metric`).
    #[serde(default, deserialize_with = "lenspath::names::deserialize")]
    pub metric: FocusMeasure,
    /// The strategy, by name (as `lenspath autofocus --strategy`).
    #[serde(default, deserialize_with = "lenspath::names::deserialize")]
    pub strategy: Strategy,
}

/// The camera that settings describe, built and checked.
#[derive(Clone)]
pub struct View {
    /// The settings.
    pub settings: ViewSettings,
    /// The realistic camera's settings, its focus as a sensor position.
    pub lens_settings: RealisticCameraSettings,
    /// What the saved scene file names as the lens.
    pub lens_reference: String,
    /// Whether the lens is a table dropped on the page (no file here to name).
    pub lens_dropped: bool,
    /// The camera.
    pub camera: RealisticCamera,
    /// The render's settings (its `spp` is set per refinement step).
    pub render: RenderSettings,
    /// Where the camera is.
    pub pose: CameraPose,
    /// The sensor's place, mm behind the stop.
    pub sensor_depth_mm: f64,
    /// The distance in focus from the sensor plane, metres (`None`: beyond infinity).
    pub focus_distance_m: Option<f64>,
    /// Infinity-focus and close-focus sensor positions, mm behind the stop.
    pub focus_range_mm: (f64, f64),
    /// Focal length, mm.
    pub focal_length_mm: f64,
    /// Wide-open f-number.
    pub wide_open_f_number: f64,
    /// The lens's paraxial longitudinal colour, BFD(F) − BFD(C), mm (0 without a glass column).
    pub longitudinal_color_mm: f64,
    /// The lens layout with the sensor where it is, as SVG.
    pub layout_svg: String,
    /// Half the diagonal field of view, degrees (the MTF's fields are fractions of it).
    pub half_diagonal_field_deg: f64,
    /// The image sensor, resolved (`None`: the image is the film's radiance).
    pub sensor: Option<SensorSettings>,
}

impl View {
    /// What the page shows of a render's `film`: the film itself, or
    /// through a sensor the raw frame it reads out, developed (its samples
    /// per pixel the film's), with how it was taken. `camera` is the camera
    /// it was rendered with.
    pub fn shown(&self, camera: &RealisticCamera, film: Image) -> Result<(Image, Option<Exposure>)> {
        let Some(sensor) = &self.sensor else {
            return Ok((film, None));
        };
        let frame = capture_through(camera, &film, (0, 0), sensor)?;
        let image = Image {
            spp_min: film.spp_min,
            spp_requested: film.spp_requested,
            ..develop(&frame, &sensor.development)
        };
        Ok((image, Some(frame.exposure.clone())))
    }
}

/// A finished refinement step: the image every pixel of which has `spp` samples.
pub struct Frame {
    /// The settings generation it belongs to.
    pub generation: u64,
    /// The image.
    pub image: Image,
    /// Its JPEG, what the page shows (shared, not copied, with every page).
    pub jpeg: Bytes,
    /// The view it was rendered with.
    pub view: Arc<View>,
    /// How it was taken, through a sensor.
    pub exposure: Option<Exposure>,
}

/// What the render thread and the handlers tell the pages.
#[derive(Clone)]
pub enum Event {
    /// A JPEG frame (a binary WebSocket message).
    Frame(Bytes),
    /// A JSON message (a text WebSocket message).
    Message(Arc<String>),
}

/// What changes while the viewer runs, under one lock.
pub struct State {
    /// The current camera.
    pub view: Arc<View>,
    /// Bumped by every change of settings: older work is dropped.
    pub generation: u64,
    /// When the current generation was asked for (the first preview's latency counts from it).
    pub changed_at: Instant,
    /// Pages connected; the render thread sleeps at 0.
    pub clients: usize,
    /// A change is being checked and its camera built; the render waits.
    pub changing: bool,
    /// An autofocus the render thread has still to run.
    pub autofocus: Option<AutofocusRequest>,
    /// The last complete image of the current generation.
    pub last_frame: Option<Arc<Frame>>,
}

/// Where a viewer's scene comes from.
pub struct SceneSource {
    /// Its name, for the page's title.
    pub name: String,
    /// What a saved scene file starts from.
    pub base: SceneBase,
    /// The settings its file gives (lens, sensor, scene unit, ...).
    pub options: SceneOptions,
    /// Its view, where the camera starts.
    pub view: SceneView,
}

/// One viewer: the scene, what the page may load, and the state.
pub struct Session {
    /// The compiled scene.
    pub scene: CompiledScene,
    /// Its name, for the page's title.
    pub scene_name: String,
    /// What views are built from.
    config: Config,
    /// Serialises changes, so two at once do not merge into the same old settings.
    change_lock: Mutex<()>,
    state: Mutex<State>,
    /// Wakes the render thread.
    pub wake: Condvar,
    /// Stops the render in progress (set by a change or by the last page leaving).
    pub cancel: AtomicBool,
    /// Messages to every connected page.
    pub events: broadcast::Sender<Event>,
}

/// What settings are checked against and views built from.
struct Config {
    /// The page's first eye, target and up: while they are unchanged, the
    /// camera is the scene's own pose (which eye, target and up derived from
    /// it would round).
    initial_look: [[f32; 3]; 3],
    base: SceneBase,
    options: SceneOptions,
    view: SceneView,
    resolution: (u32, u32),
    threads: Option<usize>,
    /// Folders and files lens paths may name: the scene's folder and the `--lens` files.
    allowed_lens_paths: Vec<PathBuf>,
    /// Lens tables dropped on the page, by their file name.
    dropped_lenses: Mutex<BTreeMap<String, LensPrescription>>,
}

/// Largest dropped lens table, bytes.
pub const MAX_LENS_TABLE_BYTES: usize = 64 * 1024;

/// Samples per pixel the preview refines to unless the page stops it
/// sooner: the viewer's own (a scene file's `spp` is for its final render),
/// enough for a picture that no longer visibly changes.
const DEFAULT_MAX_SPP: u32 = 1024;

impl Session {
    /// A viewer of `scene` as `source` describes it, `resolution` pixels,
    /// offering the lens tables `lens_files` besides the built-ins.
    pub fn new(
        scene: CompiledScene,
        source: SceneSource,
        resolution: (u32, u32),
        threads: Option<usize>,
        lens_files: &[PathBuf],
    ) -> Result<Session> {
        let SceneSource {
            name: scene_name,
            base,
            options,
            view,
        } = source;
        let mut allowed_lens_paths = Vec::new();
        if let SceneBase::File(path) = &base {
            if let Some(dir) = path.parent() {
                allowed_lens_paths.push(dir.to_path_buf());
            }
        }
        for file in lens_files {
            LensPrescription::load(&file.display().to_string())?;
            allowed_lens_paths.push(file.canonicalize().map_err(|e| lenspath::fs::io_error(file, e))?);
        }
        let (width, height) = resolution;
        let settings = initial_settings(&options, &view, (width, height))?;
        let config = Config {
            initial_look: [settings.eye, settings.target, settings.up],
            base,
            options,
            view,
            resolution,
            threads,
            allowed_lens_paths,
            dropped_lenses: Mutex::new(BTreeMap::new()),
        };
        let first = config.build_view(settings, None)?;
        let (events, _) = broadcast::channel(256);
        Ok(Session {
            scene,
            scene_name,
            config,
            change_lock: Mutex::new(()),
            state: Mutex::new(State {
                view: Arc::new(first),
                generation: 0,
                changed_at: Instant::now(),
                clients: 0,
                changing: false,
                autofocus: None,
                last_frame: None,
            }),
            wake: Condvar::new(),
            cancel: AtomicBool::new(false),
            events,
        })
    }

    /// Image width and height in pixels.
    pub fn resolution(&self) -> (u32, u32) {
        self.config.resolution
    }

    /// Render threads (`None`: every core).
    pub fn threads(&self) -> Option<usize> {
        self.config.threads
    }

    /// The state, locked (a panicked holder's state is still consistent: every change is one assignment).
    pub fn lock(&self) -> MutexGuard<'_, State> {
        self.state.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Merges `change` (a JSON object of [`ViewSettings`] fields) into the
    /// settings; when they check out, they apply and the render restarts.
    pub fn change(&self, change: &Value) -> Result<Arc<View>> {
        let asked_at = Instant::now();
        let _one_at_a_time = self.change_lock.lock().unwrap_or_else(|e| e.into_inner());
        let current = {
            let mut state = self.lock();
            // The render pauses while the camera is built: both cores go to that.
            state.changing = true;
            self.cancel.store(true, Ordering::SeqCst);
            state.view.clone()
        };
        let built = merged(&current.settings, change)
            .and_then(|settings| self.config.build_view(settings, Some(&current)).map(Arc::new));
        let mut state = self.lock();
        state.changing = false;
        if let Ok(view) = &built {
            state.view = view.clone();
            state.generation += 1;
            state.changed_at = asked_at;
            state.last_frame = None;
        }
        drop(state);
        self.wake.notify_all();
        built
    }

    /// Queues an autofocus on a patch (checked now; run by the render thread).
    pub fn request_autofocus(&self, request: AutofocusRequest) -> Result<()> {
        let [x, y, w, h] = request.patch;
        NormalizedRect::new(x, y, w, h)?;
        let mut state = self.lock();
        if state.autofocus.is_some() {
            return Err(Error::InvalidArgument("an autofocus is already waiting to run".into()));
        }
        state.autofocus = Some(request);
        self.cancel.store(true, Ordering::SeqCst);
        drop(state);
        self.wake.notify_all();
        Ok(())
    }

    /// Tells every page; nobody listening is fine.
    pub fn send(&self, message: Value) {
        let _ = self.events.send(Event::Message(Arc::new(message.to_string())));
    }

    /// Adds a lens table dropped on the page, under its file name.
    pub fn add_dropped_lens(&self, name: &str, text: &str) -> Result<()> {
        self.config.add_dropped_lens(name, text)
    }

    /// The scene file that reproduces `frame` with `lenspath render FILE`
    /// (a dropped lens table, named by its file name, must be put beside it).
    pub fn settings_file(&self, frame: &Frame) -> Result<String> {
        let view = &frame.view;
        let s = &view.settings;
        // The scene's own eye, target and up while the camera has not moved: they give its pose exactly.
        let (eye, look_at, up) = if view.pose == self.config.view.pose {
            view.pose.look_at_arguments()
        } else {
            (
                Vec3::from_array(s.eye),
                Vec3::from_array(s.target),
                Vec3::from_array(s.up),
            )
        };
        let file = SceneSettingsFile {
            base: self.config.base.clone(),
            scene_unit_m: self.config.scene_unit_m(),
            eye,
            look_at,
            up,
            lens: view.lens_reference.clone(),
            f_number: s.f_number,
            sensor_width_mm: view.lens_settings.sensor_mm.0,
            sensor_depth_mm: view.sensor_depth_mm,
            aperture: view.lens_settings.aperture.clone(),
            dispersion: view.lens_settings.dispersion,
            diffraction: view.lens_settings.diffraction,
            resolution: self.config.resolution,
            spp: frame.image.spp_min,
            max_depth: s.max_depth,
            light_samples: s.light_samples,
            seed: s.seed,
            sampler: view.render.sampler,
            integrator: view.render.integrator.kind(),
            sensor: s.sensor.as_ref().map(SensorTable::description).transpose()?,
        }
        .to_toml()?;
        // A scene reads only from its own folder unless allowed (io::ReadScope).
        let file = match &self.config.base {
            SceneBase::File(base) => format!(
                "# Saved from lenspath view. Unless this file is saved in the folder of {}, render it with\n\
                 #   lenspath render THIS.toml --allow-read {}\n{file}",
                base.display(),
                base.parent().map_or(String::from("."), |p| p.display().to_string())
            ),
            SceneBase::Builtin { .. } => file,
        };
        Ok(if view.lens_dropped {
            format!(
                "# The lens table '{}' was dropped on lenspath view's page: save it beside this file.\n{file}",
                view.lens_reference
            )
        } else {
            file
        })
    }

    /// What the page shows of the state: the settings, the camera's figures, the choices.
    pub fn describe(&self) -> Value {
        let state = self.lock();
        let v = &state.view;
        json!({
            "type": "state",
            "scene": self.scene_name,
            "resolution": [self.config.resolution.0, self.config.resolution.1],
            "generation": state.generation,
            "settings": v.settings,
            "lenses": self.config.lens_names(),
            "metrics": lenspath::autofocus::FocusMeasure::names(),
            "strategies": lenspath::autofocus::Strategy::names(),
            "metric_default": lenspath::autofocus::FocusMeasure::default().name(),
            "strategy_default": lenspath::autofocus::Strategy::default().name(),
            "integrators": IntegratorKind::names(),
            "max_spp_limit": MAX_SAMPLES_PER_PIXEL,
            "sensor_depth_mm": v.sensor_depth_mm,
            "focus_distance_m": v.focus_distance_m,
            "focus_range_mm": [v.focus_range_mm.0, v.focus_range_mm.1],
            "focal_length_mm": v.focal_length_mm,
            "wide_open_f_number": v.wide_open_f_number,
            "longitudinal_color_mm": v.longitudinal_color_mm,
            "lens_disperses": v.lens_settings.lens.is_dispersive(),
            "sensor_mm": [v.lens_settings.sensor_mm.0, v.lens_settings.sensor_mm.1],
            "sensor_models": lenspath::sensor::response::names().collect::<Vec<_>>(),
            "sensor_defaults": lenspath::sensor::SensorDescription::default()
                .resolve()
                .map(|d| SensorTable::of(&d.description()))
                .ok(),
        })
    }
}

impl Config {
    fn add_dropped_lens(&self, name: &str, text: &str) -> Result<()> {
        // It is written into saved scene files (`lens = "NAME"`) and saved beside them.
        let plain = |c: char| c.is_alphanumeric() || " ._-+()".contains(c);
        if name.is_empty() || name.len() > 128 || name.starts_with('.') || !name.chars().all(plain) {
            return Err(Error::InvalidArgument(format!(
                "a dropped lens needs a plain file name of at most 128 characters (letters, digits, \
                 spaces and . _ - + ( ), not starting with a dot), got {name:?}"
            )));
        }
        if lenspath::lens::library::is_shipped(name) || name.starts_with(lenspath::lens::lentil::PREFIX) {
            return Err(Error::InvalidArgument(format!(
                "a dropped lens may not be named like the built-in lens '{name}'; rename the file"
            )));
        }
        if text.len() > MAX_LENS_TABLE_BYTES {
            return Err(Error::InvalidArgument(format!(
                "lens table '{name}' is {} bytes; at most {MAX_LENS_TABLE_BYTES} are accepted",
                text.len()
            )));
        }
        let lens = LensPrescription::parse(text, name, TableConvention::Auto)?;
        // Checks it is a lens that images, before it is offered.
        LensAnalysis::new(&lenspath::lens::LensSystem::new(&lens), &AnalysisSettings::default())?;
        self.dropped_lenses
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .insert(name.to_string(), lens);
        Ok(())
    }

    /// The lens names the page offers: built-ins, the `--lens` files, the dropped tables.
    fn lens_names(&self) -> Vec<String> {
        let mut names: Vec<String> = lenspath::lens::library::shipped()
            .iter()
            .map(|l| l.name.clone())
            .collect();
        names.extend(
            self.allowed_lens_paths
                .iter()
                .filter(|p| p.is_file())
                .map(|p| p.display().to_string()),
        );
        names.extend(
            self.dropped_lenses
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .keys()
                .cloned(),
        );
        names
    }

    /// The lens `name` names and what a saved file calls it: a built-in, a
    /// dropped table, or a table file inside the scene's folder or given with `--lens`.
    fn resolve_lens(&self, name: &str) -> Result<(LensPrescription, String, bool)> {
        if lenspath::lens::library::is_shipped(name) {
            return Ok((LensPrescription::load(name)?, name.to_string(), false));
        }
        if let Some(lens) = self.dropped_lenses.lock().unwrap_or_else(|e| e.into_inner()).get(name) {
            return Ok((lens.clone(), name.to_string(), true));
        }
        let path = Path::new(name);
        let canonical = path.canonicalize().map_err(|_| {
            Error::InvalidArgument(format!(
                "unknown lens '{name}': not a built-in lens, a dropped table or an existing file"
            ))
        })?;
        if !self
            .allowed_lens_paths
            .iter()
            .any(|allowed| canonical.starts_with(allowed))
        {
            return Err(Error::InvalidArgument(format!(
                "lens '{name}' is outside the scene's folder; name it with `lenspath view --lens FILE` to allow it"
            )));
        }
        let reference = canonical.display().to_string();
        Ok((LensPrescription::load(&reference)?, reference, false))
    }

    /// Checks `settings` and builds their camera, or moves `previous`'s when
    /// only the view or the render settings change.
    fn build_view(&self, settings: ViewSettings, previous: Option<&View>) -> Result<View> {
        let (width, height) = self.resolution;
        let bad = |m: String| Err(Error::InvalidArgument(m));
        let (eye, target, up) = (
            Vec3::from_array(settings.eye),
            Vec3::from_array(settings.target),
            Vec3::from_array(settings.up),
        );
        let moved_pose = CameraPose::try_look_at(eye, target, up).map_err(Error::InvalidArgument)?;
        if !(1..=MAX_SAMPLES_PER_PIXEL).contains(&settings.max_spp) {
            return bad(format!(
                "max_spp must be from 1 to {MAX_SAMPLES_PER_PIXEL}, got {}",
                settings.max_spp
            ));
        }
        let sampler = SamplerKind::parse(&settings.sampler)?;
        let integrator = IntegratorKind::parse(&settings.integrator)?;
        let aperture = ApertureShape::parse(&settings.aperture)?;
        if let Some(n) = settings.f_number {
            if !(n > 0.0 && n.is_finite()) {
                return bad(format!("f_number must be a positive number, got {n}"));
            }
        }
        let focus = match settings.focus {
            Focus::Sensor { depth_mm } if depth_mm > 0.0 && depth_mm.is_finite() => LensFocus::SensorDepthMm(depth_mm),
            Focus::Distance { distance_m } if distance_m > 0.0 && distance_m.is_finite() => {
                LensFocus::Distance(distance_m / self.scene_unit_m())
            }
            other => {
                return bad(format!(
                    "focus must be a positive sensor depth or distance, got {other:?}"
                ))
            }
        };
        let (lens, lens_reference, lens_dropped) = self.resolve_lens(&settings.lens)?;
        let pose = if [settings.eye, settings.target, settings.up] == self.initial_look {
            self.view.pose
        } else {
            moved_pose
        };
        let sensor = settings
            .sensor
            .as_ref()
            .map(|table| table.description().and_then(|d| d.resolve()))
            .transpose()
            .map_err(|e| Error::InvalidArgument(format!("sensor: {e}")))?;
        let mut render = resolve_settings(
            &self.options,
            &RenderOverrides {
                resolution: Some(self.resolution),
                spp: Some(1),
                max_depth: Some(settings.max_depth),
                light_samples: Some(settings.light_samples),
                seed: Some(settings.seed),
                sampler: Some(sampler),
                integrator: Some(integrator),
                threads: self.threads,
                // Left to the EXR download (`render::render_depth`): the first preview comes sooner.
                depth: Some(false),
                ..RenderOverrides::default()
            },
        )?;
        if let Some(sensor) = &sensor {
            render.film = render.film.read_by(sensor.response)?;
        }
        // The same optics (a move, or render settings): the camera moves, nothing is built again.
        if let Some(p) = previous.filter(|p| {
            let (a, b) = (&p.settings, &settings);
            (&a.lens, a.f_number, a.focus, &a.aperture, a.dispersion, a.diffraction)
                == (&b.lens, b.f_number, b.focus, &b.aperture, b.dispersion, b.diffraction)
                && p.lens_settings.lens == lens
        }) {
            return Ok(View {
                camera: p.camera.with_pose(pose),
                settings,
                render,
                pose,
                sensor,
                ..p.clone()
            });
        }
        let description = RealisticDescription {
            lens: Some(lens),
            f_number: settings.f_number,
            aperture: Some(aperture),
            focus: Some(focus),
            dispersion: Some(settings.dispersion),
            diffraction: Some(settings.diffraction),
            ..RealisticDescription::default()
        };
        let mut lens_settings = realistic_settings(&self.options, &self.view, &description, width, height)?;
        // The page's f-number is always set: `None` there is wide open, not the file's.
        lens_settings.f_number = settings.f_number;
        let camera = RealisticCamera::new(pose, width, height, &lens_settings)?;
        // The focus is kept as the sensor's place: what a saved file and autofocus speak in.
        let sensor_depth_mm = camera.sensor_depth_mm();
        lens_settings.focus = LensFocus::SensorDepthMm(sensor_depth_mm);
        let system = camera.system();
        let report = LensReport::new(
            system,
            &LensReportSettings {
                analysis: AnalysisSettings {
                    sensor_mm: lens_settings.sensor_mm,
                    ..Default::default()
                },
                sensor_depth_mm: Some(sensor_depth_mm),
                ..Default::default()
            },
        )?;
        let analysis = &report.analysis;
        let diagonal_mm = lens_settings.sensor_mm.0.hypot(lens_settings.sensor_mm.1);
        let layout = lenspath::lens::plot::layout_focused(system, analysis, diagonal_mm, sensor_depth_mm);
        let wide_open = lenspath::lens::LensSystem::new(&lens_settings.lens).paraxial()?;
        Ok(View {
            focus_distance_m: report.focus.focus_distance_for_sensor_depth_m.flatten(),
            focus_range_mm: (analysis.infinity_focus_mm, analysis.close_focus_mm),
            focal_length_mm: analysis.effective_focal_length_mm,
            wide_open_f_number: wide_open.f_number,
            longitudinal_color_mm: report.longitudinal_color_mm,
            layout_svg: lenspath::lens::plot::layout_to_svg(&layout),
            half_diagonal_field_deg: 0.5 * analysis.diagonal_fov_deg,
            settings,
            lens_settings,
            lens_reference,
            lens_dropped,
            camera,
            render,
            pose,
            sensor_depth_mm,
            sensor,
        })
    }

    fn scene_unit_m(&self) -> f64 {
        self.options.scene_unit_m.unwrap_or(lenspath::defaults::SCENE_UNIT_M)
    }
}

/// The settings a session starts with: the scene's view and the file's lens settings.
fn initial_settings(options: &SceneOptions, view: &SceneView, resolution: (u32, u32)) -> Result<ViewSettings> {
    let setup = resolve(
        options,
        view,
        &RenderOverrides {
            resolution: Some(resolution),
            ..RenderOverrides::default()
        },
    )?;
    let CameraSettings::Realistic(camera) = &setup.camera else {
        unreachable!("the default camera is the realistic one");
    };
    let m = view.pose.render_from_camera;
    let eye = Vec3::from(m.translation);
    let target = eye + Vec3::from(m.z_axis) * view.focus_distance;
    let focus = match camera.focus {
        LensFocus::SensorDepthMm(depth_mm) => Focus::Sensor { depth_mm },
        LensFocus::Distance(d) => Focus::Distance {
            distance_m: d * camera.scene_unit_m,
        },
    };
    let s = &setup.settings;
    Ok(ViewSettings {
        lens: options
            .lens
            .as_ref()
            .and_then(|l| l.lens.clone())
            .unwrap_or_else(|| lenspath::defaults::LENS.to_string()),
        f_number: camera.f_number,
        focus,
        aperture: camera.aperture.spelling().unwrap_or_else(|| "circle".into()),
        dispersion: camera.dispersion,
        diffraction: camera.diffraction,
        eye: eye.to_array(),
        target: target.to_array(),
        up: Vec3::from(m.y_axis).to_array(),
        max_spp: DEFAULT_MAX_SPP,
        max_depth: s.integrator.max_depth(),
        light_samples: s.integrator.light_samples(),
        seed: s.seed,
        sampler: s.sampler.name().into(),
        integrator: s.integrator.kind().name().into(),
        sensor: options.sensor.as_ref().map(SensorTable::of),
    })
}

fn merged(current: &ViewSettings, change: &Value) -> Result<ViewSettings> {
    let Value::Object(fields) = change else {
        return Err(Error::InvalidArgument(
            "a change must be a JSON object of settings".into(),
        ));
    };
    let mut value = serde_json::to_value(current).map_err(|e| Error::InvalidArgument(e.to_string()))?;
    if let Value::Object(target) = &mut value {
        for (k, v) in fields {
            if !target.contains_key(k) {
                return Err(Error::InvalidArgument(format!(
                    "unknown setting '{k}'; the settings are {}",
                    target.keys().cloned().collect::<Vec<_>>().join(", ")
                )));
            }
            target.insert(k.clone(), v.clone());
        }
    }
    serde_json::from_value(value).map_err(|e| Error::InvalidArgument(format!("bad setting: {e}")))
}
