//! `lenspath render`.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

use clap::Args;
use lenspath::accel::BvhSettings;
use lenspath::autofocus::Focuser;
use lenspath::camera::LensFocus;
use lenspath::film::{Filter, NormalizedRect, PixelRect};
use lenspath::integrator::{guiding_can_help, IntegratorKind};
use lenspath::io::checkpoint::{resume_state, write_checkpoint};
use lenspath::io::image::{check_output_path, write_image_with_header};
use lenspath::render::{guide_map_at_pixel, render_from, train_guide, Accumulation, Checkpoints, Continuation};
use lenspath::sampling::SamplerKind;
use lenspath::sensor::develop::develop;
use lenspath::sensor::raw_file::{write_raw, RawFormat};
use lenspath::sensor::{RawFrame, SensorDescription};
use lenspath::setup::{
    autofocus_before_render, resolve, CameraDescription, CameraKind, CameraSettings, RealisticDescription,
    RenderOverrides, SceneHash,
};
use lenspath::{Error, Result};

use crate::flags::{
    named, parse_crop, parse_duration, parse_image_point, parse_patch, parse_resolution, ApertureFlags, LensFlags,
    Resolution, SceneArgs, SensorFlags,
};
use crate::guide_map::{write_guide_map, MAP_SIZE};
use crate::progress::Progress;
use crate::Outcome;

/// Options of `lenspath render`.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct RenderArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Samples per pixel.
    #[arg(long)]
    spp: Option<u32>,
    /// Shadow rays per area or environment light at every non-specular hit (point, spot and directional lights take one).
    #[arg(long)]
    light_samples: Option<u32>,
    /// Maximum path depth, 1 = direct lighting only.
    #[arg(long)]
    max_depth: Option<u32>,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, value_parser = parse_resolution)]
    res: Option<Resolution>,
    /// Worker threads, for the BVH build and the rendering (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Seed of the sample sequences; the same seed gives the same image.
    #[arg(long)]
    seed: Option<u32>,
    /// Sample sequence: sobol (Owen-scrambled Sobol points, less noise at the same samples per
    /// pixel) or independent (PCG32 random numbers, as pbrt's and Mitsuba's `independent`).
    #[arg(long, value_parser = named::<SamplerKind>())]
    sampler: Option<SamplerKind>,
    /// Integrator: path (next-event estimation, MIS, Russian roulette), or guided: the path tracer
    /// guided by a guide of where light comes from, trained first (for caustics and light through
    /// glass or off metal; docs/guiding.md). A scene with no glass, mirror or smooth metal renders
    /// guided as with the path tracer, without training.
    #[arg(long, value_parser = named::<IntegratorKind>())]
    integrator: Option<IntegratorKind>,
    /// Guided renders: also write what the guide learned at the surface seen at --guide-at, its
    /// density over the sphere of directions in an equal-area disc (the normal at the centre, the
    /// horizon a circle, the camera's side at the bottom): .png in false colour, .exr the density
    /// per steradian (docs/guiding.md).
    #[arg(long, value_name = "FILE", requires = "guide_at")]
    guide_map: Option<PathBuf>,
    /// The point X,Y of the image whose surface --guide-map shows, as fractions of the image from
    /// its top left (0 to 1), such as 0.18,0.71.
    #[arg(long, value_name = "X,Y", value_parser = parse_image_point, requires = "guide_map")]
    guide_at: Option<(f64, f64)>,
    /// Render at this one wavelength (360-830 nm): a grey image of the spectral radiance there (default: colour).
    #[arg(long, value_name = "NM")]
    wavelength_nm: Option<f32>,
    /// Output image: .png (sRGB) or .exr (linear RGB + Z).
    #[arg(long, default_value = "render.png")]
    out: PathBuf,
    /// Exposure in stops applied to PNG output.
    #[arg(long, default_value_t = 0.0)]
    exposure: f32,
    /// Camera model: pinhole (everything in focus), thin-lens (depth of field from
    /// --aperture-radius and --focus-distance) or realistic (a real lens prescription, --lens,
    /// traced surface by surface).
    #[arg(long, value_parser = named::<CameraKind>())]
    camera: Option<CameraKind>,
    #[command(flatten)]
    lens: LensFlags,
    #[command(flatten)]
    aperture: ApertureFlags,
    #[command(flatten)]
    sensor: SensorFlags,
    /// Sensor: write the raw frame here: .dng (readable by raw developers), or .png / .tif (the
    /// 16-bit mosaic of digital numbers).
    #[arg(long, value_name = "FILE")]
    raw: Option<PathBuf>,
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
    #[arg(long)]
    aperture_radius: Option<f32>,
    /// Focus distance from the sensor, scene units (default: the scene's subject distance).
    #[arg(long)]
    focus_distance: Option<f32>,
    /// Pixel reconstruction filter: box (each pixel averages its own area) or gaussian (pbrt's:
    /// sigma 0.5 px, radius 1.5 px).
    #[arg(long, value_parser = named::<Filter>())]
    filter: Option<Filter>,
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

/// The render the flags ask for: each flag maps onto the library's
/// [`RenderOverrides`]; what a flag leaves out is the scene file's, else the
/// library's default.
fn overrides(args: &RenderArgs) -> Result<RenderOverrides> {
    let aperture = args.aperture.shape()?;
    let kind = args.camera.unwrap_or_default();
    let camera = match kind {
        CameraKind::Pinhole => {
            if aperture.is_some() {
                return Err(Error::InvalidArgument(
                    "--blades, --star and --aperture-mask shape a lens's aperture; a pinhole has none (use --camera thin-lens or realistic)".into(),
                ));
            }
            CameraDescription::Pinhole { fov_y_deg: args.fov }
        }
        CameraKind::ThinLens => CameraDescription::ThinLens {
            fov_y_deg: args.fov,
            aperture_radius: args.aperture_radius,
            focus_distance: args.focus_distance,
            aperture,
        },
        CameraKind::Realistic => {
            if args.fov.is_some() {
                return Err(Error::InvalidArgument(
                    "--fov is for --camera pinhole or thin-lens; through a real lens the field of view comes from --lens and --sensor"
                        .into(),
                ));
            }
            let focus = match (args.sensor_depth, args.focus_distance) {
                (Some(mm), _) => Some(LensFocus::SensorDepthMm(mm)),
                (None, Some(d)) => Some(LensFocus::Distance(f64::from(d))),
                (None, None) => None,
            };
            CameraDescription::Realistic(RealisticDescription {
                focus,
                aperture,
                ..args.lens.description()?
            })
        }
    };
    if args.autofocus.is_some() && kind != CameraKind::Realistic {
        return Err(Error::InvalidArgument("--autofocus needs --camera realistic".into()));
    }
    Ok(RenderOverrides {
        resolution: args.res.map(|r| (r.width, r.height)),
        spp: args.spp,
        max_depth: args.max_depth,
        light_samples: args.light_samples,
        seed: args.seed,
        sampler: args.sampler,
        integrator: args.integrator,
        filter: args.filter,
        threads: args.threads,
        crop: args.crop,
        depth: Some(true),
        wavelength_nm: args.wavelength_nm,
        camera,
        // --raw alone asks for the default sensor.
        sensor: match args.sensor.description()? {
            None if args.raw.is_some() => Some(SensorDescription::default()),
            described => described,
        },
    })
}

/// Runs `lenspath render`.
pub fn run(args: RenderArgs) -> Result<Outcome> {
    check_output_path(&args.out)?;
    if let Some(raw) = &args.raw {
        RawFormat::of(raw)?;
        lenspath::fs::check_writable(raw)?;
    }
    if !args.exposure.is_finite() {
        return Err(Error::InvalidArgument("--exposure must be a finite number".into()));
    }
    let (scene_name, scene, options) = args.scene.load()?;
    let view = scene
        .view
        .ok_or_else(|| Error::InvalidArgument(format!("scene '{scene_name}' has no camera")))?;
    let mut setup = resolve(&options, &view, &overrides(&args)?)?;
    let checkpoint_path = args.checkpoint.clone().or_else(|| args.resume.clone());
    if args.checkpoint_every.is_some() && checkpoint_path.is_none() {
        return Err(Error::InvalidArgument(
            "--checkpoint-every needs --checkpoint FILE (or --resume FILE)".into(),
        ));
    }
    if let Some(every) = args.checkpoint_every {
        lenspath::render::check_checkpoint_interval(every)
            .map_err(|e| Error::InvalidArgument(format!("--checkpoint-every: {e}")))?;
    }
    if let Some(path) = &checkpoint_path {
        if same_file(path, &args.out) {
            return Err(Error::InvalidArgument(format!(
                "{} is both the checkpoint and the output image; give them different names",
                path.display()
            )));
        }
    }
    if let Some(path) = &args.checkpoint {
        lenspath::fs::check_writable(path)?;
    }
    if let Some(path) = &args.guide_map {
        check_output_path(path)?;
        if setup.settings.integrator.kind() != IntegratorKind::Guided {
            return Err(Error::InvalidArgument(
                "--guide-map shows a guided render's guide; add --integrator guided".into(),
            ));
        }
    }
    // Hashed only for checkpoints: a million triangles take a tenth of a second.
    let scene_hash = checkpoint_path.is_some().then(|| SceneHash::of(&scene));
    let compiled = scene.compile_on(&BvhSettings::default(), args.threads)?;
    if let Some(patch) = args.autofocus {
        let search = autofocus_before_render(&setup, patch)?;
        let (scene_unit_m, measure) = (search.settings.camera.scene_unit_m, search.settings.measure);
        let result = Focuser::new(&compiled, search.pose, search.settings)?.run(search.strategy)?;
        eprintln!("{}", crate::autofocus::summary_line(&result, measure, scene_unit_m));
        if let CameraSettings::Realistic(camera) = &mut setup.camera {
            camera.focus = LensFocus::SensorDepthMm(result.sensor_depth_mm);
        }
    }
    let camera = setup.build_camera()?;
    let settings = setup.settings;
    // The checkpoint file and this render's fingerprint, when checkpointing.
    let checkpointing: Option<(PathBuf, String)> = checkpoint_path
        .zip(scene_hash)
        .map(|(path, hash)| (path, setup.fingerprint(hash, &scene_name)));
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
    if settings.integrator.kind() == IntegratorKind::Guided && !guiding_can_help(&compiled) {
        if args.guide_map.is_some() {
            return Err(Error::InvalidArgument(format!(
                "--guide-map: guiding is off for {scene_name} (nothing in it is glass, a mirror or smooth metal), so there is no guide to show"
            )));
        }
        eprintln!(
            "guiding off: nothing in {scene_name} is glass, a mirror or smooth metal, so light samples find all its light; \
             rendering with the path tracer, without training a guide"
        );
    }
    let total = u64::from(settings.width) * u64::from(settings.height) * u64::from(settings.spp);
    let progress = Progress::new(&format!("render {scene_name}"), total);
    let mut save;
    let checkpoints = match &checkpointing {
        Some((path, fingerprint)) => {
            lenspath::fs::remove_stale_temporaries(path);
            // A failed save (a full disk, a folder gone) costs the checkpoint,
            // not the render: it goes on and writes its image.
            save = |state: &Accumulation| {
                if let Err(e) = write_checkpoint(path, fingerprint, state) {
                    progress.say(&format!("warning: checkpoint not saved ({e}); the render goes on"));
                }
                Ok(())
            };
            Some(Checkpoints {
                every: args.checkpoint_every.unwrap_or(Duration::from_secs(60)),
                save: &mut save,
            })
        }
        None => None,
    };
    // With a map to write, the guide is trained here, once, for the render and the map.
    let trained_at = std::time::Instant::now();
    let guide = match &args.guide_map {
        // None only when stopped: the render then stops at once too.
        Some(_) => train_guide(&compiled, camera.as_ref(), &settings, &cancel)?,
        None => None,
    };
    // Made before the render, so that a pixel it cannot show fails before any output is written.
    let pixel = args.guide_at.map(|point| settings.pixel_at(point)).transpose()?;
    let map = match (&guide, pixel) {
        (Some(guide), Some(pixel)) => Some(guide_map_at_pixel(
            &compiled,
            camera.as_ref(),
            &settings,
            guide,
            pixel,
            MAP_SIZE,
        )?),
        _ => None,
    };
    if let Some(guide) = &guide {
        progress.say(&format!(
            "trained the guide in {:.3} s: {} regions, {} directional leaves",
            trained_at.elapsed().as_secs_f64(),
            guide.region_count(),
            guide.directional_leaf_count()
        ));
    }
    let from = Continuation {
        start,
        guide: guide.as_ref(),
        checkpoints,
    };
    let output = render_from(
        &compiled,
        camera.as_ref(),
        &settings,
        from,
        &|d, t| progress.update(d, t),
        &cancel,
    )?;
    progress.finish();
    if let (Some(map), Some(path), Some(pixel)) = (&map, &args.guide_map, pixel) {
        write_guide_map(path, map)?;
        eprintln!(
            "guide at pixel ({}, {}): {} directional leaves, {:.1}% of its samples above the surface, \
             density up to {:.3} /sr (uniform: {:.3}) -> {}",
            pixel.0,
            pixel.1,
            map.leaves,
            100.0 * map.share_above_surface,
            map.max_density_per_sr(),
            1.0 / (4.0 * std::f32::consts::PI),
            path.display()
        );
    }
    // Through a sensor the film holds its channels' electron rates: the
    // image written is the raw frame developed.
    match setup.capture(camera.as_ref(), &output.image)? {
        Some((frame, development)) => {
            if let Some(raw) = &args.raw {
                write_raw(raw, &frame)?;
            }
            let header = setup.image_header(&scene_name, Some(&frame.exposure))?;
            write_image_with_header(&args.out, &develop(&frame, &development), args.exposure, &header)?;
            eprintln!("{}", exposure_line(&frame));
        }
        None => {
            let header = setup.image_header(&scene_name, None)?;
            write_image_with_header(&args.out, &output.image, args.exposure, &header)?;
        }
    }

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

/// How the frame is exposed: its median and the share of clipped pixels.
/// An exposure time as a photographer writes it: 1/250, 0.5, 2.
fn exposure_time(seconds: f64) -> String {
    if seconds < 0.5 {
        format!("1/{:.0}", 1.0 / seconds)
    } else {
        format!("{seconds:.3}")
    }
}

fn exposure_line(frame: &RawFrame) -> String {
    let mut sorted = frame.dn.clone();
    sorted.sort_unstable();
    let median = sorted[sorted.len() / 2];
    let clipped = frame
        .dn
        .iter()
        .filter(|&&v| u32::from(v) >= frame.white_level_dn)
        .count();
    format!(
        "sensor {}: {} s at ISO {:.0}, median {} DN (black {}, white {}), {:.1}% of pixels clipped, {:.3} e-/DN",
        frame.exposure.sensor_name,
        exposure_time(frame.exposure.exposure_time_s),
        frame.exposure.iso,
        median,
        frame.black_level_dn,
        frame.white_level_dn,
        100.0 * clipped as f64 / frame.dn.len() as f64,
        frame.electrons_per_dn
    )
}

/// True when `a` and `b` name the same file (existing or not).
fn same_file(a: &Path, b: &Path) -> bool {
    let resolved = |p: &Path| p.canonicalize().or_else(|_| std::path::absolute(p));
    matches!((resolved(a), resolved(b)), (Ok(a), Ok(b)) if a == b)
}
