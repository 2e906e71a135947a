//! What the planner makes of a spec's freedom: plan it in randomized scenes of its task
//! within a budget, and report how often it plans and how quick and short the plans are,
//! beside the nominal-first candidate of the same scenes (what a planner that ignores the
//! freedom would give).

use super::FlexibilityError;
use crate::options::PlanOptions;
use crate::robot::Robot;
use crate::search::plan_best;
use akl_scene::{randomize, Task};
use akl_tsr::TaskSpec;
use serde::Serialize;

/// Settings of [`planner_gains`].
#[derive(Debug, Clone, PartialEq)]
pub struct GainOptions {
    /// Randomized scenes planned.
    pub scenes: usize,
    /// Scene i is `randomize(task, seed + i)`, planned with seed `seed + i`.
    pub seed: u64,
    /// Planner settings, budget included (their seed is replaced per scene).
    pub plan: PlanOptions,
}

/// A scene the spec could not be planned in.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SceneFailure {
    /// The scene's seed.
    pub seed: u64,
    /// Why (the planner's message).
    pub reason: String,
}

/// Best and median of a figure over the planned scenes.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Spread {
    /// Smallest.
    pub best: f64,
    /// Median (the lower middle for an even count).
    pub median: f64,
}

impl Spread {
    fn of(mut values: Vec<f64>) -> Option<Spread> {
        values.sort_by(f64::total_cmp);
        Some(Spread {
            best: *values.first()?,
            median: values[(values.len() - 1) / 2],
        })
    }
}

/// The planner's results over the randomized scenes.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Gains {
    /// Scenes planned.
    pub scenes: usize,
    /// Whole-spec candidates per scene.
    pub candidates: usize,
    /// Scenes where some candidate planned.
    pub planned: usize,
    /// `planned / scenes`.
    pub success_rate: f64,
    /// Execution time (seconds) of the plans kept.
    pub duration: Option<Spread>,
    /// Joint-path length (radians) of the plans kept.
    pub joint_path_length: Option<Spread>,
    /// Execution time of the nominal-first candidate, in the scenes where it planned.
    pub nominal_duration: Option<Spread>,
    /// Median over the scenes where both planned of kept / nominal-first execution time.
    pub median_duration_ratio: Option<f64>,
    /// The scenes that could not be planned.
    pub failures: Vec<SceneFailure>,
}

/// Plans `spec` in `options.scenes` randomized scenes of `task` with the budgeted planner.
pub fn planner_gains(
    robot: &Robot,
    task: &Task,
    spec: &TaskSpec,
    options: &GainOptions,
) -> Result<Gains, FlexibilityError> {
    let mut durations = Vec::new();
    let mut lengths = Vec::new();
    let mut nominal = Vec::new();
    let mut ratios = Vec::new();
    let mut failures = Vec::new();
    for i in 0..options.scenes {
        let seed = options.seed.wrapping_add(i as u64);
        let world = randomize(task, seed).map_err(|e| FlexibilityError::Scene(e.to_string()))?;
        let plan_options = PlanOptions {
            seed,
            ..options.plan.clone()
        };
        match plan_best(robot, spec, &world, &plan_options) {
            Ok(best) => {
                durations.push(best.plan.duration);
                lengths.push(best.plan.joint_path_length());
                if let Some(d) = best.nominal_duration() {
                    nominal.push(d);
                    ratios.push(best.plan.duration / d);
                }
            }
            Err(e) => failures.push(SceneFailure {
                seed,
                reason: e.to_string(),
            }),
        }
    }
    let planned = durations.len();
    Ok(Gains {
        scenes: options.scenes,
        candidates: options.plan.budget.candidates,
        planned,
        success_rate: if options.scenes == 0 {
            0.0
        } else {
            planned as f64 / options.scenes as f64
        },
        duration: Spread::of(durations),
        joint_path_length: Spread::of(lengths),
        nominal_duration: Spread::of(nominal),
        median_duration_ratio: Spread::of(ratios).map(|s| s.median),
        failures,
    })
}
