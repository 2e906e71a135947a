//! The deployment gate: a spec passes only if its trials pass the sequential gate
//! ([`akl_stats::gate`]: it succeeds with probability at least `P` at confidence `C`), every
//! keyframe and line of it is essential ([`crate::ablation`], the same gate on the spec without
//! each), and, given the demonstration it was learned from, the simulation contradicts none of
//! the teacher's answers ([`crate::answers`]).

use crate::ablation::{ablate, Ablation, Necessity};
use crate::answers::{check_answers, AnswerCheck, Answers, DemoSource};
use crate::trials::{run_gated, Gated};
use crate::ValidateError;
use akl_exec::ExecOptions;
use akl_planner::Robot;
use akl_scene::Task;
use akl_stats::{Decision, Gate, GateOptions};
use akl_tsr::TaskSpec;
use serde::Serialize;

/// How a spec is validated.
#[derive(Debug, Clone, PartialEq)]
pub struct ValidateOptions {
    /// Seed of the first trial (trial i places the objects and plans with seed + i).
    pub seed: u64,
    /// Trials run in parallel (at least 1).
    pub jobs: usize,
    /// What the gate asks, and its most trials.
    pub gate: GateOptions,
    /// Execution settings (the planner's goals are drawn across the TSRs whatever they say,
    /// see [`crate::trials::verifying`]); its interrupt stops the validation.
    pub exec: ExecOptions,
}

/// Which stage of a validation is running, for progress reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// The spec's own trials.
    Spec,
    /// The spec without one keyframe or line (index among the removals).
    Removal(usize),
    /// One flipped answer (index among the answers).
    Answer(usize),
}

/// The gate's answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// The spec passes the gate and nothing in it is superfluous: deploy.
    Passes,
    /// The spec passes the gate, but a removal passes it too, or an answer is contradicted.
    NotMinimal,
    /// The spec fails the gate.
    Fails,
    /// The gate could not decide within its trials.
    Undecided,
}

impl Verdict {
    /// The verdict in words, as tables print it.
    pub fn label(&self) -> &'static str {
        match self {
            Verdict::Passes => "passes, minimal",
            Verdict::NotMinimal => "not minimal",
            Verdict::Fails => "fails",
            Verdict::Undecided => "undecided",
        }
    }
}

/// Everything a validation found.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Validation {
    /// Seed of the first trial.
    pub seed: u64,
    /// What the gate asked.
    pub gate: GateOptions,
    /// The spec's own trials and the gate's decision on them.
    pub spec: Gated,
    /// The spec without each keyframe and each line (none when the spec does not pass).
    pub removals: Vec<Ablation>,
    /// The demonstration's answers, when it was given (and the gate decided on the spec).
    pub answers: Option<Answers>,
    /// The verdict; `None` when the validation was interrupted before it was reached.
    pub verdict: Option<Verdict>,
    /// Whether it was interrupted (Ctrl-C): what ran is kept, what did not is missing.
    pub interrupted: bool,
}

impl Validation {
    /// The removals that pass the gate.
    pub fn not_essential(&self) -> impl Iterator<Item = &Ablation> {
        self.removals
            .iter()
            .filter(|a| a.essential == Necessity::NotEssential)
    }

    /// The answers the simulation contradicts.
    pub fn contradicted(&self) -> impl Iterator<Item = &AnswerCheck> {
        self.answers.iter().flat_map(Answers::contradicted)
    }
}

/// Validates `spec` on `task`; `progress` is called as trials finish with the stage and the
/// trials it has judged. The spec's own trial reports are kept (for `--report`).
pub fn validate(
    robot: &Robot,
    task: &Task,
    spec: &TaskSpec,
    options: &ValidateOptions,
    demo: Option<DemoSource>,
    progress: &(dyn Fn(Stage, usize) + Sync),
) -> Result<Validation, ValidateError> {
    let gate = Gate::new(options.gate).map_err(|e| ValidateError::Options(e.to_string()))?;
    let (seed, jobs, exec) = (options.seed, options.jobs, &options.exec);
    let interrupted = || exec.interrupt.raised();
    let spec_gated = run_gated(robot, task, spec, exec, &gate, seed, jobs, true, &|n| {
        progress(Stage::Spec, n)
    })?;
    let mut validation = Validation {
        seed,
        gate: options.gate,
        spec: spec_gated,
        removals: Vec::new(),
        answers: None,
        verdict: None,
        interrupted: false,
    };
    let decided = validation.spec.decision;
    // Minimality matters only for a spec that could be deployed.
    if decided == Some(Decision::Passes) {
        validation.removals = ablate(robot, task, spec, exec, &gate, seed, jobs, &|_, done, _| {
            progress(Stage::Removal(done), 0)
        })?;
    }
    // The answers matter most when the spec fails: a wrong "no" is a reason it does.
    if let (Some(d), Some(_)) = (demo, decided) {
        if !interrupted() {
            validation.answers = Some(check_answers(
                robot,
                task,
                d,
                spec,
                &validation.spec,
                exec,
                &gate,
                seed,
                jobs,
                &|done, _| progress(Stage::Answer(done), 0),
            )?);
        }
    }
    validation.interrupted = interrupted();
    validation.verdict = match decided {
        _ if validation.interrupted => None,
        None => None,
        Some(Decision::Fails) => Some(Verdict::Fails),
        Some(Decision::Undecided) => Some(Verdict::Undecided),
        Some(Decision::Passes)
            if validation.not_essential().next().is_some()
                || validation.contradicted().next().is_some() =>
        {
            Some(Verdict::NotMinimal)
        }
        Some(Decision::Passes) => Some(Verdict::Passes),
    };
    Ok(validation)
}
