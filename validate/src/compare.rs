//! Specs of one task side by side: how many keyframes and lines each has, the freedom it
//! leaves the planner (bits of freedom), what the budgeted planner makes of it, how it executes
//! and whether it passes validation.

use crate::validation::{validate, ValidateOptions, Verdict};
use crate::ValidateError;
use akl_planner::flexibility::{planner_gains, FreedomOptions, GainOptions, Workspace};
use akl_planner::{PlanBudget, PlanOptions, Robot};
use akl_scene::Task;
use akl_tsr::TaskSpec;
use serde::Serialize;

/// How specs are compared.
#[derive(Debug, Clone, PartialEq)]
pub struct CompareOptions {
    /// The validation every spec goes through (its trials give the pass rate).
    pub validate: ValidateOptions,
    /// Randomized scenes the budgeted planner plans each spec in (seeded like the trials).
    pub scenes: usize,
    /// The planner's budget per scene (milliseconds, as `akl plan --budget`).
    pub budget_ms: u64,
}

/// One spec's row.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Row {
    /// The spec's name (its file).
    pub spec: String,
    /// How it was made (`akl`, `kd`, `macl`, `truth`, ...).
    pub method: String,
    /// Its keyframes.
    pub keyframes: usize,
    /// Its `move_in_line` segments.
    pub constraints: usize,
    /// Its bits of freedom (`None`: no trace meets it).
    pub bits: Option<f64>,
    /// Share of the scenes the budgeted planner planned it in.
    pub plan_success: f64,
    /// The quickest plan's execution time over those scenes (seconds).
    pub best_duration: Option<f64>,
    /// Share of the validation trials that passed.
    pub pass_rate: f64,
    /// The validation verdict.
    pub verdict: Verdict,
    /// What validation found superfluous (removals that passed every trial, contradicted
    /// answers are not checked here).
    pub not_essential: Vec<String>,
}

/// Compares `specs` (name, spec) on `task`; `progress` is called after each spec with
/// (done, total).
pub fn compare(
    robot: &Robot,
    task: &Task,
    specs: &[(String, TaskSpec)],
    options: &CompareOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Vec<Row>, ValidateError> {
    let workspace = Workspace::new(robot, task, &FreedomOptions::default())?;
    let mut rows = Vec::with_capacity(specs.len());
    for (done, (name, spec)) in specs.iter().enumerate() {
        let gains = planner_gains(
            robot,
            task,
            spec,
            &GainOptions {
                scenes: options.scenes,
                seed: options.validate.trials.seed,
                plan: PlanOptions {
                    budget: PlanBudget::from_millis(options.budget_ms, spec.keyframes.len()),
                    ..PlanOptions::default()
                },
            },
        )?;
        let validation = validate(robot, task, spec, &options.validate, None, &|_, _| {})?;
        rows.push(Row {
            spec: name.clone(),
            method: spec.method.clone(),
            keyframes: spec.keyframes.len(),
            constraints: spec.line_count(),
            bits: workspace.bits(spec)?,
            plan_success: gains.success_rate,
            best_duration: gains.duration.map(|d| d.best),
            pass_rate: validation.outcome.pass_rate(),
            verdict: validation.verdict,
            not_essential: validation.not_essential().map(|a| a.what.clone()).collect(),
        });
        progress(done + 1, specs.len());
    }
    Ok(rows)
}
