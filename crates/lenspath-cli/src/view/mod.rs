//! `lenspath view`: look through the lens in a browser. A local web server
//! renders the scene through the realistic camera, refining as samples
//! accumulate and starting again on every change, and streams the frames to
//! a page (plain JavaScript modules, embedded in the binary) with the lens,
//! f-stop, focus and aperture controls, click-to-autofocus, orbit, pan and
//! zoom, the lens layout, and saving of the image and the settings.
//!
//! Built with the `viewer` feature (the Python package and the test suite
//! have it; the README's first render does without its web server, for a
//! quicker first build); without it the command says how to get it.
//!
//! - `launch`: loading the scene, the server's socket and its runtime
//! - `session`: the settings, checked like CLI input, and the camera built from them
//! - `worker`: the render thread (progressive steps, autofocus, idle without a page)
//! - `server`: the HTTP routes and the WebSocket
//! - `web/`: the page

#[cfg(feature = "viewer")]
mod launch;
#[cfg(feature = "viewer")]
mod server;
#[cfg(feature = "viewer")]
mod session;
#[cfg(feature = "viewer")]
mod worker;

use std::net::IpAddr;
use std::path::PathBuf;

use clap::Args;

use crate::flags::{parse_resolution, Resolution, SceneArgs};
#[cfg(feature = "viewer")]
pub use launch::run;

/// Options of `lenspath view`.
#[derive(Args, Debug)]
#[cfg_attr(not(feature = "viewer"), allow(dead_code))]
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

/// `lenspath view` in a build without the viewer: says how to get one.
#[cfg(not(feature = "viewer"))]
pub fn run(_args: ViewArgs) -> lenspath::Result<crate::Outcome> {
    Err(lenspath::Error::InvalidArgument(
        "this lenspath was built without its viewer (the `viewer` feature); build it with \
         `cargo run --release --features viewer -- view`, or use the Python package's `lenspath view`"
            .into(),
    ))
}
