//! Stopping a run part-way, keeping what was done: on Ctrl-C (or SIGTERM) a command raises a
//! flag, batches start no more trials, the trials under way finish, and the command reports
//! what finished.
//!
//! The flag travels in [`crate::options::ExecOptions::interrupt`], so everything that runs
//! batches with those options (execution, the grounding check, validation, relaxation,
//! comparison) stops starting trials without being handed the flag again. A batch run once the
//! flag is up runs no trial at all and says it was interrupted
//! ([`crate::report::BatchReport::interrupted`]); code that runs batch after batch should check
//! [`Interrupt::raised`] between them, stop, and report what it has.

use std::fmt;
use std::sync::atomic::{AtomicBool, Ordering};

/// A flag that, once raised, stops batches from starting trials. Cheap to copy; two handles
/// are equal when they watch the same flag (or both none).
#[derive(Clone, Copy, Default)]
pub struct Interrupt(Option<&'static AtomicBool>);

impl Interrupt {
    /// Never raised: every trial asked for runs (the default).
    pub const NEVER: Interrupt = Interrupt(None);

    /// Raised once `flag` is (e.g. the flag a signal handler sets).
    pub fn on(flag: &'static AtomicBool) -> Interrupt {
        Interrupt(Some(flag))
    }

    /// Whether the flag is up: no trial should start any more.
    pub fn raised(&self) -> bool {
        self.0.is_some_and(|f| f.load(Ordering::SeqCst))
    }
}

impl PartialEq for Interrupt {
    fn eq(&self, other: &Interrupt) -> bool {
        match (self.0, other.0) {
            (Some(a), Some(b)) => std::ptr::eq(a, b),
            (None, None) => true,
            _ => false,
        }
    }
}

impl fmt::Debug for Interrupt {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.0 {
            Some(_) => write!(f, "Interrupt(raised: {})", self.raised()),
            None => f.write_str("Interrupt::NEVER"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_interrupt_is_raised_with_its_flag_and_never_without_one() {
        static FLAG: AtomicBool = AtomicBool::new(false);
        let on = Interrupt::on(&FLAG);
        assert!(!on.raised() && !Interrupt::NEVER.raised());
        assert_eq!(on, Interrupt::on(&FLAG));
        assert_ne!(on, Interrupt::NEVER);
        assert_eq!(Interrupt::default(), Interrupt::NEVER);
        FLAG.store(true, Ordering::SeqCst);
        assert!(on.raised() && !Interrupt::NEVER.raised());
    }
}
