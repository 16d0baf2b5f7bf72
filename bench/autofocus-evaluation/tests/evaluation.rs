//! The evaluation tool end to end: its reuse of recorded ground truths.

use std::path::Path;
use std::process::{Command, Output};

fn evaluation(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_autofocus-evaluation"))
        .args(args)
        .output()
        .expect("the evaluation binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn autofocus_evaluation_refuses_truths_for_other_settings() {
    let dir = tempfile::tempdir().unwrap();
    let truths = dir.path().join("truths.json");
    std::fs::write(
        &truths,
        r#"{"metric": "tenengrad", "spp": 64, "resolution": [640, 480], "patches": []}"#,
    )
    .unwrap();
    let o = evaluation(&["--truths", truths.to_str().unwrap(), "--spp", "16"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("truths.json"), "{}", stderr(&o));
    assert!(stderr(&o).contains("64 spp"), "{}", stderr(&o));
}

/// The evaluation of the built-in scene's fifth patch at a tiny size, reusing
/// `truth` (a patch's ground truth as `--evaluate-json` writes it) through
/// `--truths`; returns the run's JSON.
fn evaluate_with_truth(dir: &Path, truth: serde_json::Value, extra: &[&str]) -> serde_json::Value {
    let (truths, out) = (dir.join("truths.json"), dir.join("out.json"));
    let earlier = serde_json::json!({
        "metric": "tenengrad", "spp": 2, "resolution": [64, 48],
        "patches": [{"patch": "cornell-spheres#5", "rect": [0.35, 0.0, 0.12, 0.08], "truth": truth}],
    });
    std::fs::write(&truths, earlier.to_string()).unwrap();
    let mut args = vec![
        "--only",
        "cornell-spheres#5",
        "--res",
        "64x48",
        "--spp",
        "2",
        "--truths",
        truths.to_str().unwrap(),
        "--evaluate-json",
        out.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let o = evaluation(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap()
}

#[test]
fn autofocus_evaluation_reuses_settled_truths_only_and_runs_several_seeds() {
    let dir = tempfile::tempdir().unwrap();
    let truth = |spread: f64, spp: u32| {
        serde_json::json!({"sensor_depth_mm": 55.5, "seed_spread_dof": spread, "spp": spp,
                           "depth_conjugate_z_mm": null, "lens_best_focus_z_mm": null})
    };
    // Seeds that agreed: kept as it is, however wrong.
    let settled = evaluate_with_truth(dir.path(), truth(0.1, 8), &["--seeds", "3"]);
    let patch = &settled["patches"][0];
    assert_eq!(patch["truth"]["sensor_depth_mm"], 55.5);
    let runs = |name: &str| -> Vec<u64> {
        patch["results"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|r| r["strategy"] == name)
            .map(|r| r["seed"].as_u64().unwrap())
            .collect()
    };
    assert_eq!(runs("sweep"), [0]);
    assert_eq!(runs("fast"), [0, 1, 2]);
    assert_eq!(runs("depth"), [0, 1, 2]);
    // Seeds that disagreed with fewer samples than now allowed: computed again.
    let unsettled = evaluate_with_truth(dir.path(), truth(3.0, 8), &[]);
    let recomputed = &unsettled["patches"][0]["truth"];
    assert_ne!(recomputed["sensor_depth_mm"], 55.5);
    assert!(recomputed["seed_spread_dof"].as_f64().unwrap() < 3.0);
}
