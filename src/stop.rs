//! Ctrl-C ends a recording cleanly instead of killing the process mid-write.

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
