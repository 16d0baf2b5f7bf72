//! A render continued from a checkpoint is bit-identical to one that never
//! stopped, however it was stopped: between passes, in the middle of one
//! (some tiles ahead of others), or through a file on disk.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use lenspath::accel::BvhSettings;
use lenspath::builtin::builtin_scene;
use lenspath::camera::PerspectiveCamera;
use lenspath::io::checkpoint::{read_checkpoint, write_checkpoint};
use lenspath::render::{
    render, render_depth, render_from, Accumulation, Checkpoints, Continuation, PixelRect, RenderSettings,
};
use lenspath::scene::CompiledScene;

/// Continuing from `start`, nothing else given.
fn from(start: Accumulation) -> Continuation<'static> {
    Continuation {
        start: Some(start),
        ..Continuation::default()
    }
}

/// From the start, saving through `checkpoints`.
fn checkpointed(checkpoints: Checkpoints<'_>) -> Continuation<'_> {
    Continuation {
        checkpoints: Some(checkpoints),
        ..Continuation::default()
    }
}

fn setup() -> (CompiledScene, PerspectiveCamera) {
    let scene = builtin_scene("cornell-spheres", 0).unwrap();
    let view = scene.view.unwrap();
    let camera = PerspectiveCamera::thin_lens(view.pose, view.fov_y_deg, 48, 36, 0.1, 3.5);
    (scene.compile(&BvhSettings::default()).unwrap(), camera)
}

fn settings(spp: u32) -> RenderSettings {
    RenderSettings {
        width: 48,
        height: 36,
        spp,
        seed: 11,
        threads: Some(2),
        ..RenderSettings::default()
    }
}

/// Renders `spp` samples, saving a checkpoint after every pass; stops (as
/// Ctrl-C does) once `stop_after` samples are done. Returns the saves.
fn saves(scene: &CompiledScene, camera: &PerspectiveCamera, s: &RenderSettings, stop_after: u64) -> Vec<Accumulation> {
    let mut saved = Vec::new();
    let mut save = |a: &Accumulation| {
        saved.push(a.clone());
        Ok(())
    };
    let cancel = AtomicBool::new(false);
    let checkpoints = Checkpoints {
        every: Duration::ZERO,
        save: &mut save,
    };
    let progress = |done: u64, _| {
        if done >= stop_after {
            cancel.store(true, Ordering::SeqCst);
        }
    };
    render_from(scene, camera, s, checkpointed(checkpoints), &progress, &cancel).unwrap();
    saved
}

#[test]
fn a_continued_render_is_bit_identical_to_an_uninterrupted_one() {
    let (scene, camera) = setup();
    let never = AtomicBool::new(false);
    let whole = render(&scene, &camera, &settings(12), &|_, _| {}, &never).unwrap();

    let every_pass = saves(&scene, &camera, &settings(12), u64::MAX);
    assert_eq!(
        every_pass.iter().map(Accumulation::spp_min).collect::<Vec<_>>(),
        (1..=12).collect::<Vec<_>>(),
        "saves due at once keep passes to one sample, and follow each"
    );
    // Stopped in the middle of the third pass: some tiles have 3 samples, some 2.
    let stopped = saves(&scene, &camera, &settings(12), 48 * 36 * 2 + 100);
    let last = stopped.last().unwrap();
    assert!(
        last.spp_min() < last.count.iter().copied().max().unwrap(),
        "a pass was cut off"
    );

    for start in every_pass.iter().step_by(3).chain([last]) {
        let continued = render_from(&scene, &camera, &settings(12), from(start.clone()), &|_, _| {}, &never).unwrap();
        assert_eq!(continued.image, whole.image, "continued from {} spp", start.spp_min());
        assert!(!continued.stats.cancelled);
    }

    // From the state a render returns (how the viewer refines its image step by step).
    let half = render(&scene, &camera, &settings(5), &|_, _| {}, &never).unwrap();
    assert_eq!(half.accumulation.spp_min(), 5);
    let stepped = render_from(
        &scene,
        &camera,
        &settings(12),
        from(half.accumulation),
        &|_, _| {},
        &never,
    )
    .unwrap();
    assert_eq!(stepped.image, whole.image, "continued from a returned state");
    assert_eq!(stepped.accumulation.spp_min(), 12);

    // Through a file, and to more samples than the first render asked for.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("render.ckpt");
    write_checkpoint(&path, "test", every_pass.last().unwrap()).unwrap();
    let (_, from_file) = read_checkpoint(&path).unwrap();
    let more = render_from(&scene, &camera, &settings(20), from(from_file), &|_, _| {}, &never).unwrap();
    let straight = render(&scene, &camera, &settings(20), &|_, _| {}, &never).unwrap();
    assert_eq!(more.image, straight.image);
    assert_eq!(
        more.stats.samples,
        48 * 36 * 8,
        "only the 8 new samples per pixel were taken"
    );
}

/// A render without the depth channel has the same colours, and
/// `render_depth` gives the channel a render with it computes: what `lenspath
/// view` relies on to show its first preview sooner and still save the
/// render's EXR.
#[test]
fn the_depth_channel_alone_is_the_renders() {
    let (scene, camera) = setup();
    let never = AtomicBool::new(false);
    for crop in [
        None,
        Some(PixelRect {
            x0: 5,
            y0: 7,
            width: 21,
            height: 13,
        }),
    ] {
        let with = RenderSettings { crop, ..settings(3) };
        let without = RenderSettings { depth: false, ..with };
        let full = render(&scene, &camera, &with, &|_, _| {}, &never).unwrap().image;
        let mut colours = render(&scene, &camera, &without, &|_, _| {}, &never).unwrap().image;
        assert_eq!(colours.rgb, full.rgb);
        assert!(colours.depth.iter().all(|d| d.is_infinite()));
        colours.depth = render_depth(&scene, &camera, &with).unwrap();
        assert_eq!(colours, full);
        assert!(full.depth.iter().any(|d| d.is_finite()), "the box is in view");
    }
}

#[test]
fn a_checkpoint_of_another_render_is_refused() {
    let (scene, camera) = setup();
    let never = AtomicBool::new(false);
    let state = saves(&scene, &camera, &settings(4), u64::MAX).pop().unwrap();
    let run = |s: RenderSettings, start: Accumulation| {
        render_from(&scene, &camera, &s, from(start), &|_, _| {}, &never)
            .unwrap_err()
            .to_string()
    };
    let message = run(settings(2), state.clone());
    assert!(
        message.contains("already has 4 samples per pixel, more than the 2"),
        "{message}"
    );
    let mut cropped = settings(8);
    cropped.crop = Some(PixelRect {
        x0: 0,
        y0: 0,
        width: 8,
        height: 8,
    });
    let message = run(cropped, state.clone());
    assert!(message.contains("covers 48x36 pixels"), "{message}");
    let mut retiled = settings(8);
    retiled.tile_size = 5;
    let mut uneven = state;
    uneven.count[0] = 2;
    let message = run(retiled, uneven);
    assert!(message.contains("different sample counts"), "{message}");
}
