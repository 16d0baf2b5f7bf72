//! The flags several subcommands share (the scene, the lens, the aperture)
//! and the parsers of their values. They only spell options: what a flag left
//! out means is decided by the library ([`lenspath::setup`]).

use std::ffi::OsStr;
use std::marker::PhantomData;
use std::path::{Path, PathBuf};
use std::time::Duration;

use clap::builder::{PossibleValue, TypedValueParser};
use clap::error::ErrorKind;
use clap::Args;
use lenspath::builtin::DEFAULT_MESH_TRIANGLES;
use lenspath::camera::{Aperture, ApertureShape, Radiometry};
use lenspath::film::{NormalizedRect, PixelRect};
use lenspath::io::{load_named_scene, LoadedScene};
use lenspath::lens::LensPrescription;
use lenspath::names::Named;
use lenspath::options::SceneOptions;
use lenspath::scene::Scene;
use lenspath::sensor::{Cfa, Demosaic, SensorDescription, ToneCurve, WhiteBalance};
use lenspath::setup::RealisticDescription;
use lenspath::{Error, Result};

/// Sensor size as WIDTHxHEIGHT in mm.
#[derive(Clone, Copy, Debug)]
pub struct SensorSize {
    pub width_mm: f64,
    pub height_mm: f64,
}

impl From<(f64, f64)> for SensorSize {
    fn from((width_mm, height_mm): (f64, f64)) -> Self {
        SensorSize { width_mm, height_mm }
    }
}

impl std::fmt::Display for SensorSize {
    /// As the flag is written: WIDTHxHEIGHT.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}", self.width_mm, self.height_mm)
    }
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

/// The value parser of a flag choosing a library value by name
/// ([`Named`]): its names are the flag's possible values (in the help and
/// in shell completion), in the library's spelling and order, and a value
/// parses as [`Named::parse`] parses it (any case, its error), so the CLI
/// keeps no list of its own.
pub fn named<T: Named + Send + Sync>() -> NamedValue<T> {
    NamedValue(PhantomData)
}

/// See [`named`].
#[derive(Clone, Copy)]
pub struct NamedValue<T>(PhantomData<fn() -> T>);

impl<T: Named + Send + Sync> TypedValueParser for NamedValue<T> {
    type Value = T;

    fn parse_ref(&self, cmd: &clap::Command, arg: Option<&clap::Arg>, value: &OsStr) -> clap::error::Result<T> {
        let flag = arg.map_or_else(String::new, |a| format!("invalid value for '{a}': "));
        T::parse(&value.to_string_lossy())
            .map_err(|e| clap::Error::raw(ErrorKind::InvalidValue, format!("{flag}{e}\n")).with_cmd(cmd))
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        Some(Box::new(T::names().into_iter().map(PossibleValue::new)))
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

pub fn parse_crop(s: &str) -> std::result::Result<PixelRect, String> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let numbers: Vec<u32> = parts.iter().filter_map(|p| p.parse().ok()).collect();
    match numbers[..] {
        [x0, y0, width, height] if parts.len() == 4 => Ok(PixelRect { x0, y0, width, height }),
        _ => Err(format!(
            "expected X,Y,WIDTH,HEIGHT in pixels such as 100,80,64,48, got '{s}'"
        )),
    }
}

/// Parses X,Y, a point of the image as fractions of its width and height
/// from the top left (0 to 1), for `--guide-at`.
pub fn parse_image_point(s: &str) -> std::result::Result<(f64, f64), String> {
    let inside = |v: &str| v.trim().parse::<f64>().ok().filter(|v| (0.0..=1.0).contains(v));
    match s.split_once(',').map(|(x, y)| (inside(x), inside(y))) {
        Some((Some(x), Some(y))) => Ok((x, y)),
        _ => Err(format!(
            "expected X,Y as fractions of the image from its top left (0 to 1), such as 0.18,0.71; got '{s}'"
        )),
    }
}

/// Parses a duration such as 90s, 5m, 1h or 1.5 (seconds).
pub fn parse_duration(s: &str) -> std::result::Result<Duration, String> {
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
    /// Scene file: .dae (COLLADA, CS184), .obj, .ply, .gltf/.glb or .toml (lenspath), or a
    /// built-in scene's name. Default: the built-in scene named by --scene.
    pub file: Option<PathBuf>,
    /// Built-in scene: cornell-spheres, cornell-empty or cornell-mesh.
    #[arg(long, default_value = "cornell-spheres", conflicts_with = "file")]
    pub scene: String,
    /// Triangles of the procedural mesh in cornell-mesh.
    #[arg(long, default_value_t = DEFAULT_MESH_TRIANGLES)]
    pub mesh_triangles: usize,
    #[command(flatten)]
    pub allow_read: AllowRead,
}

/// Which folders a scene file may read the files it names from.
#[derive(Args, Debug)]
pub struct AllowRead {
    /// Let the scene file read the files it names (base scenes, meshes, buffers, material
    /// libraries, lens tables) from DIR too; by default only from its own folder (repeatable).
    #[arg(long = "allow-read", value_name = "DIR")]
    pub dirs: Vec<PathBuf>,
}

impl AllowRead {
    /// Loads the scene `name` (a built-in scene's name, else a file read within its folder and
    /// these; [`load_named_scene`]).
    pub fn load_scene(&self, name: &Path, mesh_triangles: usize) -> Result<LoadedScene> {
        load_named_scene(name, &self.dirs, mesh_triangles)
    }
}

impl SceneArgs {
    /// The built-in scene these flags name (by --scene, or by its name as the file), if any.
    #[cfg(feature = "viewer")]
    pub fn builtin(&self) -> Option<&str> {
        match &self.file {
            None => Some(&self.scene),
            Some(file) => lenspath::io::builtin_scene_named(file),
        }
    }

    /// The scene's name, the scene and the settings its file gives; warnings go to stderr.
    pub fn load(&self) -> Result<(String, Scene, SceneOptions)> {
        let loaded = match &self.file {
            Some(path) => self.allow_read.load_scene(path, self.mesh_triangles)?,
            None => LoadedScene::builtin(&self.scene, self.mesh_triangles)?,
        };
        for (what, n) in loaded.warnings.iter() {
            eprintln!(
                "warning: {what}{}",
                if n > 1 { format!(" (×{n})") } else { String::new() }
            );
        }
        let name = self
            .file
            .as_ref()
            .map_or(self.scene.clone(), |f| f.display().to_string());
        Ok((name, loaded.scene, loaded.options))
    }
}

/// The image sensor's flags: with `--sensor-model` (or any of them) the film
/// records the sensor's channels and a raw frame is read out of it.
#[derive(Args, Debug)]
pub struct SensorFlags {
    /// Record through an image sensor with this spectral response: `ideal` (CIE x̄ȳz̄) or a
    /// measured camera (sony_ilce_7m3, nikon_d850, canon_eos_5d_mkiv, ...). Noise, gain and
    /// levels default to ISETCam's Sony IMX363.
    #[arg(long, value_name = "NAME")]
    pub sensor_model: Option<String>,
    /// Sensor: colour filter array, rggb, bggr, grbg, gbrg or mono.
    #[arg(long, value_name = "PATTERN")]
    pub cfa: Option<String>,
    /// Sensor: exposure time in seconds.
    #[arg(long, value_name = "S")]
    pub exposure_time: Option<f64>,
    /// Sensor: ISO speed; the analogue gain is ISO over the sensor's base ISO.
    #[arg(long)]
    pub iso: Option<f64>,
    /// Sensor: luminance in cd/m² of a white emitter of value 1 in the scene (72983 reads emission
    /// as W/(m² sr nm)).
    #[arg(long, value_name = "CD_M2")]
    pub white_luminance: Option<f64>,
    /// Sensor: read noise, electrons RMS.
    #[arg(long, value_name = "E")]
    pub read_noise: Option<f64>,
    /// Sensor: full-well capacity per µm² of pixel, electrons (a pixel's is this times its area,
    /// the sensor's size over the image's squared).
    #[arg(long, value_name = "E")]
    pub full_well_per_um2: Option<f64>,
    /// Sensor: dark current per µm² of pixel, electrons per second.
    #[arg(long, value_name = "E_PER_S")]
    pub dark_current_per_um2: Option<f64>,
    /// Sensor: dark signal non-uniformity, electrons RMS (a fixed offset per pixel).
    #[arg(long, value_name = "E")]
    pub dsnu: Option<f64>,
    /// Sensor: photo-response non-uniformity, RMS of the pixels' relative gains (0.01 is 1%).
    #[arg(long, value_name = "FRACTION")]
    pub prnu: Option<f64>,
    /// Sensor: bits per digital number, 1 to 16.
    #[arg(long, value_name = "BITS")]
    pub bit_depth: Option<u32>,
    /// Sensor: digital number of no light.
    #[arg(long, value_name = "DN")]
    pub black_level: Option<u32>,
    /// Sensor: quantum efficiency at the most sensitive channel's peak, 0 to 1.
    #[arg(long, value_name = "QE")]
    pub peak_qe: Option<f64>,
    /// Sensor: seed of the temporal noise; another seed is another frame of the same sensor.
    #[arg(long)]
    pub frame_seed: Option<u64>,
    /// Sensor: seed of the fixed patterns (PRNU, DSNU); another seed is another sensor of the model.
    #[arg(long)]
    pub fixed_pattern_seed: Option<u64>,
    /// Sensor: meter the exposure time and ISO from the render (a camera's program mode: the mean
    /// green to 18% of the full well at the base ISO; past --max-exposure-time the ISO rises, up to
    /// --max-iso).
    #[arg(long)]
    pub auto_exposure: bool,
    /// Sensor, auto exposure: the longest exposure time, s.
    #[arg(long, value_name = "S")]
    pub max_exposure_time: Option<f64>,
    /// Sensor, auto exposure: the highest ISO.
    #[arg(long, value_name = "ISO")]
    pub max_iso: Option<f64>,
    /// Sensor: the light the camera is balanced for: daylight (D65), grey-world, or a black body
    /// such as 2856K (tungsten).
    #[arg(long, value_name = "WB")]
    pub white_balance: Option<String>,
    /// Sensor: how the developed image is demosaicked: mhc (Malvar-He-Cutler) or bilinear.
    #[arg(long, value_name = "METHOD")]
    pub demosaic: Option<String>,
    /// Sensor: the developed image's tone curve: linear or filmic.
    #[arg(long, value_name = "CURVE")]
    pub tone_curve: Option<String>,
}

impl SensorFlags {
    /// The sensor the flags describe, `None` when no flag asks for one.
    pub fn description(&self) -> Result<Option<SensorDescription>> {
        let described = SensorDescription {
            model: self.sensor_model.clone(),
            cfa: self.cfa.as_deref().map(Cfa::parse).transpose()?,
            exposure_time_s: self.exposure_time,
            iso: self.iso,
            white_luminance_cd_m2: self.white_luminance,
            read_noise_e: self.read_noise,
            full_well_e_per_um2: self.full_well_per_um2,
            dark_current_e_per_s_um2: self.dark_current_per_um2,
            dsnu_e: self.dsnu,
            prnu: self.prnu,
            bit_depth: self.bit_depth,
            black_level_dn: self.black_level,
            peak_qe: self.peak_qe,
            frame_seed: self.frame_seed,
            fixed_pattern_seed: self.fixed_pattern_seed,
            white_balance: self.white_balance.as_deref().map(WhiteBalance::parse).transpose()?,
            demosaic: self.demosaic.as_deref().map(Demosaic::parse).transpose()?,
            tone_curve: self.tone_curve.as_deref().map(ToneCurve::parse).transpose()?,
            auto_exposure: self.auto_exposure.then_some(true),
            max_exposure_time_s: self.max_exposure_time,
            max_iso: self.max_iso,
        };
        Ok((described != SensorDescription::default()).then_some(described))
    }
}

/// The realistic camera's lens flags (`render` and `autofocus`).
#[derive(Args, Debug)]
pub struct LensFlags {
    /// Realistic camera: a shipped lens (`lenspath lens --list`: dgauss50, triplet50, tessar100, nikon-z14, lentil:0001 ...), a Zemax .zmx file or a lens table file.
    #[arg(long)]
    pub lens: Option<String>,
    /// Realistic camera: sensor WIDTHxHEIGHT in mm; its width is kept and its height follows the
    /// image aspect.
    #[arg(long, value_parser = parse_sensor)]
    pub sensor: Option<SensorSize>,
    /// Realistic camera: stop down to this f-number (default: wide open).
    #[arg(long, value_name = "N")]
    pub fstop: Option<f64>,
    /// Realistic camera: metres per scene unit, since lenses are in mm.
    #[arg(long, value_name = "M")]
    pub scene_unit: Option<f64>,
    /// Realistic camera: exposure normalisation: normalized (the image centre reads the scene
    /// radiance at any f-number) or physical (stopping down darkens the image by (N2/N1)^2, as on
    /// a real camera).
    #[arg(long, value_parser = named::<Radiometry>())]
    pub radiometry: Option<Radiometry>,
    /// Realistic camera: every glass at its d-line index, so the lens shows no colour (and a
    /// little less colour noise, no tracing back per wavelength; default: glasses disperse).
    #[arg(long)]
    pub no_dispersion: bool,
    /// Realistic camera: whether the pupil diffracts, each film point spread by the aperture's
    /// Fraunhofer pattern at the ray's wavelength and the lens's working f-number (the Airy disc
    /// of a circle, the starburst of blades; default: the scene file's, else off).
    #[arg(long, value_name = "on|off", value_parser = clap::builder::BoolishValueParser::new())]
    pub diffraction: Option<bool>,
    /// Realistic camera with an anamorphic lens: stretch the image's width by the lens's
    /// squeeze, as projected (default: as the sensor records it, squeezed).
    #[arg(long)]
    pub desqueeze: bool,
}

impl LensFlags {
    /// The realistic camera the flags describe; what they leave out is the
    /// scene file's, else the library's default ([`lenspath::setup::realistic_settings`]).
    pub fn description(&self) -> Result<RealisticDescription> {
        Ok(RealisticDescription {
            lens: self.lens.as_deref().map(LensPrescription::load).transpose()?,
            sensor_width_mm: self.sensor.map(|s| s.width_mm),
            f_number: self.fstop,
            scene_unit_m: self.scene_unit,
            radiometry: self.radiometry,
            dispersion: self.no_dispersion.then_some(false),
            diffraction: self.diffraction,
            desqueeze: self.desqueeze.then_some(true),
            ..RealisticDescription::default()
        })
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
    /// The shape the flags ask for; `None` when they ask for none (the
    /// scene file's, else the circle).
    pub fn shape(&self) -> Result<Option<ApertureShape>> {
        let with_flag = |e: Error, flag: &str| match e {
            Error::InvalidArgument(m) => Error::InvalidArgument(format!("{flag}: {m}")),
            other => other,
        };
        if let Some(path) = &self.aperture_mask {
            return lenspath::io::image::read_aperture_mask(path).map(Some);
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
            (None, None) => return Ok(None),
        };
        // Checks the values (blade count, curvature, ratio) now, before any rendering.
        Aperture::new(&shape).map_err(|e| with_flag(e, if self.star.is_some() { "--star" } else { "--blades" }))?;
        Ok(Some(shape))
    }
}
