//! Why a validation, relaxation or comparison could not be carried out. A spec that fails its
//! trials is not an error: it is a verdict.

use akl_exec::ExecError;
use akl_learn::okl::LearnError;
use akl_planner::flexibility::FlexibilityError;

/// What stopped a command of this crate.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ValidateError {
    /// The trials could not run (a spec that does not fit the task, a layout that cannot be
    /// drawn, a bad option).
    #[error(transparent)]
    Exec(#[from] ExecError),
    /// Bits of freedom could not be counted.
    #[error("bits of freedom: {0}")]
    Flexibility(#[from] FlexibilityError),
    /// The demonstration could not be learned from again.
    #[error("re-learning the demonstration: {0}")]
    Learn(#[from] LearnError),
    /// The demonstration could not be replayed through the online detector.
    #[error("replaying the demonstration: {0}")]
    Replay(String),
    /// The demonstration holds no answers to judge: it was recorded without the online
    /// detector.
    #[error("recorded without the online detector: it holds no answers to check")]
    NoDetector,
    /// The spec fails its own trials: there is nothing to relax.
    #[error("the spec fails its own trials, so there is nothing to relax: {0}")]
    SpecFails(String),
    /// An option is out of range.
    #[error("{0}")]
    Options(String),
}
