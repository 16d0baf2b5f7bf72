//! The autofocus evaluation: every strategy of `lenspath autofocus` against
//! ground truth on a fixed set of patches in five scenes (docs/autofocus.md).
//! A bench tool, run from a checkout (its scenes are the repository's and
//! ../shared's):
//!
//! ```sh
//! cargo run --release -p lenspath-autofocus-evaluation -- --seeds 4 \
//!     --truths docs/autofocus/evaluation.json --evaluate-json /tmp/evaluation.json
//! ```

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use clap::Parser;
use lenspath::accel::BvhSettings;
use lenspath::autofocus::plot::{focus_curve_svg, working_range_svg, Series};
use lenspath::autofocus::{
    AutofocusResult, AutofocusSettings, FocusMeasure, FocusSensor, Focuser, GroundTruth, SensorSignal, Strategy,
};
use lenspath::builtin::builtin_scene;
use lenspath::camera::CameraPose;
use lenspath::defaults;
use lenspath::film::NormalizedRect;
use lenspath::fs::{check_writable, write_text};
use lenspath::io::{load_scene_in, ReadScope};
use lenspath::lens::LensPrescription;
use lenspath::names::Named;
use lenspath::options::SceneOptions;
use lenspath::scene::CompiledScene;
use lenspath::sensor::SensorDescription;
use lenspath::setup::{autofocus_setup, realistic_settings, AutofocusOverrides, RealisticDescription};
use lenspath::{Error, Result};
use serde_json::json;

/// Every autofocus strategy against ground truth on the evaluation patches.
#[derive(Parser, Debug)]
#[command(name = "autofocus-evaluation", allow_negative_numbers = true)]
struct Args {
    /// Image size, WIDTHxHEIGHT.
    #[arg(long, value_parser = parse_resolution)]
    res: Option<(u32, u32)>,
    /// Focus measure: variance, normalized-variance, sml, tenengrad, brenner, laplacian-energy, vollath.
    #[arg(long, default_value = FocusMeasure::default().name())]
    metric: String,
    /// early-exit: stop after this many steps without a new best.
    #[arg(long, default_value_t = defaults::AUTOFOCUS_PATIENCE)]
    patience: usize,
    /// Samples per pixel of each patch render.
    #[arg(long, default_value_t = defaults::AUTOFOCUS_PATCH_SPP)]
    spp: u32,
    /// Maximum path depth of the patch renders.
    #[arg(long, default_value_t = defaults::AUTOFOCUS_PATCH_MAX_DEPTH)]
    max_depth: u32,
    /// Seed of the patch renders (the first, with --seeds).
    #[arg(long, default_value_t = defaults::AUTOFOCUS_SEED)]
    seed: u32,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Built-in lens or lens table [default: dgauss50, whatever the scene file's].
    #[arg(long)]
    lens: Option<String>,
    /// Stop down to this f-number [default: wide open, whatever the scene file's].
    #[arg(long, value_name = "N")]
    fstop: Option<f64>,
    /// Run each strategy with this many seeds (--seed and the ones after it)
    /// on each patch, so one lucky or unlucky noise draw does not decide a
    /// patch; the sweep and early-exit, whose cost dominates the run, with the
    /// first only.
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..))]
    seeds: u32,
    /// Only these strategies (comma-separated; default: every one).
    #[arg(long, value_name = "NAMES", value_delimiter = ',')]
    strategies: Vec<String>,
    /// Write every result as JSON here.
    #[arg(long, value_name = "FILE")]
    evaluate_json: Option<PathBuf>,
    /// Write each patch's focus-curve SVG into this folder.
    #[arg(long, value_name = "DIR")]
    plots_dir: Option<PathBuf>,
    /// Only these patches (comma-separated, such as CBdragon#2,glass-and-gold#3) or scenes (CBbunny).
    #[arg(long, value_name = "IDS", value_delimiter = ',')]
    only: Vec<String>,
    /// Evaluate through the default sensor at these scene luminances, EV at ISO 100 (comma-separated,
    /// such as 12,6,0,-3): the patch's mean luminance is set to 2^EV x 12.5/100 cd/m², the sensor
    /// meters its first frame (auto exposure within its limits) and contrast autofocus scores its
    /// noisy frames.
    #[arg(long, value_name = "EVS", value_delimiter = ',')]
    light_levels: Vec<f64>,
    /// With --light-levels: the sensor's highest ISO for auto exposure [default: the sensor's].
    #[arg(long, value_name = "ISO")]
    max_iso: Option<f64>,
    /// With --light-levels: what autofocus reads of the frames, raw-green or luminance.
    #[arg(long, value_name = "SIGNAL", default_value = SensorSignal::default().name())]
    af_signal: String,
    /// Reuse the ground truths of an earlier --evaluate-json for the patches
    /// it has with the same place, metric, samples and image size (the truth
    /// is deterministic and costs most of the run); others are computed, as
    /// are those whose two seeds disagreed when more samples are now allowed.
    #[arg(long, value_name = "FILE")]
    truths: Option<PathBuf>,
}

fn parse_resolution(s: &str) -> std::result::Result<(u32, u32), String> {
    let parsed = s
        .split_once(['x', 'X'])
        .and_then(|(w, h)| Some((w.trim().parse::<u32>().ok()?, h.trim().parse::<u32>().ok()?)));
    match parsed {
        Some((w, h)) if w > 0 && h > 0 => Ok((w, h)),
        _ => Err(format!("expected WIDTHxHEIGHT such as 640x480, got '{s}'")),
    }
}

fn main() -> ExitCode {
    let args = Args::parse();
    let checked = args.evaluate_json.as_deref().map_or(Ok(()), check_writable);
    match checked.and_then(|()| evaluate(&args)) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}

/// The patch renders the flags ask for.
fn overrides(args: &Args) -> Result<AutofocusOverrides> {
    Ok(AutofocusOverrides {
        spp: Some(args.spp),
        max_depth: Some(args.max_depth),
        seed: Some(args.seed),
        threads: args.threads,
        metric: Some(FocusMeasure::parse(&args.metric)?),
        patience: Some(args.patience),
        sensor_signal: Some(SensorSignal::parse(&args.af_signal)?),
        ..AutofocusOverrides::default()
    })
}

/// Luminance of a scene at `ev` (exposure value at ISO 100), cd/m²: the
/// reflected-light meter equation L = 2^EV · K / S with K = 12.5 cd/m²·s
/// (ISO 2720's calibration constant) and S = 100.
fn luminance_at_ev(ev: f64) -> f64 {
    ev.exp2() * 12.5 / 100.0
}

/// A scene of the evaluation set: where it comes from and the patches on it.
struct EvaluationScene {
    name: &'static str,
    /// `builtin:NAME`, or a path relative to the repository (`../shared/...` or `scenes/...`).
    source: &'static str,
    patches: &'static [[f64; 4]],
}

/// The lens of the evaluation (issue 5's targets are for it, wide open at f/2).
const EVALUATION_LENS: &str = "dgauss50";

/// The evaluation set: patches on edges and texture at different depths,
/// in five scenes (docs/autofocus.md shows them).
const EVALUATION_SET: [EvaluationScene; 5] = [
    EvaluationScene {
        name: "cornell-spheres",
        source: "builtin:cornell-spheres",
        patches: &[
            [0.52, 0.70, 0.10, 0.12],
            [0.20, 0.68, 0.10, 0.12],
            [0.74, 0.74, 0.10, 0.12],
            [0.15, 0.30, 0.10, 0.12],
            [0.35, 0.00, 0.12, 0.08],
        ],
    },
    EvaluationScene {
        name: "CBspheres_lambertian",
        source: "../shared/scenes/cs184/sky/CBspheres_lambertian.dae",
        patches: &[
            [0.26, 0.60, 0.08, 0.10],
            [0.68, 0.62, 0.08, 0.10],
            [0.33, 0.16, 0.08, 0.08],
            [0.21, 0.35, 0.08, 0.12],
            [0.45, 0.60, 0.10, 0.10],
        ],
    },
    EvaluationScene {
        name: "CBbunny",
        source: "../shared/scenes/cs184/sky/CBbunny.dae",
        patches: &[
            [0.45, 0.50, 0.08, 0.10],
            [0.40, 0.62, 0.08, 0.10],
            [0.56, 0.62, 0.08, 0.10],
            [0.33, 0.16, 0.08, 0.08],
            [0.71, 0.35, 0.08, 0.12],
        ],
    },
    EvaluationScene {
        name: "CBdragon",
        source: "scenes/cbdragon.toml",
        patches: &[
            [0.52, 0.46, 0.10, 0.10],
            [0.20, 0.58, 0.10, 0.10],
            [0.38, 0.58, 0.10, 0.12],
            [0.33, 0.16, 0.08, 0.08],
            [0.71, 0.35, 0.08, 0.12],
        ],
    },
    EvaluationScene {
        name: "glass-and-gold",
        source: "scenes/glass-and-gold.toml",
        patches: &[
            [0.52, 0.50, 0.08, 0.10],
            [0.82, 0.55, 0.08, 0.10],
            [0.08, 0.55, 0.08, 0.10],
            [0.88, 0.62, 0.10, 0.10],
            [0.18, 0.82, 0.12, 0.10],
        ],
    },
];

/// Ground truths of an earlier evaluation (its `--evaluate-json`), for the
/// same metric, samples and image size.
struct EarlierTruths {
    patches: Vec<serde_json::Value>,
}

impl EarlierTruths {
    /// Reads `path`; an error if it is not an evaluation of `metric` at `spp` and `size`.
    fn load(path: &Path, metric: &str, spp: u32, size: (u32, u32)) -> Result<EarlierTruths> {
        let bad = |message: String| Error::Parse {
            kind: lenspath::FileKind::Other,
            path: path.to_path_buf(),
            message,
        };
        let text = lenspath::fs::read_text(path, lenspath::FileKind::Other)?;
        let file: serde_json::Value = serde_json::from_str(&text).map_err(|e| bad(e.to_string()))?;
        let (their_metric, their_spp, their_size) = (&file["metric"], &file["spp"], &file["resolution"]);
        if their_metric != metric || their_spp != spp || *their_size != json!([size.0, size.1]) {
            return Err(bad(format!(
                "its truths are for metric {their_metric}, {their_spp} spp, resolution {their_size}; \
                 this run is {metric}, {spp} spp, {}x{}",
                size.0, size.1
            )));
        }
        let patches = file["patches"]
            .as_array()
            .ok_or_else(|| bad("no \"patches\" array".into()))?
            .clone();
        Ok(EarlierTruths { patches })
    }

    /// The truth recorded for patch `id` at `rect`, if any and settled
    /// ([`GroundTruth::is_settled`] for strategies at `spp`): one whose seeds
    /// disagreed is computed again when more samples are now allowed.
    fn get(&self, id: &str, rect: &[f64; 4], spp: u32) -> Option<GroundTruth> {
        let patch = self
            .patches
            .iter()
            .find(|p| p["patch"] == id && p["rect"] == json!(rect))?;
        serde_json::from_value::<GroundTruth>(patch["truth"].clone())
            .ok()
            .filter(|truth| truth.is_settled(spp))
    }
}

/// The repository root (this package is two levels down): the evaluation's
/// scenes are the repository's and ../shared's, so it runs from a checkout.
fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Every strategy on every evaluation patch, against ground truth.
fn evaluate(args: &Args) -> Result<()> {
    for name in &args.strategies {
        Strategy::parse(name)?;
    }
    let (width, height) = args.res.unwrap_or(defaults::IMAGE_SIZE);
    let earlier_truths = args
        .truths
        .as_deref()
        .map(|path| EarlierTruths::load(path, &args.metric, args.spp, (width, height)))
        .transpose()?;
    let mut rows = Vec::new();
    let mut patches_run = 0;
    let wanted = |id: &str, scene: &str| args.only.is_empty() || args.only.iter().any(|o| o == id || o == scene);
    for scene_spec in EVALUATION_SET
        .iter()
        .filter(|s| (1..=s.patches.len()).any(|k| wanted(&format!("{}#{k}", s.name), s.name)))
    {
        let (scene, options) = match scene_spec.source.strip_prefix("builtin:") {
            Some(name) => (builtin_scene(name, 0)?, SceneOptions::default()),
            None => {
                let path = repo_root().join(scene_spec.source);
                if !path.exists() || (scene_spec.source.contains("cb") && !repo_root().join("../shared").exists()) {
                    eprintln!(
                        "skipping {}: {} not found (../shared absent?)",
                        scene_spec.name,
                        path.display()
                    );
                    continue;
                }
                // The cb* scenes name meshes in ../shared.
                let shared: Vec<_> = Some(repo_root().join("../shared"))
                    .filter(|s| s.exists())
                    .into_iter()
                    .collect();
                let scope = ReadScope::of_scene(&path, &shared)?;
                let loaded = load_scene_in(&path, &scope)?;
                (loaded.scene, loaded.options)
            }
        };
        let view = scene.view.ok_or_else(|| Error::InvalidArgument("no camera".into()))?;
        // dgauss50 wide open (f/2) unless the flags say otherwise, whatever the scene file's lens.
        let description = RealisticDescription {
            lens: Some(LensPrescription::load(args.lens.as_deref().unwrap_or(EVALUATION_LENS))?),
            f_number: args.fstop,
            ..RealisticDescription::default()
        };
        let mut lens = realistic_settings(&options, &view, &description, width, height)?;
        lens.f_number = args.fstop;
        let compiled = scene.compile(&BvhSettings::default())?;
        for (k, p) in scene_spec.patches.iter().enumerate() {
            let id = format!("{}#{}", scene_spec.name, k + 1);
            if !wanted(&id, scene_spec.name) {
                continue;
            }
            let patch = NormalizedRect {
                x: p[0],
                y: p[1],
                width: p[2],
                height: p[3],
            };
            let settings =
                autofocus_setup(lens.clone(), (width, height), patch, &overrides(args)?, view.pose)?.settings;
            let mut focuser = Focuser::new(&compiled, view.pose, settings.clone())?;
            let truth = match earlier_truths.as_ref().and_then(|t| t.get(&id, p, args.spp)) {
                Some(truth) => truth,
                None => focuser.ground_truth()?,
            };
            let dof = focuser.depth_of_focus_mm(truth.sensor_depth_mm);
            if !args.light_levels.is_empty() {
                // The patch's luminance per scene unit of emission, from its sharp image.
                let relative = focuser.patch_luminance(truth.sensor_depth_mm)?;
                for &ev in &args.light_levels {
                    let white_luminance_cd_m2 = luminance_at_ev(ev) / relative;
                    let sensor = SensorDescription {
                        auto_exposure: Some(true),
                        max_iso: args.max_iso,
                        white_luminance_cd_m2: Some(white_luminance_cd_m2),
                        ..SensorDescription::default()
                    }
                    .resolve()?;
                    let through_sensor = AutofocusSettings {
                        sensor: Some(FocusSensor {
                            sensor,
                            signal: SensorSignal::parse(&args.af_signal)?,
                        }),
                        ..settings.clone()
                    };
                    let results = run_strategies(&compiled, view.pose, &through_sensor, args)?;
                    eprintln!("{}", row_text(&format!("{id} at EV {ev}"), &truth, dof, &results));
                    let mut row = result_row(&id, p, &truth, dof, &results);
                    row["light_level_ev"] = json!(ev);
                    row["patch_luminance_cd_m2"] = json!(luminance_at_ev(ev));
                    rows.push(row);
                }
                patches_run += 1;
                continue;
            }
            let results = run_strategies(&compiled, view.pose, &settings, args)?;
            eprintln!("{}", row_text(&id, &truth, dof, &results));
            if let Some(dir) = &args.plots_dir {
                std::fs::create_dir_all(dir).map_err(|e| Error::Io {
                    path: dir.clone(),
                    source: e,
                })?;
                // The first seed's runs: one series per strategy.
                let series: Vec<Series> = results
                    .iter()
                    .filter(|(seed, _)| *seed == args.seed)
                    .map(|(_, r)| Series {
                        label: r.strategy,
                        points: &r.evaluations,
                        chosen_mm: Some(r.sensor_depth_mm),
                        line: r.strategy == "sweep",
                    })
                    .collect();
                let title = format!("{id} ({}, {} spp)", args.metric, args.spp);
                let svg = focus_curve_svg(&title, &series, Some(truth.sensor_depth_mm));
                write_text(&dir.join(format!("{}-{}.svg", scene_spec.name, k + 1)), &svg)?;
            }
            rows.push(result_row(&id, p, &truth, dof, &results));
            patches_run += 1;
        }
    }
    let summary = if args.light_levels.is_empty() {
        summarize(&rows)
    } else {
        let label = format!(
            "{} signal, frames at most 1/{:.0} s and ISO {}",
            args.af_signal,
            1.0 / defaults::SENSOR_MAX_EXPOSURE_TIME_S,
            args.max_iso.unwrap_or(defaults::SENSOR_MAX_ISO)
        );
        let (table, svg) = working_range(&rows, &args.light_levels, &label);
        if let Some(dir) = &args.plots_dir {
            std::fs::create_dir_all(dir).map_err(|e| Error::Io {
                path: dir.clone(),
                source: e,
            })?;
            write_text(&dir.join("working-range.svg"), &svg)?;
        }
        table
    };
    println!("{summary}");
    if let Some(path) = &args.evaluate_json {
        let out = json!({
            "metric": args.metric,
            "spp": args.spp,
            "resolution": [width, height],
            "patches": rows,
        });
        write_text(path, &serde_json::to_string_pretty(&out).expect("JSON serializes"))?;
    }
    if patches_run == 0 {
        return Err(Error::InvalidArgument(
            "no evaluation patch could be loaded (or none matched --only)".into(),
        ));
    }
    Ok(())
}

/// Every strategy on one patch with `settings`: with the first seed, then
/// the cheap ones (not the sweep and early-exit) with the rest of `--seeds`.
fn run_strategies(
    compiled: &CompiledScene,
    pose: CameraPose,
    settings: &AutofocusSettings,
    args: &Args,
) -> Result<Vec<(u32, AutofocusResult)>> {
    let mut results = Vec::new();
    for run in 0..args.seeds {
        let seed = args.seed.wrapping_add(run);
        let mut focuser = Focuser::new(
            compiled,
            pose,
            AutofocusSettings {
                seed,
                ..settings.clone()
            },
        )?;
        for &(strategy, name) in Strategy::NAMED {
            if !args.strategies.is_empty() && !args.strategies.iter().any(|s| s == name) {
                continue;
            }
            let strategy = match strategy {
                Strategy::Sweep | Strategy::EarlyExit { .. } if run > 0 => continue,
                s => s.with_patience(args.patience),
            };
            results.push((seed, focuser.run(strategy)?));
        }
    }
    Ok(results)
}

/// One patch's results as JSON.
fn result_row(
    id: &str,
    rect: &[f64; 4],
    truth: &GroundTruth,
    dof: f64,
    results: &[(u32, AutofocusResult)],
) -> serde_json::Value {
    json!({
        "patch": id,
        "rect": rect,
        "truth": truth,
        "depth_of_focus_mm": dof,
        "results": results.iter().map(|(seed, r)| json!({
            "strategy": r.strategy,
            "seed": seed,
            "sensor_depth_mm": r.sensor_depth_mm,
            "error_dof": (r.sensor_depth_mm - truth.sensor_depth_mm) / dof,
            "evaluations": r.evaluations.len(),
            "patch_renders": r.patch_renders(),
            "light_fields": r.light_fields,
            "camera_rays": r.camera_rays,
            "seconds": r.seconds,
            "exposure_time_s": r.exposure_time_s,
            "iso": r.iso,
        })).collect::<Vec<_>>(),
    })
}

/// The working range: per light level, each strategy's runs within 1 DoF
/// (a Markdown table with the frames' median exposure), and the same as an
/// SVG plot titled with `label`. A patch whose truth's seeds disagree (at
/// the samples' cap) has no reference and is left out.
fn working_range(rows: &[serde_json::Value], levels: &[f64], label: &str) -> (String, String) {
    let agrees = |r: &&serde_json::Value| {
        serde_json::from_value::<GroundTruth>(r["truth"].clone()).is_ok_and(|truth| truth.seeds_agree())
    };
    let mut left_out: Vec<&str> = rows
        .iter()
        .filter(|r| !agrees(r))
        .filter_map(|r| r["patch"].as_str())
        .collect();
    left_out.dedup();
    let rows: Vec<&serde_json::Value> = rows.iter().filter(agrees).collect();
    let mut table = String::from("| scene EV (ISO 100) | patch luminance (cd/m²) | frames: median exposure |");
    let mut rule = String::from("|---|---|---|");
    for name in Strategy::names() {
        table += &format!(" {name} |");
        rule += "---|";
    }
    table += &format!("\n{rule}\n");
    let mut series: Vec<(&str, Vec<(f64, f64)>)> =
        Strategy::names().into_iter().map(|name| (name, Vec::new())).collect();
    for &ev in levels {
        let results: Vec<&serde_json::Value> = rows
            .iter()
            .filter(|r| r["light_level_ev"].as_f64() == Some(ev))
            .flat_map(|r| r["results"].as_array().into_iter().flatten())
            .collect();
        let median = |key: &str| {
            let mut v: Vec<f64> = results.iter().filter_map(|r| r[key].as_f64()).collect();
            v.sort_by(f64::total_cmp);
            v.get(v.len() / 2).copied()
        };
        let exposure = match (median("exposure_time_s"), median("iso")) {
            (Some(t), Some(iso)) => format!("1/{:.0} s, ISO {iso:.0}", 1.0 / t),
            _ => "none (no frame)".into(),
        };
        table += &format!("| {ev:+} | {:.3} | {exposure} |", luminance_at_ev(ev));
        for (name, points) in &mut series {
            let of_strategy: Vec<f64> = results
                .iter()
                .filter(|r| r["strategy"] == *name)
                .map(|r| r["error_dof"].as_f64().unwrap_or(f64::INFINITY).abs())
                .collect();
            let within = of_strategy.iter().filter(|&&e| e <= 1.0).count();
            if of_strategy.is_empty() {
                table += " |";
            } else {
                table += &format!(" {within}/{} |", of_strategy.len());
                points.push((ev, within as f64 / of_strategy.len() as f64));
            }
        }
        table += "\n";
    }
    if !left_out.is_empty() {
        table += &format!("\n(left out, their truths' seeds disagree: {})\n", left_out.join(", "));
    }
    let svg = working_range_svg(&format!("autofocus working range ({label})"), &series);
    (table, svg)
}

/// One patch's line of the evaluation's progress: its truth and each run's error.
fn row_text(id: &str, truth: &GroundTruth, dof: f64, results: &[(u32, AutofocusResult)]) -> String {
    let offset = |z: Option<f64>| {
        z.map_or("none".into(), |z| {
            format!("{:+.2} DoF", (z - truth.sensor_depth_mm) / dof)
        })
    };
    let mut line = format!(
        "{id:<24} truth {:.4} mm (seed spread {:.2} DoF, {} spp; depth conjugate {}, lens best focus {})",
        truth.sensor_depth_mm,
        truth.seed_spread_dof,
        truth.spp,
        offset(truth.depth_conjugate_z_mm),
        offset(truth.lens_best_focus_z_mm),
    );
    for (seed, r) in results {
        line += &format!(
            " | {} (seed {seed}) {:+.2} DoF {} renders",
            r.strategy,
            (r.sensor_depth_mm - truth.sensor_depth_mm) / dof,
            r.patch_renders()
        );
        if r.light_fields > 0 {
            line += &format!(" + {} light field", r.light_fields);
        }
    }
    line
}

/// A Markdown table: per strategy, runs within 1 DoF, median and max |error|, cost relative to the sweep.
fn summarize(rows: &[serde_json::Value]) -> String {
    let mut out = String::from(
        "| strategy | runs within 1 DoF | median abs error (DoF) | max abs error (DoF) | patch renders (mean) | camera rays vs sweep | seconds (mean) |\n|---|---|---|---|---|---|---|\n",
    );
    // The sweep's mean camera rays per run (strategies may have more runs per patch than it).
    let sweep_runs: Vec<f64> = rows
        .iter()
        .flat_map(|r| r["results"].as_array().into_iter().flatten())
        .filter(|r| r["strategy"] == "sweep")
        .map(|r| r["camera_rays"].as_f64().unwrap_or(0.0))
        .collect();
    let sweep_rays = sweep_runs.iter().sum::<f64>() / sweep_runs.len().max(1) as f64;
    for name in Strategy::names() {
        let results: Vec<&serde_json::Value> = rows
            .iter()
            .flat_map(|r| r["results"].as_array().into_iter().flatten())
            .filter(|r| r["strategy"] == name)
            .collect();
        if results.is_empty() {
            continue;
        }
        let n = results.len() as f64;
        let mut errors: Vec<f64> = results
            .iter()
            .map(|r| r["error_dof"].as_f64().unwrap_or(f64::INFINITY).abs())
            .collect();
        errors.sort_by(f64::total_cmp);
        let within = errors.iter().filter(|&&e| e <= 1.0).count();
        let rays: f64 = results.iter().map(|r| r["camera_rays"].as_f64().unwrap_or(0.0)).sum();
        let evals: f64 = results.iter().map(|r| r["patch_renders"].as_f64().unwrap_or(0.0)).sum();
        let secs: f64 = results.iter().map(|r| r["seconds"].as_f64().unwrap_or(0.0)).sum();
        out += &format!(
            "| {name} | {within}/{} ({:.0}%) | {:.2} | {:.2} | {:.1} | {:.1}% | {:.2} |\n",
            results.len(),
            100.0 * within as f64 / n,
            errors[errors.len() / 2],
            errors.last().copied().unwrap_or(0.0),
            evals / n,
            100.0 * rays / n / sweep_rays,
            secs / n
        );
    }
    out
}
