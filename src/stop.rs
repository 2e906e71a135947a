//! How akl stops on a signal: the first Ctrl-C (SIGINT) or SIGTERM (what a cluster's scheduler
//! sends) raises a flag, so that a recording ends cleanly and a run of trials stops starting
//! trials and reports the ones that finished, instead of the process dying mid-write; a second
//! signal exits at once with 130. A reader that goes away (`akl ... | head`) ends it quietly.
//!
//! A command that runs trials passes [`interrupt`] down in its execution options
//! (`akl_exec::ExecOptions::interrupt`): every batch run with them then stops starting
//! trials once the flag is up (see `akl_exec::Interrupt`). It reports what finished and exits
//! with [`crate::exit::INTERRUPTED`] ([`crate::exit::CliError::interrupted`]).

use crate::exit::INTERRUPTED;
use akl_exec::Interrupt;
use std::sync::atomic::{AtomicBool, Ordering};

/// Raised by the first SIGINT or SIGTERM.
static STOP: AtomicBool = AtomicBool::new(false);

/// Installs the handler of SIGINT and SIGTERM (and SIGHUP) and returns the flag it raises. A
/// second signal, once the flag is already up, exits at once with 130.
pub(crate) fn on_ctrl_c() -> &'static AtomicBool {
    // Installing twice fails; the first handler is the one that matters.
    let _ = ctrlc::set_handler(|| {
        if STOP.swap(true, Ordering::SeqCst) {
            std::process::exit(INTERRUPTED.into());
        }
    });
    &STOP
}

/// Installs the handler (as [`on_ctrl_c`]) and returns the flag as an [`Interrupt`], to be put
/// in the execution options of the trials a command runs.
pub(crate) fn interrupt() -> Interrupt {
    Interrupt::on(on_ctrl_c())
}

/// Lets a closed output pipe end the process silently, as it does for other command-line
/// tools, instead of turning the failed write into a panic. Rust ignores SIGPIPE by default.
pub(crate) fn end_quietly_on_closed_pipe() {
    // SAFETY: restoring a signal's default disposition at start-up, before any thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
