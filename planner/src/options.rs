//! How a spec is planned: the planner's settings ([`PlanOptions`]) and how many whole-spec
//! candidates it may plan ([`PlanBudget`], see [`crate::search`]).

use crate::error::PlanError;
use crate::goal::GoalOptions;
use crate::line::LineOptions;
use crate::robot::Robot;
use crate::rrt::RrtOptions;

/// Milliseconds one candidate takes per keyframe on the reference machine (BENCHMARKS.md,
/// "Planning budget"): the calibration that turns `--budget MS` into a candidate count.
///
/// Measured by `cargo bench -p akl-planner --bench budget`: the planning time of 21-candidate
/// searches on the three ground truths divided by candidates and keyframes gave 2.25 ms
/// (pick_place), 1.93 ms (inspection) and 7.15 ms (assembly, whose pipe grasp plans a line
/// ahead for every goal it accepts); their mean is 3.8 ms. A second run (14 candidates) gave
/// 1.4, 1.9 and 5.3 ms; with 3.8 ms a 200 ms budget then took 107, 154 and 286 ms.
pub const MS_PER_KEYFRAME: f64 = 3.8;

/// How many whole-spec candidates [`crate::search::plan_best`] plans.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlanBudget {
    /// Candidates planned (at least one).
    pub candidates: usize,
}

impl PlanBudget {
    /// One candidate: the nominal-first plan.
    pub(crate) const SINGLE: PlanBudget = PlanBudget { candidates: 1 };

    /// A budget of `candidates` candidates (at least one).
    pub fn candidates(candidates: usize) -> PlanBudget {
        PlanBudget {
            candidates: candidates.max(1),
        }
    }

    /// The candidates `ms` milliseconds of planning buy for a spec of `keyframes` keyframes on
    /// the reference machine: one, plus one per [`MS_PER_KEYFRAME`] × `keyframes` ms. A fixed
    /// conversion, so the plan never depends on how fast this machine happens to be.
    pub fn from_millis(ms: u64, keyframes: usize) -> PlanBudget {
        let per_candidate = MS_PER_KEYFRAME * keyframes.max(1) as f64;
        PlanBudget::candidates(1 + (ms as f64 / per_candidate).floor() as usize)
    }
}

impl Default for PlanBudget {
    fn default() -> Self {
        PlanBudget::SINGLE
    }
}

/// Settings of [`crate::search::plan_task`].
#[derive(Debug, Clone, PartialEq)]
pub struct PlanOptions {
    /// Seed of every random choice.
    pub seed: u64,
    /// How far back along the tool axis grasps and releases are approached from (metres).
    pub approach_distance: f64,
    /// RRT-Connect settings.
    pub rrt: RrtOptions,
    /// Random shortcut attempts per free path.
    pub shortcut_attempts: usize,
    /// Goal sampling settings.
    pub goals: GoalOptions,
    /// Straight-line settings.
    pub line: LineOptions,
    /// Pause after the gripper has moved, before the arm moves on (seconds).
    pub gripper_settle: f64,
    /// How many whole-spec candidates to plan, keeping the quickest (see `search`). The
    /// default, one candidate, is the nominal-first plan; `PlanBudget::from_millis` turns a
    /// planning time into a candidate count.
    pub budget: PlanBudget,
    /// How fast the arm may move, in (0, 1]: the joint velocity limits are multiplied by it and
    /// the acceleration limits by its square, so every motion is the one planned at full speed
    /// played 1/S times as long (MoveIt's velocity scaling factor S with its acceleration
    /// scaling factor S²; with S for both, as MoveIt users often set them, a short move limited
    /// by acceleration would only take 1/√S as long, and "half speed" would not halve the
    /// speed). The fingers, joints too, move at S times their speed, and the pause after each
    /// gripper motion, which lets a closing that pushed the object first finish, is 1/S times
    /// as long. The paths are the same; only their timing changes: the whole plan is played
    /// 1/S times as long.
    pub speed_scale: f64,
}

impl PlanOptions {
    /// The joint velocity and acceleration limits the plan is timed with: the robot's,
    /// scaled by [`PlanOptions::speed_scale`] and its square.
    pub(crate) fn limits(&self, robot: &Robot) -> (Vec<f64>, Vec<f64>) {
        let scale = |v: &[f64], by: f64| v.iter().map(|x| x * by).collect();
        let s = self.speed_scale;
        (
            scale(robot.velocity_limits(), s),
            scale(robot.acceleration_limits(), s * s),
        )
    }

    /// Checks [`PlanOptions::speed_scale`].
    pub fn check(&self) -> Result<(), PlanError> {
        if self.speed_scale > 0.0 && self.speed_scale <= 1.0 {
            Ok(())
        } else {
            Err(PlanError::Options(format!(
                "the speed scale must be in (0, 1], not {}",
                self.speed_scale
            )))
        }
    }
}

impl Default for PlanOptions {
    fn default() -> Self {
        PlanOptions {
            seed: 0,
            approach_distance: 0.06,
            rrt: RrtOptions::default(),
            shortcut_attempts: 100,
            goals: GoalOptions::default(),
            line: LineOptions::default(),
            gripper_settle: 0.2,
            budget: PlanBudget::SINGLE,
            speed_scale: 1.0,
        }
    }
}
