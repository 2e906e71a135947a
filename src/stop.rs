//! How akl stops on a signal: Ctrl-C ends a recording cleanly instead of killing the process
//! mid-write, and a reader that goes away (`akl ... | head`) ends it quietly.

use std::sync::atomic::{AtomicBool, Ordering};

/// Raised by the first Ctrl-C.
static STOP: AtomicBool = AtomicBool::new(false);

/// Installs the Ctrl-C handler and returns the flag it raises. A second Ctrl-C, once the
/// flag is already up, exits at once.
pub fn on_ctrl_c() -> &'static AtomicBool {
    // Installing twice fails; the first handler is the one that matters.
    let _ = ctrlc::set_handler(|| {
        if STOP.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
    });
    &STOP
}

/// Lets a closed output pipe end the process silently, as it does for other command-line
/// tools, instead of turning the failed write into a panic. Rust ignores SIGPIPE by default.
pub fn end_quietly_on_closed_pipe() {
    // SAFETY: restoring a signal's default disposition at start-up, before any thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}
