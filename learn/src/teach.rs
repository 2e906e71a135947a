//! Teaching with the simulated teacher: its recording streamed through a [`TeachingSession`]
//! frame by frame, exactly as a live teacher's would be.

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::calibration::Calibration;
use crate::demo::{Demo, DemoHeader};
use crate::dialogue::{AnswerSource, Oracle};
use crate::session::{RecordingSink, SessionError, TeachingSession};
use crate::teacher::{SimulatedDemo, TeacherProfile};

/// How long after a required line ends the oracle still answers "yes" (s): the detector
/// switches up to a few filter steps late, and a person remembers the line they just made.
pub const ORACLE_MEMORY: f64 = 1.0;

/// The oracle for a simulated demonstration: knows the required lines, errs as the profile says.
pub fn oracle_for(sim: &SimulatedDemo, profile: &TeacherProfile, seed: u64) -> Oracle {
    let window = (ORACLE_MEMORY * profile.rate).round() as usize;
    Oracle::new(
        sim.intended_line.clone(),
        window,
        profile.wrong_answer_rate,
        profile.unknown_answer_rate,
        ChaCha8Rng::seed_from_u64(seed ^ 0xA5A5_A5A5),
    )
}

/// Streams a simulated recording through a teaching session: the detector runs online, the
/// dialogue asks `answers`, and the teacher's keyframe marks are recorded.
pub fn run_session(
    sim: &SimulatedDemo,
    calibration: Calibration,
    answers: &mut dyn AnswerSource,
    sink: Option<&mut dyn RecordingSink>,
) -> Result<Demo, SessionError> {
    let header = session_header(&sim.demo.header, None);
    let pace = Pace::default();
    let (demo, _) = stream_demo(
        &sim.demo,
        header,
        &sim.marked_keyframes,
        calibration,
        answers,
        sink,
        &pace,
    )?;
    Ok(demo)
}

/// The header of a session recording `recorded`: the same, naming the calibration used
/// (`calibration`, or what the recording named, or `default`).
pub fn session_header(recorded: &DemoHeader, calibration: Option<&str>) -> DemoHeader {
    let mut header = recorded.clone();
    header.calibration = calibration
        .map(str::to_string)
        .or(header.calibration)
        .or_else(|| Some("default".to_string()));
    header
}

/// How a recorded demonstration is played into a session.
#[derive(Debug, Default)]
pub struct Pace<'a> {
    /// Play frames at the pace of their timestamps (as a live teacher would), instead of as
    /// fast as possible.
    pub realtime: bool,
    /// Stop early, keeping what was played, once this is set (e.g. by Ctrl-C).
    pub stop: Option<&'a AtomicBool>,
}

/// Streams the frames of a recorded `demo` through a fresh teaching session recording under
/// `header`, marking a keyframe after each frame listed in `marks` (ascending): the online
/// detector and the dialogue run exactly as they would have live. Returns the session's
/// recording (the demo's frames with the new detector states and dialogue) and whether `pace`
/// stopped it early.
pub fn stream_demo(
    demo: &Demo,
    header: DemoHeader,
    marks: &[usize],
    calibration: Calibration,
    answers: &mut dyn AnswerSource,
    sink: Option<&mut dyn RecordingSink>,
    pace: &Pace,
) -> Result<(Demo, bool), SessionError> {
    let names: Vec<String> = demo.objects.iter().map(|o| o.name.clone()).collect();
    let mut session = TeachingSession::new(header, &names, calibration, answers);
    if let Some(sink) = sink {
        session = session.with_sink(sink);
    }
    let mut marks = marks.iter().peekable();
    let mut poses = Vec::with_capacity(names.len());
    let started = Instant::now();
    let mut stopped = false;
    for i in 0..demo.len() {
        if pace.stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
            stopped = true;
            break;
        }
        if pace.realtime {
            let due = Duration::from_secs_f64((demo.times[i] - demo.times[0]).max(0.0));
            if let Some(wait) = due.checked_sub(started.elapsed()) {
                std::thread::sleep(wait);
            }
        }
        poses.clear();
        poses.extend(demo.objects.iter().map(|o| o.poses[i]));
        session.push(demo.times[i], demo.ee[i], demo.gripper[i], &poses)?;
        while marks.next_if(|m| **m <= i).is_some() {
            session.mark_keyframe()?;
        }
    }
    Ok((session.finish()?, stopped))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::{Answer, DialogueKind};
    use crate::dialogue::AllYes;
    use crate::teacher::demonstrate;
    use akl_scene::builtin;

    fn answers(demo: &Demo) -> Vec<Answer> {
        demo.events
            .iter()
            .filter_map(|e| match e.kind {
                DialogueKind::Answer(a) => Some(a),
                _ => None,
            })
            .collect()
    }

    #[test]
    fn a_careful_teacher_is_asked_once_per_required_line() {
        for (name, lines) in [("pick_place", 0), ("inspection", 1), ("assembly", 1)] {
            let task = builtin::resolve(name).unwrap();
            let profile = TeacherProfile::careful();
            for seed in 0..5 {
                let sim = demonstrate(&task, &task.world, &profile, seed).unwrap();
                let mut oracle = oracle_for(&sim, &profile, seed);
                let demo = run_session(&sim, Calibration::default(), &mut oracle, None).unwrap();
                let given = answers(&demo);
                let yes = given.iter().filter(|a| **a == Answer::Yes).count();
                assert_eq!(yes, lines, "{name} seed {seed}: answers {given:?}");
                assert_eq!(demo.detector.len(), demo.len());
            }
        }
    }

    #[test]
    fn a_teacher_who_moves_straight_is_asked_and_told_off() {
        let task = builtin::resolve("pick_place").unwrap();
        let profile = TeacherProfile::straight();
        let sim = demonstrate(&task, &task.world, &profile, 2).unwrap();
        let mut oracle = oracle_for(&sim, &profile, 2);
        let demo = run_session(&sim, Calibration::default(), &mut oracle, None).unwrap();
        let given = answers(&demo);
        assert!(
            !given.is_empty() && given.iter().all(|a| *a == Answer::No),
            "{given:?}"
        );
        let suggestions = demo
            .events
            .iter()
            .filter(|e| e.kind == DialogueKind::Suggestion)
            .count();
        assert_eq!(suggestions, given.len());
        let mut yes = AllYes;
        let kept = run_session(&sim, Calibration::default(), &mut yes, None).unwrap();
        assert!(
            kept.detector.iter().filter(|c| **c).count()
                > demo.detector.iter().filter(|c| **c).count()
        );
    }
}
