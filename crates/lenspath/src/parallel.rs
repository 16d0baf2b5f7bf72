//! Worker threads: every parallel loop of the library (render tiles, light
//! fields, lens analysis) runs in a pool made here.

use crate::error::{Error, Result};

/// Most worker threads a render, autofocus or lens analysis may ask for:
/// far more than any machine's cores, far fewer than what makes the
/// operating system stall starting them (100 000 did).
pub const MAX_THREADS: usize = 1024;

/// A pool of `threads` worker threads (`None`: one per core); more than
/// [`MAX_THREADS`] is refused.
pub fn worker_pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    check_threads(threads)?;
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| Error::InvalidArgument(format!("cannot start worker threads: {e}")))
}

/// Fails for a thread count a worker pool cannot have: 0, or more than
/// [`MAX_THREADS`].
pub fn check_threads(threads: Option<usize>) -> Result<()> {
    match threads {
        Some(0) => Err(Error::InvalidArgument("threads must be at least 1".into())),
        Some(n) if n > MAX_THREADS => Err(Error::InvalidArgument(format!(
            "{n} threads asked for; at most {} (one per core is the default)",
            MAX_THREADS
        ))),
        _ => Ok(()),
    }
}
