//! What execution found: one [`TrialReport`] per trial and a [`BatchReport`] over a batch,
//! both serializable to `report.json`.

use crate::contacts::{Collision, ContactLimits, Extreme};
use crate::shard::Shard;
use akl_scene::GoalCheck;
use akl_stats::{GateVerdict, PassRate};
use akl_tsr::PoseJson;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::fmt;
use std::path::Path;

/// The `akl_report` version this build writes.
pub const REPORT_VERSION: u32 = 1;

/// The stage of a trial a failure belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Stage {
    /// The planner could not produce a plan on the perceived world.
    Planning,
    /// The simulated execution of the plan failed a check.
    Simulation,
}

/// Why a trial failed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Cause {
    /// Planning: a keyframe's TSR has no pose the arm can reach.
    Unreachable,
    /// Planning: the planner found no plan (budget exhausted, a line it cannot follow, a bad
    /// start).
    NoPlan,
    /// Planning: poses of a keyframe are reachable, but every IK solution (or its approach)
    /// would make the arm or the held object touch something.
    NoCollisionFreeGoal,
    /// Simulation: the arm or the held object touched something the step does not
    /// manipulate, or an allowed contact went too deep or pushed too hard.
    Collision,
    /// Simulation: the pads closed on nothing, on another object than the spec's, on two
    /// objects, or unsoundly (off the pads' mid-plane, too little pad overlap).
    GraspFailed,
    /// Simulation: the held object moved in the hand by more than the slip limit.
    Slipped,
    /// Simulation: a released object fell further than the drop limit.
    Dropped,
    /// Simulation: the simulated TCP was not within a keyframe's TSR grounded on its
    /// reference's simulated pose.
    KeyframeMissed,
    /// Simulation: the simulated TCP left a `move_in_line` segment's line by more than the
    /// tolerance.
    LineDeviation,
    /// Simulation: a goal predicate of the task does not hold after settling, an object is
    /// still moving, or an object was never released.
    GoalNotMet,
}

impl Cause {
    /// Every cause, in report order.
    pub const ALL: [Cause; 10] = [
        Cause::Unreachable,
        Cause::NoPlan,
        Cause::NoCollisionFreeGoal,
        Cause::Collision,
        Cause::GraspFailed,
        Cause::Slipped,
        Cause::Dropped,
        Cause::KeyframeMissed,
        Cause::LineDeviation,
        Cause::GoalNotMet,
    ];

    /// The cause in words, as tables print it.
    pub fn label(&self) -> &'static str {
        match self {
            Cause::Unreachable => "unreachable",
            Cause::NoPlan => "no plan",
            Cause::NoCollisionFreeGoal => "no collision-free goal",
            Cause::Collision => "collision",
            Cause::GraspFailed => "grasp failed",
            Cause::Slipped => "slipped",
            Cause::Dropped => "dropped",
            Cause::KeyframeMissed => "keyframe missed",
            Cause::LineDeviation => "line deviation",
            Cause::GoalNotMet => "goal not met",
        }
    }

    /// The stage the cause belongs to.
    pub fn stage(&self) -> Stage {
        match self {
            Cause::Unreachable | Cause::NoPlan | Cause::NoCollisionFreeGoal => Stage::Planning,
            _ => Stage::Simulation,
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
    /// The stage the cause belongs to.
    pub stage: Stage,
    /// The keyframe it concerns (or the keyframe of the segment it happened in), for scripts
    /// that group failures; absent for failures of the whole trial (goals, the start).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub keyframe: Option<usize>,
    /// When it occurred (simulated seconds): 0 for planning, the closing for a grasp, the first
    /// step beyond the limit for a slip or a line, the contact for a collision, the reach for a
    /// keyframe, the release for a drop, the end of settling for a goal. `null` when it has no
    /// moment (a keyframe the plan never reaches). The failures of a trial are in this order.
    pub t: Option<f64>,
    /// Whether this is the trial's root cause: its earliest failure, which the others may
    /// follow from. Exactly one failure of a failed trial has it (the first).
    pub root: bool,
    /// What exactly failed, naming the keyframe, segment or objects.
    pub detail: String,
}

impl Failure {
    /// A failure for `cause`, saying `detail`, with no time yet and not the root.
    pub fn new(cause: Cause, detail: impl Into<String>) -> Failure {
        Failure {
            cause,
            stage: cause.stage(),
            keyframe: None,
            t: None,
            root: false,
            detail: detail.into(),
        }
    }

    /// The same failure, about keyframe `keyframe` (or `None`).
    pub fn at(self, keyframe: impl Into<Option<usize>>) -> Failure {
        Failure {
            keyframe: keyframe.into(),
            ..self
        }
    }

    /// The same failure, occurring at simulated time `t` (seconds).
    pub fn at_time(self, t: f64) -> Failure {
        Failure { t: Some(t), ..self }
    }
}

/// Puts a trial's failures in the order they occurred and marks the first as the root cause.
///
/// The sort is stable, so failures at the same time keep the order the checks gave them (grasp,
/// slip, release, collision, keyframe, line, goals); failures with no time come last.
pub(crate) fn rank(failures: &mut [Failure]) {
    failures.sort_by(|a, b| match (a.t, b.t) {
        (Some(x), Some(y)) => x.total_cmp(&y),
        (Some(_), None) => std::cmp::Ordering::Less,
        (None, Some(_)) => std::cmp::Ordering::Greater,
        (None, None) => std::cmp::Ordering::Equal,
    });
    for (i, f) in failures.iter_mut().enumerate() {
        f.root = i == 0;
    }
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

/// The outcome of closing the gripper, measured on the simulated hand and object.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GraspCheck {
    /// The keyframe of the grasp.
    pub keyframe: usize,
    /// When the pads stopped, or the closing ended (simulated seconds).
    pub t: f64,
    /// The object the spec closes on.
    pub planned: String,
    /// The object both pads closed on, if they closed on one.
    pub grasped: Option<String>,
    /// What each pad touched.
    pub pads: [Option<String>; 2],
    /// Distance of the object's centre from the point between the pads (metres).
    pub offset_from_pads: Option<f64>,
    /// Distance of the object's centre from the pads' mid-plane (metres).
    pub centre_offset: Option<f64>,
    /// The smaller share of a pad's face the object covers (0–1).
    pub overlap: Option<f64>,
    /// Whether the grasp was sound and the object carried.
    pub held: bool,
    /// The turn (radians) by which the pads' squeeze seated the object flat on them about the
    /// hand's approach axis (0 when it was square, round, or turned too far to be seated).
    pub squared: f64,
    /// Largest displacement of the object in the hand until it was let go (metres).
    pub slip: f64,
    /// Largest force along the pads' faces the grasp carried (N).
    pub peak_load: f64,
    /// When the load exceeded what friction holds, if it did.
    pub broke_at: Option<f64>,
}

/// An object let go of, and how far it fell.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ReleaseCheck {
    /// The opening keyframe.
    pub keyframe: usize,
    /// The object.
    pub object: String,
    /// When (simulated seconds).
    pub t: f64,
    /// Height of its bottom when let go above where it came to rest (metres).
    pub fall: f64,
}

/// How closely the simulated TCP followed the planned one.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Tracking {
    /// Largest distance (metres).
    pub max: f64,
    /// Root mean square distance (metres).
    pub rms: f64,
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
    /// The checks that failed, in the order they occurred; the first is the root cause.
    pub failures: Vec<Failure>,
    /// Where the objects randomization moves truly were (world poses): the movable objects and
    /// the furniture moved by its own range, its group's or that of what it stands on.
    pub placements: BTreeMap<String, PoseJson>,
    /// Where perception saw the movable objects (world poses): what the planner planned on.
    pub perceived: BTreeMap<String, PoseJson>,
    /// Wall-clock seconds spent planning.
    pub plan_seconds: f64,
    /// Configurations the planner probed for collisions, over every whole-spec draw, when it
    /// planned (0 when it did not): planning's work, the same on any machine.
    pub plan_probes: u64,
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
    /// One check per object let go of.
    pub releases: Vec<ReleaseCheck>,
    /// Contacts that should not have happened.
    pub collisions: Vec<Collision>,
    /// Deepest contact of the arm or the held object.
    pub deepest_contact: Extreme,
    /// Largest force of a contact of the arm or the held object.
    pub largest_force: Extreme,
    /// How closely the simulated TCP followed the plan.
    pub tracking: Tracking,
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

    /// The trial's root cause: its first failure (the earliest, once ranked by time), if it failed.
    pub fn root(&self) -> Option<&Failure> {
        self.failures.first()
    }

    /// The distinct causes of the trial's failures other than its root's cause: what went
    /// wrong besides (often because of) the root cause.
    pub fn secondary_causes(&self) -> Vec<Cause> {
        let root = self.root().map(|f| f.cause);
        self.causes()
            .into_iter()
            .filter(|c| Some(*c) != root)
            .collect()
    }

    /// The largest line deviation of the trial, if it has lines.
    pub fn worst_line_deviation(&self) -> Option<f64> {
        self.lines.iter().map(|l| l.deviation).reduce(f64::max)
    }
}

/// The settings a batch ran with, so that a report says what it measured against.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// Version of the execution engine (the `akl-exec` crate).
    pub version: String,
    /// SHA-256 of the spec's canonical JSON.
    pub spec_hash: String,
    /// Perception error: standard deviation of position along world x and y (metres).
    pub pose_noise_position: f64,
    /// Perception error: standard deviation of the turn about the vertical (radians).
    pub pose_noise_yaw: f64,
    /// Natural frequency of the joint servos (Hz).
    pub servo_frequency: f64,
    /// Damping ratio of the joint servos.
    pub servo_damping_ratio: f64,
    /// Joint torque limits (N·m).
    pub torque_limits: Vec<f64>,
    /// Force the hand holds a grasped object with (N).
    pub grasp_force: f64,
    /// Simulation step (seconds).
    pub step: f64,
    /// Constraint solver iterations per step.
    pub solver_iterations: usize,
    /// How far the TCP may leave a line (metres).
    pub line_tolerance: f64,
    /// Slack added to keyframe position bounds (metres).
    pub keyframe_position_slack: f64,
    /// Slack added to keyframe angle bounds (radians).
    pub keyframe_angle_slack: f64,
    /// How far a held object may move in the hand (metres).
    pub slip_limit: f64,
    /// How far a released object may fall (metres).
    pub drop_limit: f64,
    /// Largest distance of a grasped object's centre from the pads' mid-plane (metres).
    pub grasp_centre_offset: f64,
    /// Smallest share of a pad's face a grasped object must cover.
    pub grasp_overlap: f64,
    /// Contact depth and force limits.
    pub contacts: ContactLimits,
    /// Settling time after the plan (seconds).
    pub settle: f64,
    /// Longest settling time after the plan, while an object still moves (seconds).
    pub settle_max: f64,
    /// Share of the joint velocity and acceleration limits the plans were timed with.
    pub speed_scale: f64,
}

/// What a batch's totals are computed from, and what its summary and JUnit output show of a
/// trial: implemented by the [`TrialReport`] a run makes and by the [`StoredTrial`] read back
/// from a report file, so a merged or resumed report is summed up as a run's.
pub trait TrialOutcome {
    /// Index of the trial in its run.
    fn index(&self) -> usize;
    /// Its seed.
    fn seed(&self) -> u64;
    /// Whether every check held.
    fn passed(&self) -> bool;
    /// Its failures in the order they occurred (the first is the root cause): cause and detail.
    fn failure_list(&self) -> Vec<(Cause, &str)>;
    /// The largest line deviation of the trial, if it has lines (metres).
    fn line_deviation(&self) -> Option<f64>;
    /// Wall-clock seconds spent planning and simulating.
    fn seconds(&self) -> (f64, f64);
    /// Largest tracking error, deepest contact (metres) and largest contact force (N).
    fn extremes(&self) -> [f64; 3];
}

impl TrialOutcome for TrialReport {
    fn index(&self) -> usize {
        self.trial
    }
    fn seed(&self) -> u64 {
        self.seed
    }
    fn passed(&self) -> bool {
        self.passed
    }
    fn failure_list(&self) -> Vec<(Cause, &str)> {
        self.failures
            .iter()
            .map(|f| (f.cause, f.detail.as_str()))
            .collect()
    }
    fn line_deviation(&self) -> Option<f64> {
        self.worst_line_deviation()
    }
    fn seconds(&self) -> (f64, f64) {
        (self.plan_seconds, self.sim_seconds)
    }
    fn extremes(&self) -> [f64; 3] {
        [
            self.tracking.max,
            self.deepest_contact.value,
            self.largest_force.value,
        ]
    }
}

/// The parts of a trial's report a summary reads, as stored in `report.json`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
struct StoredSummary {
    trial: usize,
    seed: u64,
    passed: bool,
    failures: Vec<StoredFailure>,
    lines: Vec<StoredLine>,
    plan_seconds: f64,
    sim_seconds: f64,
    tracking: Tracking,
    deepest_contact: StoredValue,
    largest_force: StoredValue,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
struct StoredFailure {
    cause: Cause,
    detail: String,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
struct StoredLine {
    deviation: f64,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
struct StoredValue {
    value: f64,
}

/// A trial's report read back from a report file: its JSON kept as written (so a merged
/// report holds each trial exactly as its shard wrote it), with what summaries need parsed.
#[derive(Debug, Clone, PartialEq)]
pub struct StoredTrial {
    json: serde_json::Value,
    summary: StoredSummary,
}

impl StoredTrial {
    /// The trial's report as JSON.
    pub fn json(&self) -> &serde_json::Value {
        &self.json
    }

    /// A trial's report as JSON, read back.
    pub fn from_json(json: serde_json::Value) -> serde_json::Result<StoredTrial> {
        let summary = serde_json::from_value(json.clone())?;
        Ok(StoredTrial { json, summary })
    }

    /// A trial just run, as a report file will hold it.
    pub fn from_report(report: &TrialReport) -> serde_json::Result<StoredTrial> {
        StoredTrial::from_json(serde_json::to_value(report)?)
    }
}

impl Serialize for StoredTrial {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        self.json.serialize(s)
    }
}

impl<'de> Deserialize<'de> for StoredTrial {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<StoredTrial, D::Error> {
        let json = serde_json::Value::deserialize(d)?;
        StoredTrial::from_json(json).map_err(serde::de::Error::custom)
    }
}

impl TrialOutcome for StoredTrial {
    fn index(&self) -> usize {
        self.summary.trial
    }
    fn seed(&self) -> u64 {
        self.summary.seed
    }
    fn passed(&self) -> bool {
        self.summary.passed
    }
    fn failure_list(&self) -> Vec<(Cause, &str)> {
        self.summary
            .failures
            .iter()
            .map(|f| (f.cause, f.detail.as_str()))
            .collect()
    }
    fn line_deviation(&self) -> Option<f64> {
        self.summary
            .lines
            .iter()
            .map(|l| l.deviation)
            .reduce(f64::max)
    }
    fn seconds(&self) -> (f64, f64) {
        (self.summary.plan_seconds, self.summary.sim_seconds)
    }
    fn extremes(&self) -> [f64; 3] {
        [
            self.summary.tracking.max,
            self.summary.deepest_contact.value,
            self.summary.largest_force.value,
        ]
    }
}

/// What makes the reports of two runs (or of the shards of one) parts of the same run: the
/// same engine, spec, task, robot and settings, and the same number of trials asked for.
/// Hashes are SHA-256, hex.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Identity {
    /// Version of the execution engine (the `akl-exec` crate).
    pub version: String,
    /// The CPU architecture and operating system the trials ran on (`x86_64-linux`): floating
    /// point may round differently on another, so parts of one run must share it.
    #[serde(default)]
    pub platform: String,
    /// The spec's canonical JSON.
    pub spec_hash: String,
    /// The task's canonical JSON: its world, goals and randomization ranges.
    pub task_hash: String,
    /// The robot: its `robot.toml` settings, URDF and every mesh's triangles.
    pub robot_hash: String,
    /// Every execution setting (simulation, servos, grasp and contact limits, perception
    /// noise, planner settings including where goals are drawn and the budget).
    pub settings_hash: String,
    /// Trials the whole run asks for (all shards together).
    pub trials: usize,
}

/// One part a merged report was joined from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MergedPart {
    /// The part's file.
    pub file: String,
    /// Its shard.
    pub shard: Option<Shard>,
    /// Worker threads it used.
    pub jobs: usize,
    /// Its wall-clock seconds.
    pub wall_seconds: f64,
}

/// The outcome of a batch of trials of one spec on one task: [`TrialReport`]s as a run makes
/// them, or [`StoredTrial`]s as a merged or resumed report holds them (both serialize alike).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BatchReport<T = TrialReport> {
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
    /// Number of trials run (fewer than asked when interrupted; a shard's own).
    pub trials: usize,
    /// Number that passed.
    pub passed: usize,
    /// The pass rate with its 95 % confidence interval (exact, Clopper–Pearson).
    pub pass_rate: PassRate,
    /// The deployment gate that judged these trials, when a gate did (`akl validate`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub gate: Option<GateVerdict>,
    /// Whether the batch was stopped (Ctrl-C) before every trial asked for had started: the
    /// report covers only the trials that finished.
    pub interrupted: bool,
    /// The shard of the run these trials are (`akl execute --shard`); absent for a whole run.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<Shard>,
    /// What makes this report comparable with others of the same run (checked by
    /// [`crate::merge`] and `--resume`); absent in reports of older builds.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub identity: Option<Identity>,
    /// For each cause, how many failed trials it was the root cause of (its earliest failure); these
    /// add up to the failed trials.
    pub failures: BTreeMap<Cause, usize>,
    /// For each cause, how many failed trials it occurred in without being their root cause.
    pub secondary: BTreeMap<Cause, usize>,
    /// The largest line deviation over all trials (metres), if the spec has lines.
    pub worst_line_deviation: Option<f64>,
    /// Mean wall-clock seconds per trial (planning plus simulation).
    pub seconds_per_trial: f64,
    /// Mean wall-clock seconds of planning per trial.
    pub plan_seconds_per_trial: f64,
    /// Mean wall-clock seconds of simulation per trial.
    pub sim_seconds_per_trial: f64,
    /// Wall-clock seconds for the whole batch (of a merged report: its longest part's).
    pub wall_seconds: f64,
    /// Worker threads used (of a merged report: the most a part used).
    pub jobs: usize,
    /// The parts a merged report was joined from (`akl report merge`); absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub merged: Option<Vec<MergedPart>>,
    /// What the trials measured against.
    pub settings: Settings,
    /// Every trial run, in order.
    pub reports: Vec<T>,
}

impl<T: TrialOutcome> BatchReport<T> {
    /// Summarizes `reports` (in trial order) run on `jobs` threads in `wall_seconds` with
    /// `settings`; not interrupted, not a shard, no identity (the caller sets those).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        task: &str,
        method: &str,
        seed: u64,
        randomized: bool,
        reports: Vec<T>,
        jobs: usize,
        wall_seconds: f64,
        settings: Settings,
    ) -> BatchReport<T> {
        let passed = reports.iter().filter(|r| r.passed()).count();
        let mut failures: BTreeMap<Cause, usize> = BTreeMap::new();
        let mut secondary: BTreeMap<Cause, usize> = BTreeMap::new();
        for r in &reports {
            let causes = r.failure_list();
            let Some(&(root, _)) = causes.first() else {
                continue;
            };
            *failures.entry(root).or_default() += 1;
            let mut others: Vec<Cause> = causes
                .iter()
                .map(|(c, _)| *c)
                .filter(|c| *c != root)
                .collect();
            others.sort();
            others.dedup();
            for c in others {
                *secondary.entry(c).or_default() += 1;
            }
        }
        let n = reports.len().max(1) as f64;
        let plan: f64 = reports.iter().map(|r| r.seconds().0).sum();
        let sim: f64 = reports.iter().map(|r| r.seconds().1).sum();
        BatchReport {
            akl_report: REPORT_VERSION,
            task: task.to_string(),
            method: method.to_string(),
            seed,
            randomized,
            trials: reports.len(),
            passed,
            pass_rate: PassRate::new(passed, reports.len()),
            gate: None,
            interrupted: false,
            shard: None,
            identity: None,
            failures,
            secondary,
            worst_line_deviation: reports
                .iter()
                .filter_map(TrialOutcome::line_deviation)
                .reduce(f64::max),
            seconds_per_trial: (plan + sim) / n,
            plan_seconds_per_trial: plan / n,
            sim_seconds_per_trial: sim / n,
            wall_seconds,
            jobs,
            merged: None,
            settings,
            reports,
        }
    }

    /// Whether every trial passed.
    pub fn all_passed(&self) -> bool {
        self.passed == self.trials
    }
}

impl<T: Serialize> BatchReport<T> {
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

impl BatchReport<TrialReport> {
    /// The same report with its trials as a report file holds them.
    pub fn stored(&self) -> serde_json::Result<BatchReport<StoredTrial>> {
        let reports = self
            .reports
            .iter()
            .map(StoredTrial::from_report)
            .collect::<serde_json::Result<Vec<_>>>()?;
        Ok(BatchReport {
            akl_report: self.akl_report,
            task: self.task.clone(),
            method: self.method.clone(),
            seed: self.seed,
            randomized: self.randomized,
            trials: self.trials,
            passed: self.passed,
            pass_rate: self.pass_rate,
            gate: self.gate,
            interrupted: self.interrupted,
            shard: self.shard,
            identity: self.identity.clone(),
            failures: self.failures.clone(),
            secondary: self.secondary.clone(),
            worst_line_deviation: self.worst_line_deviation,
            seconds_per_trial: self.seconds_per_trial,
            plan_seconds_per_trial: self.plan_seconds_per_trial,
            sim_seconds_per_trial: self.sim_seconds_per_trial,
            wall_seconds: self.wall_seconds,
            jobs: self.jobs,
            merged: self.merged.clone(),
            settings: self.settings.clone(),
            reports,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A trial whose failures are `failures` (cause, time), ranked as a trial ranks them.
    fn trial(i: usize, failures: &[(Cause, f64)], deviation: Option<f64>) -> TrialReport {
        let mut failures: Vec<Failure> = failures
            .iter()
            .map(|(c, t)| Failure::new(*c, String::new()).at_time(*t))
            .collect();
        rank(&mut failures);
        TrialReport {
            trial: i,
            seed: i as u64,
            passed: failures.is_empty(),
            failures,
            placements: BTreeMap::new(),
            perceived: BTreeMap::new(),
            plan_seconds: 0.1,
            plan_probes: 1000,
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
            releases: Vec::new(),
            collisions: Vec::new(),
            deepest_contact: Default::default(),
            largest_force: Default::default(),
            tracking: Tracking::default(),
            goals: Vec::new(),
        }
    }

    fn batch(reports: Vec<TrialReport>) -> BatchReport {
        BatchReport::new(
            "t",
            "truth",
            0,
            true,
            reports,
            2,
            1.0,
            crate::batch::settings(
                &akl_planner::Robot::panda().unwrap(),
                &crate::options::ExecOptions::default(),
                &akl_scene::builtin::task("inspection")
                    .unwrap()
                    .unwrap()
                    .truth
                    .unwrap(),
            ),
        )
    }

    #[test]
    fn failures_are_ranked_by_time_and_the_earliest_is_the_root() {
        // In the checks' order: slip before collision before goals, but the collision came
        // first; the untimed keyframe failure goes last, ties keep the checks' order.
        let mut failures = vec![
            Failure::new(Cause::Slipped, "slipped").at_time(2.26),
            Failure::new(Cause::Collision, "touched wall_e").at_time(2.25),
            Failure::new(Cause::Collision, "touched wall_w").at_time(2.26),
            Failure::new(Cause::KeyframeMissed, "never reached"),
            Failure::new(Cause::GoalNotMet, "on(tube, rack)").at_time(4.0),
        ];
        rank(&mut failures);
        let order: Vec<&str> = failures.iter().map(|f| f.detail.as_str()).collect();
        assert_eq!(
            order,
            [
                "touched wall_e",
                "slipped",
                "touched wall_w",
                "on(tube, rack)",
                "never reached"
            ]
        );
        let roots: Vec<bool> = failures.iter().map(|f| f.root).collect();
        assert_eq!(roots, [true, false, false, false, false]);
        let json = serde_json::to_value(&failures).unwrap();
        assert_eq!(json[0]["root"], true);
        assert_eq!(json[0]["t"], 2.25);
        assert_eq!(json[1]["root"], false);
        assert!(json[4]["t"].is_null());
    }

    #[test]
    fn a_batch_counts_failed_trials_by_root_cause_and_the_rest_apart() {
        let b = batch(vec![
            trial(0, &[], Some(0.001)),
            trial(
                1,
                &[
                    (Cause::GoalNotMet, 5.0),
                    (Cause::Collision, 1.0),
                    (Cause::Collision, 2.0),
                    (Cause::Slipped, 1.5),
                ],
                Some(0.004),
            ),
            trial(2, &[(Cause::Unreachable, 0.0)], None),
            trial(3, &[(Cause::Slipped, 3.0), (Cause::Collision, 3.5)], None),
        ]);
        assert_eq!((b.trials, b.passed), (4, 1));
        assert!(!b.interrupted);
        assert_eq!(b.settings.spec_hash.len(), 64);
        let roots: BTreeMap<Cause, usize> = [
            (Cause::Unreachable, 1),
            (Cause::Collision, 1),
            (Cause::Slipped, 1),
        ]
        .into();
        assert_eq!(b.failures, roots);
        assert_eq!(b.failures.values().sum::<usize>(), b.trials - b.passed);
        let secondary: BTreeMap<Cause, usize> = [
            (Cause::Collision, 1),
            (Cause::Slipped, 1),
            (Cause::GoalNotMet, 1),
        ]
        .into();
        assert_eq!(b.secondary, secondary);
        assert_eq!(b.worst_line_deviation, Some(0.004));
        assert!((b.seconds_per_trial - 0.4).abs() < 1e-12);
        assert!(!b.all_passed());
        let json = b.to_json().unwrap();
        assert!(json.contains("\"interrupted\": false"), "{json}");
        assert!(json.contains("\"secondary\": {"), "{json}");
    }
}
