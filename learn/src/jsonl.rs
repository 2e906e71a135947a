//! The JSONL demonstration format: a header line, then one frame or dialogue event per line.
//!
//! Any robot driver can write it. The header line is
//! `{"akl_demo": 1, "task": "...", "frame": "world"}`, optionally with `"shapes": {NAME: SHAPE}`
//! declaring tracked objects' shapes as a task file writes them (see [`crate::read_shapes_file`]). A
//! frame line is
//! `{"t": 0.01, "ee": POSE, "gripper": "open", "objects": {"part": POSE}}`, optionally with
//! `"constrained": true|false` (the online detector's state, written by `akl teach`); an event line
//! is `{"t": 3.2, "event": "query" | "answer" | "suggestion" | "keyframe", "value": ...}`.

use std::collections::BTreeMap;
use std::io::Write;

use akl_tsr::{Gripper, Pose, PoseJson};
use serde::{Deserialize, Serialize};

use crate::demo::{
    Answer, Demo, DemoHeader, DialogueEvent, DialogueKind, ObjectTrack, DEMO_VERSION,
};
use crate::demo_error::DemoError;
use crate::session::{write_demo, RecordingSink};
use crate::validate::FrameChecker;

/// One frame line as written.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct FrameLine {
    t: f64,
    ee: PoseJson,
    gripper: Gripper,
    #[serde(default)]
    objects: BTreeMap<String, PoseJson>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    constrained: Option<bool>,
}

/// One dialogue line as written.
#[derive(Debug, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct EventLine {
    t: f64,
    event: EventName,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    value: Option<Answer>,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
enum EventName {
    Query,
    Answer,
    Suggestion,
    Keyframe,
}

/// One line of a JSONL demonstration after the header, parsed and checked on its own.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Record {
    /// A frame: time, end-effector pose, gripper, object poses (sorted by name) and, when the
    /// recorder ran the online detector, its state.
    Frame {
        /// Time (s).
        t: f64,
        /// End-effector pose.
        ee: Pose,
        /// Gripper state.
        gripper: Gripper,
        /// Object poses by name, in name order.
        objects: Vec<(String, Pose)>,
        /// The detector state, when recorded.
        constrained: Option<bool>,
    },
    /// A dialogue event or a keyframe mark.
    Event {
        /// Time (s).
        t: f64,
        /// What happened.
        kind: DialogueKind,
    },
}

/// Why a line of a JSONL demonstration cannot be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub(crate) enum LineError {
    /// The first line is not a header.
    #[error("not an `akl_demo` header: {0}")]
    NotHeader(String),
    /// The header's version is not the one this build reads.
    #[error("unsupported akl_demo version {0} (this build reads {DEMO_VERSION})")]
    Version(u32),
    /// The line is not JSON of a frame or an event (serde's message).
    #[error("{0}")]
    Json(String),
    /// An event's time is NaN or infinite.
    #[error("event time {0} is not finite")]
    EventTime(f64),
    /// An answer event without its answer.
    #[error("an answer needs a `value` (yes, no or unknown)")]
    AnswerWithoutValue,
    /// A pose of the frame is not a pose (`ee` or `object `NAME``).
    #[error("{what}: {source}")]
    Pose {
        /// Whose pose.
        what: String,
        /// What is wrong with it.
        source: akl_tsr::PoseError,
    },
}

impl From<LineError> for String {
    fn from(e: LineError) -> String {
        e.to_string()
    }
}

/// Parses the header line; the error says what is wrong.
pub(crate) fn parse_header(line: &str) -> Result<DemoHeader, LineError> {
    let header: DemoHeader =
        serde_json::from_str(line).map_err(|e| LineError::NotHeader(plain(&e, line)))?;
    if header.akl_demo != DEMO_VERSION {
        return Err(LineError::Version(header.akl_demo));
    }
    Ok(header)
}

/// Parses a frame or event line; the error says what is wrong.
pub(crate) fn parse_record(line: &str) -> Result<Record, LineError> {
    let value: serde_json::Value =
        serde_json::from_str(line).map_err(|e| LineError::Json(plain(&e, line)))?;
    if value.get("event").is_some() {
        let event: EventLine =
            serde_json::from_value(value).map_err(|e| LineError::Json(e.to_string()))?;
        if !event.t.is_finite() {
            return Err(LineError::EventTime(event.t));
        }
        let kind = match (event.event, event.value) {
            (EventName::Answer, Some(a)) => DialogueKind::Answer(a),
            (EventName::Answer, None) => return Err(LineError::AnswerWithoutValue),
            (EventName::Query, _) => DialogueKind::Query,
            (EventName::Suggestion, _) => DialogueKind::Suggestion,
            (EventName::Keyframe, _) => DialogueKind::Keyframe,
        };
        return Ok(Record::Event { t: event.t, kind });
    }
    let frame: FrameLine =
        serde_json::from_value(value).map_err(|e| LineError::Json(e.to_string()))?;
    let ee = frame.ee.to_pose().map_err(|source| LineError::Pose {
        what: "ee".into(),
        source,
    })?;
    let mut objects = Vec::with_capacity(frame.objects.len());
    for (name, pose) in frame.objects {
        let pose = pose.to_pose().map_err(|source| LineError::Pose {
            what: format!("object `{name}`"),
            source,
        })?;
        objects.push((name, pose));
    }
    Ok(Record::Frame {
        t: frame.t,
        ee,
        gripper: frame.gripper,
        objects,
        constrained: frame.constrained,
    })
}

/// Reads a JSONL demonstration; errors name the 1-based line.
pub fn read_jsonl(text: &str) -> Result<Demo, DemoError> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let (_, first) = lines.next().ok_or(DemoError::Format(
        "the file is empty: expected an `akl_demo` header line".into(),
    ))?;
    let header = parse_header(first).map_err(|e| DemoError::Line {
        line: 1,
        message: e.into(),
    })?;
    let mut builder = DemoBuilder::new(header);
    for (index, line) in lines {
        let at = |message: String| DemoError::Line {
            line: index + 1,
            message,
        };
        match parse_record(line).map_err(|e| at(e.into()))? {
            Record::Frame {
                t,
                ee,
                gripper,
                objects,
                constrained,
            } => builder.frame(t, ee, gripper, objects, constrained),
            Record::Event { t, kind } => builder.event(t, kind),
        }
        .map_err(at)?;
    }
    builder.finish()
}

/// Writes a demonstration as JSONL: header, then frames and events merged in time order
/// (an event at the same time as a frame follows it).
pub fn write_jsonl(demo: &Demo) -> String {
    let mut out = Vec::new();
    let written = JsonlDemoWriter::new(&mut out, &demo.header).and_then(|mut w| {
        write_demo(&mut w, demo)?;
        w.finish()
    });
    // Writing into memory cannot fail, and serde_json writes valid UTF-8.
    written.expect("writing to memory");
    String::from_utf8(out).expect("JSON is UTF-8")
}

/// Streams a demonstration into JSONL as it is recorded: a line per frame and per event,
/// flushed at every event and at least once a second of demonstration time, so a killed
/// recording keeps everything but its last second.
pub(crate) struct JsonlDemoWriter<W: Write> {
    out: W,
    last_flush: f64,
}

impl<W: Write> JsonlDemoWriter<W> {
    /// Starts a recording with its header line.
    pub(crate) fn new(mut out: W, header: &DemoHeader) -> std::io::Result<Self> {
        serde_json::to_writer(&mut out, header)?;
        out.write_all(b"\n")?;
        out.flush()?;
        Ok(JsonlDemoWriter {
            out,
            last_flush: f64::NEG_INFINITY,
        })
    }

    /// Writes frame `i` of `demo` (with its detector state when it has one).
    pub(crate) fn write_frame(&mut self, demo: &Demo, i: usize) -> std::io::Result<()> {
        let frame = FrameLine {
            t: demo.times[i],
            ee: PoseJson::from_pose(&demo.ee[i]),
            gripper: demo.gripper[i],
            objects: demo
                .objects
                .iter()
                .map(|o| (o.name.clone(), PoseJson::from_pose(&o.poses[i])))
                .collect(),
            constrained: demo.detector.get(i).copied(),
        };
        serde_json::to_writer(&mut self.out, &frame)?;
        self.out.write_all(b"\n")?;
        if frame.t - self.last_flush >= 1.0 {
            self.out.flush()?;
            self.last_flush = frame.t;
        }
        Ok(())
    }

    /// Writes a dialogue event or keyframe mark.
    pub(crate) fn write_event(&mut self, event: &DialogueEvent) -> std::io::Result<()> {
        let (name, value) = match event.kind {
            DialogueKind::Query => (EventName::Query, None),
            DialogueKind::Answer(a) => (EventName::Answer, Some(a)),
            DialogueKind::Suggestion => (EventName::Suggestion, None),
            DialogueKind::Keyframe => (EventName::Keyframe, None),
        };
        let line = EventLine {
            t: event.t,
            event: name,
            value,
        };
        serde_json::to_writer(&mut self.out, &line)?;
        self.out.write_all(b"\n")?;
        self.out.flush()
    }

    /// Flushes and returns the underlying writer.
    pub(crate) fn finish(mut self) -> std::io::Result<W> {
        self.out.flush()?;
        Ok(self.out)
    }
}

impl<W: Write> RecordingSink for JsonlDemoWriter<W> {
    fn frame(&mut self, demo: &Demo, index: usize) -> std::io::Result<()> {
        self.write_frame(demo, index)
    }

    fn event(&mut self, event: &DialogueEvent) -> std::io::Result<()> {
        self.write_event(event)
    }
}

/// A serde_json message without its position (the caller names the line).
fn plain(err: &serde_json::Error, text: &str) -> String {
    akl_tsr::describe_json_error(err, text).2
}

/// Accumulates frames and events in arrival order, checking each as it comes.
struct DemoBuilder {
    demo: Demo,
    checker: FrameChecker,
    detector_given: Option<bool>,
}

impl DemoBuilder {
    fn new(header: DemoHeader) -> Self {
        DemoBuilder {
            demo: Demo::empty(header, &[]),
            checker: FrameChecker::default(),
            detector_given: None,
        }
    }

    fn frame(
        &mut self,
        t: f64,
        ee: Pose,
        gripper: Gripper,
        objects: Vec<(String, Pose)>,
        constrained: Option<bool>,
    ) -> Result<(), String> {
        let names: Vec<&str> = objects.iter().map(|(n, _)| n.as_str()).collect();
        self.checker.check(t, &names)?;
        match (self.detector_given, constrained) {
            (None, c) => self.detector_given = Some(c.is_some()),
            (Some(true), None) | (Some(false), Some(_)) => {
                return Err("`constrained` must be given on every frame or on none".into())
            }
            _ => {}
        }
        if self.demo.objects.is_empty() && self.demo.times.is_empty() {
            self.demo.objects = objects
                .iter()
                .map(|(n, _)| ObjectTrack {
                    name: n.clone(),
                    poses: Vec::new(),
                })
                .collect();
        }
        for (track, (_, pose)) in self.demo.objects.iter_mut().zip(objects) {
            track.poses.push(pose);
        }
        self.demo.times.push(t);
        self.demo.ee.push(ee);
        self.demo.gripper.push(gripper);
        if let Some(c) = constrained {
            self.demo.detector.push(c);
        }
        Ok(())
    }

    fn event(&mut self, t: f64, kind: DialogueKind) -> Result<(), String> {
        if let Some(last) = self.demo.events.last() {
            if t < last.t {
                return Err(format!(
                    "event time {t} goes back before the previous event ({})",
                    last.t
                ));
            }
        }
        let frame = frame_at(&self.demo.times, t);
        self.demo.events.push(DialogueEvent { t, frame, kind });
        Ok(())
    }

    fn finish(self) -> Result<Demo, DemoError> {
        if self.demo.is_empty() {
            return Err(DemoError::Empty);
        }
        Ok(self.demo)
    }
}

/// Index of the last frame at or before `t` (0 before the first frame).
pub(crate) fn frame_at(times: &[f64], t: f64) -> usize {
    times.partition_point(|&x| x <= t).saturating_sub(1)
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEADER: &str = r#"{"akl_demo": 1, "task": "inspection", "frame": "world"}"#;

    fn frame(t: f64, x: f64, objects: &str) -> String {
        format!(
            r#"{{"t": {t}, "ee": {{"p": [{x}, 0, 0.3], "q": [0, 0, 0, 1]}}, "gripper": "open", "objects": {{{objects}}}}}"#
        )
    }

    const PART: &str = r#""part": {"p": [0.4, 0.1, 0.2], "q": [0, 0, 0, 1]}"#;

    #[test]
    fn a_written_demo_reads_back_identically() {
        let text = [
            HEADER.to_string(),
            frame(0.0, 0.1, PART),
            frame(0.01, 0.11, PART),
            r#"{"t": 0.01, "event": "query"}"#.into(),
            r#"{"t": 0.01, "event": "answer", "value": "no"}"#.into(),
            frame(0.02, 0.12, PART),
        ]
        .join("\n");
        let demo = read_jsonl(&text).unwrap();
        assert_eq!(demo.len(), 3);
        assert_eq!(demo.events.len(), 2);
        assert_eq!(demo.events[1].kind, DialogueKind::Answer(Answer::No));
        assert_eq!(demo.events[1].frame, 1);
        let again = read_jsonl(&write_jsonl(&demo)).unwrap();
        assert_eq!(again, demo);
    }

    fn error_of(lines: &[String]) -> String {
        read_jsonl(&lines.join("\n")).unwrap_err().to_string()
    }

    #[test]
    fn bad_frames_are_named_by_line() {
        let back_in_time =
            error_of(&[HEADER.into(), frame(0.1, 0.1, PART), frame(0.05, 0.1, PART)]);
        assert!(
            back_in_time.starts_with("line 3:") && back_in_time.contains("increas"),
            "{back_in_time}"
        );
        let nan = error_of(&[HEADER.into(), frame(0.1, 0.1, PART).replace("0.3]", "NaN]")]);
        assert!(
            nan.starts_with("line 2:") && nan.contains("non-finite"),
            "{nan}"
        );
        let quat = error_of(&[
            HEADER.into(),
            frame(0.1, 0.1, PART).replace("[0, 0, 0, 1]}, \"gripper", "[0, 0, 0, 2]}, \"gripper"),
        ]);
        assert!(
            quat.starts_with("line 2:") && quat.contains("unit length"),
            "{quat}"
        );
        let vanish = error_of(&[HEADER.into(), frame(0.1, 0.1, PART), frame(0.2, 0.1, "")]);
        assert!(
            vanish.starts_with("line 3:") && vanish.contains("part"),
            "{vanish}"
        );
        let appear = error_of(&[HEADER.into(), frame(0.1, 0.1, ""), frame(0.2, 0.1, PART)]);
        assert!(
            appear.starts_with("line 3:") && appear.contains("part"),
            "{appear}"
        );
        assert_eq!(read_jsonl(HEADER).unwrap_err(), DemoError::Empty);
        let version = error_of(&[HEADER.replace("1,", "7,")]);
        assert!(
            version.starts_with("line 1:") && version.contains("version 7"),
            "{version}"
        );
    }
}
