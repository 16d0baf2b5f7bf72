//! lenspath: a physically based CPU path tracer whose camera is a real compound lens.
//!
//! Data flow: a [`scene::Scene`] description is compiled into a
//! [`scene::CompiledScene`] (a SAH [`accel::Bvh`] over every primitive plus
//! area lights); [`render::render`] splits the film into tiles, asks a
//! [`camera::Camera`] for rays, and the [`integrator`] estimates the radiance
//! along each; the [`film::Image`] is written by [`io::image`].
//!
//! The library never prints or exits; every failure is an [`Error`].

#![warn(missing_docs)]

pub mod accel;
pub mod builtin;
pub mod camera;
pub mod error;
pub mod film;
pub mod integrator;
pub mod io;
pub mod lights;
pub mod materials;
pub mod math;
pub mod ray;
pub mod raysets;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod shapes;

pub use error::{Error, Result};
