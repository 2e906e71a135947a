//! A progress bar on standard error while trials run (indicatif), drawn only when standard
//! error is a terminal, so logs and pipes stay clean.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A progress bar for `total` trials; workers call [`Progress::tick`] from any thread.
pub(crate) struct Progress {
    bar: ProgressBar,
    failed: AtomicUsize,
}

impl Progress {
    /// A bar titled `label` for `total` trials, shown if standard error is a terminal.
    pub(crate) fn new(label: &str, total: usize) -> Progress {
        Progress::counting(label, total, "trials")
    }

    /// A bar titled `label` for `total` items called `unit` (e.g. "problems").
    pub(crate) fn counting(label: &str, total: usize, unit: &str) -> Progress {
        let target = if std::io::stderr().is_terminal() {
            ProgressDrawTarget::stderr()
        } else {
            ProgressDrawTarget::hidden()
        };
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
        }
    }

    /// Counts one more trial, failed or not.
    pub(crate) fn tick(&self, passed: bool) {
        if !passed {
            let failed = self.failed.fetch_add(1, Ordering::Relaxed) + 1;
            self.bar.set_message(failed.to_string());
        }
        self.bar.inc(1);
    }

    /// Sets the count of trials done.
    pub(crate) fn set(&self, done: usize) {
        self.bar.set_position(done as u64);
    }

    /// Renames what the bar counts (a new stage of the same run).
    pub(crate) fn relabel(&self, label: &str) {
        self.bar.set_prefix(label.to_string());
    }

    /// Erases the bar, leaving the line for what is printed next.
    pub(crate) fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
