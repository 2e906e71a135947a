//! Typed errors of the spec format.

use std::path::PathBuf;

/// Why a task spec could not be read, validated or grounded.
#[non_exhaustive]
#[derive(Debug, thiserror::Error)]
pub enum SpecError {
    /// The file could not be read.
    #[error("cannot read: {0}")]
    Io(#[from] std::io::Error),
    /// The text is not valid JSON, or does not have the spec's shape.
    #[error("line {line}, column {column}: {message}")]
    Json {
        /// 1-based line of the problem.
        line: usize,
        /// 1-based column of the problem.
        column: usize,
        /// What is wrong there.
        message: String,
    },
    /// The `akl_spec` version is missing or not one this build reads.
    #[error("unsupported spec version {found} (this build reads akl_spec {expected})")]
    UnsupportedVersion {
        /// The version found, as written.
        found: String,
        /// The version this build reads.
        expected: u32,
    },
    /// A value is out of its allowed range; `location` is a path such as `keyframes[2].tsr.bw`.
    #[error("{location}: {problem}")]
    Invalid {
        /// Where in the spec.
        location: String,
        /// What is wrong.
        problem: String,
    },
    /// A keyframe refers to an object the world does not have.
    #[error("keyframes[{keyframe}]: unknown reference object `{reference}`{}", known_objects(.known))]
    UnknownReference {
        /// Index of the keyframe.
        keyframe: usize,
        /// The object name it refers to.
        reference: String,
        /// The objects the world has.
        known: Vec<String>,
    },
}

fn known_objects(known: &[String]) -> String {
    if known.is_empty() {
        String::new()
    } else {
        format!(" (the world has: {})", known.join(", "))
    }
}

/// Why a serialized pose is not a pose.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PoseError {
    /// A position or quaternion component is NaN or infinite.
    #[error("pose holds a non-finite number ({0})")]
    NotFinite(f64),
    /// The quaternion is too far from unit length to be a rounded rotation.
    #[error("quaternion [{}, {}, {}, {}] is not unit length (norm {norm:.6})", q[0], q[1], q[2], q[3])]
    NotUnit {
        /// The quaternion as written, `[x, y, z, w]`.
        q: [f64; 4],
        /// Its length.
        norm: f64,
    },
}

/// Why the bounds of a TSR are not a region.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum BoundsError {
    /// A bound is NaN or infinite.
    #[error("bound on {coordinate} is not finite ([{lo}, {hi}])")]
    NotFinite {
        /// The coordinate (`x` ... `yaw`).
        coordinate: &'static str,
        /// Its lower bound.
        lo: f64,
        /// Its upper bound.
        hi: f64,
    },
    /// A lower bound exceeds its upper bound.
    #[error("bound on {coordinate} has min {lo} > max {hi}")]
    Unordered {
        /// The coordinate (`x` ... `yaw`).
        coordinate: &'static str,
        /// Its lower bound.
        lo: f64,
        /// Its upper bound.
        hi: f64,
    },
}

/// An error tied to the file it came from; displays as `path: error`.
#[derive(Debug, thiserror::Error)]
#[error("{}: {source}", path.display())]
pub struct FileError<E: std::error::Error + 'static> {
    /// The file at fault.
    pub path: PathBuf,
    /// What went wrong in it.
    #[source]
    pub source: E,
}

impl SpecError {
    /// Converts a serde_json error, recognising the non-finite literals JSON does not allow.
    pub fn from_json(err: &serde_json::Error, text: &str) -> Self {
        let (line, column, message) = describe_json_error(err, text);
        SpecError::Json {
            line,
            column,
            message,
        }
    }
}

/// Line, column and a plain message for a serde_json error on `text`; a NaN or infinity
/// literal (which JSON does not allow) is named as such instead of "expected value".
pub fn describe_json_error(err: &serde_json::Error, text: &str) -> (usize, usize, String) {
    let (line, column) = (err.line(), err.column());
    let message = match non_finite_literal_at(text, line, column) {
        Some(lit) => format!("non-finite number `{lit}` (JSON numbers must be finite)"),
        None => strip_position(&err.to_string()),
    };
    (line, column, message)
}

/// serde_json appends " at line L column C" to its messages; the position is reported separately.
fn strip_position(message: &str) -> String {
    match message.rfind(" at line ") {
        Some(i) => message[..i].to_string(),
        None => message.to_string(),
    }
}

/// If the text near the error position starts with NaN or an infinity literal, returns it.
fn non_finite_literal_at(text: &str, line: usize, column: usize) -> Option<&'static str> {
    let row = text.lines().nth(line.checked_sub(1)?)?;
    // serde_json reports the column of the offending character, or one past it.
    let start = column.saturating_sub(1).min(row.len());
    let from = row.get(start.saturating_sub(1)..).unwrap_or("");
    ["-Infinity", "Infinity", "-inf", "inf", "NaN", "nan"]
        .into_iter()
        .find(|lit| {
            from.starts_with(lit) || from.get(1..).is_some_and(|rest| rest.starts_with(lit))
        })
}
