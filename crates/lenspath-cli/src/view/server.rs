//! The viewer's HTTP server (axum): the page's files, a JSON API checked like
//! the CLI's flags, downloads of the image and the settings, and the
//! WebSocket that streams frames and messages to the page.
//!
//! | route | what |
//! |---|---|
//! | `GET /`, `/app.js`, `/style.css` | the page, embedded in the binary |
//! | `GET /api/state` | settings, lens choices, the camera's figures |
//! | `POST /api/settings` | a JSON object of the settings that change |
//! | `POST /api/autofocus` | `{"patch": [x, y, w, h], "metric", "strategy"}` |
//! | `POST /api/lens?name=FILE` | a dropped lens table (its text) |
//! | `GET /api/layout.svg` | the lens layout, the sensor where it is |
//! | `GET /api/mtf.svg` | the lens's MTF at the sensor, at the F, d and C lines, at three fields |
//! | `GET /api/image.png`, `/api/image.exr`, `/api/scene.toml` | the last complete image, and the scene file that renders it again |
//! | `GET /ws` | frames (binary, JPEG) and messages (text, JSON) |

use std::collections::HashMap;
use std::net::SocketAddr;
use std::sync::atomic::Ordering;
use std::sync::Arc;

use axum::body::Bytes;
use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::{DefaultBodyLimit, Query, Request, State};
use axum::http::{header, HeaderMap, HeaderValue, StatusCode};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::routing::{get, post};
use axum::{Json, Router};
use lenspath::io::image::{encode_image, ImageFormat, ImageHeader};
use lenspath::lens::wave_analysis::{WaveAnalysis, WaveAnalysisSettings, WeightedWavelength, SHOWN_FIELD_FRACTIONS};
use lenspath::lens::wave_plot::mtf_svg;
use lenspath::render::{render_depth, RenderSettings};
use lenspath::setup::{CameraSettings, RenderSetup};
use lenspath::Error;
use serde_json::{json, Value};
use tokio::sync::broadcast::error::RecvError;

use super::session::{AutofocusRequest, Event, Frame, Session, MAX_LENS_TABLE_BYTES};

/// Serves the viewer on `listener` until the process ends.
pub async fn serve(listener: std::net::TcpListener, session: Arc<Session>) -> std::io::Result<()> {
    let address = listener.local_addr()?;
    let app = Router::new()
        .route("/", get(|| async { page(INDEX_HTML, "text/html; charset=utf-8") }))
        .route(
            "/app.js",
            get(|| async { page(APP_JS, "text/javascript; charset=utf-8") }),
        )
        .route(
            "/style.css",
            get(|| async { page(STYLE_CSS, "text/css; charset=utf-8") }),
        )
        .route("/favicon.ico", get(|| async { StatusCode::NO_CONTENT }))
        .route("/api/state", get(state))
        .route("/api/settings", post(change))
        .route("/api/autofocus", post(autofocus))
        .route("/api/lens", post(drop_lens))
        .route("/api/layout.svg", get(layout))
        .route("/api/mtf.svg", get(mtf))
        .route("/api/image.png", get(|s| download(s, Download::Png)))
        .route("/api/image.exr", get(|s| download(s, Download::Exr)))
        .route("/api/scene.toml", get(|s| download(s, Download::SceneFile)))
        .route("/ws", get(websocket))
        .layer(DefaultBodyLimit::max(MAX_LENS_TABLE_BYTES + 1024))
        .layer(middleware::from_fn_with_state(Arc::new(address), same_origin))
        .with_state(session);
    listener.set_nonblocking(true)?;
    axum::serve(tokio::net::TcpListener::from_std(listener)?, app).await
}

const INDEX_HTML: &str = include_str!("web/index.html");
const APP_JS: &str = include_str!("web/app.js");
const STYLE_CSS: &str = include_str!("web/style.css");

fn page(body: &'static str, content_type: &'static str) -> Response {
    ([(header::CONTENT_TYPE, content_type)], body).into_response()
}

/// An input error as the page shows it: 400 and `{"error": message}`.
fn bad_request(e: impl std::fmt::Display) -> Response {
    (StatusCode::BAD_REQUEST, Json(json!({ "error": e.to_string() }))).into_response()
}

/// Refuses requests whose `Host` (or `Origin`) names another server than
/// this loopback one, so that a web page elsewhere cannot reach it through
/// a rebinding DNS name. Served on another address, any host is let in.
async fn same_origin(State(address): State<Arc<SocketAddr>>, request: Request, next: Next) -> Response {
    if address.ip().is_loopback() {
        let port = address.port();
        let allowed = [
            format!("127.0.0.1:{port}"),
            format!("localhost:{port}"),
            format!("[::1]:{port}"),
        ];
        let headers = request.headers();
        let host_ok = headers
            .get(header::HOST)
            .and_then(|h| h.to_str().ok())
            .is_some_and(|h| allowed.iter().any(|a| a == h));
        let origin_ok = headers
            .get(header::ORIGIN)
            .and_then(|o| o.to_str().ok())
            .is_none_or(|o| allowed.iter().any(|a| o == format!("http://{a}")));
        if !(host_ok && origin_ok) {
            return (
                StatusCode::FORBIDDEN,
                format!("lenspath view answers only pages of http://127.0.0.1:{port}/"),
            )
                .into_response();
        }
    }
    next.run(request).await
}

async fn state(State(session): State<Arc<Session>>) -> Response {
    Json(session.describe()).into_response()
}

/// The MTF of the view's lens, stopped and focused as it renders, at
/// [`SHOWN_FIELD_FRACTIONS`] of its half-diagonal field, over the visible
/// lines: what `lenspath lens --mtf --mtf-plot` draws.
async fn mtf(State(session): State<Arc<Session>>) -> Response {
    let (system, sensor_depth_mm, half_field_deg) = {
        let session = session.lock();
        let view = &session.view;
        (
            view.camera.system().clone(),
            view.sensor_depth_mm,
            view.half_diagonal_field_deg,
        )
    };
    let result = blocking(move || {
        let settings = WaveAnalysisSettings {
            spectrum: WeightedWavelength::visible_lines(),
            sensor_depth_mm: Some(sensor_depth_mm),
            ..WaveAnalysisSettings::default()
        };
        let analyses = SHOWN_FIELD_FRACTIONS
            .iter()
            .map(|fraction| {
                WaveAnalysis::new(
                    &system,
                    &WaveAnalysisSettings {
                        field_deg: fraction * half_field_deg,
                        ..settings.clone()
                    },
                )
            })
            .collect::<lenspath::Result<Vec<_>>>()?;
        Ok(mtf_svg(system.prescription().name(), &analyses))
    })
    .await;
    match result {
        Ok(svg) => (
            [
                (header::CONTENT_TYPE, "image/svg+xml"),
                (header::CACHE_CONTROL, "no-store"),
            ],
            svg,
        )
            .into_response(),
        Err(e) => bad_request(e),
    }
}

/// Runs `work` (which builds cameras or parses tables) off the async threads.
async fn blocking<T: Send + 'static>(
    work: impl FnOnce() -> lenspath::Result<T> + Send + 'static,
) -> lenspath::Result<T> {
    tokio::task::spawn_blocking(work)
        .await
        .unwrap_or_else(|e| Err(Error::InvalidArgument(format!("the request failed: {e}"))))
}

fn parse_json(body: &Bytes) -> lenspath::Result<Value> {
    serde_json::from_slice(body).map_err(|e| Error::InvalidArgument(format!("the request is not JSON: {e}")))
}

async fn change(State(session): State<Arc<Session>>, body: Bytes) -> Response {
    let result = blocking(move || {
        let change = parse_json(&body)?;
        session.change(&change)?;
        Ok(session.describe())
    })
    .await;
    match result {
        Ok(described) => Json(described).into_response(),
        Err(e) => bad_request(e),
    }
}

async fn autofocus(State(session): State<Arc<Session>>, body: Bytes) -> Response {
    let request = parse_json(&body).and_then(|v| {
        serde_json::from_value::<AutofocusRequest>(v)
            .map_err(|e| Error::InvalidArgument(format!("bad autofocus request: {e}")))
    });
    match request.and_then(|r| session.request_autofocus(r)) {
        Ok(()) => (StatusCode::ACCEPTED, Json(json!({ "queued": true }))).into_response(),
        Err(e) => bad_request(e),
    }
}

async fn drop_lens(
    State(session): State<Arc<Session>>,
    Query(query): Query<HashMap<String, String>>,
    body: Bytes,
) -> Response {
    let result = blocking(move || {
        let name = query
            .get("name")
            .ok_or_else(|| Error::InvalidArgument("a dropped lens needs ?name=FILE".into()))?;
        let text = std::str::from_utf8(&body)
            .map_err(|_| Error::InvalidArgument(format!("lens table '{name}' is not UTF-8 text")))?;
        session.add_dropped_lens(name, text)?;
        Ok(session.describe())
    })
    .await;
    match result {
        Ok(described) => Json(described).into_response(),
        Err(e) => bad_request(e),
    }
}

async fn layout(State(session): State<Arc<Session>>) -> Response {
    let svg = session.lock().view.layout_svg.clone();
    (
        [
            (header::CONTENT_TYPE, "image/svg+xml"),
            (header::CACHE_CONTROL, "no-store"),
        ],
        svg,
    )
        .into_response()
}

/// What the save buttons fetch.
#[derive(Clone, Copy)]
enum Download {
    Png,
    Exr,
    SceneFile,
}

async fn download(State(session): State<Arc<Session>>, what: Download) -> Response {
    let Some(frame) = session.lock().last_frame.clone() else {
        return (
            StatusCode::CONFLICT,
            Json(json!({ "error": "no complete image yet: wait for the first frame" })),
        )
            .into_response();
    };
    let result = blocking(move || encode(&session, &frame, what)).await;
    match result {
        Ok((bytes, content_type, name)) => {
            let mut headers = HeaderMap::new();
            headers.insert(header::CONTENT_TYPE, HeaderValue::from_static(content_type));
            if let Ok(v) = HeaderValue::from_str(&format!("attachment; filename=\"{name}\"")) {
                headers.insert(header::CONTENT_DISPOSITION, v);
            }
            (headers, bytes).into_response()
        }
        Err(e) => bad_request(e),
    }
}

fn encode(session: &Session, frame: &Frame, what: Download) -> lenspath::Result<(Vec<u8>, &'static str, String)> {
    let stem = format!("lenspath-view-{}spp", frame.image.spp_min);
    Ok(match what {
        Download::Png => (
            encode_image(&frame.image, ImageFormat::Png, 0.0, &ImageHeader::default())?,
            "image/png",
            format!("{stem}.png"),
        ),
        Download::Exr => {
            // The depth channel the view's renders leave out, as `lenspath render` computes it.
            let mut image = frame.image.clone();
            let settings = RenderSettings {
                depth: true,
                ..frame.view.render
            };
            image.depth = render_depth(&session.scene, &frame.view.camera, &settings)?;
            // The header `lenspath render` writes for the same render.
            let setup = RenderSetup {
                settings: RenderSettings {
                    spp: frame.image.spp_min,
                    ..frame.view.render
                },
                camera: CameraSettings::Realistic(frame.view.lens_settings.clone()),
                pose: frame.view.pose,
                sensor: None,
            };
            let header = setup.image_header(&session.scene_name, frame.exposure.as_ref())?;
            (
                encode_image(&image, ImageFormat::Exr, 0.0, &header)?,
                "image/x-exr",
                format!("{stem}.exr"),
            )
        }
        Download::SceneFile => (
            session.settings_file(frame)?.into_bytes(),
            "application/toml; charset=utf-8",
            format!("{stem}.toml"),
        ),
    })
}

async fn websocket(State(session): State<Arc<Session>>, upgrade: WebSocketUpgrade) -> Response {
    upgrade.on_upgrade(move |socket| client(socket, session))
}

/// One page: counted while connected (the render thread sleeps at none), sent
/// the state and the last frame, then every message and frame.
async fn client(mut socket: WebSocket, session: Arc<Session>) {
    let mut events = session.events.subscribe();
    let last_frame = {
        let mut state = session.lock();
        if state.clients == 0 {
            // The render was idle: the first preview's wait starts now.
            state.changed_at = std::time::Instant::now();
        }
        state.clients += 1;
        state.last_frame.clone()
    };
    session.wake.notify_all();
    let mut ok = socket
        .send(Message::Text(session.describe().to_string().into()))
        .await
        .is_ok();
    if let (true, Some(frame)) = (ok, last_frame) {
        ok = socket.send(Message::Binary(frame.jpeg.clone())).await.is_ok();
    }
    while ok {
        tokio::select! {
            event = events.recv() => {
                ok = match event {
                    Ok(Event::Frame(jpeg)) => socket.send(Message::Binary(jpeg)).await.is_ok(),
                    Ok(Event::Message(text)) => socket.send(Message::Text(text.as_str().into())).await.is_ok(),
                    // A slow page skips what it missed; the next frame catches it up.
                    Err(RecvError::Lagged(_)) => true,
                    Err(RecvError::Closed) => false,
                };
            }
            incoming = socket.recv() => {
                ok = matches!(incoming, Some(Ok(m)) if !matches!(m, Message::Close(_)));
            }
        }
    }
    let mut state = session.lock();
    state.clients -= 1;
    if state.clients == 0 {
        // Nobody is looking: stop rendering.
        session.cancel.store(true, Ordering::SeqCst);
    }
}
