//! Focusing a realistic camera on an image patch: rendering the patch at a
//! sensor position and scoring it ([`Focuser::measure_at`]) and the contrast
//! search strategies ([`Strategy`]). The range finder is in `range`, the
//! ground truth the strategies are checked against in `truth`, band-pass and
//! peak fitting in `signal`. docs/autofocus.md explains the designs.
//!
//! Sensor positions are in mm behind the aperture stop (lens coordinates);
//! the sweep runs from the infinity focus to the close focus of
//! [`LensAnalysis`]. One depth of focus (DoF) is the sensor shift that grows
//! the blur circle of a point to one pixel: pitch × (z − z_exit pupil) / D_exit pupil.

use std::sync::atomic::AtomicBool;
use std::time::Instant;

use super::frames::{frame_key, FocusSensor, HeldExposure};
use super::light_field::{FilmRegion, LightField, Recording, Splat};
use super::measures::{FocusMeasure, Patch};
use super::signal::{interior_peak_index, log_parabola_peak, stream_seed, Detail};
use crate::camera::{ApertureShape, Camera, CameraPose, LensFocus, RealisticCamera, RealisticCameraSettings};
use crate::color::luminance;
use crate::error::{Error, Result};
use crate::film::Filter;
use crate::film::PixelRect;
use crate::integrator::Integrator;
use crate::lens::{AnalysisSettings, LensAnalysis, LensSystem};
use crate::names::Named;
use crate::render::{render, FilmResponse, RenderSettings};
use crate::sampling::SamplerKind;
use crate::scene::CompiledScene;

/// The spatial frequency, cycles per pixel, at which the lens's best focus is
/// found for the range finder: where the band-passed Tenengrad responds most
/// (the peak of ν²·(G₁(ν) − G₄(ν))² is at 0.16).
pub const BEST_FOCUS_CYCLES_PER_PIXEL: f64 = 0.15;

/// The `fast` search's budget, as a fraction of the sweep's camera rays: its
/// light field takes fewer samples when the coarse scan has spent much (low
/// resolutions, where the sweep has few steps).
pub const FAST_BUDGET_OF_SWEEP: f64 = 0.1;

/// The `depth` search's budget, as a fraction of the sweep's camera rays.
pub const DEPTH_BUDGET_OF_SWEEP: f64 = 0.02;

/// How far, in DoF either way, a light field is refocused from where it was
/// recorded: the range finder's error on the patches without glass is at
/// most 1.4 DoF, and the peak's fit needs 2 DoF beyond it. The margin the
/// patch is recorded with grows with it (1.3 to 1.6× the patch's pixels at
/// 3.5 DoF, mostly the image's breathing).
pub const LIGHT_FIELD_REACH_DOF: f64 = 3.5;

/// The most samples a light field keeps (28 bytes each: about 230 MB); a
/// large patch's light field takes fewer samples per pixel than the budget
/// allows (its many pixels average the noise out).
pub const LIGHT_FIELD_MAX_SAMPLES: u64 = 1 << 23;

/// The independent groups a light field's samples are drawn in (each with
/// its own seed), scored as a U-statistic over their pairs
/// ([`FocusMeasure::evaluate_groups`]): at the `depth` search's budget, 8
/// groups instead of 2 put 93 of 100 searches within 1 DoF instead of 92
/// (seeds 0 to 3 of docs/autofocus.md's evaluation; 95 with seeds 4 to 7).
pub const LIGHT_FIELD_GROUPS: u32 = 8;

/// The farthest, in DoF either way, a light field is refocused to reach all
/// the depths the range finder's probes saw (the margin grows with it).
pub const LIGHT_FIELD_MAX_REACH_DOF: f64 = 8.0;

/// Real-ray height for converting between sensor positions and distances (as the camera focuses).
const FOCUS_RAY_HEIGHT_MM: f64 = 0.1;

/// Samples per pixel of each patch render when the caller gives none.
pub const DEFAULT_PATCH_SPP: u32 = 16;
/// Maximum path depth of the patch renders when the caller gives none (a
/// full render's depth is capped at this for `render --autofocus`).
pub const DEFAULT_PATCH_MAX_DEPTH: u32 = 8;
/// Seed of the patch renders when the caller gives none.
pub const DEFAULT_SEED: u32 = 0;
/// The early-exit strategy's patience when the caller gives none: steps
/// without a new best before it stops.
pub const DEFAULT_PATIENCE: usize = 12;

/// A search strategy.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Strategy {
    /// Every pixel-pitch step from infinity focus to close focus; the reference.
    Sweep,
    /// The sweep, stopped after `patience` steps without a new best (the course project's speed-up).
    EarlyExit {
        /// Steps without improvement before stopping.
        patience: usize,
    },
    /// Hybrid search: a start from the range finder (or, with nothing to range
    /// on, a coarse contrast scan of the whole range), then the contrast peak
    /// around it, refocused from one light field with the rest of 10% of the
    /// sweep's camera rays. The default.
    #[default]
    Fast,
    /// Range finder: probe rays find the patch's dominant surface, the lens's
    /// through-focus modulation gives its best-contrast sensor position. No
    /// patch renders.
    Rangefinder,
    /// Range finder, then a short contrast refinement: the contrast peak
    /// around it, refocused from one light field with the rest of 2% of the
    /// sweep's camera rays.
    Depth,
}

impl Named for Strategy {
    const WHAT: &'static str = "autofocus strategy";
    const NAMED: &'static [(Strategy, &'static str)] = &[
        (Strategy::Sweep, "sweep"),
        (
            Strategy::EarlyExit {
                patience: DEFAULT_PATIENCE,
            },
            "early-exit",
        ),
        (Strategy::Fast, "fast"),
        (Strategy::Rangefinder, "rangefinder"),
        (Strategy::Depth, "depth"),
    ];
}

impl Strategy {
    /// The same strategy, early-exit's with patience `patience` (the others have none).
    pub fn with_patience(self, patience: usize) -> Strategy {
        match self {
            Strategy::EarlyExit { .. } => Strategy::EarlyExit { patience },
            s => s,
        }
    }
}

/// What autofocus looks at and how.
#[derive(Clone, Debug)]
pub struct AutofocusSettings {
    /// The camera; its `focus` is what autofocus sets, and is ignored.
    pub camera: RealisticCameraSettings,
    /// Full image width in pixels.
    pub width: u32,
    /// Full image height in pixels.
    pub height: u32,
    /// The patch to focus on, in pixels of the full image.
    pub patch: PixelRect,
    /// The focus measure.
    pub measure: FocusMeasure,
    /// Samples per pixel of a patch render.
    pub spp: u32,
    /// The integrator of the patch renders.
    pub integrator: Integrator,
    /// Seed of the patch renders (every render uses it: common random numbers
    /// make the focus curve smooth in the sensor position).
    pub seed: u32,
    /// Worker threads (`None`: all cores).
    pub threads: Option<usize>,
    /// The sensor the patch images are captured through and what the
    /// measure reads of them ([`FocusSensor`]); `None`: the film's noiseless
    /// radiance.
    pub sensor: Option<FocusSensor>,
}

/// One scored patch image: a patch render, or the patch refocused from a light field.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Evaluation {
    /// Sensor position, mm behind the stop.
    pub sensor_depth_mm: f64,
    /// Focus measure of the patch.
    pub score: f64,
    /// Samples per pixel it was rendered (or its light field recorded) with.
    pub spp: u32,
    /// The scale it was scored at.
    pub detail: Detail,
    /// Whether it is the patch refocused from a light field (no render of its own).
    pub refocused: bool,
}

/// What a strategy found and what it cost.
#[derive(Clone, Debug, serde::Serialize)]
pub struct AutofocusResult {
    /// The strategy's name.
    pub strategy: &'static str,
    /// The chosen sensor position, mm behind the stop.
    pub sensor_depth_mm: f64,
    /// The distance in focus there, from the sensor plane, in scene units
    /// (`None` when the sensor is nearer than the infinity focus).
    pub focus_distance: Option<f64>,
    /// Every scored patch image, in order: patch renders and refocused light fields.
    pub evaluations: Vec<Evaluation>,
    /// Light fields recorded ([`LightField`]: the patch with a margin, every
    /// sample kept, refocused to many sensor positions).
    pub light_fields: usize,
    /// Camera rays generated: patch render and light-field samples and range-finder probes.
    pub camera_rays: u64,
    /// Wall time.
    pub seconds: f64,
    /// The exposure time the search held, s (`None`: no sensor, or no frame taken).
    pub exposure_time_s: Option<f64>,
    /// The ISO speed the search held.
    pub iso: Option<f64>,
    /// What the strategy could not do as its name says, and what it did
    /// instead (empty when it did all of it): no surface in the patch to
    /// range on, or too little budget left for the contrast refinement.
    pub fallbacks: Vec<String>,
}

impl AutofocusResult {
    /// How many of its evaluations are patch renders (the others are refocused light fields).
    pub fn patch_renders(&self) -> usize {
        self.evaluations.iter().filter(|e| !e.refocused).count()
    }
}

/// What [`Focuser::on_evaluation`] calls.
type EvaluationObserver<'a> = Box<dyn FnMut(&Evaluation) + Send + 'a>;

/// Focuses one camera on one patch of one scene.
pub struct Focuser<'a> {
    pub(super) scene: &'a CompiledScene,
    pub(super) pose: CameraPose,
    pub(super) settings: AutofocusSettings,
    pub(super) system: LensSystem,
    pub(super) range_mm: (f64, f64),
    pub(super) pitch_mm: f64,
    pub(super) exit_pupil: (f64, f64),
    pub(super) mm_per_scene: f64,
    pub(super) evaluations: Vec<Evaluation>,
    /// Told of each evaluation as it is made (`lenspath view` draws the curve).
    pub(super) observer: Option<EvaluationObserver<'a>>,
    pub(super) light_fields: usize,
    pub(super) camera_rays: u64,
    /// The sensor exposure of the running search, from its first frame.
    pub(super) held_exposure: HeldExposure,
    /// What the running search could not do ([`AutofocusResult::fallbacks`]).
    pub(super) fallbacks: Vec<String>,
}

impl<'a> Focuser<'a> {
    /// Checks the settings and finds the sweep range and the pixel pitch.
    pub fn new(scene: &'a CompiledScene, pose: CameraPose, settings: AutofocusSettings) -> Result<Self> {
        let p = settings.patch;
        if p.width < 3 || p.height < 3 || p.x0 + p.width > settings.width || p.y0 + p.height > settings.height {
            return Err(Error::InvalidArgument(format!(
                "the patch {}x{} at ({}, {}) must be at least 3x3 pixels and inside the {}x{} image",
                p.width, p.height, p.x0, p.y0, settings.width, settings.height
            )));
        }
        if settings.spp == 0 {
            return Err(Error::InvalidArgument(
                "autofocus needs at least 1 sample per pixel".into(),
            ));
        }
        let wide_open = LensSystem::new(&settings.camera.lens);
        let system = match settings.camera.f_number {
            Some(n) => wide_open.with_f_number(n)?,
            None => wide_open,
        };
        let (sw, sh) = settings.camera.sensor_mm;
        let analysis = LensAnalysis::new(
            &system,
            &AnalysisSettings {
                sensor_mm: (sw, sh),
                ..Default::default()
            },
        )?;
        let paraxial = system.paraxial()?;
        let pitch_mm = sw.hypot(sh) / f64::from(settings.width).hypot(f64::from(settings.height));
        Ok(Focuser {
            scene,
            pose,
            range_mm: (analysis.infinity_focus_mm, analysis.close_focus_mm),
            pitch_mm,
            exit_pupil: (paraxial.exit_pupil_z_mm, paraxial.exit_pupil_diameter_mm),
            mm_per_scene: settings.camera.scene_unit_m * 1e3,
            system,
            settings,
            evaluations: Vec::new(),
            observer: None,
            light_fields: 0,
            camera_rays: 0,
            held_exposure: HeldExposure::default(),
            fallbacks: Vec::new(),
        })
    }

    /// Calls `observer` with every evaluation as it is made, so a front end
    /// can show the search while it runs.
    pub fn on_evaluation(&mut self, observer: impl FnMut(&Evaluation) + Send + 'a) {
        self.observer = Some(Box::new(observer));
    }

    pub(super) fn record(&mut self, evaluation: Evaluation) {
        if let Some(observer) = &mut self.observer {
            observer(&evaluation);
        }
        self.evaluations.push(evaluation);
    }

    /// The search's settings.
    pub fn settings(&self) -> &AutofocusSettings {
        &self.settings
    }

    /// Infinity-focus and close-focus sensor positions, mm behind the stop.
    pub fn sweep_range_mm(&self) -> (f64, f64) {
        self.range_mm
    }

    /// Sensor diagonal over image diagonal in pixels, mm: the sweep's step.
    pub fn pixel_pitch_mm(&self) -> f64 {
        self.pitch_mm
    }

    /// The depth of focus at sensor position `z`: the shift that blurs a point to one pixel.
    pub fn depth_of_focus_mm(&self, z: f64) -> f64 {
        let (pupil_z, pupil_diameter) = self.exit_pupil;
        self.pitch_mm * (z - pupil_z).abs() / pupil_diameter
    }

    /// The distance in focus at sensor position `z`, scene units from the sensor.
    pub fn focus_distance_at(&self, z: f64) -> Option<f64> {
        self.system
            .focus_distance_mm(z, FOCUS_RAY_HEIGHT_MM)
            .map(|mm| mm / self.mm_per_scene)
    }

    /// The sensor position that focuses `distance` (scene units from the sensor).
    pub fn sensor_depth_mm_for_distance(&self, distance: f64) -> Result<f64> {
        self.system
            .sensor_depth_mm_for_focus_distance(distance * self.mm_per_scene, FOCUS_RAY_HEIGHT_MM)
    }

    pub(super) fn camera_settings(&self, z: f64) -> RealisticCameraSettings {
        RealisticCameraSettings {
            focus: LensFocus::SensorDepthMm(z),
            ..self.settings.camera.clone()
        }
    }

    /// Renders the patch with the sensor at `z` and returns its score; counted
    /// in the evaluations and camera rays of the running strategy. The `spp`
    /// samples are split between two renders with independent seeds, scored as
    /// a pair ([`FocusMeasure::evaluate_pair`]) so render noise does not pass
    /// for sharpness; with 1 sample, one render. Each render is band-passed
    /// first, at the scale of `detail`.
    pub fn measure_at(&mut self, z: f64, spp: u32, seed: u32, detail: Detail) -> Result<f64> {
        let camera = self.patch_camera(z, self.settings.camera.aperture.clone())?;
        let halves = if spp >= 2 { [spp / 2, spp - spp / 2] } else { [spp, 0] };
        let frames = halves.iter().filter(|&&h| h > 0).count() as u32;
        let mut images = Vec::new();
        for (k, &half) in halves.iter().enumerate().filter(|(_, &h)| h > 0) {
            let key = frame_key(z, seed, k);
            images.push(self.render_patch(&camera, half, stream_seed(seed, k), detail, (frames, key))?);
        }
        let score = self.score(&images)?;
        self.record(Evaluation {
            sensor_depth_mm: z,
            score,
            spp,
            detail,
            refocused: false,
        });
        Ok(score)
    }

    /// The focus measure of one band-passed patch image, or of several with
    /// independent noise ([`FocusMeasure::evaluate_groups`]).
    pub(super) fn score(&self, images: &[Vec<f32>]) -> Result<f64> {
        let s = &self.settings;
        let (w, h) = (s.patch.width as usize, s.patch.height as usize);
        let patches = images
            .iter()
            .map(|rgb| Patch::new(w, h, rgb))
            .collect::<Result<Vec<_>>>()?;
        Ok(s.measure.evaluate_groups(&patches))
    }

    /// The patch's light field recorded with the sensor at `z0` over `region`
    /// ([`Focuser::light_field_region`]), in [`LIGHT_FIELD_GROUPS`] groups (as
    /// many as there are samples per pixel, when fewer) with
    /// independent seeds (scored as a U-statistic, as [`Focuser::measure_at`]
    /// scores its pair) of together `spp` samples per pixel.
    pub(super) fn record_light_fields(&mut self, z0: f64, region: FilmRegion, spp: u32) -> Result<Vec<LightField>> {
        let s = &self.settings;
        let camera = LightField::recording_camera(self.pose, s.width, s.height, &self.camera_settings(z0), region)?;
        let groups = LIGHT_FIELD_GROUPS.min(spp);
        let fields = (0..groups)
            .map(|k| {
                let recording = Recording {
                    spp: (spp + k) / groups,
                    seed: stream_seed(s.seed, k as usize),
                    integrator: s.integrator,
                    threads: s.threads,
                    film: self.film_response(),
                };
                LightField::record(self.scene, camera.clone(), region, &recording)
            })
            .collect::<Result<Vec<_>>>()?;
        self.camera_rays += fields.iter().map(LightField::samples).sum::<u64>();
        self.light_fields += 1;
        Ok(fields)
    }

    /// The film region a light field recorded at `z0` needs for refocusing
    /// the patch anywhere in `sensor_depth_mm` (near, far).
    pub(super) fn light_field_region(&self, z0: f64, sensor_depth_mm: (f64, f64)) -> Result<FilmRegion> {
        let camera = self.patch_camera(z0, self.settings.camera.aperture.clone())?;
        Ok(LightField::region_for(&camera, self.settings.patch, sensor_depth_mm))
    }

    /// The score of the patch refocused from `fields` to `z` (bilinear
    /// splats, so the score is smooth in `z`), at [`Detail::Fine`]; `None`
    /// out of their reach. Through a sensor, each field's image is one of
    /// the frames at `z`.
    pub(super) fn refocused_score(&mut self, fields: &[LightField], z: f64) -> Result<Option<f64>> {
        let (width, patch, seed) = (
            self.settings.patch.width as usize,
            self.settings.patch,
            self.settings.seed,
        );
        let mut images = Vec::new();
        for (k, field) in fields.iter().enumerate() {
            let Some(rgb) = field.refocus(z, patch, Splat::Bilinear) else {
                return Ok(None);
            };
            let seen = self.held_exposure.see(
                self.settings.sensor.as_ref(),
                patch,
                rgb,
                field.camera().film_radiometry(),
                (fields.len() as u32, frame_key(z, seed, k)),
            )?;
            images.push(Detail::Fine.band_pass(&seen, width));
        }
        self.score(&images).map(Some)
    }

    /// What the film records: a sensor's channels when the search looks through one.
    fn film_response(&self) -> FilmResponse {
        self.settings
            .sensor
            .as_ref()
            .map_or(FilmResponse::Srgb, |s| FilmResponse::Sensor(s.sensor.response))
    }

    /// The camera for patch renders with the sensor at `z`, its stop opening shaped as `aperture`.
    pub(super) fn patch_camera(&self, z: f64, aperture: ApertureShape) -> Result<RealisticCamera> {
        let s = &self.settings;
        let settings = RealisticCameraSettings {
            aperture,
            ..self.camera_settings(z)
        };
        RealisticCamera::for_region(self.pose, s.width, s.height, &settings, s.patch)
    }

    /// The patch rendered through `camera` at `spp` samples with `seed`, as
    /// the search sees it (`HeldExposure::see`: through a sensor, one of
    /// `frames.0` frames at this position, its key `frames.1`), band-passed
    /// at the scale of `detail`.
    pub(super) fn render_patch(
        &mut self,
        camera: &RealisticCamera,
        spp: u32,
        seed: u32,
        detail: Detail,
        (frames, key): (u32, u64),
    ) -> Result<Vec<f32>> {
        let film = self.render_film(camera, spp, seed)?;
        let seen = self.held_exposure.see(
            self.settings.sensor.as_ref(),
            self.settings.patch,
            film,
            camera.film_radiometry(),
            (frames, key),
        )?;
        Ok(detail.band_pass(&seen, self.settings.patch.width as usize))
    }

    /// The patch's film rendered through `camera` at `spp` samples with
    /// `seed` (a sensor's channels when the search looks through one); its
    /// samples are counted as camera rays of the running strategy.
    fn render_film(&mut self, camera: &RealisticCamera, spp: u32, seed: u32) -> Result<Vec<f32>> {
        let s = &self.settings;
        let render_settings = RenderSettings {
            width: s.width,
            height: s.height,
            spp,
            integrator: s.integrator,
            seed,
            sampler: SamplerKind::Sobol,
            filter: Filter::Box,
            threads: s.threads,
            tile_size: 16,
            crop: Some(s.patch),
            depth: false,
            film: self.film_response(),
        };
        let output = render(
            self.scene,
            camera,
            &render_settings,
            &|_, _| {},
            &AtomicBool::new(false),
        )?;
        self.camera_rays += output.stats.samples;
        Ok(output.image.rgb)
    }

    /// The patch's mean luminance with the sensor at `z`, relative to a
    /// white emitter of 1 (linear sRGB, noiseless, at the settings' samples
    /// and seed): what sets its luminance in cd/m² through a sensor's
    /// `white_luminance_cd_m2`. Not counted in any strategy's cost.
    pub fn patch_luminance(&mut self, z: f64) -> Result<f64> {
        let rays = self.camera_rays;
        let film = self.without_sensor(|f| {
            let camera = f.patch_camera(z, f.settings.camera.aperture.clone())?;
            f.render_film(&camera, f.settings.spp, f.settings.seed)
        });
        self.camera_rays = rays;
        let film = film?;
        let pixels = (film.len() / 3).max(1) as f64;
        Ok(film
            .chunks_exact(3)
            .map(|p| f64::from(luminance([p[0], p[1], p[2]])))
            .sum::<f64>()
            / pixels)
    }

    /// `work` done on the film's noiseless radiance: with the sensor set
    /// aside, and put back whatever `work` returns.
    pub(super) fn without_sensor<T>(&mut self, work: impl FnOnce(&mut Self) -> Result<T>) -> Result<T> {
        let sensor = self.settings.sensor.take();
        let done = work(self);
        self.settings.sensor = sensor;
        done
    }

    /// Runs `strategy` and reports what it found and what it cost.
    pub fn run(&mut self, strategy: Strategy) -> Result<AutofocusResult> {
        let started = Instant::now();
        self.evaluations.clear();
        self.light_fields = 0;
        self.camera_rays = 0;
        self.held_exposure = HeldExposure::default();
        self.fallbacks.clear();
        let z = match strategy {
            Strategy::Sweep => self.sweep(None)?,
            Strategy::EarlyExit { patience } => self.sweep(Some(patience.max(1)))?,
            Strategy::Fast => self.fast()?,
            Strategy::Rangefinder => self.rangefinder()?,
            Strategy::Depth => self.depth()?,
        };
        Ok(AutofocusResult {
            strategy: strategy.name(),
            sensor_depth_mm: z,
            focus_distance: self.focus_distance_at(z),
            evaluations: std::mem::take(&mut self.evaluations),
            light_fields: self.light_fields,
            camera_rays: self.camera_rays,
            seconds: started.elapsed().as_secs_f64(),
            exposure_time_s: self.held_exposure.held().map(|e| e.exposure_time_s),
            iso: self.held_exposure.held().map(|e| e.iso),
            fallbacks: std::mem::take(&mut self.fallbacks),
        })
    }

    /// How many sensor positions `step` apart fit from infinity to close focus.
    pub(super) fn steps(&self, step: f64) -> usize {
        let (near, far) = self.range_mm;
        ((far - near) / step).floor() as usize + 1
    }

    /// Sensor positions from infinity to close focus, `step` apart.
    pub(super) fn grid(&self, step: f64) -> Vec<f64> {
        let near = self.range_mm.0;
        (0..self.steps(step)).map(|i| near + i as f64 * step).collect()
    }

    /// The pixel-pitch sweep; with `patience`, it stops after that many steps without a new best.
    pub(super) fn sweep(&mut self, patience: Option<usize>) -> Result<f64> {
        let (spp, seed) = (self.settings.spp, self.settings.seed);
        let mut best = (f64::NEG_INFINITY, self.range_mm.0);
        let mut since_best = 0;
        for z in self.grid(self.pitch_mm) {
            let score = self.measure_at(z, spp, seed, Detail::Fine)?;
            if score > best.0 {
                best = (score, z);
                since_best = 0;
            } else {
                since_best += 1;
                if patience.is_some_and(|p| since_best >= p) {
                    break;
                }
            }
        }
        Ok(best.1)
    }

    /// Hybrid search, as a camera that ranges and then checks the contrast
    /// focuses (docs/autofocus.md): a start from the range finder
    /// ([`Focuser::range_focus`]), or, with nothing in the patch to range on,
    /// from a coarse contrast scan ([`Focuser::coarse_peak`]); then the
    /// contrast peak near it, refocused from one light field with the rest of
    /// [`FAST_BUDGET_OF_SWEEP`] ([`Focuser::refocused_peak`]).
    pub(super) fn fast(&mut self) -> Result<f64> {
        match self.range_focus()? {
            Some(range) => self.refocused_peak(range.best_focus_z_mm, range.probe_span_z_mm, FAST_BUDGET_OF_SWEEP),
            None => self.contrast_search(),
        }
    }

    /// The contrast search from nothing: the coarse scan's peak, refined from
    /// a light field. What the range-finding strategies do when no probe hits
    /// anything (only sky in the patch), saying so in the result.
    pub(super) fn contrast_search(&mut self) -> Result<f64> {
        self.fallbacks
            .push("no surface in the patch to range on (every probe ray missed): a contrast search instead".into());
        let z0 = self.coarse_peak()?;
        self.refocused_peak(z0, (z0, z0), FAST_BUDGET_OF_SWEEP)
    }

    /// The contrast peak near `z0`, refocused from one light field recorded
    /// there with what is left of `budget_of_sweep` (a fraction of the
    /// sweep's camera rays):
    /// 1. the patch refocused in quarter-DoF steps over
    ///    [`LIGHT_FIELD_REACH_DOF`] either way of `z0` and 2 DoF beyond
    ///    `span` (the sensor positions of the patch's depths: a wall the
    ///    range finder ranges on may lie behind the edge that carries the
    ///    contrast), at most [`LIGHT_FIELD_MAX_REACH_DOF`] from `z0`, scored at
    ///    [`Detail::Fine`] as a U-statistic over the light field's
    ///    [`LIGHT_FIELD_GROUPS`] groups;
    /// 2. the highest peak the curve shows (a point above both neighbours:
    ///    a maximum at an end of the refocused range is a slope whose peak
    ///    lies beyond it), or its highest point when it shows none;
    /// 3. the vertex of the least-squares log-parabola over 2 DoF either side
    ///    of it (a Gaussian fit of the peak).
    ///
    /// Every refocused image is made of the same samples, gathered by
    /// bilinear splats, so the curve is smooth in the sensor position (common
    /// random numbers without tracing again) and costs one render's rays. It
    /// is one noise draw, whose tilt (the noise projected on how the image
    /// changes with focus) shrinks with its samples per pixel, so all the
    /// budget goes into one light field.
    /// `z0` when the budget leaves less than 2 samples per pixel (two groups).
    pub(super) fn refocused_peak(&mut self, z0: f64, span: (f64, f64), budget_of_sweep: f64) -> Result<f64> {
        let s = &self.settings;
        let patch_pixels = f64::from(s.patch.width * s.patch.height);
        let budget = budget_of_sweep * (self.steps(self.pitch_mm) as u32 * s.spp) as f64 * patch_pixels;
        let dof = self.depth_of_focus_mm(z0);
        let (near, far) = self.range_mm;
        let (reach, max_reach) = (LIGHT_FIELD_REACH_DOF * dof, LIGHT_FIELD_MAX_REACH_DOF * dof);
        let lo = (z0 - reach).min(span.0 - 2.0 * dof).max(z0 - max_reach).max(near);
        let hi = (z0 + reach).max(span.1 + 2.0 * dof).min(z0 + max_reach).min(far);
        let region = self.light_field_region(z0, (lo, hi))?;
        let left = (budget - self.camera_rays as f64).max(0.0);
        let region_pixels = f64::from(region.width) * f64::from(region.height);
        let spp = (left.min(LIGHT_FIELD_MAX_SAMPLES as f64) / region_pixels).floor() as u32;
        if spp < 2 {
            self.fallbacks.push(format!(
                "the budget left {left:.0} camera rays for the contrast refinement, under 2 samples per pixel of \
                 its {}x{} light field: the start, unrefined (more samples per pixel or a larger patch allow it)",
                region.width, region.height
            ));
            return Ok(z0);
        }
        let fields = self.record_light_fields(z0, region, spp)?;
        let steps = ((z0 - lo) / (0.25 * dof)).floor() as i32;
        let mut curve = Vec::new();
        for k in -steps.. {
            let z = z0 + f64::from(k) * 0.25 * dof;
            if z > hi {
                break;
            }
            if let Some(score) = self.refocused_score(&fields, z)? {
                curve.push((z, score));
                self.record(Evaluation {
                    sensor_depth_mm: z,
                    score,
                    spp,
                    detail: Detail::Fine,
                    refocused: true,
                });
            }
        }
        Ok(match curve.get(interior_peak_index(&curve)) {
            Some(&(peak, _)) => log_parabola_peak(&curve, peak, 2.01 * dof),
            None => z0,
        })
    }

    /// The coarse stage of a contrast search from nothing:
    /// 1. a scan of the whole range in steps of about 6 DoF at half the
    ///    samples, scored at [`Detail::Coarse`], where a peak is several steps
    ///    wide and the noise weak;
    /// 2. its local maxima that reach half of the best (at most three)
    ///    re-scored at full samples, since a half-sample score can be lucky;
    /// 3. the winner's peak from the log-parabola through it and its neighbours.
    pub(super) fn coarse_peak(&mut self) -> Result<f64> {
        let (spp, seed) = (self.settings.spp, self.settings.seed);
        let (near, far) = self.range_mm;
        let step = 6.0 * self.depth_of_focus_mm(near);
        let n = (((far - near) / step).ceil() as usize + 1).clamp(8, 64);
        let coarse: Vec<(f64, f64)> = (0..n)
            .map(|i| {
                let z = near + (far - near) * i as f64 / (n - 1) as f64;
                Ok((z, self.measure_at(z, (spp / 2).max(1), seed, Detail::Coarse)?))
            })
            .collect::<Result<_>>()?;
        let best_coarse = coarse.iter().map(|c| c.1).fold(f64::NEG_INFINITY, f64::max);
        let mut peaks: Vec<usize> = (0..n)
            .filter(|&i| {
                let left = if i > 0 { coarse[i - 1].1 } else { f64::NEG_INFINITY };
                let right = coarse.get(i + 1).map_or(f64::NEG_INFINITY, |c| c.1);
                coarse[i].1 >= left && coarse[i].1 >= right && coarse[i].1 >= 0.5 * best_coarse
            })
            .collect();
        peaks.sort_by(|&a, &b| coarse[b].1.total_cmp(&coarse[a].1));
        peaks.truncate(3);
        let mut winner = (f64::NEG_INFINITY, peaks[0]);
        if peaks.len() > 1 {
            for &i in &peaks {
                let score = self.measure_at(coarse[i].0, spp, seed, Detail::Coarse)?;
                if score > winner.0 {
                    winner = (score, i);
                }
            }
        }
        let i = winner.1;
        let around = &coarse[i.saturating_sub(1)..=(i + 1).min(n - 1)];
        Ok(log_parabola_peak(
            around,
            coarse[i].0,
            1.01 * (far - near) / (n - 1) as f64,
        ))
    }

    /// `(z, score)` at each sensor position of `zs`, scored at the fine scale.
    pub(super) fn scan(&mut self, zs: &[f64], spp: u32, seed: u32) -> Result<Vec<(f64, f64)>> {
        zs.iter()
            .map(|&z| Ok((z, self.measure_at(z, spp, seed, Detail::Fine)?)))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    pub(super) fn strategy_names_round_trip() {
        for &(s, name) in Strategy::NAMED {
            assert_eq!(Strategy::parse(name).unwrap().with_patience(12), s);
            assert_eq!(s.name(), name);
            assert_eq!(
                Strategy::parse(name).unwrap().with_patience(3).name(),
                name,
                "whatever the patience"
            );
        }
        let err = Strategy::parse("phase").unwrap_err().to_string();
        assert!(
            err.contains("use one of sweep, early-exit, fast, rangefinder, depth"),
            "{err}"
        );
    }
}
