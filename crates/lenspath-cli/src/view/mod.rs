//! `lenspath view`: look through the lens in a browser. A local web server
//! renders the scene through the realistic camera, refining as samples
//! accumulate and starting again on every change, and streams the frames to
//! a page (plain JavaScript modules, embedded in the binary) with the lens,
//! f-stop, focus and aperture controls, click-to-autofocus, orbit, pan and
//! zoom, the lens layout, and saving of the image and the settings.
//!
//! - `session`: the settings, checked like CLI input, and the camera built from them
//! - `worker`: the render thread (progressive steps, autofocus, idle without a page)
//! - `server`: the HTTP routes and the WebSocket
//! - `web/`: the page

mod server;
mod session;
mod worker;

use std::net::{IpAddr, SocketAddr};
use std::path::PathBuf;
use std::sync::Arc;

use clap::Args;
use lenspath::accel::BvhSettings;
use lenspath::io::scene_file::SceneBase;
use lenspath::{Error, Result};

use crate::flags::{parse_resolution, Resolution, SceneArgs};
use crate::Outcome;

/// The image size when neither the flag nor the scene file gives one: small
/// enough for a first preview within 200 ms on two cores.
const DEFAULT_VIEW_SIZE: (u32, u32) = (480, 360);

/// Options of `lenspath view`.
#[derive(Args, Debug)]
pub struct ViewArgs {
    #[command(flatten)]
    scene: SceneArgs,
    /// Port to listen on (0: any free port; the URL printed says which).
    #[arg(long, default_value_t = 8080)]
    port: u16,
    /// Address to listen on. The default lets only this machine in; another
    /// (such as 0.0.0.0) lets in whoever can reach it.
    #[arg(long, default_value = "127.0.0.1")]
    host: IpAddr,
    /// A lens table file the page may choose, besides the built-ins, tables
    /// in the scene's folder and tables dropped on the page (repeatable).
    #[arg(long = "lens", value_name = "FILE")]
    lenses: Vec<PathBuf>,
    /// Image size, WIDTHxHEIGHT [default: 480x360].
    #[arg(long, value_parser = parse_resolution)]
    res: Option<Resolution>,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
}

/// Runs `lenspath view` until it is stopped (Ctrl-C).
pub fn run(args: ViewArgs) -> Result<Outcome> {
    let (scene_name, scene, options) = args.scene.load()?;
    let base = match (args.scene.builtin(), &args.scene.file) {
        (None, Some(path)) => SceneBase::File(path.canonicalize().map_err(|e| lenspath::fs::io_error(path, e))?),
        _ => SceneBase::Builtin {
            name: scene_name.clone(),
            mesh_triangles: args.scene.mesh_triangles,
        },
    };
    let view = scene
        .view
        .ok_or_else(|| Error::InvalidArgument(format!("scene '{scene_name}' has no camera")))?;
    let resolution = args.res.map_or(DEFAULT_VIEW_SIZE, |r| (r.width, r.height));
    let compiled = scene.compile(&BvhSettings::default())?;
    let source = session::SceneSource {
        name: scene_name.clone(),
        base,
        options,
        view,
    };
    let session = Arc::new(session::Session::new(
        compiled,
        source,
        resolution,
        args.threads,
        &args.lenses,
    )?);
    let address = SocketAddr::new(args.host, args.port);
    let listener = std::net::TcpListener::bind(address)
        .map_err(|e| Error::InvalidArgument(format!("cannot listen on {address}: {e}")))?;
    let url_address = listener
        .local_addr()
        .map_err(|e| Error::InvalidArgument(e.to_string()))?;
    worker::spawn(session.clone())
        .map_err(|e| Error::InvalidArgument(format!("cannot start the render thread: {e}")))?;
    // The first line says where: scripts (and the tests) read the URL from it.
    println!("lenspath view: http://{url_address}/ shows {scene_name} (Ctrl-C stops)");
    use std::io::Write;
    let _ = std::io::stdout().flush();
    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .map_err(|e| Error::InvalidArgument(format!("cannot start the server: {e}")))?;
    runtime
        .block_on(server::serve(listener, session))
        .map_err(|e| Error::InvalidArgument(format!("the server stopped: {e}")))?;
    Ok(Outcome::Done)
}
