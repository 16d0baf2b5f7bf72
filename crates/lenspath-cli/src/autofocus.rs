//! `lenspath autofocus`: focus the realistic camera on an image patch. (The
//! evaluation of every strategy against ground truth is a bench tool:
//! bench/autofocus-evaluation.)

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

use clap::Args;
use lenspath::accel::BvhSettings;
use lenspath::autofocus::plot::{focus_curve_svg, Series};
use lenspath::autofocus::{AutofocusResult, FocusMeasure, Focuser, SensorSignal, Strategy};
use lenspath::camera::{LensFocus, RealisticCameraSettings};
use lenspath::defaults;
use lenspath::film::NormalizedRect;
use lenspath::fs::{check_writable, write_text};
use lenspath::io::image::{check_output_path, write_image_with_header};
use lenspath::names::Named;
use lenspath::render::{render, RenderSettings};
use lenspath::setup::{resolve_autofocus, AutofocusOverrides, CameraSettings, RenderSetup};
use lenspath::{Error, Result};
use serde_json::json;

use crate::flags::{named, parse_patch, parse_resolution, LensFlags, Resolution, SceneArgs, SensorFlags};
use crate::Outcome;

/// Options of `lenspath autofocus`.
#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct AutofocusArgs {
    #[command(flatten)]
    scene: SceneArgs,
    #[command(flatten)]
    lens: LensFlags,
    #[command(flatten)]
    sensor: SensorFlags,
    /// Sensor: what contrast autofocus reads of its frames: raw-green (the green pixels, undeveloped)
    /// or luminance (the developed frame's).
    #[arg(long, value_name = "SIGNAL", value_parser = named::<SensorSignal>())]
    af_signal: Option<SensorSignal>,
    /// The patch to focus on, X,Y,W,H in fractions of the image (0 to 1), such as 0.55,0.7,0.1,0.12.
    #[arg(long, value_name = "X,Y,W,H", value_parser = parse_patch)]
    patch: NormalizedRect,
    /// Focus measure.
    #[arg(long, value_parser = named::<FocusMeasure>())]
    metric: Option<FocusMeasure>,
    /// Search: sweep, early-exit, fast, rangefinder (probe rays and the lens model) or depth (range finder, then a short contrast refinement).
    #[arg(long, value_parser = named::<Strategy>())]
    strategy: Option<Strategy>,
    /// early-exit: stop after this many steps without a new best.
    #[arg(long)]
    patience: Option<usize>,
    /// Samples per pixel of each patch render.
    #[arg(long)]
    spp: Option<u32>,
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, value_parser = parse_resolution)]
    res: Option<Resolution>,
    /// Maximum path depth of the patch renders.
    #[arg(long)]
    max_depth: Option<u32>,
    /// Seed of the patch renders (and of --render).
    #[arg(long)]
    seed: Option<u32>,
    /// Worker threads, for the BVH build and the rendering (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// Also write the focus curve (a sweep) with the strategy's evaluations as SVG.
    #[arg(long, value_name = "FILE")]
    plot: Option<PathBuf>,
    /// Also render the full image focused there (.png or .exr).
    #[arg(long, value_name = "FILE")]
    render: Option<PathBuf>,
    /// Samples per pixel of --render.
    #[arg(long, default_value_t = defaults::SPP)]
    render_spp: u32,
}

/// "autofocus (fast, sml): sensor 52.634 mm behind the stop, in focus at 3.412 m; 21 patch renders, ..."
pub fn summary_line(r: &AutofocusResult, metric: FocusMeasure, scene_unit_m: f64) -> String {
    let distance = match r.focus_distance {
        Some(d) => format!(
            "in focus at {:.3} m ({d:.4} scene units) from the sensor",
            d * scene_unit_m
        ),
        None => "focused beyond infinity".to_string(),
    };
    let exposure = match (r.exposure_time_s, r.iso) {
        (Some(t), Some(iso)) => format!(", frames at {t:.4} s and ISO {iso:.0}"),
        _ => String::new(),
    };
    let mut line = format!(
        "autofocus ({}, {}): sensor {:.4} mm behind the stop, {distance}; {} patch renders, {} light fields, {:.2} M camera rays, {:.2} s{exposure}",
        r.strategy,
        metric.name(),
        r.sensor_depth_mm,
        r.patch_renders(),
        r.light_fields,
        r.camera_rays as f64 / 1e6,
        r.seconds
    );
    for fallback in &r.fallbacks {
        line += &format!("\n  not as '{}' says: {fallback}", r.strategy);
    }
    line
}

/// Runs `lenspath autofocus`.
pub fn run(args: AutofocusArgs) -> Result<Outcome> {
    if let Some(path) = &args.render {
        check_output_path(path)?;
    }
    if let Some(path) = &args.plot {
        check_writable(path)?;
    }
    let (scene_name, scene, options) = args.scene.load()?;
    let view = scene
        .view
        .ok_or_else(|| Error::InvalidArgument("the scene has no camera".into()))?;
    let patch = args.patch;
    let search = resolve_autofocus(&options, &view, patch, &overrides(&args)?)?;
    let compiled = scene.compile_on(&BvhSettings::default(), args.threads)?;
    let (width, height) = (search.settings.width, search.settings.height);
    let lens = search.settings.camera.clone();
    let (strategy, measure, seed) = (search.strategy, search.settings.measure, search.settings.seed);
    let mut focuser = Focuser::new(&compiled, view.pose, search.settings)?;
    let result = focuser.run(strategy)?;
    if args.json {
        let out = json!({
            "sensor_depth_mm": result.sensor_depth_mm,
            // Deprecated: the old name of `sensor_depth_mm`, kept for scripts that read it.
            "sensor_position_mm": result.sensor_depth_mm,
            "focus_distance": result.focus_distance,
            "focus_distance_m": result.focus_distance.map(|d| d * lens.scene_unit_m),
            "metric": measure.name(),
            "strategy": result.strategy,
            "evaluations": result.evaluations.len(),
            "patch_renders": result.patch_renders(),
            "light_fields": result.light_fields,
            "camera_rays": result.camera_rays,
            "seconds": result.seconds,
            "exposure_time_s": result.exposure_time_s,
            "iso": result.iso,
            "fallbacks": result.fallbacks,
            "depth_of_focus_mm": focuser.depth_of_focus_mm(result.sensor_depth_mm),
            "points": result.evaluations,
        });
        println!("{}", serde_json::to_string_pretty(&out).expect("JSON serializes"));
    } else {
        println!("{}", summary_line(&result, measure, lens.scene_unit_m));
    }
    if let Some(path) = &args.plot {
        let sweep = if strategy == Strategy::Sweep {
            result.clone()
        } else {
            focuser.run(Strategy::Sweep)?
        };
        let title = format!("{} on {} ({})", result.strategy, measure.name(), patch_label(&patch));
        let svg = focus_curve_svg(
            &title,
            &[
                Series {
                    label: "sweep",
                    points: &sweep.evaluations,
                    chosen_mm: Some(sweep.sensor_depth_mm),
                    line: true,
                },
                Series {
                    label: result.strategy,
                    points: &result.evaluations,
                    chosen_mm: Some(result.sensor_depth_mm),
                    line: false,
                },
            ],
            None,
        );
        write_text(path, &svg)?;
    }
    if let Some(path) = &args.render {
        let settings = RenderSettings {
            width,
            height,
            spp: args.render_spp,
            seed,
            threads: args.threads,
            ..Default::default()
        };
        // As `lenspath render` would set it up, so the EXR carries the same
        // header (lens, f-number, the sensor position found, the settings).
        let setup = RenderSetup {
            settings,
            camera: CameraSettings::Realistic(RealisticCameraSettings {
                focus: LensFocus::SensorDepthMm(result.sensor_depth_mm),
                ..lens
            }),
            pose: view.pose,
            sensor: None,
        };
        let camera = setup.build_camera()?;
        let output = render(
            &compiled,
            camera.as_ref(),
            &setup.settings,
            &|_, _| {},
            &AtomicBool::new(false),
        )?;
        let header = setup.image_header(&scene_name, None)?;
        write_image_with_header(path, &output.image, 0.0, &header)?;
        eprintln!("rendered {}x{} focused there -> {}", width, height, path.display());
    }
    Ok(Outcome::Done)
}

/// The search the flags ask for.
fn overrides(args: &AutofocusArgs) -> Result<AutofocusOverrides> {
    Ok(AutofocusOverrides {
        resolution: args.res.map(|r| (r.width, r.height)),
        spp: args.spp,
        max_depth: args.max_depth,
        seed: args.seed,
        threads: args.threads,
        metric: args.metric,
        strategy: args.strategy,
        patience: args.patience,
        camera: args.lens.description()?,
        sensor: args.sensor.description()?,
        sensor_signal: args.af_signal,
    })
}

fn patch_label(p: &NormalizedRect) -> String {
    format!("patch {:.2},{:.2},{:.2},{:.2}", p.x, p.y, p.width, p.height)
}
