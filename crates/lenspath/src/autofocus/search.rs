//! Focusing a realistic camera on an image patch: rendering the patch at a
//! sensor position and scoring it ([`Focuser::measure_at`]), the search
//! strategies ([`Strategy`]), and the ground truth they are checked against
//! ([`Focuser::ground_truth`]). docs/autofocus.md explains the designs.
//!
//! Sensor positions are in mm behind the aperture stop (lens coordinates);
//! the sweep runs from the infinity focus to the close focus of
//! [`LensAnalysis`]. One depth of focus (DoF) is the sensor shift that grows
//! the blur circle of a point to one pixel: pitch × (z − z_exit pupil) / D_exit pupil.

use std::sync::atomic::AtomicBool;
use std::time::Instant;

use glam::{DVec3, Vec2, Vec3};

use super::light_field::{FilmRegion, LightField, Recording, Splat};
use super::measures::{FocusMeasure, Patch};
use crate::camera::{
    ApertureShape, Camera, CameraPose, CameraSample, LensFocus, RealisticCamera, RealisticCameraSettings,
};
use crate::error::{Error, Result};
use crate::film::Filter;
use crate::film::PixelRect;
use crate::integrator::Integrator;
use crate::lens::{AnalysisSettings, LensAnalysis, LensSystem};
use crate::render::{render, RenderSettings};
use crate::sampling::SamplerKind;
use crate::scene::CompiledScene;

/// The scale of detail a patch render is scored at: the band-pass applied
/// before the focus measure, a Gaussian minus a Gaussian four times wider. It
/// keeps detail a few pixels across (edges, texture) and drops both the
/// pixel-scale Monte Carlo noise and the smooth glow of bright things far out
/// of focus, which gradient measures would otherwise score as detail.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Detail {
    /// σ = 1 and 4 pixels: where the sharpest focus shows; for locating the peak.
    Fine,
    /// σ = 2 and 8 pixels: for scanning. A peak stays visible several DoF
    /// away, and white noise's gradient energy, which falls as σ⁻⁴, is about
    /// a sixteenth of the fine scale's while an edge's falls as σ⁻¹.
    Coarse,
}

impl Detail {
    /// The narrow and wide standard deviations of the band-pass, pixels.
    pub fn band_pass_sigmas_px(self) -> (f64, f64) {
        match self {
            Detail::Fine => (1.0, 4.0),
            Detail::Coarse => (2.0, 8.0),
        }
    }

    /// `rgb` (`width` pixels wide) band-passed at this scale.
    fn band_pass(self, rgb: &[f32], width: usize) -> Vec<f32> {
        let (narrow_sigma, wide_sigma) = self.band_pass_sigmas_px();
        let narrow = gaussian_blur(rgb, width, narrow_sigma);
        let wide = gaussian_blur(rgb, width, wide_sigma);
        narrow.iter().zip(&wide).map(|(n, w)| n - w).collect()
    }
}

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

/// The most samples the ground truth takes, as a multiple of the strategies'
/// ([`Focuser::ground_truth`]): at 32× the two seeds of three dim or glassy
/// patches still disagreed by 0.9 to 1.6 DoF, so the truth was itself noisy.
pub const TRUTH_MAX_SPP_FACTOR: u32 = 128;

/// How far apart, in DoF, the ground truth's two seeds may put the peak for
/// it to count as converged ([`Focuser::ground_truth`]).
pub const TRUTH_SEED_SPREAD_DOF: f64 = 0.25;

/// Real-ray height for converting between sensor positions and distances (as the camera focuses).
const FOCUS_RAY_HEIGHT_MM: f64 = 0.1;

/// A search strategy.
#[derive(Clone, Copy, Debug, PartialEq)]
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
    /// sweep's camera rays.
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

/// Every strategy with its command-line name.
pub const STRATEGIES: [(&str, Strategy); 5] = [
    ("sweep", Strategy::Sweep),
    (
        "early-exit",
        Strategy::EarlyExit {
            patience: crate::defaults::AUTOFOCUS_PATIENCE,
        },
    ),
    ("fast", Strategy::Fast),
    ("rangefinder", Strategy::Rangefinder),
    ("depth", Strategy::Depth),
];

impl Strategy {
    /// The strategy called `name` (see [`STRATEGIES`]); `patience` sets early-exit's.
    pub fn from_name(name: &str, patience: usize) -> Result<Strategy> {
        match STRATEGIES.iter().find(|(n, _)| *n == name) {
            Some((_, Strategy::EarlyExit { .. })) => Ok(Strategy::EarlyExit { patience }),
            Some((_, s)) => Ok(*s),
            None => Err(Error::InvalidArgument(format!(
                "unknown autofocus strategy '{name}'; use one of {}",
                STRATEGIES.map(|(n, _)| n).join(", ")
            ))),
        }
    }

    /// The command-line name.
    pub fn name(&self) -> &'static str {
        match self {
            Strategy::Sweep => "sweep",
            Strategy::EarlyExit { .. } => "early-exit",
            Strategy::Fast => "fast",
            Strategy::Rangefinder => "rangefinder",
            Strategy::Depth => "depth",
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
}

/// One scored patch image: a patch render, or the patch refocused from a light field.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Evaluation {
    /// Sensor position, mm behind the stop.
    pub sensor_z_mm: f64,
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
    pub sensor_z_mm: f64,
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
}

impl AutofocusResult {
    /// How many of its evaluations are patch renders (the others are refocused light fields).
    pub fn patch_renders(&self) -> usize {
        self.evaluations.iter().filter(|e| !e.refocused).count()
    }
}

/// The reference focus of a patch.
#[derive(Clone, Copy, Debug, serde::Serialize, serde::Deserialize)]
pub struct GroundTruth {
    /// Sensor position of the sharpest patch, mm behind the stop.
    pub sensor_z_mm: f64,
    /// How far two independent fine sweeps put the peak apart, in DoF (noise).
    pub seed_spread_dof: f64,
    /// Samples per pixel that brought the spread within [`TRUTH_SEED_SPREAD_DOF`] (or the most tried).
    pub spp: u32,
    /// The conjugate of the patch's dominant depth, mm behind the stop (`None` if the probes hit nothing).
    pub depth_conjugate_z_mm: Option<f64>,
    /// The lens's best-contrast sensor position for that depth at the patch's
    /// place in the field (what the `depth` strategy starts from).
    pub lens_best_focus_z_mm: Option<f64>,
}

impl GroundTruth {
    /// Whether computing it again could not do better: its seeds agree within
    /// [`TRUTH_SEED_SPREAD_DOF`], or it already took the most samples allowed
    /// for strategies rendering at `strategy_spp`.
    pub fn is_settled(&self, strategy_spp: u32) -> bool {
        self.seed_spread_dof <= TRUTH_SEED_SPREAD_DOF || self.spp >= TRUTH_MAX_SPP_FACTOR * strategy_spp
    }
}

/// Where the range finder puts a patch's focus, mm behind the stop.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct RangeFocus {
    /// The real-ray conjugate of the dominant depth (a focus scale's reading).
    pub conjugate_z_mm: f64,
    /// The best-contrast position for the surface there, aberrations and field curvature included.
    pub best_focus_z_mm: f64,
    /// The fraction of the probes that hit something and fall in the dominant one-DoF window.
    pub dominant_fraction: f64,
    /// The conjugates of the farthest and the nearest probe's depth, mm
    /// behind the stop: the patch's depths, whatever carries its contrast.
    pub probe_span_z_mm: (f64, f64),
}

/// What [`Focuser::on_evaluation`] calls.
type EvaluationObserver<'a> = Box<dyn FnMut(&Evaluation) + Send + 'a>;

/// Focuses one camera on one patch of one scene.
pub struct Focuser<'a> {
    scene: &'a CompiledScene,
    pose: CameraPose,
    settings: AutofocusSettings,
    system: LensSystem,
    range_mm: (f64, f64),
    pitch_mm: f64,
    exit_pupil: (f64, f64),
    mm_per_scene: f64,
    evaluations: Vec<Evaluation>,
    /// Told of each evaluation as it is made (`lenspath view` draws the curve).
    observer: Option<EvaluationObserver<'a>>,
    light_fields: usize,
    camera_rays: u64,
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
        })
    }

    /// Calls `observer` with every evaluation as it is made, so a front end
    /// can show the search while it runs.
    pub fn on_evaluation(&mut self, observer: impl FnMut(&Evaluation) + Send + 'a) {
        self.observer = Some(Box::new(observer));
    }

    fn record(&mut self, evaluation: Evaluation) {
        if let Some(observer) = &mut self.observer {
            observer(&evaluation);
        }
        self.evaluations.push(evaluation);
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
    pub fn sensor_z_for_distance(&self, distance: f64) -> Result<f64> {
        self.system
            .sensor_z_for_focus_distance(distance * self.mm_per_scene, FOCUS_RAY_HEIGHT_MM)
    }

    fn camera_settings(&self, z: f64) -> RealisticCameraSettings {
        RealisticCameraSettings {
            focus: LensFocus::SensorPositionMm(z),
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
        let mut images = Vec::new();
        for (k, &half) in halves.iter().enumerate().filter(|(_, &h)| h > 0) {
            images.push(self.render_patch(&camera, half, stream_seed(seed, k), detail)?);
        }
        let score = self.score(&images)?;
        self.record(Evaluation {
            sensor_z_mm: z,
            score,
            spp,
            detail,
            refocused: false,
        });
        Ok(score)
    }

    /// The focus measure of one band-passed patch image, or of several with
    /// independent noise ([`FocusMeasure::evaluate_groups`]).
    fn score(&self, images: &[Vec<f32>]) -> Result<f64> {
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
    fn record_light_fields(&mut self, z0: f64, region: FilmRegion, spp: u32) -> Result<Vec<LightField>> {
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
                };
                LightField::record(self.scene, camera.clone(), region, &recording)
            })
            .collect::<Result<Vec<_>>>()?;
        self.camera_rays += fields.iter().map(LightField::samples).sum::<u64>();
        self.light_fields += 1;
        Ok(fields)
    }

    /// The film region a light field recorded at `z0` needs for refocusing
    /// the patch anywhere in `sensor_z_mm` (near, far).
    fn light_field_region(&self, z0: f64, sensor_z_mm: (f64, f64)) -> Result<FilmRegion> {
        let camera = self.patch_camera(z0, self.settings.camera.aperture.clone())?;
        Ok(LightField::region_for(&camera, self.settings.patch, sensor_z_mm))
    }

    /// The score of the patch refocused from `fields` to `z` (bilinear
    /// splats, so the score is smooth in `z`), at [`Detail::Fine`]; `None`
    /// out of their reach.
    fn refocused_score(&self, fields: &[LightField], z: f64) -> Result<Option<f64>> {
        let width = self.settings.patch.width as usize;
        let mut images = Vec::new();
        for field in fields {
            match field.refocus(z, self.settings.patch, Splat::Bilinear) {
                Some(rgb) => images.push(Detail::Fine.band_pass(&rgb, width)),
                None => return Ok(None),
            }
        }
        self.score(&images).map(Some)
    }

    /// The camera for patch renders with the sensor at `z`, its stop opening shaped as `aperture`.
    fn patch_camera(&self, z: f64, aperture: ApertureShape) -> Result<RealisticCamera> {
        let s = &self.settings;
        let settings = RealisticCameraSettings {
            aperture,
            ..self.camera_settings(z)
        };
        RealisticCamera::for_region(self.pose, s.width, s.height, &settings, s.patch)
    }

    /// The patch rendered through `camera` at `spp` samples with `seed`,
    /// band-passed at the scale of `detail`; its samples are counted as
    /// camera rays of the running strategy.
    fn render_patch(&mut self, camera: &RealisticCamera, spp: u32, seed: u32, detail: Detail) -> Result<Vec<f32>> {
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
        };
        let output = render(
            self.scene,
            camera,
            &render_settings,
            &|_, _| {},
            &AtomicBool::new(false),
        )?;
        self.camera_rays += output.stats.samples;
        Ok(detail.band_pass(&output.image.rgb, output.image.width as usize))
    }

    /// Runs `strategy` and reports what it found and what it cost.
    pub fn run(&mut self, strategy: Strategy) -> Result<AutofocusResult> {
        let started = Instant::now();
        self.evaluations.clear();
        self.light_fields = 0;
        self.camera_rays = 0;
        let z = match strategy {
            Strategy::Sweep => self.sweep(None)?,
            Strategy::EarlyExit { patience } => self.sweep(Some(patience.max(1)))?,
            Strategy::Fast => self.fast()?,
            Strategy::Rangefinder => self.rangefinder()?,
            Strategy::Depth => self.depth()?,
        };
        Ok(AutofocusResult {
            strategy: strategy.name(),
            sensor_z_mm: z,
            focus_distance: self.focus_distance_at(z),
            evaluations: std::mem::take(&mut self.evaluations),
            light_fields: self.light_fields,
            camera_rays: self.camera_rays,
            seconds: started.elapsed().as_secs_f64(),
        })
    }

    /// How many sensor positions `step` apart fit from infinity to close focus.
    fn steps(&self, step: f64) -> usize {
        let (near, far) = self.range_mm;
        ((far - near) / step).floor() as usize + 1
    }

    /// Sensor positions from infinity to close focus, `step` apart.
    fn grid(&self, step: f64) -> Vec<f64> {
        let near = self.range_mm.0;
        (0..self.steps(step)).map(|i| near + i as f64 * step).collect()
    }

    /// The pixel-pitch sweep; with `patience`, it stops after that many steps without a new best.
    fn sweep(&mut self, patience: Option<usize>) -> Result<f64> {
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
    fn fast(&mut self) -> Result<f64> {
        match self.range_focus()? {
            Some(range) => self.refocused_peak(range.best_focus_z_mm, range.probe_span_z_mm, FAST_BUDGET_OF_SWEEP),
            None => self.contrast_search(),
        }
    }

    /// The contrast search from nothing: the coarse scan's peak, refined from
    /// a light field. What `fast` does when there is nothing to range on.
    fn contrast_search(&mut self) -> Result<f64> {
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
    fn refocused_peak(&mut self, z0: f64, span: (f64, f64), budget_of_sweep: f64) -> Result<f64> {
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
                    sensor_z_mm: z,
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
    fn coarse_peak(&mut self) -> Result<f64> {
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

    /// Camera rays through `k` × `k` points of the patch: what each hits, in
    /// camera space (scene units; the sensor centre is the origin and +z the
    /// view axis, so `z` is the depth along the axis).
    fn probe_points(&mut self, k: u32) -> Result<Vec<Vec3>> {
        let s = &self.settings;
        let camera = RealisticCamera::for_region(
            self.pose,
            s.width,
            s.height,
            &self.camera_settings(self.range_mm.0),
            s.patch,
        )?;
        let camera_from_render = self.pose.render_from_camera.inverse();
        let p = s.patch;
        let mut points = Vec::new();
        for j in 0..k {
            for i in 0..k {
                let film = Vec2::new(
                    p.x0 as f32 + (i as f32 + 0.5) / k as f32 * p.width as f32,
                    p.y0 as f32 + (j as f32 + 0.5) / k as f32 * p.height as f32,
                );
                // The first of a few lens positions the optics let through.
                let ray = [Vec2::splat(0.5), Vec2::new(0.25, 0.5), Vec2::new(0.75, 0.5)]
                    .into_iter()
                    .find_map(|lens| camera.generate_ray(CameraSample { film, lens }));
                if let Some(cr) = ray {
                    self.camera_rays += 1;
                    if let Some(hit) = self.scene.intersect(&cr.ray) {
                        points.push(camera_from_render.transform_point3(hit.p));
                    }
                }
            }
        }
        Ok(points)
    }

    /// Where the patch's dominant surface focuses, from 8×8 probe rays: each
    /// probe's depth conjugate; the densest one-DoF window of them (the depth
    /// most of the patch sees, robust to a background peeking past an edge)
    /// and its median; and the best-contrast sensor position of up to nine
    /// probes spread through that window, from the lens's through-focus
    /// modulation at their actual positions ([`Focuser::point_best_focus_z`]),
    /// and their median. `None` when no probe hits anything.
    pub fn range_focus(&mut self) -> Result<Option<RangeFocus>> {
        let mut probes: Vec<(f64, Vec3)> = self
            .probe_points(8)?
            .into_iter()
            .filter_map(|p| self.sensor_z_for_distance(f64::from(p.z)).ok().map(|z| (z, p)))
            .collect();
        if probes.is_empty() {
            return Ok(None);
        }
        probes.sort_by(|a, b| a.0.total_cmp(&b.0));
        let window = self.depth_of_focus_mm(probes[probes.len() / 2].0);
        let (mut best_start, mut best_count, mut end) = (0, 0, 0);
        for start in 0..probes.len() {
            while end < probes.len() && probes[end].0 - probes[start].0 <= window {
                end += 1;
            }
            if end - start > best_count {
                (best_start, best_count) = (start, end - start);
            }
        }
        let dominant = &probes[best_start..best_start + best_count];
        let picks = dominant.len().min(9);
        let mut best_focus: Vec<f64> = (0..picks)
            .map(|k| {
                let (z, p) = dominant[k * (dominant.len() - 1) / (picks - 1).max(1)];
                self.point_best_focus_z(p, z)
            })
            .collect();
        best_focus.sort_by(f64::total_cmp);
        Ok(Some(RangeFocus {
            conjugate_z_mm: dominant[dominant.len() / 2].0,
            best_focus_z_mm: best_focus[best_focus.len() / 2],
            dominant_fraction: best_count as f64 / probes.len() as f64,
            probe_span_z_mm: (probes[0].0, probes[probes.len() - 1].0),
        }))
    }

    /// The camera-space point `p` (scene units from the sensor centre) in lens
    /// coordinates (mm, from the stop) with the sensor `z` mm behind the stop.
    fn lens_point(&self, p: Vec3, z: f64) -> DVec3 {
        let mm = self.mm_per_scene;
        DVec3::new(f64::from(p.x) * mm, f64::from(p.y) * mm, z - f64::from(p.z) * mm)
    }

    /// The sensor position where the image of the camera-space point `p` has
    /// the most contrast at the frequencies the focus measures see
    /// ([`BEST_FOCUS_CYCLES_PER_PIXEL`]), searched within 5 DoF of its
    /// conjugate `conjugate_z` (which it falls back to). The point's place in
    /// lens coordinates depends on the sensor position (the lens moves to
    /// focus), so the search is repeated once from its own answer.
    fn point_best_focus_z(&self, p: Vec3, conjugate_z: f64) -> f64 {
        let frequency_per_mm = BEST_FOCUS_CYCLES_PER_PIXEL / self.pitch_mm;
        let mut z = conjugate_z;
        for _ in 0..2 {
            let half_range = 5.0 * self.depth_of_focus_mm(z);
            let bundle = self.system.spot_bundle(self.lens_point(p, z), 32);
            match bundle.best_focus_z(z - half_range, z + half_range, 100, frequency_per_mm) {
                Some(best) => z = best,
                None => return conjugate_z,
            }
        }
        z
    }

    /// Range-finder focusing ([`Focuser::range_focus`]); with nothing in the
    /// patch to range on (only sky), the contrast search instead (not `fast`,
    /// which would probe again).
    fn rangefinder(&mut self) -> Result<f64> {
        match self.range_focus()? {
            Some(range) => Ok(range.best_focus_z_mm),
            None => self.contrast_search(),
        }
    }

    /// The range finder ([`Focuser::range_focus`]), then a short contrast
    /// refinement from a light field with the rest of
    /// [`DEPTH_BUDGET_OF_SWEEP`] ([`Focuser::refocused_peak`]); with nothing
    /// in the patch to range on, the contrast search instead.
    fn depth(&mut self) -> Result<f64> {
        match self.range_focus()? {
            Some(range) => self.refocused_peak(range.best_focus_z_mm, range.probe_span_z_mm, DEPTH_BUDGET_OF_SWEEP),
            None => self.contrast_search(),
        }
    }

    /// `(z, score)` at each sensor position of `zs`, scored at the fine scale.
    fn scan(&mut self, zs: &[f64], spp: u32, seed: u32) -> Result<Vec<(f64, f64)>> {
        zs.iter()
            .map(|&z| Ok((z, self.measure_at(z, spp, seed, Detail::Fine)?)))
            .collect()
    }

    /// The reference focus: the peak of a fine sweep (half-pitch steps over
    /// ±5 pitches around the peak of a coarse 4-pitch scan at the coarse
    /// scale, widened while its maximum is near an end), located by a
    /// least-squares parabola through the log-scores within 1.5 DoF of its
    /// maximum, with two seeds; the
    /// samples are doubled (from 4× the settings', up to
    /// [`TRUTH_MAX_SPP_FACTOR`]×) until the seeds agree within
    /// [`TRUTH_SEED_SPREAD_DOF`].
    /// Its evaluations are not counted anywhere.
    pub fn ground_truth(&mut self) -> Result<GroundTruth> {
        let saved = (std::mem::take(&mut self.evaluations), self.camera_rays);
        let seed = self.settings.seed;
        let mut spp = 4 * self.settings.spp;
        let coarse_best = {
            let mut best = (f64::NEG_INFINITY, self.range_mm.0);
            for z in self.grid(4.0 * self.pitch_mm) {
                let s = self.measure_at(z, spp, seed ^ 0x5eed, Detail::Coarse)?;
                if s > best.0 {
                    best = (s, z);
                }
            }
            best.1
        };
        let (near, far) = self.range_mm;
        let half_pitch = 0.5 * self.pitch_mm;
        let mut fine: Vec<f64> = (-10..=10)
            .map(|i| coarse_best + f64::from(i) * half_pitch)
            .filter(|z| (near - 1e-9..=far + 1e-9).contains(z))
            .collect();
        // The coarse scan can miss the peak by a step or two: while the fine
        // scan's maximum is within two steps of an end, widen it there by ten.
        loop {
            let i = peak_index(&self.scan(&fine, spp, seed ^ 0xf1e1d)?);
            let (first, last) = (fine[0], fine[fine.len() - 1]);
            if i <= 1 && first - half_pitch >= near - 1e-9 {
                fine.splice(
                    0..0,
                    (1..=10)
                        .rev()
                        .map(|k| first - f64::from(k) * half_pitch)
                        .filter(|&z| z >= near - 1e-9),
                );
            } else if i + 2 >= fine.len() && last + half_pitch <= far + 1e-9 {
                fine.extend(
                    (1..=10)
                        .map(|k| last + f64::from(k) * half_pitch)
                        .filter(|&z| z <= far + 1e-9),
                );
            } else {
                break;
            }
        }
        let result = loop {
            let mut peaks = [0.0; 2];
            for (k, peak) in peaks.iter_mut().enumerate() {
                let seed = seed.wrapping_add(1000 + k as u32);
                let points = self.scan(&fine, spp, seed)?;
                let i = peak_index(&points);
                // A least-squares fit over ±1.5 DoF (about 15 half-pitch
                // steps), not the three points around the maximum: those
                // are a fifth of a DoF apart, and noise tilts their parabola.
                *peak = log_parabola_peak(&points, fine[i], 1.5 * self.depth_of_focus_mm(fine[i]));
            }
            let z = 0.5 * (peaks[0] + peaks[1]);
            let spread = (peaks[0] - peaks[1]).abs() / self.depth_of_focus_mm(z);
            if spread <= TRUTH_SEED_SPREAD_DOF || spp >= TRUTH_MAX_SPP_FACTOR * self.settings.spp {
                break (z, spread, spp);
            }
            spp *= 2;
        };
        let range = self.range_focus()?;
        (self.evaluations, self.camera_rays) = saved;
        Ok(GroundTruth {
            sensor_z_mm: result.0,
            seed_spread_dof: result.1,
            spp: result.2,
            depth_conjugate_z_mm: range.map(|r| r.conjugate_z_mm),
            lens_best_focus_z_mm: range.map(|r| r.best_focus_z_mm),
        })
    }
}

/// The seed of the `stream`-th of several renders that must be independent:
/// seeds far apart (the golden-ratio increment), so their sample sequences
/// do not overlap.
fn stream_seed(seed: u32, stream: usize) -> u32 {
    seed.wrapping_add(0x9E37_79B9u32.wrapping_mul(stream as u32))
}

/// `rgb` (`width` pixels wide, three floats each) blurred by a separable
/// Gaussian of standard deviation `sigma` pixels, renormalised at the borders.
fn gaussian_blur(rgb: &[f32], width: usize, sigma: f64) -> Vec<f32> {
    let height = rgb.len() / (3 * width.max(1));
    let radius = (3.0 * sigma).ceil() as isize;
    let weights: Vec<f64> = (-radius..=radius)
        .map(|k| (-((k * k) as f64) / (2.0 * sigma * sigma)).exp())
        .collect();
    // Taps past the patch's edge are left out and the rest renormalised; the
    // valid taps of a pixel are a contiguous range, summed in order.
    let pass = |src: &[f32], horizontal: bool| -> Vec<f32> {
        let mut out = vec![0.0f32; src.len()];
        let (along, stride) = if horizontal { (width, 3) } else { (height, 3 * width) };
        for y in 0..height {
            for x in 0..width {
                let at = if horizontal { x } else { y } as isize;
                let first = (-radius).max(-at);
                let last = radius.min(along as isize - 1 - at);
                let pixel = 3 * (y * width + x);
                let (mut sum, mut total) = ([0.0f64; 3], 0.0f64);
                for k in first..=last {
                    let w = weights[(k + radius) as usize];
                    let src_pixel = (pixel as isize + k * stride as isize) as usize;
                    for (c, s) in sum.iter_mut().enumerate() {
                        *s += w * f64::from(src[src_pixel + c]);
                    }
                    total += w;
                }
                for (c, s) in sum.iter().enumerate() {
                    out[pixel + c] = (s / total) as f32;
                }
            }
        }
        out
    };
    pass(&pass(rgb, true), false)
}

/// The index of the highest-scoring `(z, score)` point (the last of equal
/// ones; 0 for none).
fn peak_index(points: &[(f64, f64)]) -> usize {
    points
        .iter()
        .enumerate()
        .max_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
        .map_or(0, |(i, _)| i)
}

/// The index of the highest interior local maximum of a `(z, score)` curve
/// (a point above both neighbours); the highest point when there is none.
fn interior_peak_index(points: &[(f64, f64)]) -> usize {
    (1..points.len().saturating_sub(1))
        .filter(|&i| points[i].1 > points[i - 1].1 && points[i].1 > points[i + 1].1)
        .max_by(|&a, &b| points[a].1.total_cmp(&points[b].1))
        .unwrap_or_else(|| peak_index(points))
}

/// The vertex of the least-squares parabola through the log-scores of the
/// `(z, score)` points within `window` of `z` (a Gaussian fit of a focus
/// curve's peak), kept within their span; `z` itself when fewer than three
/// positive scores are there or they make no peak.
fn log_parabola_peak(points: &[(f64, f64)], z: f64, window: f64) -> f64 {
    let near: Vec<(f64, f64)> = points
        .iter()
        .filter(|&&(x, score)| score > 0.0 && (x - z).abs() <= window)
        .map(|&(x, score)| (x - z, score.ln()))
        .collect();
    if near.len() < 3 {
        return z;
    }
    let lo = near.iter().map(|p| p.0).fold(f64::INFINITY, f64::min);
    let hi = near.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
    match least_squares_parabola(&near) {
        Some((_, b, c)) if c < 0.0 => z + (-b / (2.0 * c)).clamp(lo, hi),
        _ => z,
    }
}

/// Coefficients (a, b, c) of the least-squares parabola y = a + b·x + c·x²
/// through `points`, from the 3×3 normal equations (Cramer's rule).
fn least_squares_parabola(points: &[(f64, f64)]) -> Option<(f64, f64, f64)> {
    let mut s = [0.0f64; 5]; // Σ x^k, k = 0..4
    let mut t = [0.0f64; 3]; // Σ y·x^k, k = 0..2
    for &(x, y) in points {
        let mut xk = 1.0;
        for k in 0..5 {
            s[k] += xk;
            if k < 3 {
                t[k] += y * xk;
            }
            xk *= x;
        }
    }
    let det3 = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let m = [[s[0], s[1], s[2]], [s[1], s[2], s[3]], [s[2], s[3], s[4]]];
    let d = det3(m);
    if d.abs() < 1e-300 || !d.is_finite() {
        return None;
    }
    let column = |k: usize| {
        let mut mk = m;
        for (row, &tv) in mk.iter_mut().zip(&t) {
            row[k] = tv;
        }
        det3(mk) / d
    };
    Some((column(0), column(1), column(2)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn least_squares_parabola_recovers_an_exact_one() {
        let f = |x: f64| 0.5 - 0.3 * x - 1.7 * x * x;
        let points: Vec<(f64, f64)> = [-2.0, -0.5, 0.0, 1.0, 3.0].iter().map(|&x| (x, f(x))).collect();
        let (a, b, c) = least_squares_parabola(&points).unwrap();
        assert!((a - 0.5).abs() < 1e-9 && (b + 0.3).abs() < 1e-9 && (c + 1.7).abs() < 1e-9);
    }

    #[test]
    fn strategy_names_round_trip() {
        for (name, s) in STRATEGIES {
            assert_eq!(Strategy::from_name(name, 12).unwrap(), s);
            assert_eq!(s.name(), name);
        }
        let err = Strategy::from_name("phase", 12).unwrap_err().to_string();
        assert!(
            err.contains("use one of sweep, early-exit, fast, rangefinder, depth"),
            "{err}"
        );
    }
}
