//! Typed errors of task files and randomization.

use akl_tsr::describe_json_error;
use akl_tsr::{FileError, SpecError};

/// Why a task could not be loaded, validated or randomized.
#[non_exhaustive]
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// The file could not be read.
    #[error("cannot read: {0}")]
    Io(#[from] std::io::Error),
    /// The text is not valid JSON, or does not have the task format's shape.
    #[error("line {line}, column {column}: {message}")]
    Json {
        /// 1-based line.
        line: usize,
        /// 1-based column.
        column: usize,
        /// What is wrong there.
        message: String,
    },
    /// The `akl_task` version is missing or not one this build reads.
    #[error("unsupported task version {found} (this build reads akl_task {expected})")]
    UnsupportedVersion {
        /// The version found, as written.
        found: String,
        /// The version this build reads.
        expected: u32,
    },
    /// A value is invalid; `location` is a path such as `world.objects[2] (part).mass`.
    #[error("{location}: {problem}")]
    Invalid {
        /// Where in the task.
        location: String,
        /// What is wrong.
        problem: String,
    },
    /// No built-in task has this name and no such file exists.
    #[error("unknown task `{name}` (built-in tasks: {}; or give the path of a task file)", known.join(", "))]
    UnknownTask {
        /// The name asked for.
        name: String,
        /// The built-in task names.
        known: Vec<String>,
    },
    /// The task's ground-truth spec is invalid.
    #[error("ground truth {0}")]
    Truth(#[from] FileError<SpecError>),
    /// No layout drawn from the seed was one the task can be done in.
    #[error("randomization: none of {draws} layouts drawn from seed {seed} is feasible (the last: {last})")]
    Randomize {
        /// The seed.
        seed: u64,
        /// How many layouts were drawn.
        draws: usize,
        /// Why the last one was rejected.
        last: String,
    },
}

/// Why a shape has no size the checks can use.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ShapeError {
    /// A size that must be a positive length is not.
    #[error("{what} must be a positive finite length, got {value}")]
    NotPositive {
        /// Which size (`size x`, `radius`, ...).
        what: &'static str,
        /// Its value.
        value: f64,
    },
    /// A capsule's straight part has a negative or non-finite length.
    #[error("length must be a finite length >= 0, got {0}")]
    NegativeLength(f64),
    /// A mesh shape whose file has not been read (it is read when its task file is loaded).
    #[error("mesh `{0}` was not read: a task with mesh shapes is loaded from its file, which the mesh's path is relative to")]
    MeshNotRead(String),
}

impl SceneError {
    /// Converts a serde_json error on `text`, keeping its line and column.
    pub fn from_json(err: &serde_json::Error, text: &str) -> Self {
        let (line, column, message) = describe_json_error(err, text);
        SceneError::Json {
            line,
            column,
            message,
        }
    }

    /// An invalid value at `location`.
    pub fn invalid(location: impl Into<String>, problem: impl Into<String>) -> Self {
        SceneError::Invalid {
            location: location.into(),
            problem: problem.into(),
        }
    }
}
