//! Worker threads: every parallel loop of the library (render tiles, light
//! fields, lens analysis) runs in a pool made here.

use crate::error::{Error, Result};

/// A pool of `threads` worker threads (`None`: one per core); more than
/// [`crate::defaults::MAX_THREADS`] is refused.
pub fn worker_pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    check_threads(threads)?;
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| Error::InvalidArgument(format!("cannot start worker threads: {e}")))
}

/// Fails for a thread count a worker pool cannot have: 0, or more than
/// [`crate::defaults::MAX_THREADS`].
pub fn check_threads(threads: Option<usize>) -> Result<()> {
    match threads {
        Some(0) => Err(Error::InvalidArgument("threads must be at least 1".into())),
        Some(n) if n > crate::defaults::MAX_THREADS => Err(Error::InvalidArgument(format!(
            "{n} threads asked for; at most {} (one per core is the default)",
            crate::defaults::MAX_THREADS
        ))),
        _ => Ok(()),
    }
}
