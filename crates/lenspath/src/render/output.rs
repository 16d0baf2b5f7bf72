//! What a render gives back and keeps: its image and counters, its state
//! between two samples (`Accumulation`), and the periodic saving of that
//! state (`Checkpoints`).

use std::time::Duration;

use glam::DVec3;

use crate::error::{Error, Result};
use crate::film::{Image, PixelRect};

/// Counters of a finished (or stopped) render.
#[derive(Clone, Copy, Debug, Default)]
pub struct RenderStats {
    /// Wall time in seconds.
    pub seconds: f64,
    /// Camera samples taken (by this run, when it continued a saved one).
    pub samples: u64,
    /// Rays traced: camera, bounce and shadow rays.
    pub rays: u64,
    /// Samples whose radiance was NaN or infinite (dropped as zero).
    pub invalid_samples: u64,
    /// True when the render was stopped before all samples were taken.
    pub cancelled: bool,
}

/// What a render produced.
#[derive(Clone, Debug)]
pub struct RenderOutput {
    /// The image.
    pub image: Image,
    /// How it went.
    pub stats: RenderStats,
    /// Its state at the end, to continue it from ([`super::Continuation::start`]).
    pub accumulation: Accumulation,
}

/// The state of a render between two samples, enough to continue it: for
/// each pixel of the rendered region (row-major), the sum of its samples'
/// radiance, how many samples it has, and its depth. A pixel's sum is added to
/// in sample order whatever the passes, so a render continued from this state
/// ends bit-identical to one that never stopped.
#[derive(Clone, Debug, PartialEq)]
pub struct Accumulation {
    /// The pixels it covers: the whole image, or the crop.
    pub region: PixelRect,
    /// Sum of each pixel's sample radiance.
    pub sum: Vec<DVec3>,
    /// Samples each pixel has (its sample indices `0..count`).
    pub count: Vec<u32>,
    /// Depth along the view axis (infinite: nothing hit, or not yet computed).
    pub depth: Vec<f32>,
}

impl Accumulation {
    /// Samples every pixel has.
    pub fn spp_min(&self) -> u32 {
        self.count.iter().copied().min().unwrap_or(0)
    }
}

/// Least time between two checkpoint saves a front end accepts
/// ([`check_checkpoint_interval`]): a save writes the whole image's sums,
/// so saving after every pass spends the render writing them. (The library
/// itself saves as often as [`Checkpoints::every`] says: 0 is after every
/// pass, which its tests use.)
pub const MIN_CHECKPOINT_INTERVAL: Duration = Duration::from_millis(100);

/// Periodic saving of a render's [`Accumulation`], so a stopped or killed
/// render can continue ([`super::Continuation::start`]).
pub struct Checkpoints<'a> {
    /// Least time between two saves. Passes are kept short enough (about
    /// half of it) that a save is seldom late.
    pub every: Duration,
    /// Saves the state; called at most every `every`, and once more when the
    /// render finishes or is stopped. An error stops the render.
    pub save: &'a mut (dyn FnMut(&Accumulation) -> Result<()> + Send),
}

/// Fails for a checkpoint interval under [`MIN_CHECKPOINT_INTERVAL`].
pub fn check_checkpoint_interval(every: Duration) -> Result<()> {
    if every < MIN_CHECKPOINT_INTERVAL {
        return Err(Error::InvalidArgument(format!(
            "checkpoints at most every {} s, asked for every {} s",
            MIN_CHECKPOINT_INTERVAL.as_secs_f64(),
            every.as_secs_f64()
        )));
    }
    Ok(())
}
