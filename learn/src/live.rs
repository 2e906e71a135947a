//! Teaching from a live JSONL stream: a robot driver pipes its frames in as the teacher moves
//! (`akl teach --teacher stdin`), and each frame goes through the online detector and dialogue
//! the moment it arrives.
//!
//! The stream is the JSONL demonstration format: a header line, then frame lines and, when the
//! teacher marks a keyframe, `{"t": ..., "event": "keyframe"}` lines. Queries, answers and
//! suggestions are the learner's to make, so a stream that carries them is refused.

use std::io::BufRead;
use std::sync::atomic::{AtomicBool, Ordering};

use akl_tsr::{Gripper, Pose};

use crate::demo::{DemoHeader, DialogueKind};
use crate::jsonl::{parse_header, parse_record, Record};
use crate::session::{SessionError, TeachingSession};
use crate::validate::FrameChecker;

/// Why a live stream could not be taught from.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LiveError {
    /// A line is malformed or breaks a rule of the format.
    #[error("line {line}: {message}")]
    Line {
        /// 1-based line number in the stream.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// The stream ended before its first frame.
    #[error("the stream ended before its first frame")]
    NoFrames,
    /// The stream could not be read.
    #[error("reading the stream: {0}")]
    Io(#[from] std::io::Error),
    /// The session failed (no answer to a query, the recording could not be written).
    #[error(transparent)]
    Session(#[from] SessionError),
}

/// One frame off the stream.
#[derive(Debug, Clone, PartialEq)]
struct Frame {
    t: f64,
    ee: Pose,
    gripper: Gripper,
    poses: Vec<Pose>,
}

/// What a line of the stream after the header brings.
enum Item {
    Frame(Frame),
    Mark,
}

/// The start of a stream: its header and the objects its frames carry.
#[derive(Debug, Clone, PartialEq)]
pub struct LiveStart {
    /// The stream's header.
    pub header: DemoHeader,
    /// The objects of every frame, in name order.
    pub objects: Vec<String>,
    first: Frame,
}

/// How a live session ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LiveEnd {
    /// The stream ended.
    Finished,
    /// The stop flag was raised (Ctrl-C) before the stream ended.
    Stopped,
}

/// A JSONL stream read line by line.
pub struct LiveStream<R> {
    input: R,
    line: usize,
    checker: FrameChecker,
    buffer: String,
}

impl<R: BufRead> LiveStream<R> {
    /// Reads from `input`.
    pub fn new(input: R) -> Self {
        LiveStream {
            input,
            line: 0,
            checker: FrameChecker::default(),
            buffer: String::new(),
        }
    }

    /// The next non-blank line, or `None` at the end of the stream.
    fn next_line(&mut self) -> Result<Option<&str>, LiveError> {
        loop {
            self.buffer.clear();
            if self.input.read_line(&mut self.buffer)? == 0 {
                return Ok(None);
            }
            self.line += 1;
            if !self.buffer.trim().is_empty() {
                return Ok(Some(self.buffer.trim()));
            }
        }
    }

    fn error(&self, message: String) -> LiveError {
        LiveError::Line {
            line: self.line,
            message,
        }
    }

    /// Parses the next item: a checked frame, a keyframe mark, or `None` at the end.
    fn next_item(&mut self) -> Result<Option<Item>, LiveError> {
        let Some(line) = self.next_line()? else {
            return Ok(None);
        };
        match parse_record(line).map_err(|e| self.error(e.into()))? {
            Record::Frame {
                t,
                ee,
                gripper,
                objects,
                constrained: _,
            } => {
                let names: Vec<&str> = objects.iter().map(|(n, _)| n.as_str()).collect();
                self.checker
                    .check(t, &names)
                    .map_err(|e| self.error(e.into()))?;
                let poses = objects.into_iter().map(|(_, p)| p).collect();
                Ok(Some(Item::Frame(Frame {
                    t,
                    ee,
                    gripper,
                    poses,
                })))
            }
            Record::Event {
                kind: DialogueKind::Keyframe,
                ..
            } => Ok(Some(Item::Mark)),
            Record::Event { .. } => Err(self.error(
                "a live stream carries frames and keyframe marks only: the learner asks its own questions"
                    .into(),
            )),
        }
    }

    /// Reads the header and the first frame.
    pub fn start(&mut self) -> Result<LiveStart, LiveError> {
        let header = match self.next_line()? {
            Some(line) => parse_header(line).map_err(|e| self.error(e.into()))?,
            None => return Err(LiveError::NoFrames),
        };
        match self.next_item()? {
            Some(Item::Frame(first)) => Ok(LiveStart {
                header,
                objects: self.checker.objects().to_vec(),
                first,
            }),
            Some(Item::Mark) => Err(self.error("a keyframe mark before the first frame".into())),
            None => Err(LiveError::NoFrames),
        }
    }

    /// Feeds the first frame and then every frame and mark of the stream into `session`, until
    /// the stream ends or `stop` is raised; errors name the line.
    pub fn run(
        &mut self,
        start: LiveStart,
        session: &mut TeachingSession,
        stop: &AtomicBool,
    ) -> Result<LiveEnd, LiveError> {
        let at = |line: usize, e: SessionError| match e {
            SessionError::Frame { message, .. } => LiveError::Line { line, message },
            other => LiveError::Session(other),
        };
        let first = start.first;
        session
            .push(first.t, first.ee, first.gripper, &first.poses)
            .map_err(|e| at(self.line, e))?;
        while !stop.load(Ordering::Relaxed) {
            match self.next_item()? {
                None => return Ok(LiveEnd::Finished),
                Some(Item::Frame(f)) => session
                    .push(f.t, f.ee, f.gripper, &f.poses)
                    .map_err(|e| at(self.line, e))?,
                Some(Item::Mark) => session.mark_keyframe().map_err(|e| at(self.line, e))?,
            }
        }
        Ok(LiveEnd::Stopped)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::calibration::Calibration;
    use crate::dialogue::ListedAnswers;
    use crate::jsonl::write_jsonl;
    use crate::okl::synth::DemoBuilder;

    fn stream_text() -> String {
        let mut demo = DemoBuilder::new("anything", [0.2, 0.0, 0.21], 100.0, 0.0005, 2)
            .object("part", [0.45, 0.32, 0.19])
            .curve([0.45, 0.32, 0.21], 0.25)
            .mark()
            .grasp("part")
            .curve([0.55, 0.18, 0.22], 0.25)
            .line([0.55, -0.18, 0.22], 0.15, None)
            .build();
        demo.detector.clear();
        demo.events.retain(|e| e.kind == DialogueKind::Keyframe);
        write_jsonl(&demo)
    }

    fn teach(text: &str, stop: bool) -> Result<(crate::demo::Demo, LiveEnd), LiveError> {
        let mut stream = LiveStream::new(text.as_bytes());
        let start = stream.start()?;
        let mut answers = ListedAnswers::parse("yes").unwrap();
        let mut session = TeachingSession::new(
            start.header.clone(),
            &start.objects,
            Calibration::default(),
            &mut answers,
        );
        let end = stream.run(start, &mut session, &AtomicBool::new(stop))?;
        let demo = match end {
            LiveEnd::Finished => session.finish()?,
            LiveEnd::Stopped => session.finish_early()?,
        };
        Ok((demo, end))
    }

    #[test]
    fn a_stream_is_taught_frame_by_frame_with_its_marks() {
        let (demo, end) = teach(&stream_text(), false).unwrap();
        assert_eq!(end, LiveEnd::Finished);
        assert_eq!(demo.detector.len(), demo.len());
        assert!(demo.detector.iter().any(|c| *c));
        let kinds: Vec<_> = demo.events.iter().map(|e| e.kind).collect();
        assert!(kinds.contains(&DialogueKind::Keyframe));
        assert!(kinds.contains(&DialogueKind::Query));
        let (stopped, end) = teach(&stream_text(), true).unwrap();
        assert_eq!((stopped.len(), end), (1, LiveEnd::Stopped));
    }

    #[test]
    fn bad_streams_are_named_by_line() {
        let text = stream_text();
        let mut lines: Vec<&str> = text.lines().collect();
        lines.insert(5, r#"{"t": 99.0, "event": "answer", "value": "yes"}"#);
        let e = teach(&lines.join("\n"), false).unwrap_err().to_string();
        assert!(
            e.starts_with("line 6:") && e.contains("own questions"),
            "{e}"
        );
        let e = teach(&lines[..1].join("\n"), false).unwrap_err();
        assert!(matches!(e, LiveError::NoFrames));
        let mut back = text.lines().collect::<Vec<_>>();
        back.swap(3, 4);
        let e = teach(&back.join("\n"), false).unwrap_err().to_string();
        assert!(e.starts_with("line 5:") && e.contains("increase"), "{e}");
    }
}
