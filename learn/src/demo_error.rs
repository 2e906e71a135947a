//! Why a demonstration could not be read.

use thiserror::Error;

/// A demonstration that is malformed, with the line (JSONL) or frame where it went wrong.
#[derive(Debug, Error, PartialEq)]
#[non_exhaustive]
pub enum DemoError {
    /// A JSONL line is malformed or breaks a rule of the format.
    #[error("line {line}: {message}")]
    Line {
        /// 1-based line number in the file.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A frame breaks a rule of the format (used where frames have no line, as in MCAP).
    #[error("frame {frame}: {message}")]
    Frame {
        /// 0-based frame index.
        frame: usize,
        /// What is wrong.
        message: String,
    },
    /// The recording has a header but no frames.
    #[error("the demonstration has no frames")]
    Empty,
    /// The container itself is unreadable (not MCAP, no header, ...).
    #[error("{0}")]
    Format(String),
}
