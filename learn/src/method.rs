//! One entry point for the three learning methods, so tools and benchmarks treat them alike.

use std::fmt;
use std::str::FromStr;

use akl_scene::World;
use akl_tsr::TaskSpec;
use serde::{Deserialize, Serialize};

use crate::baselines::kd::marked_frames;
use crate::baselines::kd::{learn_kd, KdParams};
use crate::baselines::macl::{learn_macl, MaclParams};
use crate::calibration::Calibration;
use crate::demo::{Demo, DialogueKind};
use crate::dialogue::{AnswerSource, ListedAnswers};
use crate::okl::{self, LearnError, OklParams};
use crate::session::SessionError;
use crate::teach::{session_header, stream_demo, Pace};

/// A way of learning a spec from a demonstration.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Active keyframe learning: the online detector's states and the teacher's answers, then
    /// offline keyframe learning (thesis chapter 3).
    Akl,
    /// Keyframe demonstrations: the teacher's marks plus the gripper commands.
    Kd,
    /// The articulated-constraint baseline with interaction keyframes.
    Macl,
}

impl Method {
    /// Every method, in the order the thesis compares them.
    pub const ALL: [Method; 3] = [Method::Akl, Method::Kd, Method::Macl];

    /// The name used on the command line and in a spec's `method` field.
    pub fn name(self) -> &'static str {
        match self {
            Method::Akl => "akl",
            Method::Kd => "kd",
            Method::Macl => "macl",
        }
    }
}

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Method {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Method::ALL
            .into_iter()
            .find(|m| m.name() == s)
            .ok_or_else(|| format!("unknown method `{s}` (use akl, kd or macl)"))
    }
}

/// The tuning of every method (each field's defaults are documented where it is defined).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct LearnOptions {
    /// OKL's parameters.
    pub okl: OklParams,
    /// KD's parameters.
    pub kd: KdParams,
    /// mACL's parameters.
    pub macl: MaclParams,
}

/// Learns a spec from `demo` with `method`. AKL needs the online detector's states (see
/// [`prepare`]); the baselines use the frames (and, for KD, the marks) only.
pub fn learn_spec(
    method: Method,
    demo: &Demo,
    world: Option<&World>,
    options: &LearnOptions,
) -> Result<TaskSpec, LearnError> {
    match method {
        Method::Akl => okl::learn(demo, world, &options.okl),
        Method::Kd => learn_kd(demo, world, &options.kd),
        Method::Macl => learn_macl(demo, world, &options.macl),
    }
}

/// Whether `method` needs detector states that `demo` lacks, so [`prepare`] will replay the
/// online detector (and ask its questions) before learning.
pub fn needs_replay(method: Method, demo: &Demo) -> bool {
    method == Method::Akl && demo.detector.is_empty()
}

/// Makes `demo` ready for `method`: a demo recorded without the online detector (a JSONL
/// file from another driver) is streamed through a teaching session with `calibration`, whose
/// queries `answers` answers, keeping the demo's frames and its keyframe marks. Returns the
/// demo unchanged when nothing is missing.
pub fn prepare(
    method: Method,
    demo: Demo,
    calibration: Calibration,
    answers: &mut dyn AnswerSource,
) -> Result<Demo, SessionError> {
    if !needs_replay(method, &demo) {
        return Ok(demo);
    }
    let marks = marked_frames(&demo);
    let header = session_header(&demo.header, None);
    let (replayed, _) = stream_demo(
        &demo,
        header,
        &marks,
        calibration,
        answers,
        None,
        &Pace::default(),
    )?;
    Ok(replayed)
}

/// The answers `demo` recorded, keyed by the time of the question each answered (an answer with
/// no query before it by its own time), for replaying the detector over a recording that kept
/// its dialogue but not the detector's states. `None` when it recorded no answer.
pub fn recorded_answers(demo: &Demo) -> Option<ListedAnswers> {
    let mut query = None;
    let mut answers = Vec::new();
    for e in &demo.events {
        match e.kind {
            DialogueKind::Query => query = Some(e.t),
            DialogueKind::Answer(a) => answers.push((query.take().unwrap_or(e.t), a)),
            DialogueKind::Suggestion | DialogueKind::Keyframe => {}
        }
    }
    (!answers.is_empty()).then(|| ListedAnswers::keyed(&answers, "the recording's answers"))
}

/// `demo` without the online detector's states and its queries, answers and suggestions (its
/// keyframe marks kept): to be replayed through the detector with other answers.
pub fn without_dialogue(mut demo: Demo) -> Demo {
    demo.detector.clear();
    demo.events.retain(|e| e.kind == DialogueKind::Keyframe);
    demo
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::Answer;
    use crate::okl::synth::DemoBuilder;

    fn inspection_without_detector() -> Demo {
        let mut demo = DemoBuilder::new("inspection", [0.2, 0.0, 0.21], 100.0, 0.0005, 2)
            .object("shelf_2", [0.45, -0.36, 0.07])
            .object("part", [0.45, 0.32, 0.19])
            .curve([0.45, 0.32, 0.21], 0.25)
            .mark()
            .pause(0.3)
            .grasp("part")
            .curve([0.55, 0.18, 0.22], 0.25)
            .line([0.55, -0.18, 0.22], 0.15, None)
            .curve([0.45, -0.36, 0.21], 0.25)
            .pause(0.3)
            .release()
            .build();
        demo.detector.clear();
        demo.events
            .retain(|e| matches!(e.kind, DialogueKind::Keyframe));
        demo
    }

    #[test]
    fn names_round_trip_and_unknown_ones_are_named() {
        for m in Method::ALL {
            assert_eq!(m.name().parse::<Method>(), Ok(m));
        }
        assert!("okl".parse::<Method>().unwrap_err().contains("`okl`"));
    }

    #[test]
    fn a_demo_without_detector_states_is_replayed_with_the_given_answers() {
        let demo = inspection_without_detector();
        assert!(matches!(
            learn_spec(Method::Akl, &demo, None, &LearnOptions::default()),
            Err(LearnError::NoDetectorStates)
        ));
        let mut answers = ListedAnswers::parse("yes").unwrap();
        let ready = prepare(
            Method::Akl,
            demo.clone(),
            Calibration::default(),
            &mut answers,
        )
        .unwrap();
        assert_eq!(ready.detector.len(), ready.len());
        assert_eq!(ready.ee, demo.ee);
        let answered: Vec<_> = ready
            .events
            .iter()
            .filter_map(|e| match e.kind {
                DialogueKind::Answer(a) => Some(a),
                _ => None,
            })
            .collect();
        assert_eq!(answered, vec![Answer::Yes]);
        assert_eq!(marked_frames(&ready), marked_frames(&demo));
        let spec = learn_spec(Method::Akl, &ready, None, &LearnOptions::default()).unwrap();
        let lines = spec.line_count();
        assert_eq!(lines, 1);
    }

    /// A recording that kept its dialogue but not the detector's states is replayed with its
    /// own answers, which fit the questions the replay asks; other answers replace them.
    #[test]
    fn a_recording_is_replayed_with_its_own_answers_unless_given_others() {
        let demo = inspection_without_detector();
        let mut yes = ListedAnswers::parse("yes").unwrap();
        let taught = prepare(Method::Akl, demo, Calibration::default(), &mut yes).unwrap();
        let mut stripped = taught.clone();
        stripped.detector.clear();
        let mut own = recorded_answers(&stripped).unwrap();
        let again = prepare(Method::Akl, stripped, Calibration::default(), &mut own).unwrap();
        assert_eq!(again, taught);
        let bare = without_dialogue(taught.clone());
        assert!(bare.detector.is_empty() && recorded_answers(&bare).is_none());
        assert_eq!(marked_frames(&bare), marked_frames(&taught));
        let mut no = ListedAnswers::parse("no").unwrap();
        let spec = learn_spec(
            Method::Akl,
            &prepare(Method::Akl, bare, Calibration::default(), &mut no).unwrap(),
            None,
            &LearnOptions::default(),
        )
        .unwrap();
        assert_eq!(spec.line_count(), 0);
    }

    #[test]
    fn the_baselines_need_no_replay() {
        let demo = inspection_without_detector();
        let mut none = ListedAnswers::parse("").unwrap();
        for m in [Method::Kd, Method::Macl] {
            assert!(!needs_replay(m, &demo));
            let same = prepare(m, demo.clone(), Calibration::default(), &mut none).unwrap();
            assert_eq!(same, demo);
            let spec = learn_spec(m, &same, None, &LearnOptions::default()).unwrap();
            assert_eq!(spec.method, m.name());
        }
    }
}
