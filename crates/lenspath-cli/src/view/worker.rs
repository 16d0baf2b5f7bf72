//! The render thread: refines the current view in steps (1, 2, 4, 8 and 16
//! samples per pixel, then 16 more a step), each continuing the last one's
//! sums, so the image after a step is the one `lenspath render --spp N`
//! gives, bit for bit. Each step is sent to the pages as a frame. It runs the
//! autofocus requests, and sleeps while no page is connected. A change is
//! first shown as a quick preview at half the width and height, one sample
//! per pixel (a quarter of the work of the first step), which the page scales
//! up until the first step replaces it.

use std::sync::atomic::Ordering;
use std::sync::Arc;
use std::time::Instant;

use axum::body::Bytes;
use lenspath::autofocus::Focuser;
use lenspath::guiding::Guide;
use lenspath::integrator::Integrator;
use lenspath::io::image::encode_jpeg;
use lenspath::names::Named;
use lenspath::render::{render, render_from, train_guide, Accumulation, Continuation, NormalizedRect, RenderOutput};
use lenspath::sensor::SensorSettings;
use lenspath::setup::{autofocus_setup, AutofocusOverrides};
use lenspath::Result;
use serde_json::json;

use super::session::{AutofocusRequest, Event, Frame, Session, View};

/// Steps double the samples up to this, then add this many.
const LINEAR_STEP_SPP: u32 = 16;

/// The samples per pixel after the step that follows `spp`.
fn next_step(spp: u32) -> u32 {
    if spp < LINEAR_STEP_SPP {
        (spp * 2).max(1)
    } else {
        spp + LINEAR_STEP_SPP
    }
}

/// Starts the render thread.
pub fn spawn(session: Arc<Session>) -> std::io::Result<std::thread::JoinHandle<()>> {
    std::thread::Builder::new()
        .name("lenspath-view-render".into())
        .spawn(move || run(&session))
}

/// What the thread does next.
enum Job {
    Render(Arc<View>),
    Autofocus(AutofocusRequest, Arc<View>),
}

/// The refinement of one generation of settings.
struct Progress {
    generation: u64,
    /// The sums so far (`None`: nothing rendered yet).
    state: Option<Accumulation>,
    /// The guided integrator's guide, trained before the first step.
    guide: Option<Guide>,
    /// Whether the generation's half-size preview was sent.
    previewed: bool,
    /// Whether its first full-size frame was sent.
    shown: bool,
}

impl Progress {
    /// Nothing done yet for `generation`.
    fn new(generation: u64) -> Progress {
        Progress {
            generation,
            state: None,
            guide: None,
            previewed: false,
            shown: false,
        }
    }

    fn spp(&self) -> u32 {
        self.state.as_ref().map_or(0, Accumulation::spp_min)
    }
}

fn run(session: &Session) {
    let mut progress = Progress::new(u64::MAX);
    loop {
        let (job, generation, changed_at) = {
            let mut state = session.lock();
            let job = loop {
                if state.clients > 0 && !state.changing {
                    if let Some(request) = state.autofocus.take() {
                        break Job::Autofocus(request, state.view.clone());
                    }
                    if progress.generation != state.generation {
                        progress = Progress::new(state.generation);
                    }
                    if progress.spp() < state.view.settings.max_spp {
                        break Job::Render(state.view.clone());
                    }
                }
                state = session.wake.wait(state).unwrap_or_else(|e| e.into_inner());
            };
            // Under the lock: a change after this sets it again.
            session.cancel.store(false, Ordering::SeqCst);
            (job, state.generation, state.changed_at)
        };
        match job {
            Job::Render(view) => {
                if let Err(e) = step(session, &mut progress, &view, changed_at) {
                    session.send(json!({"type": "error", "message": e.to_string()}));
                    // Nothing more to do for these settings.
                    progress.generation = generation;
                    progress.state = None;
                    let mut state = session.lock();
                    while state.generation == generation && state.autofocus.is_none() {
                        state = session.wake.wait(state).unwrap_or_else(|e| e.into_inner());
                    }
                }
            }
            Job::Autofocus(request, view) => {
                if let Err(e) = autofocus(session, &request, &view) {
                    session.send(json!({"type": "autofocus-failed", "message": e.to_string()}));
                }
            }
        }
    }
}

/// Renders the next step of `view` and sends it, unless a change stopped it;
/// a new generation's half-size preview first.
fn step(session: &Session, progress: &mut Progress, view: &Arc<View>, changed_at: Instant) -> Result<()> {
    if !progress.previewed {
        progress.previewed = preview(session, progress.generation, view, changed_at)?;
        return Ok(());
    }
    let target = next_step(progress.spp()).min(view.settings.max_spp);
    let settings = lenspath::render::RenderSettings {
        spp: target,
        ..view.render
    };
    // A guided render's guide is trained once, for every step of this view.
    if progress.guide.is_none() && settings.integrator.guide_training_spp(&session.scene).is_some() {
        progress.guide = train_guide(&session.scene, &view.camera, &settings, &session.cancel)?;
        if progress.guide.is_none() {
            return Ok(());
        }
    }
    let from = Continuation {
        start: progress.state.take(),
        guide: progress.guide.as_ref(),
        checkpoints: None,
    };
    let RenderOutput {
        image: film,
        stats,
        accumulation,
    } = render_from(
        &session.scene,
        &view.camera,
        &settings,
        from,
        &|_, _| {},
        &session.cancel,
    )?;
    progress.state = Some(accumulation);
    if stats.cancelled {
        return Ok(());
    }
    let (image, exposure) = view.shown(&view.camera, film)?;
    let jpeg = Bytes::from(encode_jpeg(&image, 0.0)?);
    let frame = Arc::new(Frame {
        generation: progress.generation,
        image,
        jpeg,
        view: view.clone(),
        exposure,
    });
    {
        let mut state = session.lock();
        if state.generation != progress.generation {
            return Ok(());
        }
        state.last_frame = Some(frame.clone());
    }
    let s = stats;
    let full_latency_ms = (!progress.shown).then(|| changed_at.elapsed().as_secs_f64() * 1e3);
    progress.shown = true;
    session.send(json!({
        "type": "frame",
        "generation": frame.generation,
        "spp": frame.image.spp_min,
        "max_spp": view.settings.max_spp,
        "step_seconds": s.seconds,
        "rays_per_second": s.rays as f64 / s.seconds.max(1e-9),
        "samples_per_second": s.samples as f64 / s.seconds.max(1e-9),
        "full_latency_ms": full_latency_ms,
        "sensor_depth_mm": view.sensor_depth_mm,
        "exposure": frame.exposure.as_ref().map(|e| json!({"time_s": e.exposure_time_s, "iso": e.iso})),
    }));
    let _ = session.events.send(Event::Frame(frame.jpeg.clone()));
    Ok(())
}

/// Renders and sends the half-size, one-sample preview of a new generation;
/// whether it was sent (not stopped by a change).
fn preview(session: &Session, generation: u64, view: &View, changed_at: Instant) -> Result<bool> {
    let (width, height) = ((view.render.width / 2).max(1), (view.render.height / 2).max(1));
    let camera = view.camera.with_image_size(width, height)?;
    let settings = lenspath::render::RenderSettings {
        width,
        height,
        spp: 1,
        // Unguided: a guide would take longer to train than the preview to render.
        integrator: Integrator::Path(view.render.integrator.path_settings()),
        ..view.render
    };
    let output = render(&session.scene, &camera, &settings, &|_, _| {}, &session.cancel)?;
    if output.stats.cancelled || session.lock().generation != generation {
        return Ok(false);
    }
    let jpeg = encode_jpeg(&view.shown(&camera, output.image)?.0, 0.0)?;
    session.send(json!({
        "type": "frame",
        "preview": true,
        "generation": generation,
        "spp": 0,
        "max_spp": view.settings.max_spp,
        "latency_ms": changed_at.elapsed().as_secs_f64() * 1e3,
        "sensor_depth_mm": view.sensor_depth_mm,
    }));
    let _ = session.events.send(Event::Frame(jpeg.into()));
    Ok(true)
}

/// Focuses on the request's patch as `lenspath autofocus` would (the same
/// search, samples, depth and seed), telling the pages each evaluation, then
/// moves the sensor there.
fn autofocus(session: &Session, request: &AutofocusRequest, view: &View) -> Result<()> {
    let [x, y, w, h] = request.patch;
    let patch = NormalizedRect::new(x, y, w, h)?;
    let overrides = AutofocusOverrides {
        seed: Some(view.settings.seed),
        threads: session.threads(),
        metric: Some(request.metric),
        strategy: Some(request.strategy),
        // Through the view's sensor, when it has one: what its image shows.
        sensor: view.sensor.as_ref().map(SensorSettings::description),
        ..AutofocusOverrides::default()
    };
    let search = autofocus_setup(
        view.lens_settings.clone(),
        session.resolution(),
        patch,
        &overrides,
        view.pose,
    )?;
    let strategy = search.strategy;
    let mut focuser = Focuser::new(&session.scene, view.pose, search.settings)?;
    let (infinity_mm, close_mm) = focuser.sweep_range_mm();
    session.send(json!({
        "type": "autofocus-start",
        "patch": request.patch,
        "metric": request.metric.name(),
        "strategy": request.strategy.name(),
        "range_mm": [infinity_mm, close_mm],
    }));
    focuser.on_evaluation(|e| {
        session.send(json!({
            "type": "autofocus-evaluation",
            "sensor_depth_mm": e.sensor_depth_mm,
            "score": e.score,
            "refocused": e.refocused,
        }))
    });
    let result = focuser.run(strategy)?;
    let view = session.change(&json!({"focus": {"by": "sensor", "depth_mm": result.sensor_depth_mm}}))?;
    session.send(json!({
        "type": "autofocus-done",
        "strategy": result.strategy,
        "metric": request.metric.name(),
        "sensor_depth_mm": result.sensor_depth_mm,
        "focus_distance_m": view.focus_distance_m,
        "evaluations": result.evaluations.len(),
        "camera_rays": result.camera_rays,
        "seconds": result.seconds,
    }));
    session.send(session.describe());
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_double_then_grow_by_sixteen() {
        let mut spp = 0;
        let steps: Vec<u32> = (0..8)
            .map(|_| {
                spp = next_step(spp);
                spp
            })
            .collect();
        assert_eq!(steps, [1, 2, 4, 8, 16, 32, 48, 64]);
    }
}
