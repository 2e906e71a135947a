//! The CLI's error type and exit codes: 2 for bad input, 1 for internal failures, 130 for a run
//! stopped by a signal.

use std::fmt::Display;

/// Exit code for input the user can fix: a malformed file, an unknown name, a bad flag value.
pub(crate) const BAD_INPUT: u8 = 2;
/// Exit code for failures that are not the input's fault (an output that cannot be written).
pub(crate) const INTERNAL: u8 = 1;
/// Exit code of `akl validate` when the gate cannot decide within its trials.
pub(crate) const UNDECIDED: u8 = 3;
/// Exit code of `akl validate` when the spec passes the gate but is not the least restrictive.
pub(crate) const NOT_MINIMAL: u8 = 4;
/// Exit code of a run stopped by SIGINT or SIGTERM (128 + SIGINT, as shells report Ctrl-C),
/// after it reported the trials that finished.
pub(crate) const INTERRUPTED: u8 = 130;

/// A failed command: one line of message and the process exit code.
#[derive(Debug)]
pub(crate) struct CliError {
    /// Exit code.
    pub code: u8,
    /// One line saying what went wrong and where.
    pub message: String,
}

impl CliError {
    /// A verdict reported with its own exit code (see the constants above).
    pub(crate) fn verdict(code: u8, message: impl Display) -> Self {
        CliError {
            code,
            message: message.to_string(),
        }
    }

    /// Bad input (exit code 2).
    pub(crate) fn input(message: impl Display) -> Self {
        CliError {
            code: BAD_INPUT,
            message: message.to_string(),
        }
    }

    /// A run stopped by a signal, having reported what finished (exit code 130).
    pub(crate) fn interrupted(message: impl Display) -> Self {
        CliError {
            code: INTERRUPTED,
            message: message.to_string(),
        }
    }

    /// An internal failure (exit code 1).
    pub(crate) fn internal(message: impl Display) -> Self {
        CliError {
            code: INTERNAL,
            message: message.to_string(),
        }
    }
}

/// Result of a command.
pub(crate) type CliResult = Result<(), CliError>;
