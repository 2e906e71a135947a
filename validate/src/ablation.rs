//! Least restrictive by ablation (thesis Theorem 3.2.3): a keyframe, or a `move_in_line`, is
//! essential when the spec without it fails. Every removal is judged by the same deployment
//! gate as the spec ([`akl_stats::gate`]), on trials from the same seed: the spec without it
//! is *not essential* when it passes the gate (it gives the planner more execution traces and
//! still succeeds as often as a deployment needs, Lemma 3.2.1), *essential* when it fails the
//! gate, and *undecided* when the gate cannot tell. The verdict no longer depends on how many
//! trials were asked for: a removal that fails one trial in fifty is essential whether 20 or
//! 2,000 trials would have run. Planned with goals drawn from each keyframe's own stream
//! ([`akl_planner::keyframe_stream`]), the spec and the spec without a keyframe reach
//! every other keyframe at the same goals in the same trial.
//!
//! Removing a keyframe removes the line that ends at it (a line is a property of the segment
//! into its end keyframe); a line out of it then starts at the keyframe before. Removing a
//! line keeps both its keyframes and lets the planner move freely between them.

use crate::trials::{run_gated, Outcome};
use crate::ValidateError;
use akl_exec::ExecOptions;
use akl_planner::Robot;
use akl_scene::Task;
use akl_stats::{Decision, Gate};
use akl_tsr::{Constraint, TaskSpec};
use serde::Serialize;

/// One thing taken out of a spec.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(tag = "remove", content = "keyframe", rename_all = "snake_case")]
pub enum Removal {
    /// Keyframe i (and the line into it, if any).
    Keyframe(usize),
    /// The `move_in_line` constraint of the segment that ends at keyframe i.
    Line(usize),
}

impl Removal {
    /// What is removed, in words, e.g. `keyframe 2 (constraint on scanner_2)` or
    /// `line to keyframe 2`.
    pub fn describe(&self, spec: &TaskSpec) -> String {
        match *self {
            Removal::Keyframe(i) => match spec.keyframes.get(i) {
                Some(k) => format!("keyframe {i} ({} on {})", k.kind, k.reference),
                None => format!("keyframe {i}"),
            },
            Removal::Line(i) => format!("line to keyframe {i}"),
        }
    }
}

/// Every removal of `spec`: each keyframe, then each `move_in_line`, in order.
pub fn removals(spec: &TaskSpec) -> Vec<Removal> {
    let keyframes = (0..spec.keyframes.len()).map(Removal::Keyframe);
    let lines = spec
        .keyframes
        .iter()
        .enumerate()
        .filter(|(_, k)| k.constraint == Constraint::MoveInLine)
        .map(|(i, _)| Removal::Line(i));
    keyframes.chain(lines).collect()
}

/// `spec` without what `removal` names.
pub fn without(spec: &TaskSpec, removal: Removal) -> TaskSpec {
    let mut out = spec.clone();
    match removal {
        Removal::Keyframe(i) if i < out.keyframes.len() => {
            out.keyframes.remove(i);
        }
        Removal::Line(i) => {
            if let Some(k) = out.keyframes.get_mut(i) {
                k.constraint = Constraint::None;
            }
        }
        Removal::Keyframe(_) => {}
    }
    out
}

/// Whether a spec needs what a removal takes out.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Necessity {
    /// The spec without it fails the gate, or is no spec at all.
    Essential,
    /// The spec without it passes the gate: the spec is more restrictive than it needs be.
    NotEssential,
    /// The gate could not tell within its trials (or was interrupted).
    Undecided,
}

impl Necessity {
    /// In words, as tables print it.
    pub fn label(&self) -> &'static str {
        match self {
            Necessity::Essential => "yes",
            Necessity::NotEssential => "NO",
            Necessity::Undecided => "undecided",
        }
    }
}

/// What the trials said of one removal.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Ablation {
    /// What was removed.
    #[serde(flatten)]
    pub removal: Removal,
    /// The same, in words.
    pub what: String,
    /// Whether the spec needs it.
    pub essential: Necessity,
    /// The gate's decision on the spec without it (`None` when that is no spec, or when the
    /// run was interrupted).
    pub decision: Option<Decision>,
    /// Why the spec without it is no spec (e.g. a line left with nothing to start from).
    pub invalid: Option<String>,
    /// The trials of the spec without it that the gate read (none when it is no spec).
    pub outcome: Option<Outcome>,
}

/// Judges `spec` without each of its [`removals`] with `gate`, trials from `seed`, `jobs` at a
/// time; `progress` is called after each removal with it and (done, total).
#[allow(clippy::too_many_arguments)]
pub fn ablate(
    robot: &Robot,
    task: &Task,
    spec: &TaskSpec,
    exec: &ExecOptions,
    gate: &Gate,
    seed: u64,
    jobs: usize,
    progress: &(dyn Fn(&Ablation, usize, usize) + Sync),
) -> Result<Vec<Ablation>, ValidateError> {
    let all = removals(spec);
    let mut out = Vec::with_capacity(all.len());
    for (done, removal) in all.into_iter().enumerate() {
        if exec.interrupt.raised() {
            break;
        }
        let reduced = without(spec, removal);
        let what = removal.describe(spec);
        let ablation = match reduced.validate() {
            Err(e) => Ablation {
                removal,
                what,
                essential: Necessity::Essential,
                decision: None,
                invalid: Some(e.to_string()),
                outcome: None,
            },
            Ok(()) => {
                let gated = run_gated(
                    robot,
                    task,
                    &reduced,
                    exec,
                    gate,
                    seed,
                    jobs,
                    false,
                    &|_| {},
                )?;
                Ablation {
                    removal,
                    what,
                    essential: match gated.decision {
                        Some(Decision::Fails) => Necessity::Essential,
                        Some(Decision::Passes) => Necessity::NotEssential,
                        Some(Decision::Undecided) | None => Necessity::Undecided,
                    },
                    decision: gated.decision,
                    invalid: None,
                    outcome: Some(gated.outcome),
                }
            }
        };
        progress(&ablation, done + 1, out.capacity());
        out.push(ablation);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_scene::builtin;

    #[test]
    fn removals_cover_every_keyframe_then_every_line() {
        let task = builtin::task("inspection").unwrap().unwrap();
        let truth = task.truth.clone().unwrap();
        let r = removals(&truth);
        let lines: Vec<usize> = truth
            .keyframes
            .iter()
            .enumerate()
            .filter(|(_, k)| k.constraint == Constraint::MoveInLine)
            .map(|(i, _)| i)
            .collect();
        assert_eq!(r.len(), truth.keyframes.len() + lines.len());
        assert_eq!(r[0], Removal::Keyframe(0));
        assert_eq!(r[truth.keyframes.len()], Removal::Line(lines[0]));
        let i = lines[0];
        let unlined = without(&truth, Removal::Line(i));
        assert_eq!(unlined.keyframes.len(), truth.keyframes.len());
        assert_eq!(unlined.keyframes[i].constraint, Constraint::None);
        let fewer = without(&truth, Removal::Keyframe(i));
        assert_eq!(fewer.keyframes.len(), truth.keyframes.len() - 1);
        assert_eq!(fewer.keyframes[i], truth.keyframes[i + 1]);
        assert!(Removal::Keyframe(0).describe(&truth).contains("part"));
    }

    #[test]
    fn a_removal_that_leaves_no_spec_is_essential_without_trials() {
        let robot = Robot::panda().unwrap();
        let task = builtin::task("assembly").unwrap().unwrap();
        // One keyframe: without it there is nothing left.
        let mut one = task.truth.clone().unwrap();
        one.keyframes.truncate(1);
        let gate = Gate::new(akl_stats::GateOptions::default()).unwrap();
        let found = ablate(
            &robot,
            &task,
            &one,
            &ExecOptions::default(),
            &gate,
            0,
            1,
            &|_, _, _| {},
        )
        .unwrap();
        assert_eq!(found.len(), 1);
        assert!(found[0].essential == Necessity::Essential && found[0].outcome.is_none());
        assert!(found[0].invalid.as_deref().unwrap().contains("keyframe"));
    }
}
