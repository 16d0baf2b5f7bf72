//! Progress reporting: a bar with ETA on a terminal, plain percentage lines otherwise.

use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressStyle};

/// Reports `done / total` units of work to stderr.
pub enum Progress {
    /// Interactive: an indicatif bar.
    Bar(ProgressBar),
    /// Logs and pipes: a line every 10% (and at most every 2 s otherwise).
    Plain {
        label: String,
        state: Mutex<(u64, Instant)>,
    },
}

impl Progress {
    /// A reporter suited to where stderr goes.
    pub fn new(label: &str, total: u64) -> Self {
        if std::io::stderr().is_terminal() {
            let bar = ProgressBar::new(total);
            bar.set_style(
                ProgressStyle::with_template("{msg} [{bar:40}] {percent:>3}% {elapsed_precise} ETA {eta}")
                    .expect("static template")
                    .progress_chars("=> "),
            );
            bar.set_message(label.to_string());
            bar.enable_steady_tick(Duration::from_millis(200));
            Progress::Bar(bar)
        } else {
            Progress::Plain {
                label: label.to_string(),
                state: Mutex::new((0, Instant::now())),
            }
        }
    }

    /// Records that `done` of `total` units are finished.
    pub fn update(&self, done: u64, total: u64) {
        match self {
            Progress::Bar(bar) => bar.set_position(done),
            Progress::Plain { label, state } => {
                let percent = done * 100 / total.max(1);
                let mut s = state.lock().unwrap_or_else(|p| p.into_inner());
                if percent >= s.0 + 10 || (percent > s.0 && s.1.elapsed() > Duration::from_secs(2)) {
                    *s = (percent, Instant::now());
                    eprintln!("{label}: {percent}%");
                }
            }
        }
    }

    /// Prints `message` to stderr on a line of its own (above the bar).
    pub fn say(&self, message: &str) {
        match self {
            Progress::Bar(bar) => bar.suspend(|| eprintln!("{message}")),
            Progress::Plain { .. } => eprintln!("{message}"),
        }
    }

    /// Removes the bar.
    pub fn finish(&self) {
        if let Progress::Bar(bar) = self {
            bar.finish_and_clear();
        }
    }
}
