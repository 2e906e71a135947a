//! A progress bar on standard error while trials run, drawn only when standard error is a
//! terminal (so logs and pipes stay clean).

use std::io::{IsTerminal, Write};
use std::sync::Mutex;
use std::time::Instant;

/// Width of the bar in characters.
const WIDTH: usize = 30;

/// Counts of a running batch.
struct Counts {
    done: usize,
    failed: usize,
}

/// A progress bar for `total` trials; workers call [`Progress::tick`] from any thread.
pub struct Progress {
    label: String,
    total: usize,
    started: Instant,
    counts: Mutex<Counts>,
    shown: bool,
}

impl Progress {
    /// A bar titled `label` for `total` trials, shown if standard error is a terminal.
    pub fn new(label: &str, total: usize) -> Progress {
        let progress = Progress {
            label: label.to_string(),
            total,
            started: Instant::now(),
            counts: Mutex::new(Counts { done: 0, failed: 0 }),
            shown: std::io::stderr().is_terminal(),
        };
        if progress.shown {
            progress.draw(&Counts { done: 0, failed: 0 });
        }
        progress
    }

    /// Counts one more trial, failed or not, and redraws the bar.
    pub fn tick(&self, passed: bool) {
        let mut counts = match self.counts.lock() {
            Ok(c) => c,
            Err(poisoned) => poisoned.into_inner(),
        };
        counts.done += 1;
        if !passed {
            counts.failed += 1;
        }
        if self.shown {
            self.draw(&counts);
        }
    }

    /// Sets the count of trials done (none failed) and redraws the bar.
    pub fn set(&self, done: usize) {
        let mut counts = match self.counts.lock() {
            Ok(c) => c,
            Err(poisoned) => poisoned.into_inner(),
        };
        counts.done = done;
        if self.shown {
            self.draw(&counts);
        }
    }

    /// Erases the bar, leaving the line for what is printed next.
    pub fn finish(&self) {
        if self.shown {
            let mut err = std::io::stderr().lock();
            // Clearing a progress line: a failed write to the terminal loses nothing.
            let _ = write!(err, "\r\x1b[2K");
            let _ = err.flush();
        }
    }

    fn draw(&self, counts: &Counts) {
        let total = self.total.max(1);
        let filled = WIDTH * counts.done.min(total) / total;
        let elapsed = self.started.elapsed().as_secs_f64();
        let rate = if elapsed > 0.0 {
            counts.done as f64 / elapsed
        } else {
            0.0
        };
        let left = if rate > 0.0 {
            format!(
                ", {:.0} s left",
                self.total.saturating_sub(counts.done) as f64 / rate
            )
        } else {
            String::new()
        };
        let mut err = std::io::stderr().lock();
        // Drawing a progress line: a failed write to the terminal loses nothing.
        let _ = write!(
            err,
            "\r\x1b[2K{} [{}{}] {}/{} trials, {} failed, {:.1} trials/s{left}",
            self.label,
            "#".repeat(filled),
            "-".repeat(WIDTH - filled),
            counts.done,
            self.total,
            counts.failed,
            rate
        );
        let _ = err.flush();
    }
}
