//! Autofocus: focus measures score how sharp an image patch is
//! ([`measures`]); a [`Focuser`] renders the patch through the realistic
//! camera at chosen sensor positions and searches for the sharpest
//! ([`search`]). docs/autofocus.md describes the strategies and how they were
//! checked against ground truth.

pub mod light_field;
pub mod measures;
pub mod plot;
pub mod search;

pub use measures::{FocusMeasure, Patch, FOCUS_MEASURES};
pub use search::{
    AutofocusResult, AutofocusSettings, Detail, Evaluation, Focuser, GroundTruth, RangeFocus, Strategy, STRATEGIES,
};
