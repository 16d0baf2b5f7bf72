//! `lenspath render`.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use clap::{Args, ValueEnum};
use lenspath::accel::BvhSettings;
use lenspath::builtin::{builtin_scene, DEFAULT_MESH_TRIANGLES};
use lenspath::camera::{Camera, LensFocus, PerspectiveCamera, Radiometry, RealisticCamera, RealisticCameraSettings};
use lenspath::film::Filter;
use lenspath::integrator::PathSettings;
use lenspath::io::image::{check_output_path, write_image};
use lenspath::io::{load_scene, SceneOptions};
use lenspath::lens::LensPrescription;
use lenspath::render::{render, PixelRect, RenderSettings};
use lenspath::{Error, Result};

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

/// Image size as WIDTHxHEIGHT.
#[derive(Clone, Copy, Debug)]
pub struct Resolution {
    pub width: u32,
    pub height: u32,
}

fn parse_resolution(s: &str) -> std::result::Result<Resolution, String> {
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

/// Options of `lenspath render`.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct RenderArgs {
    /// Scene file: .dae (COLLADA, CS184), .obj, .ply, .gltf/.glb or .toml (lenspath). Default: the
    /// built-in scene named by --scene.
    file: Option<PathBuf>,
    /// Built-in scene: cornell-spheres, cornell-empty or cornell-mesh.
    #[arg(long, default_value = "cornell-spheres", conflicts_with = "file")]
    scene: String,
    /// Triangles of the procedural mesh in cornell-mesh.
    #[arg(long, default_value_t = DEFAULT_MESH_TRIANGLES)]
    mesh_triangles: usize,
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
    /// Output image: .png (sRGB) or .exr (linear RGB + Z).
    #[arg(long, default_value = "render.png")]
    out: PathBuf,
    /// Exposure in stops applied to PNG output.
    #[arg(long, default_value_t = 0.0)]
    exposure: f32,
    /// Camera model.
    #[arg(long, value_enum, default_value = "realistic")]
    camera: CameraKind,
    /// Realistic camera: built-in lens (dgauss50, wide22, tele250, fisheye10) or a lens table file
    /// [default: the scene file's, else dgauss50].
    #[arg(long)]
    lens: Option<String>,
    /// Realistic camera: sensor WIDTHxHEIGHT in mm; its width is kept and its height follows the
    /// image aspect [default: the scene file's, else 36x24].
    #[arg(long, value_parser = parse_sensor)]
    sensor: Option<SensorSize>,
    /// Realistic camera: put the sensor this many mm behind the aperture stop instead of focusing by distance.
    #[arg(long, value_name = "MM", conflicts_with = "focus_distance")]
    sensor_depth: Option<f64>,
    /// Realistic camera: stop down to this f-number (default: wide open).
    #[arg(long, value_name = "N")]
    fstop: Option<f64>,
    /// Realistic camera: metres per scene unit, since lenses are in mm [default: the scene file's, else 1].
    #[arg(long, value_name = "M")]
    scene_unit: Option<f64>,
    /// Realistic camera: exposure normalisation.
    #[arg(long, value_enum, default_value = "normalized")]
    radiometry: RadiometryKind,
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
}

/// Runs `lenspath render`.
pub fn run(args: RenderArgs) -> Result<Outcome> {
    check_output_path(&args.out)?;
    if !args.exposure.is_finite() {
        return Err(Error::InvalidArgument("--exposure must be a finite number".into()));
    }
    let (scene_name, scene, options) = match &args.file {
        Some(path) => {
            let loaded = load_scene(path)?;
            for (what, n) in loaded.warnings.iter() {
                eprintln!(
                    "warning: {what}{}",
                    if n > 1 { format!(" (×{n})") } else { String::new() }
                );
            }
            (path.display().to_string(), loaded.scene, loaded.options)
        }
        None => (
            args.scene.clone(),
            builtin_scene(&args.scene, args.mesh_triangles)?,
            SceneOptions::default(),
        ),
    };
    // Flags win over the scene file, which wins over the defaults.
    let (width, height) = args
        .res
        .map(|r| (r.width, r.height))
        .or(options.resolution)
        .unwrap_or((640, 480));
    let file_lens = options.lens.clone().unwrap_or_default();
    let settings = RenderSettings {
        width,
        height,
        spp: args.spp.or(options.spp).unwrap_or(64),
        path: PathSettings {
            max_depth: args.max_depth.or(options.max_depth).unwrap_or(16),
            light_samples: args.light_samples.or(options.light_samples).unwrap_or(1),
        },
        seed: args.seed.or(options.seed).unwrap_or(0),
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
    let camera: Box<dyn Camera> = match args.camera {
        CameraKind::Pinhole => Box::new(PerspectiveCamera::pinhole(
            view.pose,
            fov,
            settings.width,
            settings.height,
        )),
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
            Box::new(PerspectiveCamera::thin_lens(
                view.pose,
                fov,
                settings.width,
                settings.height,
                args.aperture_radius,
                focus,
            ))
        }
        CameraKind::Realistic => {
            let lens =
                LensPrescription::load(args.lens.as_deref().or(file_lens.lens.as_deref()).unwrap_or("dgauss50"))?;
            let focus = match args.sensor_depth {
                Some(mm) => LensFocus::SensorPositionMm(mm),
                None => LensFocus::Distance(
                    args.focus_distance
                        .map(f64::from)
                        .or(file_lens.focus_distance)
                        .unwrap_or(f64::from(view.focus_distance)),
                ),
            };
            let width_mm = args
                .sensor
                .map(|s| s.width_mm)
                .or(file_lens.sensor_mm.map(|(w, _)| w))
                .unwrap_or(36.0);
            let height_mm = width_mm * f64::from(settings.height) / f64::from(settings.width);
            let camera = RealisticCamera::new(
                view.pose,
                settings.width,
                settings.height,
                &RealisticCameraSettings {
                    lens,
                    sensor_mm: (width_mm, height_mm),
                    focus,
                    f_number: args.fstop.or(file_lens.f_number),
                    scene_unit_m: args.scene_unit.or(options.scene_unit_m).unwrap_or(1.0),
                    radiometry: match args.radiometry {
                        RadiometryKind::Normalized => Radiometry::Normalized,
                        RadiometryKind::Physical => Radiometry::Physical,
                    },
                },
            )?;
            Box::new(camera)
        }
    };

    let compiled = scene.compile(&BvhSettings::default())?;
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
    let output = render(
        &compiled,
        camera.as_ref(),
        &settings,
        &|d, t| progress.update(d, t),
        &cancel,
    )?;
    progress.finish();
    write_image(&args.out, &output.image, args.exposure)?;

    let s = &output.stats;
    let interrupted = s.cancelled;
    if interrupted {
        eprintln!(
            "interrupted: saved {} with {} of {} samples per pixel",
            args.out.display(),
            output.image.spp_min,
            settings.spp
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
