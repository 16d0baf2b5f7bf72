//! `lenspath`: the command-line front end of the lenspath renderer, as a
//! library so that the Python package's `lenspath` command runs the same
//! code ([`run`]); `src/main.rs` is the binary.
//!
//! Every error ends in one line on stderr and exit code 2; an interrupted
//! render writes what it has and exits with 130.

mod autofocus;
mod bench;
mod bokeh;
mod flags;
mod glass;
mod guide_map;
mod info;
mod lens;
mod progress;
mod render;
mod view;

use clap::{Args, CommandFactory, FromArgMatches, Parser, Subcommand};
use lenspath::autofocus::{FocusMeasure, SensorSignal, Strategy};
use lenspath::integrator::IntegratorKind;
use lenspath::names::Named;
use lenspath::sampling::SamplerKind;

/// A physically based path tracer whose camera is a real lens.
#[derive(Parser)]
#[command(name = "lenspath", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene to an image (PNG or EXR by extension).
    Render(Box<render::RenderArgs>),
    /// Focus the realistic camera on an image patch by contrast or by range.
    Autofocus(Box<autofocus::AutofocusArgs>),
    /// Blur an image with a mask-shaped kernel (bokeh as a post-process).
    Bokeh(bokeh::BokehArgs),
    /// Show what a scene file holds: meshes, triangles, materials, lights, cameras, bounds, warnings.
    Info(info::InfoArgs),
    /// Analyse a lens: focal lengths, pupils, focus, a layout plot.
    Lens(lens::LensArgs),
    /// Optical glass: indices at the Fraunhofer lines, V_d, partial dispersion, the nearest glasses of each maker, the Abbe diagram.
    Glass(glass::GlassArgs),
    /// Look through the lens in a browser: a local server that renders as you
    /// change lens, f-stop, focus and aperture, and focuses where you click.
    View(view::ViewArgs),
    /// Measure performance.
    Bench(BenchArgs),
}

#[derive(Args)]
struct BenchArgs {
    #[command(subcommand)]
    what: BenchCommand,
}

#[derive(Subcommand)]
enum BenchCommand {
    /// BVH build time and traversal speed on a mesh.
    Bvh(bench::BvhArgs),
}

/// Exit code of an input or usage error.
const EXIT_USAGE: u8 = 2;
/// Exit code after Ctrl-C (128 + SIGINT).
const EXIT_INTERRUPTED: u8 = 130;

/// The command line, its help saying each default the library applies when
/// neither a flag nor the scene file gives the setting (the numbers are
/// `lenspath::defaults`', not copies).
fn command() -> clap::Command {
    use lenspath::defaults as d;
    let (w, h) = d::IMAGE_SIZE;
    let scene_file_else = |value: String| format!("the scene file's, else {value}");
    let defaults = [
        ("spp", scene_file_else(d::SPP.to_string())),
        ("light_samples", scene_file_else(d::LIGHT_SAMPLES.to_string())),
        ("max_depth", scene_file_else(d::MAX_DEPTH.to_string())),
        ("res", scene_file_else(format!("{w}x{h}"))),
        ("seed", scene_file_else(d::SEED.to_string())),
        ("sampler", scene_file_else(SamplerKind::default().name().to_string())),
        (
            "integrator",
            scene_file_else(IntegratorKind::default().name().to_string()),
        ),
        ("camera", lenspath::setup::CameraKind::default().name().to_string()),
        ("filter", lenspath::film::Filter::default().name().to_string()),
        ("lens", scene_file_else(d::LENS.to_string())),
        ("sensor", scene_file_else(format!("{} mm wide", d::SENSOR_WIDTH_MM))),
        ("scene_unit", scene_file_else(d::SCENE_UNIT_M.to_string())),
        ("aperture_radius", d::THIN_LENS_APERTURE_RADIUS.to_string()),
        ("radiometry", lenspath::camera::Radiometry::default().name().to_string()),
        (
            "sensor_model",
            scene_file_else(format!("{} when another sensor flag is given", d::SENSOR_RESPONSE)),
        ),
        ("cfa", lenspath::sensor::Cfa::default().name().to_string()),
        ("exposure_time", format!("1/{:.0} s", 1.0 / d::SENSOR_EXPOSURE_TIME_S)),
        (
            "iso",
            format!("{} (base ISO {})", d::SENSOR_ISO, d::SENSOR_UNITY_GAIN_ISO),
        ),
        ("white_luminance", d::SENSOR_WHITE_LUMINANCE_CD_M2.to_string()),
        ("read_noise", d::SENSOR_READ_NOISE_E.to_string()),
        ("full_well_per_um2", format!("{:.0}", d::SENSOR_FULL_WELL_E_PER_UM2)),
        ("dark_current_per_um2", d::SENSOR_DARK_CURRENT_E_PER_S_UM2.to_string()),
        ("dsnu", d::SENSOR_DSNU_E.to_string()),
        ("prnu", d::SENSOR_PRNU.to_string()),
        ("bit_depth", d::SENSOR_BIT_DEPTH.to_string()),
        ("black_level", d::SENSOR_BLACK_LEVEL_DN.to_string()),
        ("peak_qe", d::SENSOR_PEAK_QE.to_string()),
        ("white_balance", lenspath::sensor::WhiteBalance::default().spelling()),
        ("demosaic", lenspath::sensor::Demosaic::default().name().to_string()),
        ("tone_curve", lenspath::sensor::ToneCurve::default().name().to_string()),
        (
            "max_exposure_time",
            format!("1/{:.0} s", 1.0 / d::SENSOR_MAX_EXPOSURE_TIME_S),
        ),
        ("max_iso", d::SENSOR_MAX_ISO.to_string()),
    ];
    // An autofocus search's patch renders have defaults of their own (not the scene file's).
    let patch_renders = [
        ("spp", d::AUTOFOCUS_PATCH_SPP.to_string()),
        ("max_depth", d::AUTOFOCUS_PATCH_MAX_DEPTH.to_string()),
        ("seed", d::AUTOFOCUS_SEED.to_string()),
        ("patience", d::AUTOFOCUS_PATIENCE.to_string()),
        ("metric", FocusMeasure::default().name().to_string()),
        ("strategy", Strategy::default().name().to_string()),
        ("af_signal", SensorSignal::default().name().to_string()),
    ];
    // The first table that names an argument gives its default.
    let with_defaults = |tables: &[&[(&str, String)]], mut c: clap::Command| {
        let ids: Vec<String> = c.get_arguments().map(|a| a.get_id().to_string()).collect();
        for id in ids {
            if let Some((_, value)) = tables.iter().flat_map(|t| t.iter()).find(|(name, _)| *name == id) {
                c = c.mut_arg(id, |a| {
                    let help = a.get_help().map(ToString::to_string).unwrap_or_default();
                    a.help(format!("{help} [default: {value}]"))
                });
            }
        }
        c
    };
    Cli::command()
        .mut_subcommand("render", |c| with_defaults(&[&defaults], c))
        .mut_subcommand("autofocus", |c| with_defaults(&[&patch_renders, &defaults], c))
}

/// Runs the command line `args` (the program's name first, as `std::env::args_os` gives it) and
/// returns the process's exit code: 0, 2 for an input or usage error, 130 after Ctrl-C.
pub fn run<I, T>(args: I) -> u8
where
    I: IntoIterator<Item = T>,
    T: Into<std::ffi::OsString> + Clone,
{
    let parsed = command()
        .try_get_matches_from(args)
        .and_then(|mut matches| Cli::from_arg_matches_mut(&mut matches));
    let cli = match parsed {
        Ok(cli) => cli,
        Err(e) => {
            // clap's whole message as one block on stderr (which argument,
            // its suggestion or the valid values, the usage line) with exit
            // code 2; help and --version on stdout with success.
            let _ = e.print();
            return if e.use_stderr() { EXIT_USAGE } else { 0 };
        }
    };
    let outcome = match cli.command {
        Command::Render(args) => render::run(*args),
        Command::Autofocus(args) => autofocus::run(*args),
        Command::Bokeh(args) => bokeh::run(args),
        Command::Info(args) => info::run(args),
        Command::Lens(args) => lens::run(args),
        Command::Glass(args) => glass::run(args),
        Command::View(args) => view::run(args),
        Command::Bench(BenchArgs {
            what: BenchCommand::Bvh(args),
        }) => bench::run_bvh(args),
    };
    match outcome {
        Ok(Outcome::Done) => 0,
        Ok(Outcome::Interrupted) => EXIT_INTERRUPTED,
        Err(e) => {
            eprintln!("error: {e}");
            EXIT_USAGE
        }
    }
}

/// How a command ended, when it did not fail.
pub enum Outcome {
    /// Finished.
    Done,
    /// Stopped by Ctrl-C after saving its partial result.
    Interrupted,
}
