//! Specs of one task side by side: how many keyframes and lines each has, the freedom it
//! leaves the planner (bits of freedom), what the budgeted planner makes of it, how it executes
//! and whether it passes validation.
//!
//! Once the validation's [`akl_exec::Interrupt`] is raised (Ctrl-C) no further spec
//! is compared; the spec under way keeps the trials it finished, without a verdict.

use crate::validation::{validate, ValidateOptions, Verdict};
use crate::ValidateError;
use akl_planner::flexibility::{planner_gains, FreedomOptions, GainOptions, Workspace};
use akl_planner::{PlanBudget, PlanOptions, Robot};
use akl_scene::Task;
use akl_stats::PassRate;
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
    /// Validation trials of the spec itself that the gate read.
    pub trials: usize,
    /// How many of those passed, with the 95 % interval.
    pub pass_rate: PassRate,
    /// Whether its validation was interrupted (Ctrl-C) part-way.
    pub interrupted: bool,
    /// The validation verdict (`None` when interrupted: a validation cut short has none).
    pub verdict: Option<Verdict>,
    /// What validation found superfluous (removals that pass the gate; answers are not
    /// checked here); empty when interrupted.
    pub not_essential: Vec<String>,
}

/// The rows of a comparison.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Comparison {
    /// Whether it was interrupted (Ctrl-C) before every spec was compared: `rows` holds the
    /// specs compared, the last possibly interrupted (see [`Row::interrupted`]).
    pub interrupted: bool,
    /// One row per spec, in the order given.
    pub rows: Vec<Row>,
}

/// Compares `specs` (name, spec) on `task`; `progress` is called after each spec with
/// (done, total). Stops, and says so, once `options.validate.exec.interrupt` is raised.
pub fn compare(
    robot: &Robot,
    task: &Task,
    specs: &[(String, TaskSpec)],
    options: &CompareOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Comparison, ValidateError> {
    let interrupt = options.validate.exec.interrupt;
    let workspace = Workspace::new(robot, task, &FreedomOptions::default())?;
    let mut rows = Vec::with_capacity(specs.len());
    for (done, (name, spec)) in specs.iter().enumerate() {
        if interrupt.raised() {
            return Ok(Comparison {
                interrupted: true,
                rows,
            });
        }
        let gains = planner_gains(
            robot,
            task,
            spec,
            &GainOptions {
                scenes: options.scenes,
                seed: options.validate.seed,
                plan: PlanOptions {
                    budget: PlanBudget::from_millis(options.budget_ms, spec.keyframes.len()),
                    ..PlanOptions::default()
                },
            },
        )?;
        let validation = validate(robot, task, spec, &options.validate, None, &|_, _| {})?;
        let outcome = &validation.spec.outcome;
        // Raised during the validation (or just after it): its trials may be cut short, so it
        // gets no verdict.
        let interrupted = interrupt.raised();
        if interrupted && outcome.run == 0 {
            return Ok(Comparison { interrupted, rows });
        }
        rows.push(Row {
            spec: name.clone(),
            method: spec.method.clone(),
            keyframes: spec.keyframes.len(),
            constraints: spec.line_count(),
            bits: workspace.bits(spec)?,
            plan_success: gains.success_rate,
            best_duration: gains.duration.map(|d| d.best),
            trials: outcome.run,
            pass_rate: outcome.pass_rate,
            interrupted,
            verdict: validation.verdict,
            not_essential: if interrupted {
                Vec::new()
            } else {
                validation.not_essential().map(|a| a.what.clone()).collect()
            },
        });
        progress(done + 1, specs.len());
        if interrupted {
            return Ok(Comparison { interrupted, rows });
        }
    }
    Ok(Comparison {
        interrupted: false,
        rows,
    })
}
