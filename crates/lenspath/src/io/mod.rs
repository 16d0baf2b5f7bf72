//! Files in and out: image output (PNG, OpenEXR) and mesh input (PLY, OBJ).

pub mod image;
pub mod mesh;
