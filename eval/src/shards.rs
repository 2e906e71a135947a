//! A study split over machines: each shard runs a contiguous block of the participants
//! ([`crate::study::StudyOptions::only`]), each participant exactly as in the whole study (its
//! profile, order and seed are drawn with the study's, and what it learns carries only into
//! its own later trials), and [`merge_studies`] joins the shards' `trials.json` into the
//! whole study.

use crate::study::Study;
use std::path::{Path, PathBuf};

/// Why shards of a study cannot be read or joined; every variant names the part.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum StudyMergeError {
    /// No part given.
    #[error("no studies to merge")]
    NoParts,
    /// A part cannot be read.
    #[error("{}: {source}", path.display())]
    Read {
        /// The part.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A part is not a study's `trials.json`.
    #[error("{}: not the trials.json of an akl eval: {source}", path.display())]
    Parse {
        /// The part.
        path: PathBuf,
        /// Why.
        source: serde_json::Error,
    },
    /// A part of another study.
    #[error("{}: not a shard of the study of {}: {what} differs", path.display(), first.display())]
    Differs {
        /// The part.
        path: PathBuf,
        /// The part it was compared with.
        first: PathBuf,
        /// What differs, with both values.
        what: String,
    },
    /// A part that was stopped before its participants finished.
    #[error("{}: the study was interrupted; run its shard again", path.display())]
    Interrupted {
        /// The part.
        path: PathBuf,
    },
    /// A whole study among shards.
    #[error("{}: a whole study, not a shard (akl eval --shard I/N)", path.display())]
    NotAShard {
        /// The part.
        path: PathBuf,
    },
    /// Two parts running the same participants.
    #[error("{}: participants {start} to {end} are run by {} too", path.display(), other.display())]
    Overlap {
        /// The part.
        path: PathBuf,
        /// The other part.
        other: PathBuf,
        /// First participant both run (1-based).
        start: usize,
        /// Last (1-based).
        end: usize,
    },
    /// Participants no part ran.
    #[error("participants {start} to {end} (of {drawn}) are in no part given")]
    Missing {
        /// First missing (1-based).
        start: usize,
        /// Last missing (1-based).
        end: usize,
        /// Participants drawn.
        drawn: usize,
    },
    /// A part whose participants or trials are not its block's.
    #[error("{}: {detail}", path.display())]
    Block {
        /// The part.
        path: PathBuf,
        /// What is wrong.
        detail: String,
    },
}

/// Reads a study from its `trials.json` (`akl eval --out DIR`).
pub fn read_study(path: &Path) -> Result<Study, StudyMergeError> {
    let text = std::fs::read_to_string(path).map_err(|source| StudyMergeError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    serde_json::from_str(&text).map_err(|source| StudyMergeError::Parse {
        path: path.to_path_buf(),
        source,
    })
}

/// Joins the shards `parts` (each with its file) into the whole study: participants,
/// calibrations and trials in participant order, as the whole study lists them.
pub fn merge_studies(parts: &[(PathBuf, Study)]) -> Result<Study, StudyMergeError> {
    let (first_path, first) = parts.first().ok_or(StudyMergeError::NoParts)?;
    let mut blocks = Vec::with_capacity(parts.len());
    for (path, part) in parts {
        let differs = |what: String| StudyMergeError::Differs {
            path: path.clone(),
            first: first_path.clone(),
            what,
        };
        if part.seed != first.seed {
            return Err(differs(format!(
                "the seed ({} here, {} there)",
                part.seed, first.seed
            )));
        }
        if part.drawn != first.drawn {
            return Err(differs(format!(
                "the participants drawn ({} here, {} there)",
                part.drawn, first.drawn
            )));
        }
        if part.executions_per_spec != first.executions_per_spec {
            return Err(differs(format!(
                "--execute ({:?} here, {:?} there)",
                part.executions_per_spec, first.executions_per_spec
            )));
        }
        if part.population != first.population {
            return Err(differs("the population".into()));
        }
        if part.interrupted {
            return Err(StudyMergeError::Interrupted { path: path.clone() });
        }
        let block = match (&part.block, parts.len()) {
            (Some(b), _) => b.clone(),
            (None, 1) => 0..part.drawn,
            (None, _) => return Err(StudyMergeError::NotAShard { path: path.clone() }),
        };
        let ids: Vec<usize> = part.participants.iter().map(|p| p.id).collect();
        let expected: Vec<usize> = block.clone().map(|i| i + 1).collect();
        if ids != expected || block.end > part.drawn {
            return Err(StudyMergeError::Block {
                path: path.clone(),
                detail: format!(
                    "holds participants {ids:?}, not its block's {} to {}",
                    block.start + 1,
                    block.end
                ),
            });
        }
        if let Some(t) = part
            .trials
            .iter()
            .find(|t| !block.contains(&(t.participant.wrapping_sub(1))))
        {
            return Err(StudyMergeError::Block {
                path: path.clone(),
                detail: format!("holds a trial of participant {}", t.participant),
            });
        }
        blocks.push((block, path, part));
    }
    blocks.sort_by_key(|(b, _, _)| b.start);
    let mut next = 0;
    let mut previous: Option<&PathBuf> = None;
    for (block, path, _) in &blocks {
        if block.start < next {
            return Err(StudyMergeError::Overlap {
                path: (*path).clone(),
                other: previous.cloned().unwrap_or_default(),
                start: block.start + 1,
                end: next.min(block.end),
            });
        }
        if block.start > next {
            return Err(StudyMergeError::Missing {
                start: next + 1,
                end: block.start,
                drawn: first.drawn,
            });
        }
        next = block.end;
        previous = Some(path);
    }
    if next < first.drawn {
        return Err(StudyMergeError::Missing {
            start: next + 1,
            end: first.drawn,
            drawn: first.drawn,
        });
    }
    Ok(Study {
        seed: first.seed,
        drawn: first.drawn,
        block: None,
        executions_per_spec: first.executions_per_spec,
        interrupted: false,
        population: first.population,
        participants: blocks
            .iter()
            .flat_map(|(_, _, p)| p.participants.iter().cloned())
            .collect(),
        calibrations: blocks
            .iter()
            .flat_map(|(_, _, p)| p.calibrations.iter().cloned())
            .collect(),
        trials: blocks
            .iter()
            .flat_map(|(_, _, p)| p.trials.iter().cloned())
            .collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::{run_study, StudyOptions};
    use akl_scene::builtin;

    #[test]
    fn shards_of_a_study_merge_into_the_whole_study_and_gaps_or_overlaps_are_refused() {
        let tasks: Vec<_> = builtin::study_names()
            .into_iter()
            .map(|n| builtin::resolve(n).unwrap())
            .collect();
        let run = |only| {
            let options = StudyOptions {
                participants: 3,
                seed: 7,
                tasks: &tasks,
                execute: None,
                only,
                stop: None,
            };
            let mut study = run_study(&options, &|_| {}).unwrap();
            for t in &mut study.trials {
                t.runtime_s = 0.0;
            }
            study
        };
        let whole = run(None);
        let part = |name: &str, only| (PathBuf::from(name), run(Some(only)));
        let (a, b) = (part("a.json", 0..1), part("b.json", 1..3));
        let merged = merge_studies(&[b.clone(), a.clone()]).unwrap();
        assert_eq!(merged, whole);
        let e = merge_studies(std::slice::from_ref(&a)).unwrap_err();
        assert!(
            matches!(
                e,
                StudyMergeError::Missing {
                    start: 2,
                    end: 3,
                    ..
                }
            ),
            "{e}"
        );
        let e = merge_studies(&[a.clone(), b.clone(), part("c.json", 2..3)]).unwrap_err();
        assert!(matches!(e, StudyMergeError::Overlap { .. }), "{e}");
        assert!(e.to_string().starts_with("c.json"), "{e}");
        let mut other = b.clone();
        other.1.seed = 8;
        let e = merge_studies(&[a, other]).unwrap_err();
        assert!(e.to_string().contains("the seed"), "{e}");
    }
}
