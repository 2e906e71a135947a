//! The deployment gate: a spec passes only if it passes its randomized trials, every keyframe
//! and line of it is essential ([`crate::ablation`]), and, given the demonstration it was
//! learned from, the simulation contradicts none of the teacher's answers
//! ([`crate::answers`]).

use crate::ablation::{ablate, Ablation};
use crate::answers::{check_answers, AnswerCheck, Answers, DemoSource};
use crate::trials::{run_trials, Outcome, Stop, Trials};
use crate::ValidateError;
use akl_exec::trial::ExecOptions;
use akl_planner::Robot;
use akl_scene::Task;
use akl_tsr::TaskSpec;
use serde::Serialize;

/// How a spec is validated.
#[derive(Debug, Clone, PartialEq)]
pub struct ValidateOptions {
    /// The trials the spec and every removal run on.
    pub trials: Trials,
    /// Execution settings (the planner's goals are drawn across the TSRs whatever they say,
    /// see [`crate::trials::verifying`]).
    pub exec: ExecOptions,
}

/// The gate's answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// Every trial passed and nothing in the spec is superfluous: deploy.
    Passes,
    /// Every trial passed, but a removal passed too, or an answer is contradicted.
    NotMinimal,
    /// Some trial failed.
    Fails,
}

impl Verdict {
    /// The verdict in words, as tables print it.
    pub fn label(&self) -> &'static str {
        match self {
            Verdict::Passes => "passes, minimal",
            Verdict::NotMinimal => "not minimal",
            Verdict::Fails => "fails",
        }
    }
}

/// Everything a validation found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Validation {
    /// The trials run.
    pub trials: Trials,
    /// The spec's own trials (every one run).
    pub outcome: Outcome,
    /// The spec without each keyframe and each line.
    pub removals: Vec<Ablation>,
    /// The demonstration's answers, when it was given.
    pub answers: Option<Answers>,
    /// The verdict.
    pub verdict: Verdict,
}

impl Validation {
    /// The removals that passed every trial.
    pub fn not_essential(&self) -> impl Iterator<Item = &Ablation> {
        self.removals.iter().filter(|a| !a.essential)
    }

    /// The answers the simulation contradicts.
    pub fn contradicted(&self) -> impl Iterator<Item = &AnswerCheck> {
        self.answers.iter().flat_map(Answers::contradicted)
    }
}

/// Validates `spec` on `task`; `progress` is called after each check (the spec's trials, each
/// removal, each answer) with (done, total).
pub fn validate(
    robot: &Robot,
    task: &Task,
    spec: &TaskSpec,
    options: &ValidateOptions,
    demo: Option<DemoSource>,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Validation, ValidateError> {
    let answers_count = demo.map_or(0, |d| crate::answers::recorded_answers(d.demo).len());
    let removal_count = crate::ablation::removals(spec).len();
    let total = 1 + removal_count + answers_count;
    let outcome = run_trials(
        robot,
        task,
        spec,
        &options.exec,
        &options.trials,
        Stop::Never,
    )?;
    progress(1, total);
    let removals = ablate(
        robot,
        task,
        spec,
        &outcome,
        &options.exec,
        &options.trials,
        &|_, done, _| progress(1 + done, total),
    )?;
    let answers = match demo {
        Some(d) => Some(check_answers(
            robot,
            task,
            d,
            spec,
            &outcome,
            &options.exec,
            &options.trials,
            &|done, _| progress(1 + removal_count + done, total),
        )?),
        None => None,
    };
    let mut validation = Validation {
        trials: options.trials,
        outcome,
        removals,
        answers,
        verdict: Verdict::Passes,
    };
    validation.verdict = if !validation.outcome.all_passed() {
        Verdict::Fails
    } else if validation.not_essential().next().is_some()
        || validation.contradicted().next().is_some()
    {
        Verdict::NotMinimal
    } else {
        Verdict::Passes
    };
    Ok(validation)
}
