//! The CLI's error type and exit codes: 2 for bad input, 1 for internal failures.

use std::fmt::Display;

/// Exit code for input the user can fix: a malformed file, an unknown name, a bad flag value.
pub const BAD_INPUT: u8 = 2;
/// Exit code for failures that are not the input's fault (an output that cannot be written).
pub const INTERNAL: u8 = 1;

/// A failed command: one line of message and the process exit code.
#[derive(Debug)]
pub struct CliError {
    /// Exit code.
    pub code: u8,
    /// One line saying what went wrong and where.
    pub message: String,
}

impl CliError {
    /// Bad input (exit code 2).
    pub fn input(message: impl Display) -> Self {
        CliError {
            code: BAD_INPUT,
            message: message.to_string(),
        }
    }

    /// An internal failure (exit code 1).
    pub fn internal(message: impl Display) -> Self {
        CliError {
            code: INTERNAL,
            message: message.to_string(),
        }
    }
}

/// Result of a command.
pub type CliResult = Result<(), CliError>;
