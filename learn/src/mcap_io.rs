//! The MCAP demonstration format: what `akl teach` records, readable by Foxglove.
//!
//! One channel per stream with JSON messages: `/ee` and `/objects/<name>` as
//! `foxglove.PoseInFrame`, `/dialogue` as `foxglove.Log`, and AKL channels `/gripper`,
//! `/detector` and `/akl/header`; the header is also a metadata record. All messages of one
//! frame share its log time. The writer closes a chunk at least once a second (of demonstration
//! time and of wall-clock time), so a killed recording loses at most its last second; the reader
//! recovers every complete chunk of a truncated file and reports what was lost.

use std::collections::BTreeMap;
use std::io::{Seek, Write};
use std::time::{Duration, Instant};

use akl_foxglove::schema::{boolean, integer, object, object_with_optional, string};
use akl_foxglove::{Channel, Log, LogLevel, McapWriter, Message, PoseInFrame, Schema, Time};
use akl_tsr::{Gripper, Pose, PoseJson};
use serde::{Deserialize, Serialize};
use serde_json::{json, Value};

use crate::demo::{Answer, Demo, DemoHeader, DialogueEvent, DialogueKind, DEMO_VERSION};
use crate::demo_error::DemoError;
use crate::dialogue::{QUERY, SUGGESTION};
use crate::session::RecordingSink;
use crate::validate::FrameChecker;

/// The first bytes of every MCAP file.
pub(crate) const MCAP_MAGIC: &[u8] = b"\x89MCAP0\r\n";

/// Longest stretch of recording kept in an unfinished chunk.
pub(crate) const FLUSH_INTERVAL: Duration = Duration::from_secs(1);

/// `akl.Gripper`: the gripper's state in one frame.
#[derive(Serialize, Deserialize)]
struct GripperState {
    /// `open` or `closed`.
    state: Gripper,
}

impl Schema for GripperState {
    fn schema() -> Value {
        object(&[(
            "state",
            json!({"type": "string", "enum": ["open", "closed"]}),
        )])
    }
}

impl Message for GripperState {
    const NAME: &'static str = "akl.Gripper";
}

/// `akl.Detector`: whether the online detector saw a straight line in one frame.
#[derive(Serialize, Deserialize)]
struct DetectorState {
    /// The detector's state.
    constrained: bool,
}

impl Schema for DetectorState {
    fn schema() -> Value {
        object(&[("constrained", boolean())])
    }
}

impl Message for DetectorState {
    const NAME: &'static str = "akl.Detector";
}

impl Schema for DemoHeader {
    fn schema() -> Value {
        object_with_optional(
            &[
                ("akl_demo", integer()),
                ("task", string()),
                ("frame", string()),
            ],
            &[
                ("calibration", string()),
                ("shapes", json!({"type": "object"})),
            ],
        )
    }
}

impl Message for DemoHeader {
    const NAME: &'static str = "akl.DemoHeader";
}

/// Streams a demonstration into an MCAP file.
pub(crate) struct McapDemoWriter<W: Write + Seek> {
    writer: McapWriter<W>,
    ee: Channel<PoseInFrame>,
    objects: Vec<Channel<PoseInFrame>>,
    gripper: Channel<GripperState>,
    detector: Channel<DetectorState>,
    dialogue: Channel<Log>,
    last_flush_time: f64,
    last_flush_clock: Instant,
}

fn write_error(e: akl_foxglove::WriteError) -> std::io::Error {
    std::io::Error::other(e)
}

fn pose_message(t: f64, frame: &str, pose: &Pose) -> PoseInFrame {
    PoseInFrame {
        timestamp: Time::at(t),
        frame_id: frame.to_string(),
        pose: pose.into(),
    }
}

impl<W: Write + Seek> McapDemoWriter<W> {
    /// Starts a recording of `header` with the named objects.
    pub(crate) fn new(out: W, header: &DemoHeader, objects: &[String]) -> std::io::Result<Self> {
        let options = mcap::WriteOptions::new().profile("akl").chunk_size(None);
        let mut writer = McapWriter::new(out, options).map_err(write_error)?;
        let header_channel = writer
            .channel::<DemoHeader>("/akl/header")
            .map_err(write_error)?;
        let ee = writer.channel("/ee").map_err(write_error)?;
        let object_channels = objects
            .iter()
            .map(|name| writer.channel(&format!("/objects/{name}")))
            .collect::<Result<Vec<_>, _>>()
            .map_err(write_error)?;
        let gripper = writer.channel("/gripper").map_err(write_error)?;
        let detector = writer.channel("/detector").map_err(write_error)?;
        let dialogue = writer.channel("/dialogue").map_err(write_error)?;
        let mut metadata = BTreeMap::new();
        metadata.insert("task".to_string(), header.task.clone());
        metadata.insert("frame".to_string(), header.frame.clone());
        metadata.insert("akl_demo".to_string(), header.akl_demo.to_string());
        if let Some(c) = &header.calibration {
            metadata.insert("calibration".to_string(), c.clone());
        }
        writer.metadata("akl_demo", metadata).map_err(write_error)?;
        writer
            .write(header_channel, 0.0, header)
            .map_err(write_error)?;
        writer.flush().map_err(write_error)?;
        Ok(McapDemoWriter {
            writer,
            ee,
            objects: object_channels,
            gripper,
            detector,
            dialogue,
            last_flush_time: 0.0,
            last_flush_clock: Instant::now(),
        })
    }

    /// Closes the chunk if a second of demonstration or wall-clock time has passed.
    fn maybe_flush(&mut self, t: f64) -> std::io::Result<()> {
        if t - self.last_flush_time >= FLUSH_INTERVAL.as_secs_f64()
            || self.last_flush_clock.elapsed() >= FLUSH_INTERVAL
        {
            self.writer.flush().map_err(write_error)?;
            self.last_flush_time = t;
            self.last_flush_clock = Instant::now();
        }
        Ok(())
    }

    /// Writes frame `i` of `demo`.
    pub(crate) fn write_frame(&mut self, demo: &Demo, i: usize) -> std::io::Result<()> {
        let t = demo.times[i];
        self.maybe_flush(t)?;
        let frame = &demo.header.frame;
        let w = &mut self.writer;
        w.write(self.ee, t, &pose_message(t, frame, &demo.ee[i]))
            .map_err(write_error)?;
        for (channel, track) in self.objects.iter().zip(&demo.objects) {
            w.write(*channel, t, &pose_message(t, frame, &track.poses[i]))
                .map_err(write_error)?;
        }
        let state = demo.gripper[i];
        w.write(self.gripper, t, &GripperState { state })
            .map_err(write_error)?;
        if let Some(&constrained) = demo.detector.get(i) {
            w.write(self.detector, t, &DetectorState { constrained })
                .map_err(write_error)?;
        }
        Ok(())
    }

    /// Writes a dialogue event as a `foxglove.Log` line (with `name` = `akl.<kind>`).
    pub(crate) fn write_event(&mut self, event: &DialogueEvent) -> std::io::Result<()> {
        let (name, message) = match event.kind {
            DialogueKind::Query => ("akl.query", QUERY.to_string()),
            DialogueKind::Answer(a) => ("akl.answer", answer_word(a).to_string()),
            DialogueKind::Suggestion => ("akl.suggestion", SUGGESTION.to_string()),
            DialogueKind::Keyframe => ("akl.keyframe", "keyframe".to_string()),
        };
        let line = Log::new(event.t, LogLevel::Info, name, message);
        self.writer
            .write(self.dialogue, event.t, &line)
            .map_err(write_error)
    }

    /// Writes a whole demonstration and finishes the file (the tests' round trips).
    #[cfg(test)]
    pub(crate) fn write_all(mut self, demo: &Demo) -> std::io::Result<W> {
        crate::session::write_demo(&mut self, demo)?;
        self.finish()
    }

    /// Writes the summary and returns the underlying writer.
    pub(crate) fn finish(self) -> std::io::Result<W> {
        self.writer.finish().map_err(write_error)
    }
}

impl<W: Write + Seek> RecordingSink for McapDemoWriter<W> {
    fn frame(&mut self, demo: &Demo, index: usize) -> std::io::Result<()> {
        self.write_frame(demo, index)
    }

    fn event(&mut self, event: &DialogueEvent) -> std::io::Result<()> {
        self.write_event(event)
    }
}

fn answer_word(a: Answer) -> &'static str {
    match a {
        Answer::Yes => "yes",
        Answer::No => "no",
        Answer::Unknown => "unknown",
    }
}

/// What a truncated recording lost.
#[derive(Debug, Clone, PartialEq)]
pub struct Truncation {
    /// Frames recovered.
    pub frames: usize,
    /// Time of the last recovered frame (s).
    pub last_time: f64,
    /// Why reading stopped.
    pub reason: String,
}

impl std::fmt::Display for Truncation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "the recording is truncated ({}); recovered {} frames up to t = {:.2} s, anything later is lost",
            self.reason, self.frames, self.last_time
        )
    }
}

/// Reads an MCAP demonstration; a truncated file gives what its complete chunks hold plus a
/// [`Truncation`] report.
pub fn read_mcap(bytes: &[u8]) -> Result<(Demo, Option<Truncation>), DemoError> {
    let stream = crate::mcap_read::messages(bytes, true)
        .map_err(|e| DemoError::Format(format!("a damaged MCAP file: {e}")))?;
    let mut header: Option<DemoHeader> = None;
    let mut frames: BTreeMap<u64, PartialFrame> = BTreeMap::new();
    let mut events: Vec<(f64, DialogueKind)> = Vec::new();
    let mut object_names: Vec<String> = Vec::new();
    let mut stopped: Option<String> = None;
    for message in stream {
        let message = match message {
            Ok(m) => m,
            Err(e) => {
                stopped = Some(e.to_string());
                break;
            }
        };
        let topic = message.channel.topic.as_str();
        let t_ns = message.log_time;
        let t = t_ns as f64 / 1e9;
        let bad =
            |what: &str| DemoError::Format(format!("message on {topic} at t = {t:.3} s: {what}"));
        let data = message.data.as_ref();
        match topic {
            "/akl/header" => header = Some(decode::<DemoHeader>(data).map_err(|e| bad(&e))?),
            "/ee" => {
                let pose = decode::<PoseRead>(data).and_then(PoseRead::into_pose);
                frames.entry(t_ns).or_default().ee = Some(pose.map_err(|e| bad(&e))?)
            }
            "/gripper" => {
                let GripperState { state } = decode(data).map_err(|e| bad(&e))?;
                frames.entry(t_ns).or_default().gripper = Some(state);
            }
            "/detector" => {
                let DetectorState { constrained } = decode(data).map_err(|e| bad(&e))?;
                frames.entry(t_ns).or_default().detector = Some(constrained);
            }
            "/dialogue" => {
                let LogRead { name, message } = decode(data).map_err(|e| bad(&e))?;
                let kind = match name.as_str() {
                    "akl.query" => DialogueKind::Query,
                    "akl.suggestion" => DialogueKind::Suggestion,
                    "akl.keyframe" => DialogueKind::Keyframe,
                    "akl.answer" => DialogueKind::Answer(
                        crate::dialogue::parse_answer(&message)
                            .ok_or_else(|| bad("an answer must say yes, no or unknown"))?,
                    ),
                    _ => continue,
                };
                events.push((t, kind));
            }
            other => {
                if let Some(name) = other.strip_prefix("/objects/") {
                    let index = match object_names.iter().position(|n| n == name) {
                        Some(i) => i,
                        None => {
                            object_names.push(name.to_string());
                            object_names.len() - 1
                        }
                    };
                    let pose = decode::<PoseRead>(data)
                        .and_then(PoseRead::into_pose)
                        .map_err(|e| bad(&e))?;
                    let frame = frames.entry(t_ns).or_default();
                    if frame.objects.len() <= index {
                        frame.objects.resize(index + 1, None);
                    }
                    frame.objects[index] = Some(pose);
                }
            }
        }
    }
    let header = header.ok_or_else(|| {
        DemoError::Format("no `/akl/header` message: not an AKL demonstration".into())
    })?;
    if header.akl_demo != DEMO_VERSION {
        return Err(DemoError::Format(format!(
            "unsupported akl_demo version {}",
            header.akl_demo
        )));
    }
    let mut demo = Demo::empty(header, &object_names);
    let mut checker = FrameChecker::default();
    let total = frames.len();
    let mut incomplete_tail = false;
    for (i, (t_ns, frame)) in frames.into_iter().enumerate() {
        let complete = frame.ee.is_some()
            && frame.gripper.is_some()
            && frame.objects.len() == object_names.len()
            && frame.objects.iter().all(Option::is_some);
        if !complete {
            if stopped.is_some() && i + 1 == total {
                incomplete_tail = true;
                break;
            }
            return Err(DemoError::Frame {
                frame: i,
                message: "some of its streams are missing (ee, gripper or an object)".into(),
            });
        }
        let t = t_ns as f64 / 1e9;
        let names: Vec<&str> = object_names.iter().map(String::as_str).collect();
        checker.check(t, &names).map_err(|e| DemoError::Frame {
            frame: i,
            message: e.into(),
        })?;
        demo.times.push(t);
        demo.ee.push(frame.ee.expect("checked complete"));
        demo.gripper.push(frame.gripper.expect("checked complete"));
        for (track, pose) in demo.objects.iter_mut().zip(frame.objects) {
            track.poses.push(pose.expect("checked complete"));
        }
        if let Some(c) = frame.detector {
            demo.detector.push(c);
        }
    }
    if !demo.detector.is_empty() && demo.detector.len() != demo.len() {
        return Err(DemoError::Format(
            "the detector state is missing on some frames".into(),
        ));
    }
    if demo.is_empty() {
        return Err(match stopped {
            Some(reason) => DemoError::Format(format!(
                "the recording is truncated ({reason}) before its first complete frame"
            )),
            None => DemoError::Empty,
        });
    }
    let last_time = *demo.times.last().expect("not empty");
    demo.events = events
        .into_iter()
        .filter(|(t, _)| *t <= last_time)
        .map(|(t, kind)| DialogueEvent {
            t,
            frame: crate::jsonl::frame_at(&demo.times, t),
            kind,
        })
        .collect();
    let truncation = stopped.map(|reason| Truncation {
        frames: demo.len(),
        last_time,
        reason: if incomplete_tail {
            format!("{reason}; a partial last frame was dropped")
        } else {
            reason
        },
    });
    Ok((demo, truncation))
}

#[derive(Default)]
struct PartialFrame {
    ee: Option<Pose>,
    gripper: Option<Gripper>,
    detector: Option<bool>,
    objects: Vec<Option<Pose>>,
}

/// A message's JSON as `T`; the error is serde's, without a position (the caller names the
/// topic and time).
fn decode<T: serde::de::DeserializeOwned>(data: &[u8]) -> Result<T, String> {
    serde_json::from_slice(data).map_err(|e| {
        let plain = match std::str::from_utf8(data) {
            Ok(text) => akl_tsr::describe_json_error(&e, text).2,
            Err(_) => e.to_string(),
        };
        if e.is_syntax() || e.is_eof() {
            format!("not JSON: {plain}")
        } else {
            plain
        }
    })
}

/// `foxglove.PoseInFrame` as read back: only the pose; its time is the message's log time.
#[derive(Deserialize)]
struct PoseRead {
    pose: PoseFields,
}

/// `foxglove.Pose`: a position and an orientation.
#[derive(Deserialize)]
struct PoseFields {
    position: Xyz,
    orientation: Xyzw,
}

/// `foxglove.Vector3`.
#[derive(Deserialize)]
struct Xyz {
    x: f64,
    y: f64,
    z: f64,
}

/// `foxglove.Quaternion`.
#[derive(Deserialize)]
struct Xyzw {
    x: f64,
    y: f64,
    z: f64,
    w: f64,
}

impl PoseRead {
    /// The pose, checked like every pose AKL reads (finite, unit quaternion).
    fn into_pose(self) -> Result<Pose, String> {
        let PoseFields {
            position: p,
            orientation: q,
        } = self.pose;
        let json = PoseJson {
            p: [p.x, p.y, p.z],
            q: [q.x, q.y, q.z, q.w],
        };
        json.to_pose().map_err(|e| format!("pose: {e}"))
    }
}

/// `foxglove.Log` as read back: which dialogue event (`name`) and, for an answer, its word.
#[derive(Deserialize)]
struct LogRead {
    name: String,
    #[serde(default)]
    message: String,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dialogue::AllYes;
    use crate::teach::run_session;
    use crate::teacher::{demonstrate, TeacherProfile};
    use crate::Calibration;
    use akl_scene::builtin;
    use std::io::Cursor;

    fn recorded() -> Demo {
        let task = builtin::resolve("inspection").unwrap();
        let sim = demonstrate(&task, &task.world, &TeacherProfile::careful(), 4).unwrap();
        run_session(&sim, Calibration::default(), &mut AllYes, None).unwrap()
    }

    fn write(demo: &Demo) -> Vec<u8> {
        let names: Vec<String> = demo.objects.iter().map(|o| o.name.clone()).collect();
        let writer = McapDemoWriter::new(Cursor::new(Vec::new()), &demo.header, &names).unwrap();
        writer.write_all(demo).unwrap().into_inner()
    }

    fn close(a: &Pose, b: &Pose) -> bool {
        (a.translation.vector - b.translation.vector).norm() < 1e-12
            && a.rotation.angle_to(&b.rotation) < 1e-9
    }

    #[test]
    fn a_recording_reads_back() {
        let demo = recorded();
        let (back, truncation) = read_mcap(&write(&demo)).unwrap();
        assert!(truncation.is_none());
        assert_eq!(back.header, demo.header);
        assert_eq!(back.len(), demo.len());
        assert_eq!(back.gripper, demo.gripper);
        assert_eq!(back.detector, demo.detector);
        assert!(back.ee.iter().zip(&demo.ee).all(|(a, b)| close(a, b)));
        assert_eq!(
            back.events.iter().map(|e| e.kind).collect::<Vec<_>>(),
            demo.events.iter().map(|e| e.kind).collect::<Vec<_>>()
        );
    }

    #[test]
    fn a_truncated_recording_keeps_all_but_the_last_second() {
        let demo = recorded();
        let bytes = write(&demo);
        let cut = &bytes[..bytes.len() * 2 / 3];
        let (back, truncation) = read_mcap(cut).unwrap();
        let truncation = truncation.expect("the cut is reported");
        assert_eq!(truncation.frames, back.len());
        let full_duration = *demo.times.last().unwrap();
        assert!(back.len() < demo.len());
        // Everything up to the last complete chunk survives: what is lost is at most a chunk
        // (one second) plus the part of the file that was cut off.
        let kept_fraction = back.len() as f64 / demo.len() as f64;
        assert!(kept_fraction > 0.5, "kept {kept_fraction}");
        assert!(back.times.last().unwrap() + 1.0 + full_duration / 3.0 + 1.0 >= full_duration);
        assert!(back.ee.iter().zip(&demo.ee).all(|(a, b)| close(a, b)));
        assert!(truncation.to_string().contains("recovered"));
    }

    #[test]
    fn every_message_fits_the_schema_written_beside_it() {
        let mut demo = recorded();
        demo.header.calibration = Some("default".into());
        let counts = akl_foxglove::check_mcap(&write(&demo)).unwrap();
        assert_eq!(counts["/akl/header"], 1);
        for topic in ["/ee", "/gripper", "/detector"] {
            assert_eq!(counts[topic], demo.len(), "{topic}");
        }
        for o in &demo.objects {
            assert_eq!(counts[&format!("/objects/{}", o.name)], demo.len());
        }
        assert!(!demo.events.is_empty());
        assert_eq!(counts["/dialogue"], demo.events.len());
    }

    #[test]
    fn garbage_is_not_a_demonstration() {
        assert!(matches!(read_mcap(b"hello"), Err(DemoError::Format(_))));
    }
    /// An MCAP demo whose only message besides a valid header and an `/ee` pose at t = 0.5 s is
    /// `message`, written as-is on `topic` at the same time.
    fn one_frame_with(topic: &str, message: Value) -> Vec<u8> {
        #[derive(Serialize)]
        #[serde(transparent)]
        struct Raw(Value);
        impl Schema for Raw {
            fn schema() -> Value {
                json!({"type": "object"})
            }
        }
        impl Message for Raw {
            const NAME: &'static str = "test.Raw";
        }
        let out = std::io::Cursor::new(Vec::new());
        let mut w = McapWriter::new(out, mcap::WriteOptions::default()).unwrap();
        let header = w.channel::<DemoHeader>("/akl/header").unwrap();
        w.write(header, 0.0, &DemoHeader::new("pick_place"))
            .unwrap();
        let ee = w.channel::<PoseInFrame>("/ee").unwrap();
        w.write(ee, 0.5, &pose_message(0.5, "world", &Pose::identity()))
            .unwrap();
        let raw = w.channel::<Raw>(topic).unwrap();
        w.write(raw, 0.5, &Raw(message)).unwrap();
        w.finish().unwrap().into_inner()
    }

    #[test]
    fn a_malformed_message_is_named_by_topic_and_time() {
        let cases = [
            (
                "/gripper",
                json!({"state": "ajar"}),
                "unknown variant `ajar`",
            ),
            (
                "/detector",
                json!({"constrained": "yes"}),
                "expected a boolean",
            ),
            (
                "/dialogue",
                json!({"name": "akl.answer", "message": "perhaps"}),
                "yes, no or unknown",
            ),
            (
                "/dialogue",
                json!({"message": "yes"}),
                "missing field `name`",
            ),
            (
                "/objects/part",
                json!({"pose": {"position": {"x": 0.0}}}),
                "missing field",
            ),
            (
                "/objects/part",
                json!({"pose": {"position": {"x": 0.0, "y": 0.0, "z": 0.0},
                                "orientation": {"x": 0.0, "y": 0.0, "z": 0.0, "w": 2.0}}}),
                "not unit length",
            ),
        ];
        for (topic, message, expected) in cases {
            let err = read_mcap(&one_frame_with(topic, message)).unwrap_err();
            let text = err.to_string();
            assert!(matches!(err, DemoError::Format(_)), "{text}");
            assert!(
                text.contains(&format!("message on {topic} at t = 0.500 s")),
                "{text}"
            );
            assert!(text.contains(expected), "{topic}: {text}");
        }
    }
}
