//! Joining reports: the shards of a run ([`crate::Shard`]) merged into the report the whole
//! run gives, and an interrupted run's report completed by the trials it lacks (`--resume`).
//!
//! Parts are joined only when they are parts of one run: the same [`Identity`] (engine
//! version, spec, task, robot and settings hashes, trials asked for), seed, randomization
//! and settings, every shard present once, none interrupted, each holding exactly its block
//! of trials. Trials are kept exactly as their part wrote them, in trial order, and the
//! totals and interval are computed from them as a run computes its own.

use crate::report::{
    BatchReport, Identity, MergedPart, StoredTrial, TrialOutcome, TrialReport, REPORT_VERSION,
};
use crate::shard::Shard;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// Why reports cannot be read, merged or resumed. Every variant names the part.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum MergeError {
    /// No part given.
    #[error("no reports to merge")]
    NoParts,
    /// A part cannot be read.
    #[error("{}: {source}", path.display())]
    Read {
        /// The part.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A part is not a report this build reads.
    #[error("{}: not an akl report: {source}", path.display())]
    Parse {
        /// The part.
        path: PathBuf,
        /// Why.
        source: serde_json::Error,
    },
    /// A part of another report format version.
    #[error("{}: report format {found}, this akl reads {REPORT_VERSION}", path.display())]
    Version {
        /// The part.
        path: PathBuf,
        /// Its `akl_report`.
        found: u32,
    },
    /// A part without [`crate::report::Identity`] (written by an older akl, or by a gate).
    #[error(
        "{}: the report does not say what it was run with (spec, task, robot and settings \
         hashes): written by `akl validate` or by an akl older than shards; run it again with \
         this `akl execute`", path.display()
    )]
    NoIdentity {
        /// The part.
        path: PathBuf,
    },
    /// A part whose run was stopped.
    #[error(
        "{}: the run was interrupted ({done} of its {expected} trials finished): finish it \
         with `akl execute ... --resume {}` first", path.display(), path.display()
    )]
    Interrupted {
        /// The part.
        path: PathBuf,
        /// Trials it holds.
        done: usize,
        /// Trials it should hold.
        expected: usize,
    },
    /// A part that is not of the same run as the first.
    #[error("{}: not a part of the run of {}: {what} differs", path.display(), first.display())]
    Differs {
        /// The part.
        path: PathBuf,
        /// The part it was compared with.
        first: PathBuf,
        /// What differs, with both values.
        what: String,
    },
    /// A whole run's report among shards.
    #[error("{}: a whole run's report, not a shard's: merge the reports of `akl execute --shard I/N`", path.display())]
    NotAShard {
        /// The part.
        path: PathBuf,
    },
    /// Parts split into different numbers of shards.
    #[error("{}: shard {shard}, but {} is shard {first_shard}", path.display(), first.display())]
    ShardCount {
        /// The part.
        path: PathBuf,
        /// Its shard.
        shard: Shard,
        /// The first part.
        first: PathBuf,
        /// The first part's shard.
        first_shard: Shard,
    },
    /// Two parts of the same shard.
    #[error("{}: shard {shard} is given twice (also {})", path.display(), other.display())]
    Duplicate {
        /// The part.
        path: PathBuf,
        /// The other part of the same shard.
        other: PathBuf,
        /// The shard.
        shard: Shard,
    },
    /// Shards not given.
    #[error(
        "shard(s) {} of {count} missing (the parts given are shards {})",
        list(missing),
        list(given)
    )]
    Missing {
        /// The missing shards' indices.
        missing: Vec<usize>,
        /// The given ones'.
        given: Vec<usize>,
        /// The number of shards.
        count: usize,
    },
    /// A part whose trials are not its block's.
    #[error("{}: {detail}", path.display())]
    Trials {
        /// The part.
        path: PathBuf,
        /// What is wrong.
        detail: String,
    },
}

fn list(items: &[usize]) -> String {
    items
        .iter()
        .map(usize::to_string)
        .collect::<Vec<_>>()
        .join(", ")
}

/// A report file read back.
pub type StoredReport = BatchReport<StoredTrial>;

/// Reads a report file (`akl execute --report`, a merged report).
pub fn read(path: &Path) -> Result<StoredReport, MergeError> {
    let text = std::fs::read_to_string(path).map_err(|source| MergeError::Read {
        path: path.to_path_buf(),
        source,
    })?;
    let header: serde_json::Value =
        serde_json::from_str(&text).map_err(|source| MergeError::Parse {
            path: path.to_path_buf(),
            source,
        })?;
    if let Some(found) = header.get("akl_report").and_then(serde_json::Value::as_u64) {
        if found != u64::from(REPORT_VERSION) {
            return Err(MergeError::Version {
                path: path.to_path_buf(),
                found: u32::try_from(found).unwrap_or(u32::MAX),
            });
        }
    }
    let report: StoredReport =
        serde_json::from_value(header).map_err(|source| MergeError::Parse {
            path: path.to_path_buf(),
            source,
        })?;
    if let Some(s) = report.shard {
        Shard::new(s.index, s.count).map_err(|e| MergeError::Trials {
            path: path.to_path_buf(),
            detail: e.to_string(),
        })?;
    }
    Ok(report)
}

/// The trials of its run a report should hold: its shard's block, or all of them.
pub(crate) fn expected_trials(
    path: &Path,
    report: &StoredReport,
) -> Result<Range<usize>, MergeError> {
    let identity = report
        .identity
        .as_ref()
        .ok_or_else(|| MergeError::NoIdentity {
            path: path.to_path_buf(),
        })?;
    Ok(match report.shard {
        Some(shard) => shard.trials(identity.trials),
        None => 0..identity.trials,
    })
}

/// The trials of its run (or shard) a report lacks, in order: what `--resume` runs.
pub(crate) fn missing(path: &Path, report: &StoredReport) -> Result<Vec<usize>, MergeError> {
    let expected = expected_trials(path, report)?;
    let have = checked_trials(path, report, &expected)?;
    Ok(expected
        .filter(|i| have.binary_search(i).is_err())
        .collect())
}

/// The trial indices of `report`, checked: within `expected`, in order, each once, each with
/// its seed.
fn checked_trials(
    path: &Path,
    report: &StoredReport,
    expected: &Range<usize>,
) -> Result<Vec<usize>, MergeError> {
    let bad = |detail: String| MergeError::Trials {
        path: path.to_path_buf(),
        detail,
    };
    let mut have = Vec::with_capacity(report.reports.len());
    for t in &report.reports {
        let i = t.index();
        if !expected.contains(&i) {
            return Err(bad(format!(
                "holds trial {i}, which is not one of its trials ({} to {})",
                expected.start,
                expected.end.saturating_sub(1)
            )));
        }
        if have.last().is_some_and(|&last| last >= i) {
            return Err(bad(format!("trial {i} is out of order or given twice")));
        }
        if t.seed() != crate::batch::trial_seed(report.seed, i) {
            return Err(bad(format!(
                "trial {i} has seed {}, not {} (seed {} + {i})",
                t.seed(),
                crate::batch::trial_seed(report.seed, i),
                report.seed
            )));
        }
        have.push(i);
    }
    Ok(have)
}

/// Whether `b` (file `b_path`) is of the same run as `a` (file `a_path`): the same identity,
/// task, method, seed, randomization and settings.
pub(crate) fn check_same_run(
    a_path: &Path,
    a: &StoredReport,
    b_path: &Path,
    b: &StoredReport,
) -> Result<(), MergeError> {
    let differs = |what: String| MergeError::Differs {
        path: b_path.to_path_buf(),
        first: a_path.to_path_buf(),
        what,
    };
    let ia = a.identity.as_ref().ok_or_else(|| MergeError::NoIdentity {
        path: a_path.to_path_buf(),
    })?;
    let ib = b.identity.as_ref().ok_or_else(|| MergeError::NoIdentity {
        path: b_path.to_path_buf(),
    })?;
    check_identity(ia, ib).map_err(differs)?;
    let pairs: [(&str, String, String); 3] = [
        ("the task name", a.task.clone(), b.task.clone()),
        ("the seed", a.seed.to_string(), b.seed.to_string()),
        (
            "randomization",
            a.randomized.to_string(),
            b.randomized.to_string(),
        ),
    ];
    for (what, x, y) in pairs {
        if x != y {
            return Err(differs(format!("{what} ({y} here, {x} there)")));
        }
    }
    if a.settings != b.settings {
        return Err(differs("the settings recorded in the report".into()));
    }
    Ok(())
}

/// The first difference between two identities, with both values (`b`'s first).
fn check_identity(a: &Identity, b: &Identity) -> Result<(), String> {
    let pairs: [(&str, String, String); 7] = [
        ("the akl version", a.version.clone(), b.version.clone()),
        ("the platform", a.platform.clone(), b.platform.clone()),
        ("the spec", a.spec_hash.clone(), b.spec_hash.clone()),
        ("the task", a.task_hash.clone(), b.task_hash.clone()),
        (
            "the robot (robot.toml, URDF or meshes)",
            a.robot_hash.clone(),
            b.robot_hash.clone(),
        ),
        (
            "the execution settings (noise, goals, budget, speed, limits)",
            a.settings_hash.clone(),
            b.settings_hash.clone(),
        ),
        (
            "the trials asked for",
            a.trials.to_string(),
            b.trials.to_string(),
        ),
    ];
    for (what, x, y) in pairs {
        if x != y {
            return Err(format!("{what} ({y} here, {x} there)"));
        }
    }
    Ok(())
}

/// Checks that `kept` (the report in `path`) is of the run about to resume it — `identity`,
/// seeded `seed`, randomized or not, shard `shard` — and returns the trials it lacks.
pub fn check_resume(
    path: &Path,
    kept: &StoredReport,
    identity: &Identity,
    seed: u64,
    randomized: bool,
    shard: Option<Shard>,
) -> Result<Vec<usize>, MergeError> {
    let differs = |what: String| MergeError::Differs {
        path: PathBuf::from("this run"),
        first: path.to_path_buf(),
        what,
    };
    let theirs = kept
        .identity
        .as_ref()
        .ok_or_else(|| MergeError::NoIdentity {
            path: path.to_path_buf(),
        })?;
    check_identity(theirs, identity).map_err(differs)?;
    if kept.seed != seed {
        return Err(differs(format!(
            "the seed ({seed} here, {} there)",
            kept.seed
        )));
    }
    if kept.randomized != randomized {
        return Err(differs("randomization".into()));
    }
    if kept.shard != shard {
        return Err(differs(format!(
            "the shard ({} here, {} there)",
            shard_text(shard),
            shard_text(kept.shard)
        )));
    }
    missing(path, kept)
}

/// Merges the shard reports `parts` (each with its file, as [`read`] gives them) into the
/// report of the whole run.
pub fn merge(parts: &[(PathBuf, StoredReport)]) -> Result<StoredReport, MergeError> {
    let (first_path, first) = parts.first().ok_or(MergeError::NoParts)?;
    let mut by_shard: Vec<Option<&PathBuf>> = Vec::new();
    for (path, part) in parts {
        if part.akl_report != REPORT_VERSION {
            return Err(MergeError::Version {
                path: path.clone(),
                found: part.akl_report,
            });
        }
        check_same_run(first_path, first, path, part)?;
        let shard = match (part.shard, parts.len()) {
            (Some(s), _) => Shard::new(s.index, s.count).map_err(|e| MergeError::Trials {
                path: path.clone(),
                detail: e.to_string(),
            })?,
            (None, 1) => Shard { index: 0, count: 1 },
            (None, _) => return Err(MergeError::NotAShard { path: path.clone() }),
        };
        if let Some(f) = first.shard.filter(|f| f.count != shard.count) {
            return Err(MergeError::ShardCount {
                path: path.clone(),
                shard,
                first: first_path.clone(),
                first_shard: f,
            });
        }
        let expected = expected_trials(path, part)?;
        if expected.is_empty() {
            return Err(MergeError::Trials {
                path: path.clone(),
                detail: "its shard holds no trial of the run".into(),
            });
        }
        let have = checked_trials(path, part, &expected)?;
        if part.interrupted || have.len() != expected.len() {
            return Err(MergeError::Interrupted {
                path: path.clone(),
                done: have.len(),
                expected: expected.len(),
            });
        }
        by_shard.resize(shard.count, None);
        if let Some(other) = by_shard[shard.index] {
            return Err(MergeError::Duplicate {
                path: path.clone(),
                other: other.clone(),
                shard,
            });
        }
        by_shard[shard.index] = Some(path);
    }
    let missing: Vec<usize> = (0..by_shard.len())
        .filter(|&i| by_shard[i].is_none())
        .collect();
    if !missing.is_empty() {
        return Err(MergeError::Missing {
            given: (0..by_shard.len())
                .filter(|&i| by_shard[i].is_some())
                .collect(),
            count: by_shard.len(),
            missing,
        });
    }
    let mut ordered: Vec<&(PathBuf, StoredReport)> = parts.iter().collect();
    ordered.sort_by_key(|(_, p)| p.shard.map_or(0, |s| s.index));
    let reports: Vec<StoredTrial> = ordered
        .iter()
        .flat_map(|(_, p)| p.reports.iter().cloned())
        .collect();
    let mut merged = BatchReport::new(
        &first.task,
        &first.method,
        first.seed,
        first.randomized,
        reports,
        parts.iter().map(|(_, p)| p.jobs).max().unwrap_or(1),
        parts
            .iter()
            .map(|(_, p)| p.wall_seconds)
            .fold(0.0, f64::max),
        first.settings.clone(),
    );
    merged.identity = first.identity.clone();
    merged.merged = Some(
        ordered
            .iter()
            .map(|(path, p)| MergedPart {
                file: path.display().to_string(),
                shard: p.shard,
                jobs: p.jobs,
                wall_seconds: p.wall_seconds,
            })
            .collect(),
    );
    Ok(merged)
}

/// An interrupted report (`kept`, from `path`) completed by `more`, the run of the trials it
/// lacked (those [`check_resume`] returns): every trial in order, the totals computed again, interrupted only if
/// `more` was. `more` must be of the same run.
pub fn resume(
    path: &Path,
    kept: &StoredReport,
    more: &BatchReport<TrialReport>,
) -> Result<StoredReport, MergeError> {
    let fresh = more.stored().map_err(|source| MergeError::Parse {
        path: path.to_path_buf(),
        source,
    })?;
    check_same_run(path, kept, Path::new("this run"), &fresh)?;
    if kept.shard != fresh.shard {
        return Err(MergeError::Differs {
            path: path.to_path_buf(),
            first: PathBuf::from("this run"),
            what: format!(
                "the shard ({} there, {} here)",
                shard_text(kept.shard),
                shard_text(fresh.shard)
            ),
        });
    }
    let mut reports: Vec<StoredTrial> = kept.reports.clone();
    reports.extend(fresh.reports);
    reports.sort_by_key(TrialOutcome::index);
    let expected = expected_trials(path, kept)?;
    let mut resumed = BatchReport::new(
        &kept.task,
        &kept.method,
        kept.seed,
        kept.randomized,
        reports,
        more.jobs,
        kept.wall_seconds + more.wall_seconds,
        kept.settings.clone(),
    );
    let have = checked_trials(path, &resumed, &expected)?;
    resumed.interrupted = more.interrupted || have.len() < expected.len();
    resumed.shard = kept.shard;
    resumed.identity = kept.identity.clone();
    Ok(resumed)
}

fn shard_text(shard: Option<Shard>) -> String {
    shard.map_or_else(|| "the whole run".into(), |s| format!("shard {s}"))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::Settings;
    use serde_json::json;

    fn settings() -> Settings {
        let task = akl_scene::builtin::task("inspection").unwrap().unwrap();
        crate::batch::settings(
            &akl_planner::Robot::panda().unwrap(),
            &crate::ExecOptions::default(),
            &task.truth.unwrap(),
        )
    }

    /// Trial `i` of a run seeded 10, failing with a collision when `i` is odd.
    fn trial(i: usize) -> StoredTrial {
        let failures = if i % 2 == 1 {
            json!([
                {"cause": "collision", "stage": "simulation", "t": 1.0, "root": true, "detail": "hit"},
                {"cause": "goal_not_met", "stage": "simulation", "t": 4.0, "root": false, "detail": "off"}
            ])
        } else {
            json!([])
        };
        StoredTrial::from_json(json!({
            "trial": i, "seed": 10 + i, "passed": i % 2 == 0, "failures": failures,
            "lines": [{"deviation": 0.001 * i as f64}], "plan_seconds": 0.1, "sim_seconds": 0.2,
            "tracking": {"max": 0.0, "rms": 0.0},
            "deepest_contact": {"value": 0.0}, "largest_force": {"value": 0.0}
        }))
        .unwrap()
    }

    /// The report of shard `shard` (or the whole run) of a 4-trial run, holding `trials`.
    fn part(shard: Option<Shard>, trials: &[usize], settings: &Settings) -> StoredReport {
        let mut r = BatchReport::new(
            "inspection",
            "truth",
            10,
            true,
            trials.iter().map(|&i| trial(i)).collect(),
            1,
            1.0,
            settings.clone(),
        );
        r.shard = shard;
        r.identity = Some(Identity {
            version: "1".into(),
            platform: "x".into(),
            spec_hash: "s".into(),
            task_hash: "t".into(),
            robot_hash: "r".into(),
            settings_hash: "e".into(),
            trials: 4,
        });
        r
    }

    fn files(parts: Vec<StoredReport>) -> Vec<(PathBuf, StoredReport)> {
        parts
            .into_iter()
            .enumerate()
            .map(|(k, p)| (PathBuf::from(format!("part{k}.json")), p))
            .collect()
    }

    #[test]
    fn shards_merge_into_the_whole_run_and_bad_sets_are_refused_naming_the_part() {
        let s = settings();
        let shard = |index| Some(Shard { index, count: 2 });
        let whole = part(None, &[0, 1, 2, 3], &s);
        let merged = merge(&files(vec![
            part(shard(1), &[2, 3], &s),
            part(shard(0), &[0, 1], &s),
        ]))
        .unwrap();
        let order: Vec<usize> = merged.reports.iter().map(TrialOutcome::index).collect();
        assert_eq!(order, [0, 1, 2, 3]);
        assert_eq!((merged.trials, merged.passed), (whole.trials, whole.passed));
        assert_eq!(merged.pass_rate, whole.pass_rate);
        assert_eq!(merged.failures, whole.failures);
        assert_eq!(merged.secondary, whole.secondary);
        assert_eq!(merged.worst_line_deviation, Some(0.003));
        assert_eq!(merged.reports, whole.reports);
        assert_eq!(merged.merged.as_ref().map(Vec::len), Some(2));

        let refused = |parts: Vec<StoredReport>| merge(&files(parts)).unwrap_err();
        let e = refused(vec![part(shard(0), &[0, 1], &s)]);
        assert!(
            matches!(e, MergeError::Missing { ref missing, .. } if missing == &[1]),
            "{e}"
        );
        let e = refused(vec![
            part(shard(0), &[0, 1], &s),
            part(shard(0), &[0, 1], &s),
        ]);
        assert!(matches!(e, MergeError::Duplicate { .. }), "{e}");
        assert!(e.to_string().starts_with("part1.json"), "{e}");
        let mut cut = part(shard(1), &[2], &s);
        cut.interrupted = true;
        let e = refused(vec![part(shard(0), &[0, 1], &s), cut]);
        assert!(
            matches!(
                e,
                MergeError::Interrupted {
                    done: 1,
                    expected: 2,
                    ..
                }
            ),
            "{e}"
        );
        let mut other = part(shard(1), &[2, 3], &s);
        other.identity.as_mut().unwrap().spec_hash = "another".into();
        let e = refused(vec![part(shard(0), &[0, 1], &s), other]);
        assert!(
            e.to_string().contains("part1.json") && e.to_string().contains("the spec"),
            "{e}"
        );
        let e = refused(vec![
            part(shard(0), &[0, 1], &s),
            part(Some(Shard { index: 2, count: 3 }), &[3], &s),
        ]);
        assert!(matches!(e, MergeError::ShardCount { .. }), "{e}");
        let e = refused(vec![
            part(shard(0), &[0, 1], &s),
            part(Some(Shard { index: 5, count: 2 }), &[2, 3], &s),
        ]);
        assert!(matches!(e, MergeError::Trials { .. }), "{e}");
        let e = refused(vec![
            part(shard(0), &[0, 1], &s),
            part(shard(1), &[1, 3], &s),
        ]);
        assert!(e.to_string().contains("not one of its trials"), "{e}");
        let e = refused(vec![
            part(shard(0), &[0, 1], &s),
            part(None, &[0, 1, 2, 3], &s),
        ]);
        assert!(matches!(e, MergeError::NotAShard { .. }), "{e}");
    }

    #[test]
    fn an_interrupted_report_lacks_the_trials_that_did_not_finish() {
        let s = settings();
        let mut r = part(None, &[0, 2], &s);
        r.interrupted = true;
        assert_eq!(missing(Path::new("r.json"), &r).unwrap(), [1, 3]);
        let shard = Some(Shard { index: 1, count: 2 });
        let r = part(shard, &[3], &s);
        assert_eq!(missing(Path::new("r.json"), &r).unwrap(), [2]);
        let id = r.identity.clone().unwrap();
        assert!(check_resume(Path::new("r.json"), &r, &id, 10, true, shard).is_ok());
        let e = check_resume(Path::new("r.json"), &r, &id, 11, true, shard).unwrap_err();
        assert!(e.to_string().contains("the seed"), "{e}");
        let e = check_resume(Path::new("r.json"), &r, &id, 10, true, None).unwrap_err();
        assert!(e.to_string().contains("the shard"), "{e}");
    }
}
