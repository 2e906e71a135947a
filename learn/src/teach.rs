//! Teaching with the simulated teacher: its recording streamed through a [`TeachingSession`]
//! frame by frame, exactly as a live teacher's would be — either a finished recording replayed
//! ([`run_session`], [`stream_demo`]), or the teacher demonstrating step by step while the
//! learner talks to it ([`teach_simulated`]), so that it can heed the learner's suggestions.

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use akl_scene::{Task, World};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::calibration::Calibration;
use crate::demo::{Demo, DemoHeader};
use crate::dialogue::{AnswerSource, Oracle};
use crate::session::{RecordingSink, SessionError, TeachingSession};
use crate::teacher::{SimulatedDemo, SimulatedTeacher, TeacherError, TeacherProfile};

/// How long after a required line ends the oracle still answers "yes" (s): the detector
/// switches up to a few filter steps late, and a person remembers the line they just made.
pub const ORACLE_MEMORY: f64 = 1.0;

/// The oracle of a simulated teacher with `profile` that has recorded nothing yet: it learns
/// what the teacher intends as frames are recorded ([`AnswerSource::intend`]) and errs as the
/// profile says.
pub fn oracle(profile: &TeacherProfile, seed: u64) -> Oracle {
    let window = (ORACLE_MEMORY * profile.rate).round() as usize;
    Oracle::new(
        Vec::new(),
        window,
        profile.wrong_answer_rate,
        profile.unknown_answer_rate,
        ChaCha8Rng::seed_from_u64(seed ^ 0xA5A5_A5A5),
    )
}

/// The oracle for a finished simulated demonstration: knows the required lines, errs as the
/// profile says.
pub fn oracle_for(sim: &SimulatedDemo, profile: &TeacherProfile, seed: u64) -> Oracle {
    let mut oracle = oracle(profile, seed);
    oracle.intend(&sim.intended_line);
    oracle
}

/// Streams a finished simulated recording through a teaching session: the detector runs
/// online, the dialogue asks `answers`, and the teacher's keyframe marks are recorded. The
/// teacher cannot react to suggestions here (its motion is already made); see
/// [`teach_simulated`] for that.
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

/// Where a paced recording reads the time and waits: [`WallClock`] for real time; tests play
/// on a simulated clock instead, so pacing is checked without waiting.
pub trait Clock: std::fmt::Debug {
    /// Time since an origin fixed when the clock was made; never decreases.
    fn now(&self) -> Duration;
    /// Waits `duration` on this clock.
    fn sleep(&self, duration: Duration);
}

/// The real clock: monotonic time (`Instant`) and thread sleeps.
#[derive(Debug, Clone, Copy)]
pub struct WallClock {
    origin: Instant,
}

impl WallClock {
    /// A wall clock whose origin is now.
    pub fn new() -> Self {
        WallClock {
            origin: Instant::now(),
        }
    }
}

impl Default for WallClock {
    fn default() -> Self {
        WallClock::new()
    }
}

impl Clock for WallClock {
    fn now(&self) -> Duration {
        self.origin.elapsed()
    }

    fn sleep(&self, duration: Duration) {
        std::thread::sleep(duration);
    }
}

/// How a recorded demonstration is played into a session.
#[derive(Debug, Default)]
pub struct Pace<'a> {
    /// Play frames at the pace of their timestamps on this clock (as a live teacher would;
    /// [`WallClock`] for real time), instead of as fast as possible (`None`).
    pub realtime: Option<&'a dyn Clock>,
    /// Stop early, keeping what was played, once this is set (e.g. by Ctrl-C).
    pub stop: Option<&'a AtomicBool>,
}

/// Plays frames of a recording into a session at a [`Pace`], with the teacher's keyframe
/// marks after the frames they follow.
struct Player<'p> {
    pace: &'p Pace<'p>,
    /// When playing began on the pace's clock (zero when not paced).
    started: Duration,
    next_mark: usize,
}

impl<'p> Player<'p> {
    fn new(pace: &'p Pace<'p>) -> Self {
        Player {
            pace,
            started: pace.realtime.map_or(Duration::ZERO, |clock| clock.now()),
            next_mark: 0,
        }
    }

    /// Plays `frames` of `demo`, marking a keyframe after each frame listed in `marks`
    /// (ascending, for the whole recording); true when the pace's stop flag ended it early.
    fn play(
        &mut self,
        session: &mut TeachingSession,
        demo: &Demo,
        frames: Range<usize>,
        marks: &[usize],
    ) -> Result<bool, SessionError> {
        let mut poses = Vec::with_capacity(demo.objects.len());
        for i in frames {
            if self.pace.stop.is_some_and(|s| s.load(Ordering::Relaxed)) {
                return Ok(true);
            }
            if let Some(clock) = self.pace.realtime {
                let due = Duration::from_secs_f64((demo.times[i] - demo.times[0]).max(0.0));
                let elapsed = clock.now().saturating_sub(self.started);
                if let Some(wait) = due.checked_sub(elapsed) {
                    clock.sleep(wait);
                }
            }
            poses.clear();
            poses.extend(demo.objects.iter().map(|o| o.poses[i]));
            session.push(demo.times[i], demo.ee[i], demo.gripper[i], &poses)?;
            while marks.get(self.next_mark).is_some_and(|m| *m <= i) {
                session.mark_keyframe()?;
                self.next_mark += 1;
            }
        }
        Ok(false)
    }
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
    let stopped = Player::new(pace).play(&mut session, demo, 0..demo.len(), marks)?;
    let recorded = if stopped {
        session.finish_early()?
    } else {
        session.finish()?
    };
    Ok((recorded, stopped))
}

/// Why a simulated teacher could not teach.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SimulatedTeachingError {
    /// The task's teaching steps do not fit the world (the message names the step).
    #[error(transparent)]
    Teacher(#[from] TeacherError),
    /// The session failed (no answer to a query, the recording could not be written).
    #[error(transparent)]
    Session(#[from] SessionError),
}

/// What a simulated teacher taught in a live session.
#[derive(Debug, Clone)]
pub struct SimulatedTeaching {
    /// The teacher's recording with what only the simulation knows (intended and unintended
    /// lines, marks).
    pub sim: SimulatedDemo,
    /// The session's recording: the frames with the detector states and the dialogue.
    pub demo: Demo,
    /// Whether the pace's stop flag ended it early.
    pub stopped: bool,
    /// Suggestions the learner made.
    pub suggestions: usize,
    /// The teacher's chance of an unintended line at the end, lowered by the suggestions it
    /// heeded (what it carries into its next demonstration).
    pub unintended_line_chance: f64,
}

/// The simulated teacher with `profile` demonstrates `task` in `world` step by step while a
/// teaching session listens: each step's frames go through the online detector and dialogue
/// (`answers` answers; an oracle among them is told the teacher's intent as it is recorded)
/// before the next step is made, and after each suggestion the teacher heeds it as its profile
/// says ([`SimulatedTeacher::heed_suggestion`]). The recording is named after the calibration
/// `label`.
#[allow(clippy::too_many_arguments)]
pub fn teach_simulated(
    task: &Task,
    world: &World,
    profile: &TeacherProfile,
    seed: u64,
    calibration: (Calibration, Option<&str>),
    answers: &mut dyn AnswerSource,
    sink: Option<&mut dyn RecordingSink>,
    pace: &Pace,
) -> Result<SimulatedTeaching, SimulatedTeachingError> {
    let mut teacher = SimulatedTeacher::new(task, world, profile, seed)
        .map_err(SimulatedTeachingError::Teacher)?;
    let recorded = &teacher.recorded().demo;
    let header = session_header(&recorded.header, calibration.1);
    let names: Vec<String> = recorded.objects.iter().map(|o| o.name.clone()).collect();
    let mut session = TeachingSession::new(header, &names, calibration.0, answers);
    if let Some(sink) = sink {
        session = session.with_sink(sink);
    }
    let mut player = Player::new(pace);
    let (mut played, mut heard) = (0, 0);
    let stopped = loop {
        let sim = teacher.recorded();
        let frames = played..sim.demo.len();
        session.answers().intend(&sim.intended_line[frames.clone()]);
        if player.play(&mut session, &sim.demo, frames, &sim.marked_keyframes)? {
            break true;
        }
        played = sim.demo.len();
        while heard < session.suggestions() {
            teacher.heed_suggestion();
            heard += 1;
        }
        if !teacher
            .next_step()
            .map_err(SimulatedTeachingError::Teacher)?
        {
            break false;
        }
    };
    let suggestions = session.suggestions();
    let unintended_line_chance = teacher.unintended_line_chance();
    let demo = if stopped {
        session.finish_early()?
    } else {
        session.finish()?
    };
    Ok(SimulatedTeaching {
        unintended_line_chance,
        sim: teacher.finish(),
        demo,
        stopped,
        suggestions,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::{Answer, DialogueKind};
    use crate::dialogue::AllYes;
    use crate::teacher::demonstrate;
    use akl_scene::{builtin, Task};
    use std::cell::Cell;

    fn answers(demo: &Demo) -> Vec<Answer> {
        demo.events
            .iter()
            .filter_map(|e| match e.kind {
                DialogueKind::Answer(a) => Some(a),
                _ => None,
            })
            .collect()
    }

    /// A sink that raises `stop` once it has received frame `at`, as Ctrl-C would then.
    struct StopAt<'a> {
        at: usize,
        stop: &'a AtomicBool,
        frames: usize,
    }

    impl RecordingSink for StopAt<'_> {
        fn frame(&mut self, _: &Demo, index: usize) -> std::io::Result<()> {
            self.frames += 1;
            if index >= self.at {
                self.stop.store(true, Ordering::Relaxed);
            }
            Ok(())
        }

        fn event(&mut self, _: &crate::demo::DialogueEvent) -> std::io::Result<()> {
            Ok(())
        }
    }

    /// A clock that moves only when slept on, plus `work` at every reading, as if each frame
    /// took that long to process; it adds up what was slept.
    #[derive(Debug)]
    struct SimulatedClock {
        now: Cell<Duration>,
        work: Duration,
        slept: Cell<Duration>,
    }

    impl SimulatedClock {
        fn new(work: Duration) -> Self {
            SimulatedClock {
                now: Cell::new(Duration::ZERO),
                work,
                slept: Cell::new(Duration::ZERO),
            }
        }
    }

    impl Clock for SimulatedClock {
        fn now(&self) -> Duration {
            self.now.set(self.now.get() + self.work);
            self.now.get()
        }

        fn sleep(&self, duration: Duration) {
            self.now.set(self.now.get() + duration);
            self.slept.set(self.slept.get() + duration);
        }
    }

    /// A sink noting the clock's time (without reading it as work) when each frame arrives.
    struct Stamps<'a> {
        clock: &'a SimulatedClock,
        at: Vec<f64>,
    }

    impl RecordingSink for Stamps<'_> {
        fn frame(&mut self, _: &Demo, _: usize) -> std::io::Result<()> {
            self.at.push(self.clock.now.get().as_secs_f64());
            Ok(())
        }

        fn event(&mut self, _: &crate::demo::DialogueEvent) -> std::io::Result<()> {
            Ok(())
        }
    }

    /// Plays the inspection demonstration at a realtime pace on `clock`: when each frame
    /// arrived on the clock, and each frame's time since the first.
    fn play_paced(clock: &SimulatedClock) -> (Vec<f64>, Vec<f64>) {
        let task = builtin::resolve("inspection").unwrap();
        let sim = demonstrate(&task, &task.world, &TeacherProfile::careful(), 1).unwrap();
        let mut stamps = Stamps {
            clock,
            at: Vec::new(),
        };
        let pace = Pace {
            realtime: Some(clock),
            stop: None,
        };
        let (demo, stopped) = stream_demo(
            &sim.demo,
            session_header(&sim.demo.header, None),
            &sim.marked_keyframes,
            Calibration::default(),
            &mut AllYes,
            Some(&mut stamps),
            &pace,
        )
        .unwrap();
        assert!(!stopped);
        assert_eq!(stamps.at.len(), demo.len());
        let due = demo.times.iter().map(|t| t - demo.times[0]).collect();
        (stamps.at, due)
    }

    /// A realtime pace with time to spare plays every frame exactly at its time on the clock:
    /// never early, and never late by waits that add up.
    #[test]
    fn a_realtime_pace_plays_each_frame_at_its_time() {
        let clock = SimulatedClock::new(Duration::ZERO);
        let (at, due) = play_paced(&clock);
        assert!(due.last().unwrap() > &10.0);
        for (i, (at, due)) in at.iter().zip(&due).enumerate() {
            assert!(
                (at - due).abs() < 1e-6,
                "frame {i} at {at} s, due at {due} s"
            );
        }
        let slept = clock.slept.get().as_secs_f64();
        assert!(
            (slept - due.last().unwrap()).abs() < 1e-6,
            "slept {slept} s"
        );
    }

    /// A realtime pace that has fallen behind (each frame takes twice its period to process)
    /// never waits, and no frame comes before its time.
    #[test]
    fn a_realtime_pace_behind_its_frames_does_not_wait() {
        let clock = SimulatedClock::new(Duration::from_millis(20));
        let (at, due) = play_paced(&clock);
        assert!(at.iter().zip(&due).all(|(at, due)| at >= due));
        assert_eq!(clock.slept.get(), Duration::ZERO);
    }

    /// The stop flag ends a played recording at the next frame, keeping what was played.
    #[test]
    fn the_stop_flag_ends_a_recording_keeping_what_was_played() {
        let task = builtin::resolve("inspection").unwrap();
        let sim = demonstrate(&task, &task.world, &TeacherProfile::careful(), 1).unwrap();
        let stop = AtomicBool::new(false);
        let mut sink = StopAt {
            at: 300,
            stop: &stop,
            frames: 0,
        };
        let pace = Pace {
            realtime: None,
            stop: Some(&stop),
        };
        let (demo, stopped) = stream_demo(
            &sim.demo,
            session_header(&sim.demo.header, None),
            &sim.marked_keyframes,
            Calibration::default(),
            &mut AllYes,
            Some(&mut sink),
            &pace,
        )
        .unwrap();
        assert!(stopped);
        assert!(sim.demo.len() > 600);
        assert!(demo.len() > 300 && demo.len() < 400, "{}", demo.len());
        assert_eq!(demo.times[..], sim.demo.times[..demo.len()]);
        assert_eq!(sink.frames, demo.len());
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

    fn live(task: &Task, profile: &TeacherProfile, seed: u64) -> SimulatedTeaching {
        let mut oracle = oracle(profile, seed);
        teach_simulated(
            task,
            &task.world,
            profile,
            seed,
            (Calibration::default(), None),
            &mut oracle,
            None,
            &Pace::default(),
        )
        .unwrap()
    }

    #[test]
    fn without_suggestions_a_live_teacher_records_what_a_replay_does() {
        let task = builtin::resolve("inspection").unwrap();
        let profile = TeacherProfile::careful();
        let taught = live(&task, &profile, 4);
        let sim = demonstrate(&task, &task.world, &profile, 4).unwrap();
        let mut oracle = oracle_for(&sim, &profile, 4);
        let replayed = run_session(&sim, Calibration::default(), &mut oracle, None).unwrap();
        assert_eq!(taught.suggestions, 0);
        assert_eq!(taught.demo, replayed);
        assert_eq!(taught.sim.intended_line, sim.intended_line);
    }

    /// Unintended straight runs that start after the first suggestion, over 10 seeds.
    fn straight_after_suggestion(uptake: f64) -> usize {
        let task = builtin::resolve("pick_place").unwrap();
        let profile = TeacherProfile {
            unintended_line_chance: 0.9,
            suggestion_uptake: uptake,
            ..TeacherProfile::careful()
        };
        (0..10)
            .map(|seed| {
                let taught = live(&task, &profile, seed);
                let Some(first) = taught
                    .demo
                    .events
                    .iter()
                    .find(|e| e.kind == DialogueKind::Suggestion)
                else {
                    return 0;
                };
                crate::okl::segment::runs(&taught.sim.unintended_line)
                    .iter()
                    .filter(|r| *r.start() > first.frame)
                    .count()
            })
            .sum()
    }

    #[test]
    fn a_teacher_who_heeds_suggestions_moves_straight_less_afterwards() {
        assert_eq!(straight_after_suggestion(1.0), 0);
        let stubborn = straight_after_suggestion(0.0);
        let halfway = straight_after_suggestion(0.5);
        assert!(stubborn >= 10 && halfway < stubborn, "{halfway} {stubborn}");
    }
}
