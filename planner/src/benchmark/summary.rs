//! Per-set statistics of a problem file's records, and the side-by-side comparison with
//! another planner's records of the same file.

use super::run::ProblemRecord;
use serde::Serialize;
use std::collections::BTreeMap;

/// Name of the row that sums every set.
pub const ALL_SETS: &str = "all";

/// Planning times of a group of runs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Times {
    /// Runs.
    pub runs: usize,
    /// Runs that found a path.
    pub solved: usize,
    /// Median planning time over every run, found or not (nanoseconds).
    pub median_ns: f64,
    /// 95th percentile (nearest rank) of the planning time (nanoseconds).
    pub p95_ns: f64,
    /// Median number of samples drawn.
    pub median_iterations: f64,
}

impl Times {
    /// The times of the runs of `records`; `None` when they have no runs.
    pub fn of<'a>(records: impl IntoIterator<Item = &'a ProblemRecord>) -> Option<Times> {
        let runs: Vec<_> = records.into_iter().flat_map(|r| &r.runs).collect();
        if runs.is_empty() {
            return None;
        }
        let mut times: Vec<f64> = runs.iter().map(|r| r.time_ns as f64).collect();
        let mut iterations: Vec<f64> = runs.iter().map(|r| r.iterations as f64).collect();
        Some(Times {
            runs: runs.len(),
            solved: runs.iter().filter(|r| r.found).count(),
            median_ns: quantile(&mut times, 0.5),
            p95_ns: quantile(&mut times, 0.95),
            median_iterations: quantile(&mut iterations, 0.5),
        })
    }
}

/// One set's results.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SetSummary {
    /// The set ([`ALL_SETS`] for the row of every set).
    pub set: String,
    /// Problems in the set.
    pub problems: usize,
    /// Problems whose start and goal are both valid.
    pub valid: usize,
    /// Times over the valid problems' runs.
    pub times: Option<Times>,
}

/// The summary of each set in order of first appearance, then of all sets together.
pub fn summarize(records: &[ProblemRecord]) -> Vec<SetSummary> {
    by_set(records)
        .into_iter()
        .map(|(set, group)| SetSummary {
            set,
            problems: group.len(),
            valid: group.iter().filter(|r| valid(r)).count(),
            times: Times::of(group.into_iter().filter(|r| valid(r))),
        })
        .collect()
}

/// One set of both planners on the problems both call valid.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SetComparison {
    /// The set ([`ALL_SETS`] for the row of every set).
    pub set: String,
    /// Problems both planners call valid.
    pub both_valid: usize,
    /// Problems only this planner calls valid.
    pub only_ours: usize,
    /// Problems only the other planner calls valid.
    pub only_peer: usize,
    /// This planner's times on the problems both call valid.
    pub ours: Option<Times>,
    /// The other planner's.
    pub peer: Option<Times>,
}

impl SetComparison {
    /// Our median time over the peer's (how many times slower we are).
    pub fn median_ratio(&self) -> Option<f64> {
        Some(self.ours?.median_ns / self.peer?.median_ns)
    }

    /// The same at the 95th percentile.
    pub fn p95_ratio(&self) -> Option<f64> {
        Some(self.ours?.p95_ns / self.peer?.p95_ns)
    }
}

/// Compares our records with a peer's records of the same problems (matched by id; problems
/// only one side ran are left out), per set and for all sets.
pub fn compare(ours: &[ProblemRecord], peer: &[ProblemRecord]) -> Vec<SetComparison> {
    let peer_by_id: BTreeMap<&str, &ProblemRecord> =
        peer.iter().map(|r| (r.id.as_str(), r)).collect();
    let matched: Vec<(&ProblemRecord, &ProblemRecord)> = ours
        .iter()
        .filter_map(|o| Some((o, *peer_by_id.get(o.id.as_str())?)))
        .collect();
    let ours_matched: Vec<ProblemRecord> = matched.iter().map(|(o, _)| (*o).clone()).collect();
    by_set(&ours_matched)
        .into_iter()
        .map(|(set, _)| {
            let pairs: Vec<_> = matched
                .iter()
                .filter(|(o, _)| set == ALL_SETS || o.set == set)
                .collect();
            let both: Vec<_> = pairs.iter().filter(|(o, p)| valid(o) && valid(p)).collect();
            SetComparison {
                both_valid: both.len(),
                only_ours: pairs.iter().filter(|(o, p)| valid(o) && !valid(p)).count(),
                only_peer: pairs.iter().filter(|(o, p)| !valid(o) && valid(p)).count(),
                ours: Times::of(both.iter().map(|(o, _)| *o)),
                peer: Times::of(both.iter().map(|(_, p)| *p)),
                set,
            }
        })
        .collect()
}

fn valid(r: &ProblemRecord) -> bool {
    r.start_valid && r.goal_valid
}

/// The records grouped by set in order of first appearance, then all of them as [`ALL_SETS`].
fn by_set(records: &[ProblemRecord]) -> Vec<(String, Vec<&ProblemRecord>)> {
    let mut groups: Vec<(String, Vec<&ProblemRecord>)> = Vec::new();
    for r in records {
        match groups.iter_mut().find(|(s, _)| *s == r.set) {
            Some((_, group)) => group.push(r),
            None => groups.push((r.set.clone(), vec![r])),
        }
    }
    groups.push((ALL_SETS.to_string(), records.iter().collect()));
    groups
}

/// The `p` quantile of `values` by nearest rank (the smallest value with at least a fraction
/// `p` of the values at or below it); `values` must not be empty.
fn quantile(values: &mut [f64], p: f64) -> f64 {
    values.sort_by(f64::total_cmp);
    let rank = ((p * values.len() as f64).ceil() as usize).clamp(1, values.len());
    values[rank - 1]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::benchmark::run::RunRecord;

    fn record(id: &str, set: &str, valid: bool, times: &[u64]) -> ProblemRecord {
        ProblemRecord {
            id: id.into(),
            set: set.into(),
            start_valid: valid,
            goal_valid: true,
            start_in_limits: true,
            goal_in_limits: true,
            straight_edge_free: valid.then_some(false),
            runs: times
                .iter()
                .enumerate()
                .map(|(seed, &time_ns)| RunRecord {
                    seed: seed as u64,
                    found: time_ns < 1000,
                    iterations: time_ns / 10,
                    time_ns,
                    wall_ns: time_ns + 5,
                    waypoints: 3,
                    length: 1.0,
                })
                .collect(),
        }
    }

    #[test]
    fn quantiles_are_nearest_ranks() {
        let mut v: Vec<f64> = (1..=20).rev().map(f64::from).collect();
        assert_eq!(quantile(&mut v, 0.5), 10.0);
        assert_eq!(quantile(&mut v, 0.95), 19.0);
        assert_eq!(quantile(&mut [7.0], 0.95), 7.0);
    }

    #[test]
    fn sets_are_summarized_over_their_valid_problems_only() {
        let records = [
            record("a/1", "a", true, &[100, 300]),
            record("b/1", "b", true, &[2000]),
            record("a/2", "a", false, &[]),
            record("a/3", "a", true, &[200]),
        ];
        let s = summarize(&records);
        let names: Vec<_> = s.iter().map(|s| s.set.as_str()).collect();
        assert_eq!(names, ["a", "b", ALL_SETS]);
        assert_eq!((s[0].problems, s[0].valid), (3, 2));
        let a = s[0].times.unwrap();
        assert_eq!(
            (a.runs, a.solved, a.median_ns, a.p95_ns),
            (3, 3, 200.0, 300.0)
        );
        let all = s[2].times.unwrap();
        assert_eq!((all.runs, all.solved, all.p95_ns), (4, 3, 2000.0));
    }

    #[test]
    fn comparisons_keep_the_problems_both_call_valid() {
        let ours = [
            record("a/1", "a", true, &[400]),
            record("a/2", "a", true, &[800]),
            record("a/3", "a", false, &[]),
            record("a/4", "a", true, &[900]),
        ];
        let peer = [
            record("a/1", "a", true, &[100]),
            record("a/2", "a", false, &[]),
            record("a/3", "a", true, &[50]),
            record("a/4", "a", true, &[300]),
        ];
        let c = compare(&ours, &peer);
        assert_eq!(c.len(), 2);
        assert_eq!((c[0].both_valid, c[0].only_ours, c[0].only_peer), (2, 1, 1));
        assert_eq!(c[0].ours.unwrap().median_ns, 400.0);
        assert_eq!(c[0].peer.unwrap().median_ns, 100.0);
        assert_eq!(c[0].median_ratio(), Some(4.0));
        assert_eq!(c[0].p95_ratio(), Some(3.0));
    }
}
