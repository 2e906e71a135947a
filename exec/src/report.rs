//! What execution found: one [`TrialReport`] per trial and a [`BatchReport`] over a batch,
//! both serializable to `report.json`.

use crate::contacts::Collision;
use akl_scene::GoalCheck;
use akl_tsr::PoseJson;
use serde::Serialize;
use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;

/// The `akl_report` version this build writes.
pub const REPORT_VERSION: u32 = 1;

/// Why a trial failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Cause {
    /// A keyframe's TSR has no pose the arm can reach.
    Unreachable,
    /// The planner found no plan (budget exhausted, a line it cannot follow, a bad start).
    NoPlan,
    /// The arm or the held object touched something the step does not manipulate, in the
    /// simulation or, when every way to reach a keyframe would, already in planning.
    Collision,
    /// The gripper closed on nothing, or on another object than the planned one.
    GraspFailed,
    /// The TCP was not within a keyframe's TSR grounded on its reference's current pose.
    KeyframeMissed,
    /// The TCP left a `move_in_line` segment's line by more than the tolerance.
    LineDeviation,
    /// A goal predicate of the task does not hold after settling, or an object is not at rest.
    GoalNotMet,
}

impl Cause {
    /// Every cause, in report order.
    pub const ALL: [Cause; 7] = [
        Cause::Unreachable,
        Cause::NoPlan,
        Cause::Collision,
        Cause::GraspFailed,
        Cause::KeyframeMissed,
        Cause::LineDeviation,
        Cause::GoalNotMet,
    ];

    /// The cause in words, as tables print it.
    pub fn label(&self) -> &'static str {
        match self {
            Cause::Unreachable => "unreachable",
            Cause::NoPlan => "no plan",
            Cause::Collision => "collision",
            Cause::GraspFailed => "grasp failed",
            Cause::KeyframeMissed => "keyframe missed",
            Cause::LineDeviation => "line deviation",
            Cause::GoalNotMet => "goal not met",
        }
    }
}

impl fmt::Display for Cause {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.label())
    }
}

/// One failed check of a trial.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Failure {
    /// Its cause.
    pub cause: Cause,
    /// What exactly failed, naming the keyframe, segment or objects.
    pub detail: String,
}

/// Whether a keyframe was reached within its TSR grounded on its reference's current pose.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct KeyframeCheck {
    /// Index of the keyframe in the spec.
    pub keyframe: usize,
    /// When it was reached (simulated seconds).
    pub t: f64,
    /// Its reference object.
    pub reference: String,
    /// The reference's pose at that time (the TSR's `t0_w`).
    pub grounded_on: PoseJson,
    /// The TCP pose reached.
    pub tcp: PoseJson,
    /// Weighted distance of the TCP from the TSR (metres; 0 inside).
    pub distance: f64,
    /// Whether the TCP was inside (with the documented slack).
    pub reached: bool,
}

/// How straight a `move_in_line` segment was executed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LineCheck {
    /// The keyframe the line ends at.
    pub keyframe: usize,
    /// Start and end of the segment (simulated seconds).
    pub start: f64,
    /// End of the segment.
    pub end: f64,
    /// TCP position where the line starts (world).
    pub from: [f64; 3],
    /// TCP position where the line ends (world).
    pub to: [f64; 3],
    /// Largest distance of the executed TCP from the line (metres).
    pub deviation: f64,
    /// Whether it stayed within the tolerance.
    pub within: bool,
}

/// The outcome of closing the gripper.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GraspCheck {
    /// The keyframe of the grasp.
    pub keyframe: usize,
    /// When the fingers had closed (simulated seconds).
    pub t: f64,
    /// The object the plan grasps.
    pub planned: String,
    /// The object between the fingers, if any.
    pub grasped: Option<String>,
}

/// Everything one trial checked, and whether it passed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrialReport {
    /// Index of the trial in its batch.
    pub trial: usize,
    /// Seed of the object placement and of the planner.
    pub seed: u64,
    /// Whether every check held.
    pub passed: bool,
    /// The checks that failed.
    pub failures: Vec<Failure>,
    /// Where the randomized objects were placed (world poses).
    pub placements: BTreeMap<String, PoseJson>,
    /// Wall-clock seconds spent planning.
    pub plan_seconds: f64,
    /// Wall-clock seconds spent simulating.
    pub sim_seconds: f64,
    /// Simulated seconds (plan plus settling).
    pub simulated_seconds: f64,
    /// One check per keyframe reached.
    pub keyframes: Vec<KeyframeCheck>,
    /// One check per `move_in_line` segment.
    pub lines: Vec<LineCheck>,
    /// One check per grasp.
    pub grasps: Vec<GraspCheck>,
    /// Contacts that should not have happened.
    pub collisions: Vec<Collision>,
    /// The task's goal predicates and the rest check, after settling.
    pub goals: Vec<GoalCheck>,
}

impl TrialReport {
    /// The distinct causes of the trial's failures.
    pub fn causes(&self) -> Vec<Cause> {
        let mut causes: Vec<Cause> = self.failures.iter().map(|f| f.cause).collect();
        causes.sort();
        causes.dedup();
        causes
    }

    /// The largest line deviation of the trial, if it has lines.
    pub fn worst_line_deviation(&self) -> Option<f64> {
        self.lines.iter().map(|l| l.deviation).reduce(f64::max)
    }
}

/// The outcome of a batch of trials of one spec on one task.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BatchReport {
    /// Format version; always [`REPORT_VERSION`].
    pub akl_report: u32,
    /// The task executed.
    pub task: String,
    /// The spec's method (`akl`, `truth`, ...).
    pub method: String,
    /// Seed of the first trial (trial i uses seed + i).
    pub seed: u64,
    /// Whether objects were moved within the task's ranges.
    pub randomized: bool,
    /// Number of trials.
    pub trials: usize,
    /// Number that passed.
    pub passed: usize,
    /// For each cause, how many trials failed (at least) for it.
    pub failures: BTreeMap<Cause, usize>,
    /// The largest line deviation over all trials (metres), if the spec has lines.
    pub worst_line_deviation: Option<f64>,
    /// Mean wall-clock seconds per trial (planning plus simulation).
    pub seconds_per_trial: f64,
    /// Mean wall-clock seconds of planning per trial.
    pub plan_seconds_per_trial: f64,
    /// Mean wall-clock seconds of simulation per trial.
    pub sim_seconds_per_trial: f64,
    /// Wall-clock seconds for the whole batch.
    pub wall_seconds: f64,
    /// Worker threads used.
    pub jobs: usize,
    /// Every trial, in order.
    pub reports: Vec<TrialReport>,
}

impl BatchReport {
    /// Summarizes `reports` (in trial order) run on `jobs` threads in `wall_seconds`.
    pub fn new(
        task: &str,
        method: &str,
        seed: u64,
        randomized: bool,
        reports: Vec<TrialReport>,
        jobs: usize,
        wall_seconds: f64,
    ) -> BatchReport {
        let mut failures: BTreeMap<Cause, usize> = BTreeMap::new();
        for r in &reports {
            for c in r.causes() {
                *failures.entry(c).or_default() += 1;
            }
        }
        let n = reports.len().max(1) as f64;
        let plan: f64 = reports.iter().map(|r| r.plan_seconds).sum();
        let sim: f64 = reports.iter().map(|r| r.sim_seconds).sum();
        BatchReport {
            akl_report: REPORT_VERSION,
            task: task.to_string(),
            method: method.to_string(),
            seed,
            randomized,
            trials: reports.len(),
            passed: reports.iter().filter(|r| r.passed).count(),
            failures,
            worst_line_deviation: reports
                .iter()
                .filter_map(TrialReport::worst_line_deviation)
                .reduce(f64::max),
            seconds_per_trial: (plan + sim) / n,
            plan_seconds_per_trial: plan / n,
            sim_seconds_per_trial: sim / n,
            wall_seconds,
            jobs,
            reports,
        }
    }

    /// Whether every trial passed.
    pub fn all_passed(&self) -> bool {
        self.passed == self.trials
    }

    /// The report as readable JSON.
    pub fn to_json(&self) -> serde_json::Result<String> {
        akl_tsr::io::to_readable_json(self)
    }

    /// Writes the report atomically (never a half-written file).
    pub fn save(&self, path: &Path) -> std::io::Result<()> {
        let text = self.to_json().map_err(std::io::Error::other)?;
        akl_tsr::io::write_atomic(path, text.as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trial(i: usize, causes: &[Cause], deviation: Option<f64>) -> TrialReport {
        TrialReport {
            trial: i,
            seed: i as u64,
            passed: causes.is_empty(),
            failures: causes
                .iter()
                .map(|c| Failure {
                    cause: *c,
                    detail: String::new(),
                })
                .collect(),
            placements: BTreeMap::new(),
            plan_seconds: 0.1,
            sim_seconds: 0.3,
            simulated_seconds: 10.0,
            keyframes: Vec::new(),
            lines: deviation
                .map(|d| LineCheck {
                    keyframe: 1,
                    start: 0.0,
                    end: 1.0,
                    from: [0.0; 3],
                    to: [1.0, 0.0, 0.0],
                    deviation: d,
                    within: d < 0.005,
                })
                .into_iter()
                .collect(),
            grasps: Vec::new(),
            collisions: Vec::new(),
            goals: Vec::new(),
        }
    }

    #[test]
    fn a_batch_counts_each_cause_once_per_trial() {
        let b = BatchReport::new(
            "t",
            "truth",
            0,
            true,
            vec![
                trial(0, &[], Some(0.001)),
                trial(
                    1,
                    &[Cause::Collision, Cause::Collision, Cause::GoalNotMet],
                    Some(0.004),
                ),
                trial(2, &[Cause::Unreachable], None),
            ],
            2,
            1.0,
        );
        assert_eq!((b.trials, b.passed), (3, 1));
        assert_eq!(b.failures[&Cause::Collision], 1);
        assert_eq!(b.failures[&Cause::GoalNotMet], 1);
        assert_eq!(b.failures[&Cause::Unreachable], 1);
        assert_eq!(b.worst_line_deviation, Some(0.004));
        assert!((b.seconds_per_trial - 0.4).abs() < 1e-12);
        assert!(!b.all_passed());
        let json = b.to_json().unwrap();
        assert!(json.contains("\"goal_not_met\": 1"), "{json}");
    }
}
