//! A progress bar on standard error while trials run (indicatif), drawn only when standard
//! error is a terminal; otherwise (a CI log, a Slurm output file) one line at every tenth of
//! the way, so a long run shows it is alive without filling the log.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

/// A progress bar for `total` trials; workers call [`Progress::tick`] from any thread.
pub(crate) struct Progress {
    bar: ProgressBar,
    failed: AtomicUsize,
    /// The one-line reports when standard error is not a terminal.
    lines: Option<Lines>,
}

/// One line on standard error each time another tenth of the total is done.
struct Lines {
    label: Mutex<String>,
    unit: String,
    total: usize,
    done: AtomicUsize,
    /// The last tenth reported (0 to 10).
    reported: AtomicUsize,
    started: Instant,
}

impl Lines {
    /// Counts `done` items with `failed` failed, printing a line if a new tenth was reached.
    fn update(&self, done: usize, failed: usize) {
        let tenth = (done * 10).checked_div(self.total).unwrap_or(10).min(10);
        let last = self.reported.fetch_max(tenth, Ordering::Relaxed);
        if tenth > last {
            let label = self.label.lock().map(|l| l.clone()).unwrap_or_default();
            eprintln!(
                "{label}: {done}/{} {} ({} %), {failed} failed, {:.1} s",
                self.total,
                self.unit,
                tenth * 10,
                self.started.elapsed().as_secs_f64()
            );
        }
    }
}

impl Progress {
    /// A bar titled `label` for `total` trials, shown if standard error is a terminal.
    pub(crate) fn new(label: &str, total: usize) -> Progress {
        Progress::counting(label, total, "trials")
    }

    /// A bar titled `label` for `total` items called `unit` (e.g. "problems").
    pub(crate) fn counting(label: &str, total: usize, unit: &str) -> Progress {
        let terminal = std::io::stderr().is_terminal();
        let target = if terminal {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        };
        let lines = (!terminal).then(|| Lines {
            label: Mutex::new(label.to_string()),
            unit: unit.to_string(),
            total,
            done: AtomicUsize::new(0),
            reported: AtomicUsize::new(0),
            started: Instant::now(),
        });
        let style = ProgressStyle::with_template(&format!(
            "{{prefix}} [{{bar:20}}] {{pos}}/{{len}} {unit}, {{msg}} failed, {{elapsed}} ({{eta}} left)"
        ))
        .map(|s| s.progress_chars("#>-"))
        .unwrap_or_else(|_| ProgressStyle::default_bar());
        let bar = ProgressBar::with_draw_target(Some(total as u64), target)
            .with_style(style)
            .with_prefix(label.to_string())
            .with_message("0");
        bar.tick();
        Progress {
            bar,
            failed: AtomicUsize::new(0),
            lines,
        }
    }

    /// Counts one more trial, failed or not.
    pub(crate) fn tick(&self, passed: bool) {
        let failed = if passed {
            self.failed.load(Ordering::Relaxed)
        } else {
            let failed = self.failed.fetch_add(1, Ordering::Relaxed) + 1;
            self.bar.set_message(failed.to_string());
            failed
        };
        self.bar.inc(1);
        if let Some(lines) = &self.lines {
            let done = lines.done.fetch_add(1, Ordering::Relaxed) + 1;
            lines.update(done, failed);
        }
    }

    /// Sets the count of trials done.
    pub(crate) fn set(&self, done: usize) {
        self.bar.set_position(done as u64);
        if let Some(lines) = &self.lines {
            lines.done.store(done, Ordering::Relaxed);
            lines.update(done, self.failed.load(Ordering::Relaxed));
        }
    }

    /// Renames what the bar counts (a new stage of the same run).
    pub(crate) fn relabel(&self, label: &str) {
        self.bar.set_prefix(label.to_string());
        if let Some(lines) = &self.lines {
            if let Ok(mut l) = lines.label.lock() {
                *l = label.to_string();
            }
        }
    }

    /// Erases the bar, leaving the line for what is printed next.
    pub(crate) fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
