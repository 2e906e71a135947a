//! The thesis's user study (chapter 4), simulated.
//!
//! A fixed population of simulated teachers ([`Population`]) calibrates, then teaches each
//! built-in task with each method — AKL, KD and mACL — in a counterbalanced order, and every
//! learned spec is scored against the task's ground truth with the measures of §4.2.

mod plots;
mod population;
mod records;
mod shards;
mod study;
mod summary;

pub use plots::{method_label, PlotError};
pub use population::{Group, Participant, Population, Span};
pub use records::{write_records, RecordError};
pub use shards::{merge_studies, read_study, StudyMergeError};
pub use study::{run_study, Calibrated, Executor, Study, StudyError, StudyOptions, Trial};
pub use summary::{
    summarize, ConstraintErrors, PassRow, Rate, Runtime, SuccessRow, Summary, TABLE_ORDER,
    THESIS_CONSTRAINT_ERRORS, THESIS_SUCCESS,
};
