//! Importing a demonstration from a ROS 2 bag (MCAP with CDR messages), by naming its topics.
//!
//! A robot running ROS 2 records the teacher's demonstration with `ros2 bag record`; AKL reads
//! the bag directly. The end effector and every object come from a
//! `geometry_msgs/msg/PoseStamped` topic or from a frame of the transform tree
//! (`tf2_msgs/msg/TFMessage` on `/tf` and `/tf_static`); the gripper from a
//! `sensor_msgs/msg/JointState` topic whose finger joints give its opening. Every end-effector
//! message is a frame; objects and gripper hold their latest value (frames before every stream
//! has spoken are skipped). Poses given in another frame than the demonstration's are moved
//! into it through the transform tree.

use std::collections::BTreeMap;

use akl_tsr::{Gripper, Pose};
use k::nalgebra::{Quaternion, Translation3, UnitQuaternion};
use serde::{Deserialize, Serialize};

use crate::demo::{Demo, DemoHeader};
use crate::demo_error::DemoError;
use crate::mcap_io::MCAP_MAGIC;
use crate::validate::FrameChecker;

/// Where a pose stream comes from.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PoseSource {
    /// A `geometry_msgs/msg/PoseStamped` topic.
    Topic(String),
    /// A frame of the transform tree (`/tf`, `/tf_static`).
    Frame(String),
}

impl PoseSource {
    /// `tf:FRAME` names a frame of the transform tree; anything else a PoseStamped topic.
    pub fn parse(text: &str) -> PoseSource {
        match text.strip_prefix("tf:") {
            Some(frame) => PoseSource::Frame(frame.to_string()),
            None => PoseSource::Topic(text.to_string()),
        }
    }

    /// Whether this source is the PoseStamped topic `topic`.
    fn is_topic(&self, topic: &str) -> bool {
        matches!(self, PoseSource::Topic(t) if t == topic)
    }
}

/// Which streams of a bag make up the demonstration.
#[derive(Debug, Clone, PartialEq)]
pub struct Ros2Topics {
    /// The task demonstrated (the recording's header names it).
    pub task: String,
    /// The frame every pose is expressed in (the robot base or world frame of the bag).
    pub frame: String,
    /// The end effector (tool centre point).
    pub ee: PoseSource,
    /// The objects, by name.
    pub objects: Vec<(String, PoseSource)>,
    /// The `sensor_msgs/msg/JointState` topic of the gripper.
    pub gripper: String,
    /// The gripper counts as closed while the summed position of its finger joints (joints
    /// whose name contains `finger`, or all of them if none does) is below this (metres).
    pub closed_below: f64,
}

/// The type of an end-effector or object pose topic.
const POSE_STAMPED: &str = "geometry_msgs/msg/PoseStamped";
/// The type of the gripper's topic.
const JOINT_STATE: &str = "sensor_msgs/msg/JointState";
/// The type of `/tf` and `/tf_static`.
const TF_MESSAGE: &str = "tf2_msgs/msg/TFMessage";

impl Ros2Topics {
    /// The message types the import decodes on `topic`: one per role the topic plays (none
    /// when the import does not read it).
    fn expected_schemas(&self, topic: &str) -> impl Iterator<Item = &'static str> + '_ {
        let is_pose_topic = std::iter::once(&self.ee)
            .chain(self.objects.iter().map(|(_, source)| source))
            .any(|source| source.is_topic(topic));
        [
            (topic == "/tf" || topic == "/tf_static", TF_MESSAGE),
            (topic == self.gripper, JOINT_STATE),
            (is_pose_topic, POSE_STAMPED),
        ]
        .into_iter()
        .filter_map(|(reads, schema)| reads.then_some(schema))
    }

    /// Refuses a topic the import reads whose declared type is not the one it decodes, rather
    /// than failing later on bytes that do not parse. An empty type name (a bag without
    /// schemas) passes; `pkg/Type` is taken as `pkg/msg/Type`.
    fn check_schema(&self, topic: &str, schema: &str) -> Result<(), String> {
        if schema.is_empty() {
            return Ok(());
        }
        let declared = if schema.contains("/msg/") {
            schema.to_string()
        } else {
            schema.replacen('/', "/msg/", 1)
        };
        let Some(expected) = self.expected_schemas(topic).find(|e| *e != declared) else {
            return Ok(());
        };
        let hint = if schema.ends_with("JointState") && expected == POSE_STAMPED {
            ": a pose from joint states needs the robot's forward kinematics, which the import \
             does not do; name a frame of the transform tree instead (tf:FRAME, e.g. the tool \
             frame the robot's state publisher broadcasts)"
        } else {
            ""
        };
        Err(format!(
            "topic {topic} carries `{schema}`, but the import reads `{expected}` there{hint}"
        ))
    }
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
struct Time {
    sec: i32,
    nanosec: u32,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
struct Header {
    stamp: Time,
    #[serde(deserialize_with = "cdr_string")]
    frame_id: String,
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
struct Vector3Msg {
    x: f64,
    y: f64,
    z: f64,
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
struct QuaternionMsg {
    x: f64,
    y: f64,
    z: f64,
    w: f64,
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
struct PoseMsg {
    position: Vector3Msg,
    orientation: QuaternionMsg,
}

/// `geometry_msgs/msg/PoseStamped`.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct PoseStamped {
    header: Header,
    pose: PoseMsg,
}

#[derive(Debug, Clone, Copy, Serialize, Deserialize)]
struct TransformMsg {
    translation: Vector3Msg,
    rotation: QuaternionMsg,
}

#[derive(Debug, Clone, Serialize, Deserialize)]
struct TransformStamped {
    header: Header,
    #[serde(deserialize_with = "cdr_string")]
    child_frame_id: String,
    transform: TransformMsg,
}

/// `tf2_msgs/msg/TFMessage`.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct TfMessage {
    transforms: Vec<TransformStamped>,
}

/// `sensor_msgs/msg/JointState`.
#[derive(Debug, Clone, Serialize, Deserialize)]
struct JointState {
    header: Header,
    #[serde(deserialize_with = "cdr_strings")]
    name: Vec<String>,
    position: Vec<f64>,
    velocity: Vec<f64>,
    effort: Vec<f64>,
}

fn pose_of(p: Vector3Msg, q: QuaternionMsg) -> Result<Pose, String> {
    let quaternion = Quaternion::new(q.w, q.x, q.y, q.z);
    let norm = quaternion.norm();
    if (norm - 1.0).abs() >= 1e-3 || norm.is_nan() {
        return Err(format!("a quaternion of norm {norm:.4} is not a rotation"));
    }
    let values = [p.x, p.y, p.z, q.x, q.y, q.z, q.w];
    if values.iter().any(|v| !v.is_finite()) {
        return Err("a pose holds a non-finite number".into());
    }
    Ok(Pose::from_parts(
        Translation3::new(p.x, p.y, p.z),
        UnitQuaternion::from_quaternion(quaternion),
    ))
}

/// The latest transform of every frame to its parent.
#[derive(Debug, Default)]
struct TfTree {
    parent: BTreeMap<String, (String, Pose)>,
}

impl TfTree {
    fn insert(&mut self, t: &TransformStamped) -> Result<(), String> {
        let pose = pose_of(t.transform.translation, t.transform.rotation)?;
        self.parent
            .insert(t.child_frame_id.clone(), (t.header.frame_id.clone(), pose));
        Ok(())
    }

    /// The pose of `frame` in `root`, following the latest transforms.
    fn lookup(&self, frame: &str, root: &str) -> Option<Pose> {
        let mut pose = Pose::identity();
        let mut at = frame;
        for _ in 0..=self.parent.len() {
            if at == root {
                return Some(pose);
            }
            let (parent, to_parent) = self.parent.get(at)?;
            pose = to_parent * pose;
            at = parent;
        }
        None
    }
}

/// The import in progress: the latest value of every stream and the frames made so far.
struct Importer<'t> {
    topics: &'t Ros2Topics,
    tree: TfTree,
    objects: Vec<Option<Pose>>,
    gripper: Option<Gripper>,
    demo: Demo,
    checker: FrameChecker,
}

impl Importer<'_> {
    /// Takes one message of `topic`, logged at `t` seconds.
    fn take(&mut self, topic: &str, t: f64, data: &[u8]) -> Result<(), String> {
        let is_tf = topic == "/tf" || topic == "/tf_static";
        let mut ee_moved = false;
        if is_tf {
            let tf: TfMessage = decode(data)?;
            for transform in &tf.transforms {
                self.tree.insert(transform)?;
                ee_moved |= self.topics.ee == PoseSource::Frame(transform.child_frame_id.clone());
            }
        }
        if topic == self.topics.gripper {
            let state: JointState = decode(data)?;
            self.gripper = Some(gripper_state(&state, self.topics.closed_below)?);
        }
        for (latest, (_, source)) in self.objects.iter_mut().zip(&self.topics.objects) {
            if source.is_topic(topic) {
                *latest = Some(stamped_pose(data, &self.tree, &self.topics.frame)?);
            }
        }
        let ee = match &self.topics.ee {
            PoseSource::Topic(ee) if ee == topic => {
                Some(stamped_pose(data, &self.tree, &self.topics.frame)?)
            }
            PoseSource::Frame(f) if ee_moved => self.tree.lookup(f, &self.topics.frame),
            _ => None,
        };
        match ee {
            Some(ee) => self.push_frame(t, ee),
            None => Ok(()),
        }
    }

    /// Appends a frame at `t`, once the gripper and every object have been heard.
    fn push_frame(&mut self, t: f64, ee: Pose) -> Result<(), String> {
        let Some(gripper) = self.gripper else {
            return Ok(());
        };
        let mut poses = Vec::with_capacity(self.objects.len());
        for (latest, (_, source)) in self.objects.iter().zip(&self.topics.objects) {
            let pose = match source {
                PoseSource::Topic(_) => *latest,
                PoseSource::Frame(f) => self.tree.lookup(f, &self.topics.frame),
            };
            match pose {
                Some(p) => poses.push(p),
                None => return Ok(()),
            }
        }
        let names: Vec<&str> = self.demo.objects.iter().map(|o| o.name.as_str()).collect();
        self.checker.check(t, &names)?;
        self.demo.times.push(t);
        self.demo.ee.push(ee);
        self.demo.gripper.push(gripper);
        for (track, pose) in self.demo.objects.iter_mut().zip(poses) {
            track.poses.push(pose);
        }
        Ok(())
    }
}

/// Reads the demonstration `topics` name out of a ROS 2 bag; errors name the topic and the
/// message that is wrong.
pub fn import_ros2(bytes: &[u8], topics: &Ros2Topics) -> Result<Demo, DemoError> {
    if !bytes.starts_with(MCAP_MAGIC) {
        return Err(DemoError::Format(
            "not an MCAP file (a ROS 2 bag in MCAP format)".into(),
        ));
    }
    let stream = crate::mcap_read::messages(bytes, false)
        .map_err(|e| DemoError::Format(format!("reading the bag: {e}")))?;
    let names: Vec<String> = topics.objects.iter().map(|(n, _)| n.clone()).collect();
    let header = DemoHeader {
        frame: topics.frame.clone(),
        ..DemoHeader::new(topics.task.clone())
    };
    let mut importer = Importer {
        topics,
        tree: TfTree::default(),
        objects: vec![None; names.len()],
        gripper: None,
        demo: Demo::empty(header, &names),
        checker: FrameChecker::default(),
    };
    let mut counts = BTreeMap::<String, usize>::new();
    for message in stream {
        let message = message.map_err(|e| DemoError::Format(format!("reading the bag: {e}")))?;
        let topic = message.channel.topic.as_str();
        let count = counts.entry(topic.to_string()).or_default();
        *count += 1;
        let t = message.log_time as f64 * 1e-9;
        if *count == 1 {
            if let Some(schema) = &message.channel.schema {
                topics
                    .check_schema(topic, &schema.name)
                    .map_err(DemoError::Format)?;
            }
        }
        importer
            .take(topic, t, &message.data)
            .map_err(|m| DemoError::Format(format!("{topic}, message {count}: {m}")))?;
    }
    if importer.demo.is_empty() {
        let heard: Vec<String> = counts.into_keys().collect();
        return Err(DemoError::Format(format!(
            "no frame could be made: the end effector, every object and the gripper must all be heard; the bag has {}",
            if heard.is_empty() {
                "no messages".into()
            } else {
                format!("topics {}", heard.join(", "))
            }
        )));
    }
    Ok(importer.demo)
}

/// A CDR string (a u32 length counting a closing NUL, then the bytes) read byte by byte: cdr
/// allocates a string's stated length before reading it, so a corrupt length asked for up to
/// 4 GiB (found by the `ros2_bag` fuzz target); here memory grows only with the bytes there are.
struct CdrString(String);

impl<'de> Deserialize<'de> for CdrString {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Bytes;
        impl<'de> serde::de::Visitor<'de> for Bytes {
            type Value = CdrString;

            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a CDR string")
            }

            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<CdrString, A::Error> {
                use serde::de::Error;
                let short = || A::Error::custom("a string shorter than its length");
                let length: u32 = seq.next_element()?.ok_or_else(short)?;
                let mut bytes = Vec::new();
                for _ in 0..length {
                    bytes.push(seq.next_element::<u8>()?.ok_or_else(short)?);
                }
                bytes.pop(); // the closing NUL
                String::from_utf8(bytes)
                    .map(CdrString)
                    .map_err(A::Error::custom)
            }
        }
        // cdr reads a tuple's elements one after another with nothing in between, each aligned
        // as on its own: the length as a u32, then the bytes, as its string reader does.
        deserializer.deserialize_tuple(usize::MAX, Bytes)
    }
}

/// A CDR string field (see [`CdrString`]).
fn cdr_string<'de, D: serde::Deserializer<'de>>(deserializer: D) -> Result<String, D::Error> {
    CdrString::deserialize(deserializer).map(|s| s.0)
}

/// A CDR sequence of strings (see [`CdrString`]).
fn cdr_strings<'de, D: serde::Deserializer<'de>>(deserializer: D) -> Result<Vec<String>, D::Error> {
    let strings = Vec::<CdrString>::deserialize(deserializer)?;
    Ok(strings.into_iter().map(|s| s.0).collect())
}

fn decode<'de, T: Deserialize<'de>>(data: &'de [u8]) -> Result<T, String> {
    cdr::deserialize(data).map_err(|e| format!("not the expected CDR message: {e}"))
}

/// A PoseStamped message's pose in `frame`.
fn stamped_pose(data: &[u8], tree: &TfTree, frame: &str) -> Result<Pose, String> {
    let msg: PoseStamped = decode(data)?;
    let pose = pose_of(msg.pose.position, msg.pose.orientation)?;
    if msg.header.frame_id == frame || msg.header.frame_id.is_empty() {
        return Ok(pose);
    }
    let to_frame = tree.lookup(&msg.header.frame_id, frame).ok_or_else(|| {
        format!(
            "the pose is in frame `{}`, which the transform tree does not link to `{frame}`",
            msg.header.frame_id
        )
    })?;
    Ok(to_frame * pose)
}

/// Open or closed from the finger joints' summed position.
fn gripper_state(state: &JointState, closed_below: f64) -> Result<Gripper, String> {
    if state.name.len() != state.position.len() {
        return Err(format!(
            "{} joint names but {} positions",
            state.name.len(),
            state.position.len()
        ));
    }
    let fingers: Vec<f64> = state
        .name
        .iter()
        .zip(&state.position)
        .filter(|(n, _)| n.contains("finger"))
        .map(|(_, p)| *p)
        .collect();
    let positions = if fingers.is_empty() {
        &state.position[..]
    } else {
        &fingers[..]
    };
    if positions.is_empty() {
        return Err("the joint state names no joints".into());
    }
    let opening: f64 = positions.iter().sum();
    if !opening.is_finite() {
        return Err("a finger position is not finite".into());
    }
    Ok(if opening < closed_below {
        Gripper::Closed
    } else {
        Gripper::Open
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    fn stamp(t: f64) -> Time {
        Time {
            sec: t.floor() as i32,
            nanosec: ((t - t.floor()) * 1e9) as u32,
        }
    }

    fn header(t: f64, frame: &str) -> Header {
        Header {
            stamp: stamp(t),
            frame_id: frame.into(),
        }
    }

    fn v(x: f64, y: f64, z: f64) -> Vector3Msg {
        Vector3Msg { x, y, z }
    }

    const IDENTITY: QuaternionMsg = QuaternionMsg {
        x: 0.0,
        y: 0.0,
        z: 0.0,
        w: 1.0,
    };

    struct Bag {
        writer: mcap::Writer<Cursor<Vec<u8>>>,
        channels: BTreeMap<String, u16>,
        sequence: u32,
    }

    impl Bag {
        fn new() -> Bag {
            Bag {
                writer: mcap::Writer::new(Cursor::new(Vec::new())).unwrap(),
                channels: BTreeMap::new(),
                sequence: 0,
            }
        }

        fn send<T: Serialize>(&mut self, topic: &str, schema: &str, t: f64, msg: &T) {
            let writer = &mut self.writer;
            let channel = *self.channels.entry(topic.into()).or_insert_with(|| {
                let s = writer.add_schema(schema, "ros2msg", b"").unwrap();
                writer
                    .add_channel(s, topic, "cdr", &BTreeMap::new())
                    .unwrap()
            });
            self.sequence += 1;
            let data = cdr::serialize::<_, _, cdr::CdrLe>(msg, cdr::Infinite).unwrap();
            self.writer
                .write_to_known_channel(
                    &mcap::records::MessageHeader {
                        channel_id: channel,
                        sequence: self.sequence,
                        log_time: (t * 1e9) as u64,
                        publish_time: (t * 1e9) as u64,
                    },
                    &data,
                )
                .unwrap();
        }

        fn finish(mut self) -> Vec<u8> {
            self.writer.finish().unwrap();
            self.writer.into_inner().into_inner()
        }
    }

    fn joints(t: f64, opening: f64) -> JointState {
        JointState {
            header: header(t, ""),
            name: vec![
                "panda_joint1".into(),
                "panda_finger_joint1".into(),
                "panda_finger_joint2".into(),
            ],
            position: vec![0.3, opening / 2.0, opening / 2.0],
            velocity: vec![],
            effort: vec![],
        }
    }

    /// A bag where the hand moves along x, closes at t = 0.5 and the part is seen through the
    /// transform tree, in a camera frame mounted 1 m above the base.
    fn bag() -> Vec<u8> {
        let mut bag = Bag::new();
        let tf = |t: f64, parent: &str, child: &str, p: Vector3Msg| TfMessage {
            transforms: vec![TransformStamped {
                header: header(t, parent),
                child_frame_id: child.into(),
                transform: TransformMsg {
                    translation: p,
                    rotation: IDENTITY,
                },
            }],
        };
        bag.send(
            "/tf_static",
            "tf2_msgs/msg/TFMessage",
            0.0,
            &tf(0.0, "base", "camera", v(0.0, 0.0, 1.0)),
        );
        for i in 0..=10 {
            let t = i as f64 * 0.1;
            bag.send(
                "/joint_states",
                "sensor_msgs/msg/JointState",
                t,
                &joints(t, if t < 0.5 { 0.08 } else { 0.04 }),
            );
            bag.send(
                "/tf",
                "tf2_msgs/msg/TFMessage",
                t,
                &tf(t, "camera", "part", v(0.4, 0.0, -0.8)),
            );
            let ee = PoseStamped {
                header: header(t, "base"),
                pose: PoseMsg {
                    position: v(0.3 + t * 0.1, 0.0, 0.2),
                    orientation: IDENTITY,
                },
            };
            bag.send("/ee_pose", "geometry_msgs/msg/PoseStamped", t, &ee);
        }
        bag.finish()
    }

    fn topics() -> Ros2Topics {
        Ros2Topics {
            task: "pick".into(),
            frame: "base".into(),
            ee: PoseSource::parse("/ee_pose"),
            objects: vec![("part".into(), PoseSource::parse("tf:part"))],
            gripper: "/joint_states".into(),
            closed_below: 0.075,
        }
    }

    #[test]
    fn a_bag_becomes_a_demonstration() {
        let demo = import_ros2(&bag(), &topics()).unwrap();
        assert_eq!(demo.len(), 11);
        assert_eq!(demo.header.frame, "base");
        assert!((demo.ee[10].translation.x - 0.4).abs() < 1e-12);
        let part = &demo.objects[0];
        assert_eq!(part.name, "part");
        assert!(
            (part.poses[3].translation.vector - k::nalgebra::Vector3::new(0.4, 0.0, 0.2)).norm()
                < 1e-12
        );
        let closed: Vec<bool> = demo.gripper.iter().map(|g| *g == Gripper::Closed).collect();
        assert_eq!(closed.iter().position(|c| *c), Some(5));
        assert!(demo.detector.is_empty());
    }

    #[test]
    fn missing_or_unlinked_streams_are_named() {
        let mut t = topics();
        t.gripper = "/gripper".into();
        let e = import_ros2(&bag(), &t).unwrap_err().to_string();
        assert!(e.contains("no frame") && e.contains("/joint_states"), "{e}");
        let mut t = topics();
        t.frame = "map".into();
        let e = import_ros2(&bag(), &t).unwrap_err().to_string();
        assert!(e.contains("/ee_pose") && e.contains("`map`"), "{e}");
        let e = import_ros2(b"nonsense", &topics()).unwrap_err().to_string();
        assert!(e.contains("MCAP"), "{e}");
    }

    #[test]
    fn a_topic_of_the_wrong_type_is_named_with_its_type() {
        let mut t = topics();
        t.ee = PoseSource::parse("/joint_states");
        let e = import_ros2(&bag(), &t).unwrap_err().to_string();
        assert!(
            e.contains("/joint_states")
                && e.contains("sensor_msgs/msg/JointState")
                && e.contains("tf:FRAME"),
            "{e}"
        );
        let mut t = topics();
        t.gripper = "/ee_pose".into();
        let e = import_ros2(&bag(), &t).unwrap_err().to_string();
        assert!(
            e.contains("/ee_pose") && e.contains("geometry_msgs/msg/PoseStamped"),
            "{e}"
        );
        assert!(!e.contains("tf:FRAME"), "{e}");
    }

    #[test]
    fn a_string_longer_than_its_message_is_an_error_without_its_memory() {
        // A little-endian CDR header, a stamp, then a frame id claiming 4 GiB and holding 3
        // bytes: cdr allocated the 4 GiB first (the `ros2_bag` fuzz target's find).
        let mut data = vec![0, 1, 0, 0];
        data.extend_from_slice(&[0; 8]);
        data.extend_from_slice(&u32::MAX.to_le_bytes());
        data.extend_from_slice(b"abc");
        let e = decode::<Header>(&data).unwrap_err();
        assert!(e.contains("not the expected CDR message"), "{e}");
        let names = JointState {
            name: vec!["a".into(), String::new(), "finger_joint1".into()],
            ..joints(0.0, 0.08)
        };
        let data = cdr::serialize::<_, _, cdr::CdrLe>(&names, cdr::Infinite).unwrap();
        assert_eq!(decode::<JointState>(&data).unwrap().name, names.name);
    }

    #[test]
    fn type_names_without_msg_and_bags_without_types_pass() {
        let t = topics();
        assert!(t
            .check_schema("/ee_pose", "geometry_msgs/PoseStamped")
            .is_ok());
        assert!(t.check_schema("/ee_pose", "").is_ok());
        assert!(t.check_schema("/other", "anything/msg/Else").is_ok());
        assert!(t
            .check_schema("/tf", "geometry_msgs/msg/PoseStamped")
            .is_err());
    }
}
