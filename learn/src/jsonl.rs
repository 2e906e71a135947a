//! The JSONL demonstration format: a header line, then one frame or dialogue event per line.
//!
//! Any robot driver can write it. A frame line is
//! `{"t": 0.01, "ee": POSE, "gripper": "open", "objects": {"part": POSE}}`, optionally with
//! `"constrained": true|false` (the online detector's state, written by `akl teach`); an event line
//! is `{"t": 3.2, "event": "query" | "answer" | "suggestion" | "keyframe", "value": ...}`.

use std::collections::BTreeMap;

use akl_tsr::{Gripper, Pose, PoseJson};
use serde::{Deserialize, Serialize};

use crate::demo::{
    Answer, Demo, DemoHeader, DialogueEvent, DialogueKind, ObjectTrack, DEMO_VERSION,
};
use crate::demo_error::DemoError;
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

/// Reads a JSONL demonstration; errors name the 1-based line.
pub fn read_jsonl(text: &str) -> Result<Demo, DemoError> {
    let mut lines = text
        .lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty());
    let (_, first) = lines.next().ok_or(DemoError::Format(
        "the file is empty: expected an `akl_demo` header line".into(),
    ))?;
    let header: DemoHeader = serde_json::from_str(first).map_err(|e| DemoError::Line {
        line: 1,
        message: format!("not an `akl_demo` header: {}", plain(&e, first)),
    })?;
    if header.akl_demo != DEMO_VERSION {
        return Err(DemoError::Line {
            line: 1,
            message: format!(
                "unsupported akl_demo version {} (this build reads {DEMO_VERSION})",
                header.akl_demo
            ),
        });
    }
    let mut builder = DemoBuilder::new(header);
    for (index, line) in lines {
        let number = index + 1;
        let at = |message: String| DemoError::Line {
            line: number,
            message,
        };
        let value: serde_json::Value =
            serde_json::from_str(line).map_err(|e| at(plain(&e, line)))?;
        if value.get("event").is_some() {
            let event: EventLine = serde_json::from_value(value).map_err(|e| at(e.to_string()))?;
            builder.event(event).map_err(at)?;
        } else {
            let frame: FrameLine = serde_json::from_value(value).map_err(|e| at(e.to_string()))?;
            builder.frame(frame).map_err(at)?;
        }
    }
    builder.finish()
}

/// Writes a demonstration as JSONL: header, then frames and events merged in time order
/// (an event at the same time as a frame follows it).
pub fn write_jsonl(demo: &Demo) -> String {
    let mut out = String::new();
    out.push_str(&serde_json::to_string(&demo.header).expect("a header serializes"));
    out.push('\n');
    let mut events = demo.events.iter().peekable();
    for i in 0..demo.len() {
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
        out.push_str(&serde_json::to_string(&frame).expect("a frame serializes"));
        out.push('\n');
        while let Some(event) = events.next_if(|e| e.frame <= i) {
            push_event(&mut out, event);
        }
    }
    for event in events {
        push_event(&mut out, event);
    }
    out
}

fn push_event(out: &mut String, event: &DialogueEvent) {
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
    out.push_str(&serde_json::to_string(&line).expect("an event serializes"));
    out.push('\n');
}

/// A serde_json message without its position (the caller names the line).
fn plain(err: &serde_json::Error, text: &str) -> String {
    akl_tsr::error::describe_json_error(err, text).2
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
            demo: Demo {
                header,
                times: Vec::new(),
                ee: Vec::new(),
                gripper: Vec::new(),
                objects: Vec::new(),
                detector: Vec::new(),
                events: Vec::new(),
            },
            checker: FrameChecker::default(),
            detector_given: None,
        }
    }

    fn frame(&mut self, frame: FrameLine) -> Result<(), String> {
        let ee = frame.ee.to_pose().map_err(|e| format!("ee: {e}"))?;
        let mut objects: Vec<(String, Pose)> = Vec::with_capacity(frame.objects.len());
        for (name, pose) in &frame.objects {
            objects.push((
                name.clone(),
                pose.to_pose()
                    .map_err(|e| format!("object `{name}`: {e}"))?,
            ));
        }
        let names: Vec<&str> = objects.iter().map(|(n, _)| n.as_str()).collect();
        self.checker.check(frame.t, &names)?;
        match (self.detector_given, frame.constrained) {
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
        self.demo.times.push(frame.t);
        self.demo.ee.push(ee);
        self.demo.gripper.push(frame.gripper);
        if let Some(c) = frame.constrained {
            self.demo.detector.push(c);
        }
        Ok(())
    }

    fn event(&mut self, event: EventLine) -> Result<(), String> {
        if !event.t.is_finite() {
            return Err(format!("event time {} is not finite", event.t));
        }
        let kind = match (event.event, event.value) {
            (EventName::Answer, Some(a)) => DialogueKind::Answer(a),
            (EventName::Answer, None) => {
                return Err("an answer needs a `value` (yes, no or unknown)".into())
            }
            (EventName::Query, _) => DialogueKind::Query,
            (EventName::Suggestion, _) => DialogueKind::Suggestion,
            (EventName::Keyframe, _) => DialogueKind::Keyframe,
        };
        if let Some(last) = self.demo.events.last() {
            if event.t < last.t {
                return Err(format!(
                    "event time {} goes back before the previous event ({})",
                    event.t, last.t
                ));
            }
        }
        let frame = frame_at(&self.demo.times, event.t);
        self.demo.events.push(DialogueEvent {
            t: event.t,
            frame,
            kind,
        });
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
pub fn frame_at(times: &[f64], t: f64) -> usize {
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
