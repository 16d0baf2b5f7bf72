//! Contrast autofocus. So far: the focus measures, which score how sharp an
//! image patch is (patch rendering and the search strategies come next).

pub mod measures;

pub use measures::{FocusMeasure, Patch};
