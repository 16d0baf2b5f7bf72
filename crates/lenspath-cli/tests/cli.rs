//! The `lenspath` binary as a user meets it: exit codes, error lines,
//! outputs, Ctrl-C.

use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn lenspath(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lenspath"))
        .args(args)
        .output()
        .expect("the lenspath binary runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn the_old_lens_focus_distance_flag_still_works_and_says_the_new_one() {
    let old = lenspath(&["lens", "dgauss50", "--json", "--focus-distance", "2"]);
    let new = lenspath(&["lens", "dgauss50", "--json", "--focus-distance-m", "2"]);
    assert!(old.status.success() && new.status.success(), "{}", stderr(&old));
    assert_eq!(old.stdout, new.stdout);
    assert!(stderr(&old).contains("use --focus-distance-m"), "{}", stderr(&old));
}

#[test]
fn renders_png_and_exr_with_a_summary_line() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["small.png", "small.exr"] {
        let out = dir.path().join(name);
        let o = lenspath(&["render", "--res", "32x24", "--spp", "2", "--out", out.to_str().unwrap()]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(
            stderr(&o).contains("rendered cornell-spheres 32x24 at 2 spp"),
            "{}",
            stderr(&o)
        );
        assert!(stderr(&o).contains("M rays/s"));
        assert!(out.metadata().unwrap().len() > 100);
    }
    let exr = lenspath::io::image::read_exr(&dir.path().join("small.exr")).unwrap();
    assert_eq!((exr.width, exr.height, exr.spp_min, exr.spp_requested), (32, 24, 2, 2));
    assert!(
        exr.depth.iter().all(|z| z.is_finite() && *z > 0.0),
        "the box surrounds the camera's view"
    );
    // No temporary files are left behind.
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names.len(), 2, "{names:?}");
}

/// `autofocus --render` writes the header `render` would: the lens, its
/// f-number and the sensor position autofocus found.
#[test]
fn an_autofocus_render_carries_the_render_header() {
    use lenspath::io::exr::HeaderValue;
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("focused.exr");
    let o = lenspath(&[
        "autofocus",
        "--patch",
        "0.4,0.6,0.2,0.2",
        "--res",
        "48x36",
        "--fstop",
        "4",
        "--json",
        "--render",
        out.to_str().unwrap(),
        "--render-spp",
        "1",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let found: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let sensor_mm = found["sensor_depth_mm"].as_f64().unwrap() as f32;
    // The deprecated name says the same.
    assert_eq!(found["sensor_position_mm"], found["sensor_depth_mm"]);
    let (image, header) = lenspath::io::image::read_exr_with_header(&out).unwrap();
    assert_eq!((image.width, image.height), (48, 36));
    let a = &header.attributes;
    assert_eq!(a.get("lenspath/sensorDepthMm"), Some(&HeaderValue::Float(sensor_mm)));
    assert_eq!(a.get("aperture"), Some(&HeaderValue::Float(4.0)));
    assert_eq!(a.get("lenspath/lens"), Some(&HeaderValue::Text("dgauss50".into())));
    assert_eq!(a.get("lenspath/camera"), Some(&HeaderValue::Text("realistic".into())));
}

/// `bokeh` carries an EXR's header over to the blurred image (the camera,
/// the scene, the settings) and names the blur's mask in it.
#[test]
fn a_blurred_exr_keeps_its_header() {
    use lenspath::io::exr::HeaderValue;
    let dir = tempfile::tempdir().unwrap();
    let (sharp, blurred) = (dir.path().join("sharp.exr"), dir.path().join("blurred.exr"));
    let o = lenspath(&[
        "render",
        "--res",
        "32x24",
        "--spp",
        "1",
        "--out",
        sharp.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let o = lenspath(&[
        "bokeh",
        sharp.to_str().unwrap(),
        "--mask",
        "blades:6",
        "--size",
        "5",
        "--out",
        blurred.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let (_, before) = lenspath::io::image::read_exr_with_header(&sharp).unwrap();
    let (_, after) = lenspath::io::image::read_exr_with_header(&blurred).unwrap();
    assert!(before.attributes.contains_key("worldToCamera"));
    let mut expected = before.attributes.clone();
    expected.insert("lenspath/bokehMask".into(), HeaderValue::Text("blades:6".into()));
    assert_eq!(after.attributes, expected);
}

#[test]
fn bad_input_gives_one_error_line_and_exit_code_2() {
    let dir = tempfile::tempdir().unwrap();
    let ok_out = dir.path().join("x.png");
    let ok = ok_out.to_str().unwrap();
    let bad_lens = dir.path().join("bad.dat");
    std::fs::write(&bad_lens, "# a lens\n10 2 1.5 8\n0 1 0 4\n-10 x 1 8\n").unwrap();
    let bad_lens = bad_lens.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["render", "--lens", "nosuch", "--out", ok], "unknown lens 'nosuch'"),
        (
            vec!["render", "--lens", bad_lens, "--out", ok],
            "bad.dat: line 4: thickness 'x' is not a number",
        ),
        (
            vec!["render", "--fstop", "1.2", "--out", ok],
            "f/1.2 is faster than dgauss50",
        ),
        (
            vec!["render", "--sensor", "0x24", "--out", ok],
            "not a positive number of mm",
        ),
        (
            vec!["render", "--focus-distance", "0.05", "--out", ok],
            "cannot focus at 0.0500 m",
        ),
        (
            vec!["render", "--sensor-depth", "3", "--out", ok],
            "must lie behind the rear element",
        ),
        (
            vec!["render", "--scene-unit", "0", "--out", ok],
            "scene unit must be a positive",
        ),
        (vec!["lens", "nosuch"], "unknown lens 'nosuch'"),
        (
            vec!["render", "--crop", "600,0,64,48", "--out", ok],
            "leaves the 640x480 image",
        ),
        (vec!["render", "--crop", "1,2,3", "--out", ok], "X,Y,WIDTH,HEIGHT"),
        (
            vec!["render", "--checkpoint-every", "5s", "--out", ok],
            "--checkpoint-every needs --checkpoint FILE",
        ),
        (
            vec!["render", "--checkpoint", "x", "--checkpoint-every", "soon", "--out", ok],
            "expected a duration such as 60s",
        ),
        (
            vec!["render", "--resume", "/no/such.ckpt", "--out", ok],
            "/no/such.ckpt",
        ),
        (
            vec!["lens", "dgauss50", "--ray-height-mm", "-1"],
            "--ray-height-mm must be positive",
        ),
        (
            vec!["lens", "dgauss50", "--mtf", "95"],
            "a field angle lies within ±90°, got 95",
        ),
        (
            vec![
                "lens",
                "dgauss50",
                "--psf",
                "0",
                "--wavelength-nm",
                "500,600",
                "--wavelength-weights",
                "1",
            ],
            "--wavelength-weights gives 1 weights for 2 wavelengths",
        ),
        (
            vec!["render", "--scene", "teapot-nope", "--out", ok],
            "unknown scene 'teapot-nope'",
        ),
        (vec!["render", "--res", "0x10", "--out", ok], "must be positive"),
        (vec!["render", "--res", "ten", "--out", ok], "WIDTHxHEIGHT"),
        (
            vec!["render", "--spp", "0", "--out", ok],
            "samples per pixel must be in 1..=",
        ),
        (vec!["render", "--spp", "-4", "--out", ok], "--spp"),
        (
            vec!["render", "--out", "/nonexistent-dir/x.png"],
            "/nonexistent-dir/x.png",
        ),
        (vec!["render", "--out", "picture.bmp"], "unknown image extension '.bmp'"),
        (
            vec!["render", "--threads", "0", "--out", ok],
            "threads must be at least 1",
        ),
        (
            vec!["render", "--camera", "pinhole", "--fov", "200", "--out", ok],
            "field of view must be between 0 and 180",
        ),
        (
            vec!["render", "--fov", "40", "--out", ok],
            "--fov is for --camera pinhole or thin-lens",
        ),
        (vec!["render", "--camera", "fisheye", "--out", ok], "fisheye"),
        (vec!["render", "--no-such-flag"], "--no-such-flag"),
        (vec!["bench", "bvh", "missing.ply"], "missing.ply"),
        (vec!["bench", "bvh", "--procedural", "10"], "512"),
        (vec!["view", "--lens", "nosuch.dat"], "unknown lens 'nosuch.dat'"),
        (vec!["view", "/no/such/scene.dae"], "/no/such/scene.dae"),
        (vec!["view", "--res", "0x10"], "must be positive"),
        (vec!["view", "--host", "localhost"], "--host"),
        // An address of no interface here (TEST-NET-1): the bind fails, nothing is sent.
        (
            vec!["view", "--host", "192.0.2.1", "--port", "0"],
            "cannot listen on 192.0.2.1:0",
        ),
    ];
    for (args, expected) in cases {
        let o = lenspath(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?} → {err}");
        assert!(err.contains(expected), "{args:?}: expected '{expected}' in: {err}");
        assert_one_error(&args, &err);
    }
    assert!(!ok_out.exists(), "a failed command must not write output");
}

/// One error, never a panic: lenspath's own errors are one line; a usage
/// error clap finds is clap's whole block (the problem, its tips, and the
/// pointer to --help).
fn assert_one_error(args: &[&str], err: &str) {
    assert!(err.starts_with("error: "), "{args:?}: {err}");
    assert_eq!(err.matches("error:").count(), 1, "{args:?}: one error, got: {err}");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    if !err.trim_end().ends_with("For more information, try '--help'.") {
        assert_eq!(err.trim_end().lines().count(), 1, "{args:?}: one line, got: {err}");
    }
}

/// A usage error says what is missing or what was meant: the missing
/// argument by name, clap's "a similar argument exists" and the valid
/// values, with exit code 2.
#[test]
fn usage_errors_name_the_argument_and_what_was_meant() {
    let cases: Vec<(Vec<&str>, Vec<&str>)> = vec![
        (vec!["lens"], vec!["required arguments were not provided", "<LENS>"]),
        (
            vec!["autofocus", "--res", "64x48"],
            vec!["required arguments were not provided", "--patch <X,Y,W,H>"],
        ),
        (
            vec!["bokeh", "x.png"],
            vec!["required arguments were not provided", "--mask <MASK>"],
        ),
        (
            vec!["render", "--sp", "2"],
            vec!["unexpected argument '--sp'", "similar argument exists: '--spp'"],
        ),
        // A library choice: its names and message are the library's (`Named`).
        (
            vec!["render", "--camera", "thinlens"],
            vec![
                "invalid value for '--camera <CAMERA>'",
                "unknown camera 'thinlens'; use one of pinhole, thin-lens, realistic",
            ],
        ),
        (
            vec!["render", "--filter", "tent"],
            vec!["unknown filter 'tent'; use one of box, gaussian"],
        ),
        (
            vec!["render", "--sampler", "bogus"],
            vec![
                "invalid value for '--sampler <SAMPLER>'",
                "unknown sampler 'bogus'; use one of sobol, independent",
            ],
        ),
        (
            vec!["autofocus", "--patch", "0.5,0.5,0.1,0.1", "--metric", "sharpness"],
            vec!["unknown focus measure 'sharpness'", "tenengrad"],
        ),
    ];
    for (args, expected) in cases {
        let o = lenspath(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?} → {err}");
        for e in expected {
            assert!(err.contains(e), "{args:?}: expected '{e}' in: {err}");
        }
        assert_one_error(&args, &err);
    }
}

/// Each flag's help states the one default the library applies: a render's
/// settings fall back on the scene file's, an autofocus search's patch
/// renders have their own (a flag's help once said both).
#[test]
fn the_help_states_each_default_once() {
    let help = |command: &str, flag: &str| {
        let o = lenspath(&[command, "--help"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let text = String::from_utf8_lossy(&o.stdout).into_owned();
        let at = text
            .find(&format!("      {flag} "))
            .unwrap_or_else(|| panic!("{command}: no {flag}"));
        // The flag's line and its help, up to the next flag.
        let mut lines = text[at..].lines();
        let head = lines.next().unwrap_or_default();
        let rest = lines.take_while(|l| !l.trim_start().starts_with('-'));
        let entry = std::iter::once(head).chain(rest).collect::<Vec<_>>().join("\n");
        assert_eq!(entry.matches("[default:").count(), 1, "{command} {flag}: {entry}");
        entry
    };
    let lens = lenspath::defaults::LENS;
    assert!(help("render", "--spp").contains("[default: the scene file's, else 64]"));
    assert!(help("render", "--lens").contains(&format!("else {lens}]")));
    for (flag, default) in [
        ("--spp", "16"),
        ("--max-depth", "8"),
        ("--seed", "0"),
        ("--patience", "12"),
    ] {
        assert!(
            help("autofocus", flag).contains(&format!("[default: {default}]")),
            "{flag}"
        );
    }
    assert!(help("autofocus", "--metric").contains("[default: tenengrad]"));
    assert!(help("autofocus", "--res").contains("[default: the scene file's, else 640x480]"));
}

#[test]
fn failed_write_keeps_the_previous_image() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("keep.png");
    std::fs::write(&out, b"previous").unwrap();
    // A run that fails before rendering leaves the file alone.
    let o = lenspath(&["render", "--spp", "0", "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert_eq!(std::fs::read(&out).unwrap(), b"previous");
}

/// `kill -9` during a render with `--checkpoint`, then `--resume`: the image
/// is the uninterrupted render's, byte for byte (EXR and PNG).
#[test]
fn a_killed_render_resumes_to_the_uninterrupted_image() {
    let dir = tempfile::tempdir().unwrap();
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let args = |out: &str| -> Vec<String> {
        ["render", "--res", "64x48", "--spp", "1500", "--out", out]
            .map(String::from)
            .to_vec()
    };
    let ckpt = path("render.ckpt");
    let mut child = Command::new(env!("CARGO_BIN_EXE_lenspath"))
        .args(args(&path("resumed.exr")))
        .args(["--checkpoint", &ckpt, "--checkpoint-every", "0.2s"])
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let started = Instant::now();
    while !Path::new(&ckpt).exists() {
        assert!(started.elapsed() < Duration::from_secs(60), "no checkpoint was written");
        std::thread::sleep(Duration::from_millis(10));
    }
    std::thread::sleep(Duration::from_millis(300));
    let killed = Command::new("kill")
        .args(["-9", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    child.wait().unwrap();
    let (_, saved) = lenspath::io::checkpoint::read_checkpoint(Path::new(&ckpt)).unwrap();
    assert!(
        saved.spp_min() > 0 && saved.spp_min() < 1500,
        "killed with {} of 1500 samples per pixel saved",
        saved.spp_min()
    );

    // Another seed is another render: refused, and the checkpoint is kept.
    let o = Command::new(env!("CARGO_BIN_EXE_lenspath"))
        .args(args(&path("other.exr")))
        .args(["--seed", "1", "--resume", &ckpt])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("is the checkpoint of another render"),
        "{}",
        stderr(&o)
    );

    for out in ["resumed.exr", "resumed.png"] {
        let o = Command::new(env!("CARGO_BIN_EXE_lenspath"))
            .args(args(&path(out)))
            .args(["--resume", &ckpt])
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(stderr(&o).contains("resuming"), "{}", stderr(&o));
    }
    for out in ["straight.exr", "straight.png"] {
        let o = lenspath(&args(&path(out)).iter().map(String::as_str).collect::<Vec<_>>());
        assert!(o.status.success(), "{}", stderr(&o));
    }
    for ext in ["exr", "png"] {
        let resumed = std::fs::read(path(&format!("resumed.{ext}"))).unwrap();
        let straight = std::fs::read(path(&format!("straight.{ext}"))).unwrap();
        assert!(
            resumed == straight,
            "the resumed {ext} differs from the uninterrupted one"
        );
    }
}

/// A checkpoint that cannot be saved (its folder is removed mid-render, as
/// a full disk would refuse it) costs the checkpoint, not the render: it
/// warns, goes on and writes its image. Temporary files that killed writers
/// left beside the checkpoint are removed when a render starts.
#[test]
fn a_failed_checkpoint_save_warns_and_the_render_still_writes_its_image() {
    let dir = tempfile::tempdir().unwrap();
    let saves = dir.path().join("saves");
    std::fs::create_dir(&saves).unwrap();
    let ckpt = saves.join("render.ckpt");
    let dead_pid = {
        let mut child = Command::new("true").spawn().unwrap();
        child.wait().unwrap();
        child.id()
    };
    let stale = saves.join(format!(".render.ckpt.{dead_pid}.tmp"));
    std::fs::write(&stale, b"left by a killed render").unwrap();
    let out = dir.path().join("image.png");
    let child = Command::new(env!("CARGO_BIN_EXE_lenspath"))
        .args([
            "render",
            "--res",
            "64x48",
            "--spp",
            "1500",
            "--checkpoint-every",
            "0.1s",
        ])
        .arg("--checkpoint")
        .arg(&ckpt)
        .arg("--out")
        .arg(&out)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let started = Instant::now();
    while !ckpt.exists() {
        assert!(started.elapsed() < Duration::from_secs(60), "no checkpoint was written");
        std::thread::sleep(Duration::from_millis(5));
    }
    assert!(!stale.exists(), "the stale temporary file is still there");
    std::fs::remove_dir_all(&saves).unwrap();
    let o = child.wait_with_output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("warning: checkpoint not saved"), "{}", stderr(&o));
    assert!(out.exists(), "no image was written");
}

#[test]
fn ctrl_c_stops_within_a_second_and_saves_the_partial_image() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("partial.exr");
    let mut child = Command::new(env!("CARGO_BIN_EXE_lenspath"))
        .args([
            "render",
            "--res",
            "64x48",
            "--spp",
            "60000",
            "--out",
            out.to_str().unwrap(),
        ])
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    let sent = Instant::now();
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        assert!(
            sent.elapsed() < Duration::from_secs(5),
            "render did not stop after Ctrl-C"
        );
        std::thread::sleep(Duration::from_millis(20));
    };
    let stopped_after = sent.elapsed();
    let mut err = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut err).unwrap();
    assert_eq!(status.code(), Some(130), "{err}");
    assert!(
        stopped_after < Duration::from_secs(1),
        "stopping took {stopped_after:?}"
    );
    assert!(err.contains("interrupted: saved"), "{err}");
    let image = lenspath::io::image::read_exr(Path::new(&out)).unwrap();
    assert!(
        image.spp_min > 0 && image.spp_min < 60000,
        "spp reached {}",
        image.spp_min
    );
    assert_eq!(image.spp_requested, 60000);
    assert!(image.mean()[0] > 0.01, "the partial image holds light");
}

#[test]
fn bench_bvh_reports_json() {
    let o = lenspath(&["bench", "bvh", "--procedural", "20000", "--rays", "20000", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!((19_000..=21_000).contains(&v["triangles"].as_u64().unwrap()));
    for key in ["build_ms", "coherent_mrays_s", "incoherent_mrays_s"] {
        assert!(v[key].as_f64().unwrap() > 0.0, "{key}");
    }
    // Coherent rays come from outside toward the mesh; many must hit it.
    assert!(v["coherent_hit_fraction"].as_f64().unwrap() > 0.1);
}

#[test]
fn lens_reports_json_and_plots_the_layout() {
    let dir = tempfile::tempdir().unwrap();
    let svg = dir.path().join("dgauss.svg");
    let o = lenspath(&[
        "lens",
        "dgauss50",
        "--json",
        "--plot",
        svg.to_str().unwrap(),
        "--focus-distance-m",
        "2",
        "--sensor-depth",
        "52",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let field = |name: &str| json[name].as_f64().unwrap_or_else(|| panic!("no {name} in {json}"));
    assert!((field("effective_focal_length_mm") - 50.0).abs() < 1.0);
    assert!((field("focal_length_mm") - field("effective_focal_length_mm")).abs() < 0.01);
    assert!(field("close_focus_mm") > field("infinity_focus_mm"));
    assert!((field("f_number") - 2.0).abs() < 0.1);
    for name in [
        "back_focal_distance_mm",
        "front_focal_distance_mm",
        "entrance_pupil_diameter_mm",
        "exit_pupil_mm",
        "diagonal_fov_deg",
        "passing_fraction_centre",
    ] {
        assert!(field(name).is_finite(), "{name}");
    }
    // The two focus conversions are each other's inverse.
    assert!(field("sensor_depth_for_focus_distance_mm") > field("infinity_focus_mm"));
    assert!(
        field("focus_distance_for_sensor_depth_m") > 2.0,
        "52 mm is nearer the infinity focus than 2 m's"
    );
    let drawing = std::fs::read_to_string(&svg).unwrap();
    assert!(
        drawing.starts_with("<svg") && drawing.matches("<polygon").count() == 6,
        "six glass elements"
    );
    assert!(drawing.matches("<polyline").count() >= 15, "three ray fans");
}

/// The wave-optics analysis: one entry per field (the PSF's field shared
/// with --mtf's), per-wavelength figures, an MTF no better than a perfect
/// lens's, and both plots drawn.
#[test]
fn lens_reports_the_wave_optics_at_each_field_and_plots_mtf_and_psf() {
    let dir = tempfile::tempdir().unwrap();
    let (mtf_svg, psf_svg) = (dir.path().join("mtf.svg"), dir.path().join("psf.svg"));
    let o = lenspath(&[
        "lens",
        "dgauss50",
        "--fstop",
        "8",
        "--json",
        "--mtf",
        "0,15",
        "--psf",
        "0",
        "--wavelength-nm",
        "486.13,587.56,656.27",
        "--pupil-samples",
        "64",
        "--mtf-plot",
        mtf_svg.to_str().unwrap(),
        "--psf-plot",
        psf_svg.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let wave = json["wave"].as_array().unwrap();
    assert_eq!(wave.len(), 2, "the PSF's field 0 is --mtf's first");
    for field in wave {
        let strehl = field["strehl_ratio"].as_f64().unwrap();
        assert!(strehl > 0.0 && strehl <= 1.0, "{strehl}");
        assert_eq!(field["wavelengths"].as_array().unwrap().len(), 3);
        for sample in field["mtf"].as_array().unwrap() {
            let (mtf, limit) = (
                sample["tangential"].as_f64().unwrap(),
                sample["diffraction_limit"].as_f64().unwrap(),
            );
            assert!(mtf <= limit + 0.01, "{sample}");
        }
    }
    assert!(
        wave[0]["mtf50_tangential_per_mm"].as_f64().unwrap() > wave[1]["mtf50_tangential_per_mm"].as_f64().unwrap()
    );
    assert_eq!(
        std::fs::read_to_string(&mtf_svg).unwrap().matches("<polyline").count(),
        5
    );
    assert_eq!(
        std::fs::read_to_string(&psf_svg).unwrap().matches("<polyline").count(),
        3
    );
}

/// `render FILE` takes the file's film and integrator settings (a flag wins),
/// and `info` reports what was loaded; a broken file is one line and exit 2,
/// with nothing written.
#[test]
fn scene_files_render_and_describe_themselves() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("scene.toml");
    std::fs::write(
        &scene,
        "[film]\nwidth = 24\nheight = 16\n[integrator]\nspp = 2\n\
         [camera]\neye = [0, 0, 5]\nlook_at = [0, 0, 0]\nfov_y_deg = 30\n\
         [materials.white]\ntype = \"diffuse\"\nreflectance = 0.8\n\
         [[shapes]]\ntype = \"sphere\"\ncenter = [0, 0, 0]\nradius = 1\nmaterial = \"white\"\n\
         [[lights]]\ntype = \"environment\"\nradiance = 1\n",
    )
    .unwrap();
    let out = dir.path().join("out.png");
    let o = lenspath(&["render", scene.to_str().unwrap(), "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("24x16 at 2 spp"), "{}", stderr(&o));
    let o = lenspath(&[
        "render",
        scene.to_str().unwrap(),
        "--spp",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(stderr(&o).contains("24x16 at 1 spp"), "{}", stderr(&o));

    let o = lenspath(&["info", scene.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let info: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(info["spheres"], 1);
    assert_eq!(info["materials"]["diffuse"], 1);
    assert_eq!(info["lights"]["environment"], 1);
    assert_eq!(info["cameras"], 1);
    assert_eq!(info["bounds"]["min"], serde_json::json!([-1.0, -1.0, -1.0]));

    // A built-in scene's name works wherever a scene file does.
    let o = lenspath(&["info", "cornell-spheres", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let info: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(
        (info["format"].as_str(), info["spheres"].as_u64()),
        (Some("built-in"), Some(2))
    );
    let o = lenspath(&[
        "render",
        "cornell-empty",
        "--res",
        "8x6",
        "--spp",
        "1",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(stderr(&o).contains("rendered cornell-empty 8x6"), "{}", stderr(&o));

    let broken = dir.path().join("broken.obj");
    std::fs::write(&broken, "v 0 0 0\nv 1 0 0\nf 1 2 3\n").unwrap();
    let never = dir.path().join("never.png");
    let o = lenspath(&["render", broken.to_str().unwrap(), "--out", never.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    let err = stderr(&o);
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("broken.obj: line 3: face refers to vertex 3, but 2 are defined"),
        "{err}"
    );
    assert!(!never.exists());
}

#[test]
fn bokeh_spreads_light_into_the_mask_and_refuses_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let (w, h) = (48usize, 40usize);
    let mut rgb = vec![0.01f32; w * h * 3];
    // One bright point in the middle.
    rgb[(20 * w + 24) * 3..(20 * w + 24) * 3 + 3].copy_from_slice(&[100.0, 80.0, 60.0]);
    let image = lenspath::film::Image {
        width: w as u32,
        height: h as u32,
        depth: vec![f32::INFINITY; w * h],
        rgb,
        spp_min: 1,
        spp_requested: 1,
    };
    let input = dir.path().join("in.exr");
    lenspath::io::image::write_image(&input, &image, 0.0).unwrap();
    let input = input.to_str().unwrap();
    let mut results = Vec::new();
    for method in ["direct", "fft"] {
        let out = dir.path().join(format!("{method}.exr"));
        let o = lenspath(&[
            "bokeh",
            input,
            "--mask",
            "blades:3",
            "--size",
            "21",
            "--method",
            method,
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(String::from_utf8_lossy(&o.stdout).contains("with a 21x21 kernel"));
        results.push(lenspath::io::image::read_exr(&out).unwrap());
    }
    let (a, b) = (&results[0], &results[1]);
    assert!(a.rgb.iter().zip(&b.rgb).all(|(x, y)| (x - y).abs() <= 1e-5 * 100.0));
    // Light is kept, and the triangle points up: narrow above the point, wide below.
    let total = |img: &lenspath::film::Image| img.rgb.iter().step_by(3).map(|&v| f64::from(v)).sum::<f64>();
    assert!((total(a) / total(&image) - 1.0).abs() < 1e-3);
    let row = |y: u32| (0..w as u32).filter(|&x| a.pixel(x, y)[0] > 0.1).count();
    assert!(row(14) < row(25) && row(25) > 5, "{} vs {}", row(14), row(25));

    let out = dir.path().join("x.png");
    let out = out.to_str().unwrap();
    for (args, expected) in [
        (
            vec!["bokeh", input, "--mask", "hexagon", "--out", out],
            "no such file, and not a shape",
        ),
        (
            vec!["bokeh", input, "--mask", "circle", "--highlights", "4", "--out", out],
            "is linear",
        ),
        (
            vec!["bokeh", input, "--mask", "circle", "--size", "0", "--out", out],
            "--size",
        ),
        (vec!["bokeh", "nope.png", "--mask", "circle", "--out", out], "nope.png"),
        (vec!["render", "--blades", "2", "--out", out], "at least 3 blades"),
        (
            vec!["render", "--camera", "pinhole", "--star", "5", "--out", out],
            "a pinhole has none",
        ),
        (
            vec!["render", "--aperture-mask", "nomask.png", "--out", out],
            "nomask.png",
        ),
    ] {
        let o = lenspath(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?} → {err}");
        assert!(err.contains(expected), "{args:?}: expected '{expected}' in: {err}");
        assert_one_error(&args, &err);
    }
    // Depth-aware blur's own mistakes ({in} and {out} stand for the paths).
    for (line, expected) in [
        (
            "bokeh {in} --mask circle --depth {in} --out {out}",
            "--depth needs --focus-distance",
        ),
        (
            "bokeh {in} --mask circle --focus-distance 2 --out {out}",
            "needs a lens",
        ),
        (
            "bokeh {in} --mask circle --focus-distance 2 --fstop 2 --focal-length 50 --size 9 --out {out}",
            "--size is for a uniform blur",
        ),
        (
            "bokeh {in} --mask circle --focus-distance 0.01 --fstop 2 --focal-length 50 --out {out}",
            "cannot focus at 0.0100 m",
        ),
    ] {
        let line = line.replace("{in}", input).replace("{out}", out);
        let o = lenspath(&line.split(' ').collect::<Vec<_>>());
        assert_eq!(o.status.code(), Some(2), "{line}");
        assert!(
            stderr(&o).contains(expected),
            "{line}: expected '{expected}' in: {}",
            stderr(&o)
        );
    }
    assert!(!Path::new(out).exists());

    // Depth-aware: a render's own Z channel, blurred as its thin lens would.
    let render = dir.path().join("box.exr");
    let o = lenspath(&[
        "render",
        "--camera",
        "pinhole",
        "--res",
        "64x48",
        "--spp",
        "4",
        "--out",
        render.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let blurred = dir.path().join("box-dof.png");
    let o = lenspath(&[
        "bokeh",
        render.to_str().unwrap(),
        "--mask",
        "blades:6",
        "--focus-distance",
        "3",
        "--aperture-radius",
        "0.1",
        "--fov",
        "29",
        "--out",
        blurred.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(String::from_utf8_lossy(&o.stdout).contains("by depth (circles of confusion up to"));
    assert!(blurred.exists());
}

/// `render --guide-map FILE --guide-at X,Y` writes what a guided render's
/// guide learned at a floor point of the caustic scene (PNG and EXR: the EXR
/// holds the density, whose sum over the equal-area disc is the guide's
/// whole probability, 1); asked of a pixel it cannot show, of a render that
/// is not guided or of a scene where guiding is off, it says why, with exit
/// code 2 and no output written.
#[test]
fn guided_renders_write_the_guide_map_or_say_why_not() {
    let dir = tempfile::tempdir().unwrap();
    let scene = concat!(env!("CARGO_MANIFEST_DIR"), "/../../scenes/caustics.toml");
    let (image, png, exr) = (
        dir.path().join("c.png"),
        dir.path().join("map.png"),
        dir.path().join("map.exr"),
    );
    let guided = |map: &Path, pixel: &str| {
        let (out, map) = (image.to_str().unwrap().to_owned(), map.to_str().unwrap().to_owned());
        lenspath(&[
            "render",
            scene,
            "--res",
            "48x36",
            "--spp",
            "2",
            "--integrator",
            "guided",
            "--out",
            &out,
            "--guide-map",
            &map,
            "--guide-at",
            pixel,
        ])
    };
    for map in [&png, &exr] {
        let o = guided(map, "0.5,0.95");
        let err = stderr(&o);
        assert!(o.status.success(), "{err}");
        // A floor point's guide sends (almost) all its samples above the floor.
        let share: f64 = err
            .split_once("guide at pixel (24, 34): ")
            .and_then(|(_, rest)| rest.split_once("% of its samples above the surface"))
            .and_then(|(head, _)| head.rsplit(' ').next()?.parse().ok())
            .unwrap_or_else(|| panic!("no share in: {err}"));
        assert!(share > 95.0, "{share}% above the floor");
    }
    let exr = lenspath::io::exr::read_exr_image(&exr).unwrap();
    let density = &exr.channels["Y"];
    let pixel_sr = (4.0 / f64::from(exr.width)).powi(2);
    let total: f64 = density.iter().map(|&d| f64::from(d) * pixel_sr).sum();
    assert!(
        (total - 1.0).abs() < 0.03,
        "the map holds {total} of the guide's probability"
    );
    assert!(png.metadata().unwrap().len() > 1000);

    std::fs::remove_file(&image).unwrap();
    let out = image.to_str().unwrap();
    let map = png.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (
            vec![
                "render",
                scene,
                "--res",
                "48x36",
                "--integrator",
                "guided",
                "--out",
                out,
                "--guide-map",
                map,
                "--guide-at",
                "0.3,0.5",
            ],
            "pixel (14, 18) sees glass, a mirror or smooth metal",
        ),
        (
            vec![
                "render",
                scene,
                "--res",
                "48x36",
                "--integrator",
                "guided",
                "--out",
                out,
                "--guide-map",
                map,
                "--guide-at",
                "1.2,0",
            ],
            "expected X,Y as fractions of the image",
        ),
        (
            vec![
                "render",
                scene,
                "--res",
                "48x36",
                "--out",
                out,
                "--guide-map",
                map,
                "--guide-at",
                "0.5,0.95",
            ],
            "add --integrator guided",
        ),
        (
            vec![
                "render",
                "--res",
                "48x36",
                "--integrator",
                "guided",
                "--out",
                out,
                "--guide-map",
                map,
                "--guide-at",
                "0.5,0.95",
            ],
            "guiding is off for cornell-spheres",
        ),
    ];
    for (args, expected) in cases {
        let o = lenspath(&args);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{args:?} → {err}");
        assert!(err.contains(expected), "{args:?}: expected '{expected}' in: {err}");
        assert_one_error(&args, &err);
    }
    assert!(!image.exists(), "a failed command must not write its image");
    let o = lenspath(&["render", "--guide-map", map]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("--guide-at <X,Y>"), "{}", stderr(&o));
}
