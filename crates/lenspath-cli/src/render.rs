//! `lenspath render`.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use clap::{Args, ValueEnum};
use lenspath::accel::BvhSettings;
use lenspath::builtin::{builtin_scene, DEFAULT_MESH_TRIANGLES};
use lenspath::camera::{
    sensor_for_image, Aperture, ApertureShape, Camera, LensFocus, PerspectiveCamera, Radiometry, RealisticCamera,
    RealisticCameraSettings,
};
use lenspath::film::Filter;
use lenspath::integrator::PathSettings;
use lenspath::io::checkpoint::{read_checkpoint, write_checkpoint};
use lenspath::io::image::{check_output_path, write_image};
use lenspath::io::{load_scene, SceneOptions};
use lenspath::lens::LensPrescription;
use lenspath::render::{
    render_from, Accumulation, Checkpoints, NormalizedRect, PixelRect, RenderSettings, DEFAULT_IMAGE_SIZE,
};
use lenspath::sampling::SamplerKind;
use lenspath::scene::{Scene, SceneView};
use lenspath::{Error, Result};

use sha2::{Digest, Sha256};

use crate::progress::Progress;
use crate::Outcome;

/// Camera models.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum CameraKind {
    /// Ideal pinhole: everything in focus.
    Pinhole,
    /// Ideal thin lens: depth of field from --aperture-radius and --focus-distance.
    ThinLens,
    /// A real lens prescription (--lens), traced surface by surface.
    Realistic,
}

/// Exposure normalisation of the realistic camera.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum RadiometryKind {
    /// The image centre reads the scene radiance at any f-number.
    Normalized,
    /// Stopping down darkens the image by (N2/N1)^2, as on a real camera.
    Physical,
}

/// Sensor size as WIDTHxHEIGHT in mm.
#[derive(Clone, Copy, Debug)]
pub struct SensorSize {
    pub width_mm: f64,
    pub height_mm: f64,
}

pub fn parse_sensor(s: &str) -> std::result::Result<SensorSize, String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT in mm such as 36x24, got '{s}'"))?;
    let parse = |v: &str| match v.trim().parse::<f64>() {
        Ok(x) if x > 0.0 && x.is_finite() => Ok(x),
        _ => Err(format!("'{v}' is not a positive number of mm")),
    };
    Ok(SensorSize {
        width_mm: parse(w)?,
        height_mm: parse(h)?,
    })
}

/// Pixel filters.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum FilterKind {
    /// Box of one pixel.
    Box,
    /// Gaussian, sigma 0.5 px, radius 1.5 px.
    Gaussian,
}

/// Sample sequences.
#[derive(Clone, Copy, Debug, ValueEnum)]
pub enum SamplerArg {
    /// Owen-scrambled Sobol points: less noise at the same samples per pixel.
    Sobol,
    /// Independent random numbers (PCG32), as pbrt's and Mitsuba's `independent`.
    Independent,
}

impl From<SamplerArg> for SamplerKind {
    fn from(arg: SamplerArg) -> Self {
        match arg {
            SamplerArg::Sobol => SamplerKind::Sobol,
            SamplerArg::Independent => SamplerKind::Independent,
        }
    }
}

/// Image size as WIDTHxHEIGHT.
#[derive(Clone, Copy, Debug)]
pub struct Resolution {
    pub width: u32,
    pub height: u32,
}

pub fn parse_resolution(s: &str) -> std::result::Result<Resolution, String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT such as 640x480, got '{s}'"))?;
    let parse = |v: &str| {
        v.trim()
            .parse::<u32>()
            .map_err(|_| format!("'{v}' is not a positive whole number"))
    };
    let (width, height) = (parse(w)?, parse(h)?);
    if width == 0 || height == 0 {
        return Err(format!("width and height must be positive, got {s}"));
    }
    Ok(Resolution { width, height })
}

/// Parses X,Y,W,H (fractions of the image) for `--patch` and `--autofocus`.
pub fn parse_patch(s: &str) -> std::result::Result<NormalizedRect, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let numbers: Vec<f64> = parts.iter().filter_map(|p| p.parse().ok()).collect();
    match numbers[..] {
        [x, y, width, height] if parts.len() == 4 => {
            NormalizedRect::new(x, y, width, height).map_err(|e| e.to_string())
        }
        _ => Err(format!(
            "expected X,Y,WIDTH,HEIGHT as fractions of the image, inside it, such as 0.55,0.7,0.1,0.12; got '{s}'"
        )),
    }
}

fn parse_crop(s: &str) -> std::result::Result<PixelRect, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let numbers: Vec<u32> = parts.iter().filter_map(|p| p.parse().ok()).collect();
    match numbers[..] {
        [x0, y0, width, height] if parts.len() == 4 => Ok(PixelRect { x0, y0, width, height }),
        _ => Err(format!(
            "expected X,Y,WIDTH,HEIGHT in pixels such as 100,80,64,48, got '{s}'"
        )),
    }
}

/// Parses a duration such as 90s, 5m, 1h or 1.5 (seconds).
fn parse_duration(s: &str) -> std::result::Result<Duration, String> {
    let t = s.trim();
    let (number, unit_s) = match t.char_indices().last() {
        Some((i, 's')) => (&t[..i], 1.0),
        Some((i, 'm')) => (&t[..i], 60.0),
        Some((i, 'h')) => (&t[..i], 3600.0),
        _ => (t, 1.0),
    };
    match number.trim().parse::<f64>() {
        Ok(v) if v >= 0.0 && (v * unit_s).is_finite() => Ok(Duration::from_secs_f64(v * unit_s)),
        _ => Err(format!("expected a duration such as 60s, 5m or 1h, got '{s}'")),
    }
}

/// Which scene: a file or a built-in one (`render` and `autofocus`).
#[derive(Args, Debug)]
pub struct SceneArgs {
    /// Scene file: .dae (COLLADA, CS184), .obj, .ply, .gltf/.glb or .toml (lenspath). Default: the
    /// built-in scene named by --scene.
    pub file: Option<PathBuf>,
    /// Built-in scene: cornell-spheres, cornell-empty or cornell-mesh.
    #[arg(long, default_value = "cornell-spheres", conflicts_with = "file")]
    pub scene: String,
    /// Triangles of the procedural mesh in cornell-mesh.
    #[arg(long, default_value_t = DEFAULT_MESH_TRIANGLES)]
    pub mesh_triangles: usize,
}

impl SceneArgs {
    /// The scene's name, the scene and the settings its file gives; warnings go to stderr.
    pub fn load(&self) -> Result<(String, Scene, SceneOptions)> {
        match &self.file {
            Some(path) => {
                let loaded = load_scene(path)?;
                for (what, n) in loaded.warnings.iter() {
                    eprintln!(
                        "warning: {what}{}",
                        if n > 1 { format!(" (×{n})") } else { String::new() }
                    );
                }
                Ok((path.display().to_string(), loaded.scene, loaded.options))
            }
            None => Ok((
                self.scene.clone(),
                builtin_scene(&self.scene, self.mesh_triangles)?,
                SceneOptions::default(),
            )),
        }
    }
}

/// The realistic camera's lens flags (`render` and `autofocus`).
#[derive(Args, Debug)]
pub struct LensFlags {
    /// Realistic camera: built-in lens (dgauss50, wide22, tele250, fisheye10) or a lens table file
    /// [default: the scene file's, else dgauss50].
    #[arg(long)]
    pub lens: Option<String>,
    /// Realistic camera: sensor WIDTHxHEIGHT in mm; its width is kept and its height follows the
    /// image aspect [default: the scene file's, else 36x24].
    #[arg(long, value_parser = parse_sensor)]
    pub sensor: Option<SensorSize>,
    /// Realistic camera: stop down to this f-number (default: wide open).
    #[arg(long, value_name = "N")]
    pub fstop: Option<f64>,
    /// Realistic camera: metres per scene unit, since lenses are in mm [default: the scene file's, else 1].
    #[arg(long, value_name = "M")]
    pub scene_unit: Option<f64>,
    /// Realistic camera: exposure normalisation.
    #[arg(long, value_enum, default_value = "normalized")]
    pub radiometry: RadiometryKind,
}

impl LensFlags {
    /// The realistic camera's settings for a `width` × `height` image: flags
    /// win over the scene file's lens settings, which win over the defaults
    /// ([`RealisticCameraSettings::for_scene`]). The aperture is the file's;
    /// [`ApertureFlags::shape_or`] applies the flags'.
    pub fn settings(
        &self,
        options: &SceneOptions,
        view: &SceneView,
        width: u32,
        height: u32,
    ) -> Result<RealisticCameraSettings> {
        let mut settings = RealisticCameraSettings::for_scene(options, view, width, height)?;
        if let Some(lens) = &self.lens {
            settings.lens = LensPrescription::load(lens)?;
        }
        if let Some(sensor) = self.sensor {
            settings.sensor_mm = sensor_for_image(sensor.width_mm, width, height);
        }
        settings.f_number = self.fstop.or(settings.f_number);
        settings.scene_unit_m = self.scene_unit.unwrap_or(settings.scene_unit_m);
        settings.radiometry = match self.radiometry {
            RadiometryKind::Normalized => Radiometry::Normalized,
            RadiometryKind::Physical => Radiometry::Physical,
        };
        Ok(settings)
    }
}

/// The aperture's shape, for the realistic and thin-lens cameras.
#[derive(Args, Debug, Default)]
pub struct ApertureFlags {
    /// Aperture: an iris of N blades (a regular polygon, a corner at the top).
    #[arg(long, value_name = "N", conflicts_with_all = ["star", "aperture_mask"])]
    pub blades: Option<u32>,
    /// Aperture: turn the blades or the star by this many degrees counter-clockwise.
    #[arg(long, value_name = "DEG", default_value_t = 0.0)]
    pub blade_rotation: f64,
    /// Aperture: bend the blades' edges out, from 0 (straight) to 1 (round).
    #[arg(long, value_name = "C", default_value_t = 0.0)]
    pub blade_curvature: f64,
    /// Aperture: a star of N points.
    #[arg(long, value_name = "N", conflicts_with = "aperture_mask")]
    pub star: Option<u32>,
    /// Aperture: radius of the star's notches over its points'.
    #[arg(long, value_name = "R", default_value_t = 0.5)]
    pub star_inner_ratio: f64,
    /// Aperture: a grayscale transmission mask (PNG, JPEG or EXR; white is open) laid over the
    /// stop's bounding square, top row up.
    #[arg(long, value_name = "FILE")]
    pub aperture_mask: Option<PathBuf>,
}

impl ApertureFlags {
    /// The shape the flags ask for; when they ask for none, the scene file's
    /// (`[camera] aperture`), else the circle.
    pub fn shape_or(&self, options: &SceneOptions) -> Result<ApertureShape> {
        if self.blades.is_none() && self.star.is_none() && self.aperture_mask.is_none() {
            return Ok(options
                .lens
                .as_ref()
                .and_then(|l| l.aperture.clone())
                .unwrap_or(ApertureShape::Circle));
        }
        self.shape()
    }

    /// The shape the flags ask for (the circle when none).
    pub fn shape(&self) -> Result<ApertureShape> {
        let with_flag = |e: Error, flag: &str| match e {
            Error::InvalidArgument(m) => Error::InvalidArgument(format!("{flag}: {m}")),
            other => other,
        };
        if let Some(path) = &self.aperture_mask {
            return ApertureShape::load_mask(path);
        }
        let shape = match (self.blades, self.star) {
            (Some(count), _) => ApertureShape::Blades {
                count,
                rotation_deg: self.blade_rotation,
                curvature: self.blade_curvature,
            },
            (None, Some(points)) => ApertureShape::Star {
                points,
                inner_ratio: self.star_inner_ratio,
                rotation_deg: self.blade_rotation,
            },
            (None, None) => ApertureShape::Circle,
        };
        // Checks the values (blade count, curvature, ratio) now, before any rendering.
        Aperture::new(&shape).map_err(|e| with_flag(e, if self.star.is_some() { "--star" } else { "--blades" }))?;
        Ok(shape)
    }
}

/// Options of `lenspath render`.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Samples per pixel [default: the scene file's, else 64].
    #[arg(long)]
    spp: Option<u32>,
    /// Shadow rays per light at every non-specular hit [default: the scene file's, else 1].
    #[arg(long)]
    light_samples: Option<u32>,
    /// Maximum path depth, 1 = direct lighting only [default: the scene file's, else 16].
    #[arg(long)]
    max_depth: Option<u32>,
    /// Image size, WIDTHxHEIGHT [default: the scene file's, else 640x480].
    #[arg(long, value_parser = parse_resolution)]
    res: Option<Resolution>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Seed of the sample sequences; the same seed gives the same image [default: the scene file's, else 0].
    #[arg(long)]
    seed: Option<u32>,
    /// Sample sequence [default: the scene file's, else sobol].
    #[arg(long, value_enum)]
    sampler: Option<SamplerArg>,
    /// Output image: .png (sRGB) or .exr (linear RGB + Z).
    #[arg(long, default_value = "render.png")]
    out: PathBuf,
    /// Exposure in stops applied to PNG output.
    #[arg(long, default_value_t = 0.0)]
    exposure: f32,
    /// Camera model.
    #[arg(long, value_enum, default_value = "realistic")]
    camera: CameraKind,
    #[command(flatten)]
    lens: LensFlags,
    #[command(flatten)]
    aperture: ApertureFlags,
    /// Realistic camera: focus on this patch of the image first, X,Y,W,H in fractions of the
    /// image (0 to 1) such as 0.55,0.7,0.1,0.12, with `lenspath autofocus`'s fast strategy.
    #[arg(long, value_name = "X,Y,W,H", value_parser = parse_patch, conflicts_with_all = ["focus_distance", "sensor_depth"])]
    autofocus: Option<NormalizedRect>,
    /// Realistic camera: put the sensor this many mm behind the aperture stop instead of focusing by distance.
    #[arg(long, value_name = "MM", conflicts_with = "focus_distance")]
    sensor_depth: Option<f64>,
    /// Pinhole and thin lens: vertical field of view in degrees (default: the scene's).
    #[arg(long)]
    fov: Option<f32>,
    /// Thin-lens aperture radius, scene units.
    #[arg(long, default_value_t = 0.05)]
    aperture_radius: f32,
    /// Focus distance from the sensor, scene units (default: the scene's subject distance).
    #[arg(long)]
    focus_distance: Option<f32>,
    /// Pixel reconstruction filter.
    #[arg(long, value_enum, default_value = "box")]
    filter: FilterKind,
    /// Render only this rectangle of the image, X,Y,WIDTH,HEIGHT in pixels; its pixels are exactly
    /// those of the full render.
    #[arg(long, value_name = "X,Y,W,H", value_parser = parse_crop)]
    crop: Option<PixelRect>,
    /// Save the render's state to FILE every --checkpoint-every, when it ends and when it is
    /// stopped, so that --resume can continue it after a crash or a kill.
    #[arg(long, value_name = "FILE")]
    checkpoint: Option<PathBuf>,
    /// How often to save the checkpoint, such as 60s, 5m or 1h [default: 60s].
    #[arg(long, value_name = "DURATION", value_parser = parse_duration)]
    checkpoint_every: Option<Duration>,
    /// Continue the render saved in FILE (by --checkpoint; same scene, camera and settings) up to
    /// --spp; the image is the uninterrupted render's, bit for bit. Saves go on to FILE unless
    /// --checkpoint names another.
    #[arg(long, value_name = "FILE")]
    resume: Option<PathBuf>,
}

/// A hash of the scene's content: every mesh array, material, light and the
/// view (what [`fingerprint`] starts from).
fn scene_hasher(scene: &Scene) -> Sha256 {
    let mut hasher = Sha256::new();
    for mesh in &scene.meshes {
        let mut bytes = Vec::with_capacity(12 * mesh.positions.len() + 12 * mesh.indices.len());
        let floats = mesh
            .positions
            .iter()
            .chain(mesh.normals.iter().flatten())
            .flat_map(|v| v.to_array())
            .chain(mesh.uvs.iter().flatten().flat_map(|v| v.to_array()));
        for f in floats {
            bytes.extend_from_slice(&f.to_le_bytes());
        }
        for i in mesh.indices.iter().flatten() {
            bytes.extend_from_slice(&i.to_le_bytes());
        }
        hasher.update(&bytes);
        hasher.update(format!("{:?} {:?}", mesh.material, mesh.emission));
    }
    hasher.update(format!(
        "{:?} {:?} {:?} {:?}",
        scene.spheres, scene.materials, scene.lights, scene.view
    ));
    hasher
}

/// What a render's image depends on, except its sample count: the scene's
/// content ([`scene_hasher`]), the settings and the camera. A readable head
/// and a SHA-256 of it all; checkpoints carry it so that `--resume` never
/// continues another render.
fn fingerprint(
    mut hasher: Sha256,
    scene_name: &str,
    settings: &RenderSettings,
    camera: &str,
    aperture: &ApertureShape,
) -> String {
    // A mask's Debug form gives only its size: its values go in as bytes.
    if let ApertureShape::Mask(mask) = aperture {
        let bytes: Vec<u8> = mask.values.iter().flat_map(|v| v.to_le_bytes()).collect();
        hasher.update(&bytes);
    }
    let described = RenderSettings {
        spp: 0,
        threads: None,
        ..*settings
    };
    hasher.update(format!("{described:?} {camera}"));
    let digest: String = hasher.finalize().iter().map(|b| format!("{b:02x}")).collect();
    format!(
        "lenspath {} render of {scene_name}, {}x{}, seed {}; sha256 {digest}",
        env!("CARGO_PKG_VERSION"),
        settings.width,
        settings.height,
        settings.seed
    )
}

/// The state saved in `path`, checked to be of the render `fingerprint` describes.
fn resume_state(path: &Path, fingerprint: &str) -> Result<Accumulation> {
    let (saved, state) = read_checkpoint(path)?;
    if saved != fingerprint {
        return Err(Error::InvalidArgument(format!(
            "{} is the checkpoint of another render (the scene, camera or settings differ, or \
             another lenspath made it):\n  saved:    {saved}\n  this one: {fingerprint}",
            path.display()
        )));
    }
    Ok(state)
}

/// Runs `lenspath render`.
pub fn run(args: RenderArgs) -> Result<Outcome> {
    check_output_path(&args.out)?;
    if !args.exposure.is_finite() {
        return Err(Error::InvalidArgument("--exposure must be a finite number".into()));
    }
    let (scene_name, scene, options) = args.scene.load()?;
    // Flags win over the scene file, which wins over the defaults.
    let (width, height) = args
        .res
        .map(|r| (r.width, r.height))
        .or(options.resolution)
        .unwrap_or(DEFAULT_IMAGE_SIZE);
    let settings = RenderSettings {
        width,
        height,
        spp: args.spp.or(options.spp).unwrap_or(64),
        path: PathSettings {
            max_depth: args.max_depth.or(options.max_depth).unwrap_or(16),
            light_samples: args.light_samples.or(options.light_samples).unwrap_or(1),
        },
        seed: args.seed.or(options.seed).unwrap_or(0),
        sampler: args
            .sampler
            .map(SamplerKind::from)
            .or(options.sampler)
            .unwrap_or_default(),
        filter: match args.filter {
            FilterKind::Box => Filter::Box,
            FilterKind::Gaussian => Filter::GAUSSIAN,
        },
        threads: args.threads,
        tile_size: 16,
        crop: args.crop,
        depth: true,
    };
    settings.validate()?;
    let view = scene
        .view
        .ok_or_else(|| Error::InvalidArgument(format!("scene '{scene_name}' has no camera")))?;
    if args.fov.is_some() && matches!(args.camera, CameraKind::Realistic) {
        return Err(Error::InvalidArgument(
            "--fov is for --camera pinhole or thin-lens; through a real lens the field of view comes from --lens and --sensor"
                .into(),
        ));
    }
    let fov = args.fov.unwrap_or(view.fov_y_deg);
    if !(fov > 0.0 && fov < 180.0) {
        return Err(Error::InvalidArgument(format!(
            "--fov must be between 0 and 180 degrees, got {fov}"
        )));
    }
    if args.autofocus.is_some() && !matches!(args.camera, CameraKind::Realistic) {
        return Err(Error::InvalidArgument("--autofocus needs --camera realistic".into()));
    }
    let aperture = args.aperture.shape_or(&options)?;
    if aperture != ApertureShape::Circle && matches!(args.camera, CameraKind::Pinhole) {
        return Err(Error::InvalidArgument(
            "--blades, --star and --aperture-mask shape a lens's aperture; a pinhole has none (use --camera thin-lens or realistic)".into(),
        ));
    }
    let checkpoint_path = args.checkpoint.clone().or_else(|| args.resume.clone());
    if args.checkpoint_every.is_some() && checkpoint_path.is_none() {
        return Err(Error::InvalidArgument(
            "--checkpoint-every needs --checkpoint FILE (or --resume FILE)".into(),
        ));
    }
    if let Some(path) = &args.checkpoint {
        lenspath::io::check_writable(path)?;
    }
    // Hashed only for checkpoints: a million triangles take a tenth of a second.
    let scene_hash = checkpoint_path.is_some().then(|| scene_hasher(&scene));
    let compiled = scene.compile(&BvhSettings::default())?;
    let (camera, camera_description): (Box<dyn Camera>, String) = match args.camera {
        CameraKind::Pinhole => (
            Box::new(PerspectiveCamera::pinhole(
                view.pose,
                fov,
                settings.width,
                settings.height,
            )),
            format!("pinhole, fov {fov}"),
        ),
        CameraKind::ThinLens => {
            let focus = args.focus_distance.unwrap_or(view.focus_distance);
            if !(args.aperture_radius >= 0.0 && args.aperture_radius.is_finite()) {
                return Err(Error::InvalidArgument(format!(
                    "--aperture-radius must be zero or positive, got {}",
                    args.aperture_radius
                )));
            }
            if !(focus > 0.0 && focus.is_finite()) {
                return Err(Error::InvalidArgument(format!(
                    "--focus-distance must be positive, got {focus}"
                )));
            }
            (
                Box::new(
                    PerspectiveCamera::thin_lens(
                        view.pose,
                        fov,
                        settings.width,
                        settings.height,
                        args.aperture_radius,
                        focus,
                    )
                    .with_aperture(Arc::new(Aperture::new(&aperture)?)),
                ),
                format!(
                    "thin lens, fov {fov}, radius {}, focus {focus}, {aperture:?}",
                    args.aperture_radius
                ),
            )
        }
        CameraKind::Realistic => {
            let mut lens_settings = args.lens.settings(&options, &view, settings.width, settings.height)?;
            match (args.sensor_depth, args.focus_distance) {
                (Some(mm), _) => lens_settings.focus = LensFocus::SensorPositionMm(mm),
                (None, Some(d)) => lens_settings.focus = LensFocus::Distance(f64::from(d)),
                // The scene file's focus distance, else the view's subject distance.
                (None, None) => {}
            }
            lens_settings.aperture = aperture.clone();
            if let Some(patch) = args.autofocus {
                lens_settings.focus = LensFocus::SensorPositionMm(crate::autofocus::focus_before_render(
                    &compiled,
                    view.pose,
                    &lens_settings,
                    &settings,
                    patch,
                )?);
            }
            let camera = RealisticCamera::new(view.pose, settings.width, settings.height, &lens_settings)?;
            (Box::new(camera), format!("{lens_settings:?}"))
        }
    };
    // The checkpoint file and this render's fingerprint, when checkpointing.
    let checkpointing: Option<(PathBuf, String)> = checkpoint_path.zip(scene_hash).map(|(path, hash)| {
        (
            path,
            fingerprint(hash, &scene_name, &settings, &camera_description, &aperture),
        )
    });
    let start = match (&args.resume, &checkpointing) {
        (Some(resume), Some((_, fingerprint))) => {
            let state = resume_state(resume, fingerprint)?;
            eprintln!(
                "resuming {} from {} samples per pixel",
                resume.display(),
                state.spp_min()
            );
            Some(state)
        }
        _ => None,
    };

    let cancel = Arc::new(AtomicBool::new(false));
    {
        let cancel = cancel.clone();
        // First Ctrl-C: stop and save. Second: leave at once.
        let _ = ctrlc::set_handler(move || {
            if cancel.swap(true, Ordering::SeqCst) {
                std::process::exit(i32::from(crate::EXIT_INTERRUPTED));
            }
        });
    }
    let total = u64::from(settings.width) * u64::from(settings.height) * u64::from(settings.spp);
    let progress = Progress::new(&format!("render {scene_name}"), total);
    let mut save;
    let checkpoints = match &checkpointing {
        Some((path, fingerprint)) => {
            save = |state: &Accumulation| write_checkpoint(path, fingerprint, state);
            Some(Checkpoints {
                every: args.checkpoint_every.unwrap_or(Duration::from_secs(60)),
                save: &mut save,
            })
        }
        None => None,
    };
    let output = render_from(
        &compiled,
        camera.as_ref(),
        &settings,
        start,
        checkpoints,
        &|d, t| progress.update(d, t),
        &cancel,
    )?;
    progress.finish();
    write_image(&args.out, &output.image, args.exposure)?;

    let s = &output.stats;
    let interrupted = s.cancelled;
    if interrupted {
        eprintln!(
            "interrupted: saved {} with {} of {} samples per pixel{}",
            args.out.display(),
            output.image.spp_min,
            settings.spp,
            checkpointing.as_ref().map_or(String::new(), |(p, _)| format!(
                "; continue with --resume {}",
                p.display()
            ))
        );
    }
    if s.invalid_samples > 0 {
        eprintln!(
            "warning: {} samples were NaN or infinite and were dropped",
            s.invalid_samples
        );
    }
    eprintln!(
        "rendered {} {}x{}{} at {} spp in {:.3} s: {:.2} M samples/s, {:.2} M rays/s -> {}",
        scene_name,
        output.image.width,
        output.image.height,
        args.crop.map_or(String::new(), |_| format!(
            " (crop of {}x{})",
            settings.width, settings.height
        )),
        output.image.spp_min,
        s.seconds,
        s.samples as f64 / s.seconds / 1e6,
        s.rays as f64 / s.seconds / 1e6,
        args.out.display()
    );
    Ok(if interrupted {
        Outcome::Interrupted
    } else {
        Outcome::Done
    })
}
