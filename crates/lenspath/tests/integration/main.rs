//! The library's integration tests, one module per concept, in one test
//! binary: each file of its own would link the library again and run one
//! after another (together minutes of CI); here their tests share the
//! cores. `cargo test -p lenspath --test integration sensor::` runs one
//! module's.

mod autofocus;
mod checkpoint;
mod chromatic_images;
mod depth_blur;
mod develop;
mod diffraction;
mod guiding;
mod lens_files;
mod light_field;
mod opencv_agreement;
mod prism;
mod realistic_camera;
mod render_analytic;
mod scene_import;
mod sensor;
mod shared_assets;
mod shared_folder;
