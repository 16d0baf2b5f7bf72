//! Autofocus: focus measures score how sharp an image patch is
//! ([`measures`]); a [`Focuser`] renders the patch through the realistic
//! camera at chosen sensor positions and searches for the sharpest
//! ([`search`]). docs/autofocus.md describes the strategies and how they were
//! checked against ground truth.

mod frames;
pub mod light_field;
pub mod measures;
pub mod plot;
mod range;
pub mod search;
mod signal;
mod truth;

pub use frames::{FocusSensor, SensorSignal};
pub use measures::{FocusMeasure, Patch};
pub use range::RangeFocus;
pub use search::{AutofocusResult, AutofocusSettings, Evaluation, Focuser, Strategy};
pub use signal::Detail;
pub use truth::{GroundTruth, TRUTH_MAX_SPP_FACTOR, TRUTH_SEED_SPREAD_DOF};
