//! A teaching session: frames stream in, the online detector runs, and the dialogue happens
//! at each 0→1 switch, all recorded into one [`Demo`].

use akl_tsr::{Gripper, Pose};
use k::nalgebra::Vector3;

use crate::calibration::Calibration;
use crate::demo::{Answer, Demo, DemoHeader, DialogueEvent, DialogueKind};
use crate::detector::Detector;
use crate::dialogue::{AnswerSource, DialogueError, Question, SUGGESTION};
use crate::validate::FrameChecker;

/// How many nearby objects a question mentions.
const NEAREST_OBJECTS: usize = 3;

/// Receives a session's recording as it grows (e.g. a streaming file writer).
pub trait RecordingSink {
    /// Frame `index` of `demo` was just appended (with its detector state).
    fn frame(&mut self, demo: &Demo, index: usize) -> std::io::Result<()>;
    /// A dialogue event was just appended.
    fn event(&mut self, event: &DialogueEvent) -> std::io::Result<()>;
}

/// Writes a whole recorded `demo` into `sink`, frames and events merged in time order (an
/// event at the same frame as a frame follows it), as a live session would have.
pub(crate) fn write_demo(sink: &mut dyn RecordingSink, demo: &Demo) -> std::io::Result<()> {
    let mut events = demo.events.iter().peekable();
    for i in 0..demo.len() {
        sink.frame(demo, i)?;
        while let Some(event) = events.next_if(|e| e.frame <= i) {
            sink.event(event)?;
        }
    }
    events.try_for_each(|event| sink.event(event))
}

/// What went wrong in a session.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SessionError {
    /// A frame broke a rule of the format.
    #[error("frame {frame}: {message}")]
    Frame {
        /// 0-based frame index.
        frame: usize,
        /// What is wrong.
        message: String,
    },
    /// No answer could be had.
    #[error(transparent)]
    Dialogue(#[from] DialogueError),
    /// The recording could not be written.
    #[error("writing the recording: {0}")]
    Io(#[from] std::io::Error),
}

/// An interactive demonstration in progress.
pub struct TeachingSession<'a> {
    detector: Detector,
    demo: Demo,
    checker: FrameChecker,
    answers: &'a mut dyn AnswerSource,
    sink: Option<&'a mut dyn RecordingSink>,
    queries: usize,
    suggestions: usize,
}

impl<'a> TeachingSession<'a> {
    /// Starts a session for the objects named in `objects` (the order of every frame's poses).
    pub fn new(
        header: DemoHeader,
        objects: &[String],
        calibration: Calibration,
        answers: &'a mut dyn AnswerSource,
    ) -> Self {
        TeachingSession {
            detector: Detector::new(calibration),
            demo: Demo::empty(header, objects),
            checker: FrameChecker::default(),
            answers,
            sink: None,
            queries: 0,
            suggestions: 0,
        }
    }

    /// Streams the recording into `sink` as it grows.
    pub fn with_sink(mut self, sink: &'a mut dyn RecordingSink) -> Self {
        self.sink = Some(sink);
        self
    }

    /// Number of queries asked so far.
    pub fn queries(&self) -> usize {
        self.queries
    }

    /// Number of suggestions made so far.
    pub fn suggestions(&self) -> usize {
        self.suggestions
    }

    /// Who answers: to tell a simulated teacher's oracle what the teacher intends as frames
    /// are recorded ([`AnswerSource::intend`]).
    pub fn answers(&mut self) -> &mut dyn AnswerSource {
        &mut *self.answers
    }

    /// Takes one frame; on a 0→1 switch asks the question, records the answer and, after "no"
    /// or "I don't know", shows and records the suggestion; "no" returns the detector to
    /// unconstrained. A gripper command resets the detector once the frame's state is recorded
    /// (the state at the command frame is the one detected up to it), so no detection carries
    /// into the next interaction segment.
    pub fn push(
        &mut self,
        t: f64,
        ee: Pose,
        gripper: Gripper,
        objects: &[Pose],
    ) -> Result<(), SessionError> {
        let index = self.demo.len();
        let names: Vec<&str> = self.demo.objects.iter().map(|o| o.name.as_str()).collect();
        if objects.len() != names.len() {
            return Err(SessionError::Frame {
                frame: index,
                message: format!("{} object poses for {} objects", objects.len(), names.len()),
            });
        }
        self.checker
            .check(t, &names)
            .map_err(|e| SessionError::Frame {
                frame: index,
                message: e.into(),
            })?;
        self.demo.times.push(t);
        self.demo.ee.push(ee);
        self.demo.gripper.push(gripper);
        for (track, pose) in self.demo.objects.iter_mut().zip(objects) {
            track.poses.push(*pose);
        }
        let position = ee.translation.vector;
        let command = index > 0 && self.demo.gripper[index - 1] != gripper;
        let switch = if command {
            None
        } else {
            self.detector.push(t, position)
        };
        let mut events = Vec::new();
        if let Some(switch) = switch.filter(|s| s.constrained) {
            self.queries += 1;
            let question = Question {
                t,
                frame: index,
                line_start: switch.line_start,
                line_end: position,
                nearest_objects: self.nearest_objects(&switch.line_start, &position, objects),
            };
            let answer = self.answers.answer(&question)?;
            events.push(DialogueKind::Query);
            events.push(DialogueKind::Answer(answer));
            if answer != Answer::Yes {
                self.answers.suggest(SUGGESTION)?;
                events.push(DialogueKind::Suggestion);
                self.suggestions += 1;
            }
            if answer == Answer::No {
                self.detector.reject();
            }
        }
        self.demo.detector.push(self.detector.constrained());
        if command {
            self.detector.reset();
            self.detector.push(t, position);
        }
        if let Some(sink) = self.sink.as_deref_mut() {
            sink.frame(&self.demo, index)?;
        }
        for kind in events {
            self.record(DialogueEvent {
                t,
                frame: index,
                kind,
            })?;
        }
        Ok(())
    }

    /// Records a keyframe the teacher marked at the latest frame.
    pub fn mark_keyframe(&mut self) -> Result<(), SessionError> {
        let frame = self.demo.len().saturating_sub(1);
        let t = self.demo.times.last().copied().unwrap_or(0.0);
        self.record(DialogueEvent {
            t,
            frame,
            kind: DialogueKind::Keyframe,
        })
    }

    fn record(&mut self, event: DialogueEvent) -> Result<(), SessionError> {
        if let Some(sink) = self.sink.as_deref_mut() {
            sink.event(&event)?;
        }
        self.demo.events.push(event);
        Ok(())
    }

    fn nearest_objects(
        &self,
        a: &Vector3<f64>,
        b: &Vector3<f64>,
        poses: &[Pose],
    ) -> Vec<(String, f64)> {
        let mut near: Vec<(String, f64)> = self
            .demo
            .objects
            .iter()
            .zip(poses)
            .map(|(track, pose)| {
                (
                    track.name.clone(),
                    segment_distance(a, b, &pose.translation.vector),
                )
            })
            .collect();
        near.sort_by(|x, y| x.1.total_cmp(&y.1));
        near.truncate(NEAREST_OBJECTS);
        near
    }

    /// Ends the session; an empty recording is an error, and so are answers given in advance
    /// that no question took ([`AnswerSource::finish`]).
    pub fn finish(self) -> Result<Demo, SessionError> {
        self.answers.finish()?;
        self.finish_early()
    }

    /// Ends a session stopped before the demonstration ended (Ctrl-C): answers given in advance
    /// may be left for questions that never came, so they are not checked. An empty recording
    /// is an error.
    pub fn finish_early(self) -> Result<Demo, SessionError> {
        if self.demo.is_empty() {
            return Err(SessionError::Frame {
                frame: 0,
                message: "the demonstration has no frames".into(),
            });
        }
        Ok(self.demo)
    }
}

/// Distance from `p` to the segment `a`–`b`.
fn segment_distance(a: &Vector3<f64>, b: &Vector3<f64>, p: &Vector3<f64>) -> f64 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    let s = if len2 > 0.0 {
        ((p - a).dot(&ab) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (a + ab * s - p).norm()
}
