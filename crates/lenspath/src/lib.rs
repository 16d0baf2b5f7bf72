//! lenspath: a physically based CPU path tracer whose camera is a real compound lens.
//!
//! Data flow: a [`scene::Scene`] description is compiled into a
//! [`scene::CompiledScene`] (a SAH [`accel::Bvh`] over every primitive plus
//! area lights); [`render::render`] splits the film into tiles, asks a
//! [`camera::Camera`] for rays, and the [`integrator`] estimates the radiance
//! along each; the [`film::Image`] is written by [`io::image`].
//!
//! The default camera, [`camera::RealisticCamera`], traces every ray through
//! a real lens prescription ([`lens::LensSystem`]).
//!
//! The library never prints or exits; every failure is an [`Error`].
//!
//! ```
//! use std::sync::atomic::AtomicBool;
//! use lenspath::{accel::BvhSettings, builtin::builtin_scene, camera::PerspectiveCamera};
//! use lenspath::render::{render, RenderSettings};
//!
//! let scene = builtin_scene("cornell-spheres", 0)?;
//! let view = scene.view.expect("built-in scenes have a view");
//! let camera = PerspectiveCamera::pinhole(view.pose, view.fov_y_deg, 32, 24);
//! let settings = RenderSettings { width: 32, height: 24, spp: 4, ..Default::default() };
//! let compiled = scene.compile(&BvhSettings::default())?;
//! let output = render(&compiled, &camera, &settings, &|_done, _total| {}, &AtomicBool::new(false))?;
//! assert_eq!(output.image.rgb.len(), 32 * 24 * 3);
//! assert!(output.image.mean()[0] > 0.0);
//! # Ok::<(), lenspath::Error>(())
//! ```

#![warn(missing_docs)]

pub mod accel;
pub mod autofocus;
pub mod bokeh;
pub mod builtin;
pub mod camera;
pub mod color;
pub mod defaults;
pub mod error;
pub mod film;
pub mod fs;
pub mod glass;
pub mod guiding;
pub mod integrator;
pub mod io;
pub mod lens;
pub mod lens_report;
pub mod lights;
pub mod materials;
pub mod math;
pub mod memory;
pub mod names;
pub mod options;
pub mod parallel;
pub mod ray;
pub mod raysets;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod sensor;
pub mod setup;
pub mod shapes;
pub mod spectrum;

pub use error::{Error, FileKind, Result};
