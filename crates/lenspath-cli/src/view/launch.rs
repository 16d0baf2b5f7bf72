//! Starting `lenspath view`: the scene loaded and compiled, the session
//! made, the render thread started, and the server run on its socket.

use std::net::SocketAddr;
use std::sync::Arc;

use lenspath::accel::BvhSettings;
use lenspath::io::scene_file::SceneBase;
use lenspath::{Error, Result};

use super::{server, session, worker, ViewArgs};
use crate::Outcome;

/// The image size when neither the flag nor the scene file gives one: small
/// enough for a first preview within 200 ms on two cores.
const DEFAULT_VIEW_SIZE: (u32, u32) = (480, 360);

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
