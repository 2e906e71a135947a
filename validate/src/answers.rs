//! The teacher's answers the simulation contradicts (thesis §4.6: most of AKL's constraint
//! errors came from wrong answers).
//!
//! Each answer to "Do I have to move in a straight line there?" is flipped and the
//! demonstration learned again with AKL, and the spec that gives is executed. Flipping the
//! recorded answer alone would not do: online, a "no" switched the detector off at once, so
//! the recording holds only the start of that line. The demonstration's frames are therefore
//! replayed through the online detector and the dialogue ([`akl_learn::teach::stream_demo`]),
//! each query answered as the teacher answered the latest recorded query at or before it (a
//! teacher asked again about the same stretch answers alike), the flipped one the other way.
//! Then every spec is judged by the deployment gate ([`akl_stats::gate`]), on trials from the
//! same seed:
//! - a "no" is **contradicted** when the spec learned with it fails the gate and the spec
//!   learned with "yes" there (the line restored) passes it: the line was needed. It is
//!   **confirmed** when the spec learned with it passes. When restoring the line does not make
//!   the spec pass either, something else fails first and the trials cannot tell whether the
//!   line was needed: undecided;
//! - a "yes" (or an "I don't know", which keeps the line too) is **contradicted** when the
//!   spec learned with "no" there (the line dropped) passes the gate: the line was not needed.
//!   It is **confirmed** when the line dropped fails the gate while the spec with it passes;
//! - otherwise, when a gate could not decide or both specs fail, the answer is **undecided**;
//!   an answer whose flip learns the same spec is **unchanged**.
//!
//! The answers are judged on the spec AKL learns from the demonstration as recorded (the
//! baseline), which is the spec validated when that spec was learned from this demonstration
//! with the same settings; the report says whether it is.

use crate::trials::{run_gated, Gated, Outcome};
use crate::ValidateError;
use akl_exec::ExecOptions;
use akl_learn::baselines::kd::marked_frames;
use akl_learn::dialogue::{AnswerSource, DialogueError, Question};
use akl_learn::teach::{session_header, stream_demo, Pace};
use akl_learn::{learn_spec, Answer, Calibration, Demo, DialogueKind, LearnOptions, Method};
use akl_planner::Robot;
use akl_scene::Task;
use akl_stats::{Decision, Gate};
use akl_tsr::TaskSpec;
use serde::Serialize;

/// What the trials say of one answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum AnswerVerdict {
    /// The simulation contradicts the answer.
    Contradicted,
    /// The simulation agrees with the answer.
    Confirmed,
    /// The gates could not tell (one undecided, or a spec that fails with and without the
    /// line).
    Undecided,
    /// Flipping the answer learns the same spec.
    Unchanged,
}

/// One answer of the demonstration, flipped and executed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AnswerCheck {
    /// Which answer of the demonstration (0 for the first).
    pub index: usize,
    /// When it was given (demonstration seconds).
    pub t: f64,
    /// The frame it was given at.
    pub frame: usize,
    /// The answer as recorded.
    pub answer: Answer,
    /// The answer it was flipped to.
    pub flipped_to: Answer,
    /// `move_in_line` segments of the spec learned with the flip.
    pub lines_when_flipped: usize,
    /// The gate's decision on the spec learned with the flip, when it was needed.
    pub decision: Option<Decision>,
    /// The trials of the spec learned with the flip that the gate read, when it ran.
    pub outcome: Option<Outcome>,
    /// The verdict.
    pub verdict: AnswerVerdict,
}

/// Every answer of a demonstration, judged.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Answers {
    /// Whether AKL learns exactly the validated spec's keyframes from the demonstration.
    pub spec_is_learned_from_demo: bool,
    /// `move_in_line` segments of the spec learned from the demonstration as recorded.
    pub lines: usize,
    /// The gate's decision on it (the validated spec's own when it is that spec).
    pub baseline_decision: Option<Decision>,
    /// Its trials the gate read.
    pub baseline: Outcome,
    /// One check per answer, in the order given.
    pub checks: Vec<AnswerCheck>,
}

impl Answers {
    /// The answers the simulation contradicts.
    pub fn contradicted(&self) -> impl Iterator<Item = &AnswerCheck> {
        self.checks
            .iter()
            .filter(|c| c.verdict == AnswerVerdict::Contradicted)
    }
}

/// The recorded answers, each with the frame of the query it answered (its own frame when no
/// query precedes it), in order.
pub fn recorded_answers(demo: &Demo) -> Vec<(usize, Answer)> {
    let mut query = None;
    let mut out = Vec::new();
    for e in &demo.events {
        match e.kind {
            DialogueKind::Query => query = Some(e.frame),
            DialogueKind::Answer(a) => out.push((query.take().unwrap_or(e.frame), a)),
            _ => {}
        }
    }
    out
}

/// Answers a replay's queries as the teacher answered the recording's: the answer to the
/// latest recorded query at or before the query's frame (the first recorded answer before
/// any).
#[derive(Debug, Clone)]
pub struct ReplayedAnswers {
    recorded: Vec<(usize, Answer)>,
}

impl ReplayedAnswers {
    /// The recorded answers (see [`recorded_answers`]) with the `index`-th replaced by `to`,
    /// when given.
    pub fn new(mut recorded: Vec<(usize, Answer)>, flip: Option<(usize, Answer)>) -> Self {
        if let Some((index, to)) = flip {
            if let Some(r) = recorded.get_mut(index) {
                r.1 = to;
            }
        }
        ReplayedAnswers { recorded }
    }
}

impl AnswerSource for ReplayedAnswers {
    fn answer(&mut self, question: &Question) -> Result<Answer, DialogueError> {
        let latest = self
            .recorded
            .iter()
            .rev()
            .find(|(frame, _)| *frame <= question.frame)
            .or(self.recorded.first());
        Ok(latest.map_or(Answer::Unknown, |(_, a)| *a))
    }
}

/// `demo` replayed through the online detector and dialogue with `answers`, then learned with
/// AKL.
fn relearn(
    demo: &Demo,
    task: &Task,
    calibration: &Calibration,
    learn: &LearnOptions,
    mut answers: ReplayedAnswers,
) -> Result<TaskSpec, ValidateError> {
    let header = session_header(&demo.header, None);
    let (replayed, _) = stream_demo(
        demo,
        header,
        &marked_frames(demo),
        *calibration,
        &mut answers,
        None,
        &Pace::default(),
    )
    .map_err(|e| ValidateError::Replay(e.to_string()))?;
    Ok(learn_spec(
        Method::Akl,
        &replayed,
        Some(&task.world),
        learn,
    )?)
}

/// Whether two specs have the same keyframes, where in the demonstration they came from
/// aside (a recording rounds its times).
fn same_keyframes(a: &TaskSpec, b: &TaskSpec) -> bool {
    a.keyframes.len() == b.keyframes.len()
        && a.keyframes.iter().zip(&b.keyframes).all(|(x, y)| {
            x.kind == y.kind
                && x.reference == y.reference
                && x.tsr == y.tsr
                && x.gripper == y.gripper
                && x.constraint == y.constraint
        })
}

/// The demonstration a spec was learned from, and how it was learned.
#[derive(Debug, Clone, Copy)]
pub struct DemoSource<'a> {
    /// The recording.
    pub demo: &'a Demo,
    /// The calibration its online detector ran with.
    pub calibration: &'a Calibration,
    /// The learning settings the spec was learned with.
    pub learn: &'a LearnOptions,
}

/// Judges every answer of `source`, the demonstration `spec` was learned from, with `gate`
/// on trials from `seed` (`spec_gated`: `spec`'s own gated trials from that seed); `progress`
/// is called after each answer with (done, total).
#[allow(clippy::too_many_arguments)]
pub fn check_answers(
    robot: &Robot,
    task: &Task,
    source: DemoSource,
    spec: &TaskSpec,
    spec_gated: &Gated,
    exec: &ExecOptions,
    gate: &Gate,
    seed: u64,
    jobs: usize,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Answers, ValidateError> {
    let demo = source.demo;
    if demo.detector.is_empty() {
        return Err(ValidateError::NoDetector);
    }
    let recorded = recorded_answers(demo);
    let learned = |flip| {
        relearn(
            demo,
            task,
            source.calibration,
            source.learn,
            ReplayedAnswers::new(recorded.clone(), flip),
        )
    };
    let gated =
        |spec: &TaskSpec| run_gated(robot, task, spec, exec, gate, seed, jobs, false, &|_| {});
    let baseline = learned(None)?;
    let same = same_keyframes(&baseline, spec);
    let baseline_gated = if same {
        spec_gated.clone()
    } else {
        gated(&baseline)?
    };
    let answers: Vec<(f64, usize, Answer)> = demo
        .events
        .iter()
        .filter_map(|e| match e.kind {
            DialogueKind::Answer(a) => Some((e.t, e.frame, a)),
            _ => None,
        })
        .collect();
    debug_assert_eq!(answers.len(), recorded.len());
    let mut checks = Vec::with_capacity(answers.len());
    for (index, (t, frame, answer)) in answers.iter().copied().enumerate() {
        if exec.interrupt.raised() {
            break;
        }
        let flipped_to = match answer {
            Answer::No => Answer::Yes,
            Answer::Yes | Answer::Unknown => Answer::No,
        };
        let flipped = learned(Some((index, flipped_to)))?;
        let (decision, outcome, verdict) = if same_keyframes(&flipped, &baseline) {
            (None, None, AnswerVerdict::Unchanged)
        } else if answer == Answer::No && baseline_gated.decision == Some(Decision::Passes) {
            (None, None, AnswerVerdict::Confirmed)
        } else {
            let run = gated(&flipped)?;
            let verdict = judge(answer, baseline_gated.decision, run.decision);
            (run.decision, Some(run.outcome), verdict)
        };
        checks.push(AnswerCheck {
            index,
            t,
            frame,
            answer,
            flipped_to,
            lines_when_flipped: flipped.line_count(),
            decision,
            outcome,
            verdict,
        });
        progress(index + 1, answers.len());
    }
    Ok(Answers {
        spec_is_learned_from_demo: same,
        lines: baseline.line_count(),
        baseline_decision: baseline_gated.decision,
        baseline: baseline_gated.outcome,
        checks,
    })
}

/// The verdict on `answer` from the gate's decisions on the spec learned with it (`with`) and
/// with it flipped (`flipped`).
fn judge(answer: Answer, with: Option<Decision>, flipped: Option<Decision>) -> AnswerVerdict {
    use Decision::{Fails, Passes};
    match (answer, with, flipped) {
        (Answer::No, Some(Passes), _) => AnswerVerdict::Confirmed,
        (Answer::No, Some(Fails), Some(Passes)) => AnswerVerdict::Contradicted,
        (Answer::Yes | Answer::Unknown, _, Some(Passes)) => AnswerVerdict::Contradicted,
        (Answer::Yes | Answer::Unknown, Some(Passes), Some(Fails)) => AnswerVerdict::Confirmed,
        _ => AnswerVerdict::Undecided,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_learn::DialogueEvent;
    use akl_tsr::nalgebra::Vector3;

    fn question(frame: usize) -> Question {
        Question {
            t: frame as f64 * 0.01,
            frame,
            line_start: Vector3::zeros(),
            line_end: Vector3::x(),
            nearest_objects: Vec::new(),
        }
    }

    #[test]
    fn answers_are_judged_from_the_two_gates() {
        use AnswerVerdict::*;
        use Decision::{Fails, Passes, Undecided as Open};
        let cases = [
            (Answer::No, Some(Passes), None, Confirmed),
            (Answer::No, Some(Fails), Some(Passes), Contradicted),
            (Answer::No, Some(Fails), Some(Fails), Undecided),
            (Answer::No, Some(Fails), Some(Open), Undecided),
            (Answer::No, Some(Open), Some(Passes), Undecided),
            (Answer::Yes, Some(Passes), Some(Passes), Contradicted),
            (Answer::Unknown, Some(Fails), Some(Passes), Contradicted),
            (Answer::Yes, Some(Passes), Some(Fails), Confirmed),
            (Answer::Yes, Some(Fails), Some(Fails), Undecided),
            (Answer::Yes, Some(Passes), Some(Open), Undecided),
            (Answer::Yes, None, None, Undecided),
        ];
        for (answer, with, flipped, verdict) in cases {
            assert_eq!(
                judge(answer, with, flipped),
                verdict,
                "{answer:?} {with:?} {flipped:?}"
            );
        }
    }

    #[test]
    fn a_replay_is_answered_as_the_recording_was_with_one_answer_flipped() {
        let mut demo = Demo::empty(akl_learn::DemoHeader::new("inspection"), &[]);
        let event = |frame: usize, kind| DialogueEvent {
            t: frame as f64 * 0.01,
            frame,
            kind,
        };
        demo.events = vec![
            event(10, DialogueKind::Query),
            event(12, DialogueKind::Answer(Answer::No)),
            event(13, DialogueKind::Suggestion),
            event(50, DialogueKind::Query),
            event(51, DialogueKind::Answer(Answer::Yes)),
        ];
        let recorded = recorded_answers(&demo);
        assert_eq!(recorded, vec![(10, Answer::No), (50, Answer::Yes)]);
        let mut same = ReplayedAnswers::new(recorded.clone(), None);
        assert_eq!(same.answer(&question(10)), Ok(Answer::No));
        assert_eq!(same.answer(&question(30)), Ok(Answer::No), "asked again");
        assert_eq!(same.answer(&question(50)), Ok(Answer::Yes));
        assert_eq!(same.answer(&question(3)), Ok(Answer::No), "before any");
        let mut flipped = ReplayedAnswers::new(recorded, Some((0, Answer::Yes)));
        assert_eq!(flipped.answer(&question(10)), Ok(Answer::Yes));
        assert_eq!(flipped.answer(&question(50)), Ok(Answer::Yes));
        let mut none = ReplayedAnswers::new(Vec::new(), None);
        assert_eq!(none.answer(&question(5)), Ok(Answer::Unknown));
    }
}
