//! Worker threads: every parallel loop of the library (render tiles, light
//! fields, lens analysis) runs in a pool made here.

use crate::error::{Error, Result};

/// A pool of `threads` worker threads (`None`: one per core).
pub fn worker_pool(threads: Option<usize>) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads.unwrap_or(0))
        .build()
        .map_err(|e| Error::InvalidArgument(format!("cannot start worker threads: {e}")))
}
