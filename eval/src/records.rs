//! The study's records on disk: every trial as a CSV row and the whole study as JSON, plus
//! the figures, each file written whole or not at all.

use std::path::{Path, PathBuf};

use serde::Serialize;
use serde_json::Value;

use crate::plots::{draw, PlotError, FIGURES};
use crate::study::{Study, Trial};
use crate::summary::Summary;

/// Why the records could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RecordError {
    /// A file could not be written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// The records could not be encoded.
    #[error("encoding {what}: {message}")]
    Encode {
        /// Which file.
        what: &'static str,
        /// Why.
        message: String,
    },
    /// A figure could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
}

/// The per-trial table: one row per trial with every field of [`Trial`] but the learned spec
/// (which the JSON holds); empty cells where a value does not apply.
pub(crate) fn trials_csv(trials: &[Trial]) -> Result<String, RecordError> {
    let encode = |message: String| RecordError::Encode {
        what: "trials.csv",
        message,
    };
    let mut out = csv::Writer::from_writer(Vec::new());
    for (i, t) in trials.iter().enumerate() {
        let Value::Object(mut row) = serde_json::to_value(t).map_err(|e| encode(e.to_string()))?
        else {
            return Err(encode("a trial is not a record".into()));
        };
        row.remove("spec");
        if i == 0 {
            out.write_record(row.keys())
                .map_err(|e| encode(e.to_string()))?;
        }
        let cells = row.values().map(|v| match v {
            Value::Null => String::new(),
            Value::String(s) => s.clone(),
            other => other.to_string(),
        });
        out.write_record(cells).map_err(|e| encode(e.to_string()))?;
    }
    let bytes = out.into_inner().map_err(|e| encode(e.to_string()))?;
    String::from_utf8(bytes).map_err(|e| encode(e.to_string()))
}

/// The whole study and its summary, as `trials.json` holds them.
#[derive(Serialize)]
pub(crate) struct StudyRecord<'a> {
    /// The tables.
    pub summary: &'a Summary,
    /// The study: population, participants, calibrations and trials with their specs.
    #[serde(flatten)]
    pub study: &'a Study,
}

/// Writes `trials.csv`, `trials.json` and the figures into `dir` (which must exist); returns
/// the files written.
pub fn write_records(
    dir: &Path,
    study: &Study,
    summary: &Summary,
    tasks: &[String],
) -> Result<Vec<PathBuf>, RecordError> {
    let mut files: Vec<(PathBuf, String)> = Vec::new();
    files.push((dir.join("trials.csv"), trials_csv(&study.trials)?));
    let json = akl_tsr::io::to_readable_json(&StudyRecord { summary, study }).map_err(|e| {
        RecordError::Encode {
            what: "trials.json",
            message: e.to_string(),
        }
    })?;
    files.push((dir.join("trials.json"), json));
    for figure in &FIGURES {
        files.push((dir.join(figure.file), draw(figure, &study.trials, tasks)?));
    }
    for (path, text) in &files {
        akl_tsr::io::write_atomic(path, text.as_bytes()).map_err(|source| RecordError::Io {
            path: path.clone(),
            source,
        })?;
    }
    Ok(files.into_iter().map(|(p, _)| p).collect())
}
