//! Traces: one trial as an MCAP file with Foxglove schemas, to watch in Foxglove's 3D panel.
//!
//! Channels (JSON messages):
//! - `/tf` (`foxglove.FrameTransforms`): every robot link's frame in `world`, over time;
//! - `/robot` (`foxglove.SceneUpdate`): the links' collision shapes, locked to their frames;
//! - `/robot/visual` (`foxglove.SceneUpdate`): the links' visual meshes, as models;
//! - `/objects` (`foxglove.SceneUpdate`): the task's objects, over time;
//! - `/keyframes` (`foxglove.SceneUpdate`): each keyframe's TSR (its position bounds as a box,
//!   grounded on the reference's pose when reached) and the TCP reached, green or red;
//! - `/lines` (`foxglove.SceneUpdate`): each `move_in_line` segment's line and executed path;
//! - `/events` (`foxglove.Log`): grasps, releases, collisions, a planning failure and the
//!   verdict;
//! - `/perceived` (`foxglove.SceneUpdate`): the objects where the planner perceived them;
//! - `/rejected` (`foxglove.SceneUpdate`): when planning failed at a keyframe, the arm at IK
//!   solutions of its TSR (grounded on the perceived world) that were rejected, each with what
//!   it collides with;
//! - `/joint_states` (`akl.JointState`): the simulated joint positions and gripper opening;
//! - `/contacts` (`foxglove.SceneUpdate`): contact points of the arm and the held object, red
//!   where they are collisions, sized by their force.
//!
//! The messages are `akl-foxglove`'s types; `draw` builds a scene entity's primitives and
//! `failure` draws a trial whose planning failed.

use akl_foxglove::schema::{array, number, object, string};
use akl_foxglove::{
    Channel, Encoded, FrameTransform, FrameTransforms, Log, LogLevel, McapWriter, Message,
    SceneUpdate, Schema, Time, WriteError,
};
use akl_planner::{GripperAction, Robot};
use akl_scene::World;
use akl_tsr::nalgebra::{Translation3, Vector3};
use akl_tsr::{Pose, TaskSpec};
use serde::Serialize;
use serde_json::Value;
use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::Path;

use crate::error::ExecError;
use crate::report::TrialReport;
use crate::timeline::{Frame, Timeline};

mod draw;
mod failure;

use draw::{opaque, Primitives, FAIL, FURNITURE, LINE, MOVABLE, PASS, PERCEIVED, ROBOT};

/// Frames per simulated second a trace records.
pub const TRACE_RATE: f64 = 30.0;

/// The `name` of every `foxglove.Log` line of a trace.
const LOG_NAME: &str = "akl.execute";

/// `akl.JointState`: the simulated joints, by name, and the gripper opening.
#[derive(Serialize)]
struct JointState {
    timestamp: Time,
    name: Vec<String>,
    position: Vec<f64>,
    gripper_width: f64,
}

impl Schema for JointState {
    fn schema() -> Value {
        object(&[
            ("timestamp", Time::schema()),
            ("name", array(string())),
            ("position", array(number())),
            ("gripper_width", number()),
        ])
    }
}

impl Message for JointState {
    const NAME: &'static str = "akl.JointState";
}

/// The channels of a trace being written.
#[derive(Clone, Copy)]
struct Channels {
    tf: Channel<FrameTransforms>,
    robot: Channel<SceneUpdate>,
    visual: Channel<SceneUpdate>,
    objects: Channel<SceneUpdate>,
    perceived: Channel<SceneUpdate>,
    keyframes: Channel<SceneUpdate>,
    rejected: Channel<SceneUpdate>,
    lines: Channel<SceneUpdate>,
    joints: Channel<JointState>,
    contacts: Channel<SceneUpdate>,
    events: Channel<Log>,
}

impl Channels {
    fn new<W: std::io::Write + std::io::Seek>(w: &mut McapWriter<W>) -> Result<Self, WriteError> {
        Ok(Channels {
            tf: w.channel("/tf")?,
            robot: w.channel("/robot")?,
            visual: w.channel("/robot/visual")?,
            objects: w.channel("/objects")?,
            perceived: w.channel("/perceived")?,
            keyframes: w.channel("/keyframes")?,
            rejected: w.channel("/rejected")?,
            lines: w.channel("/lines")?,
            joints: w.channel("/joint_states")?,
            contacts: w.channel("/contacts")?,
            events: w.channel("/events")?,
        })
    }
}

/// The messages of a trace, encoded, before they are sorted by time and written.
struct Outbox {
    channels: Channels,
    messages: Vec<Encoded>,
}

impl Outbox {
    fn push<M: Message>(
        &mut self,
        channel: Channel<M>,
        t: f64,
        message: &M,
    ) -> Result<(), WriteError> {
        self.messages.push(channel.encode(t, message)?);
        Ok(())
    }
}

/// One trial and what it needs to be drawn.
pub(crate) struct TraceInput<'a> {
    /// The robot.
    pub robot: &'a Robot,
    /// The world the trial ran in (object shapes and names).
    pub world: &'a World,
    /// The spec executed.
    pub spec: &'a TaskSpec,
    /// The trial's report.
    pub report: &'a TrialReport,
    /// The trial's recorded frames.
    pub timeline: &'a Timeline,
}

/// Writes `input` as an MCAP trace to `path` (atomically: a temporary file, then renamed).
pub(crate) fn write_trace(path: &Path, input: &TraceInput) -> Result<(), ExecError> {
    let error = |e: WriteError| ExecError::Write {
        path: path.to_path_buf(),
        source: std::io::Error::other(e),
    };
    let bytes = trace_bytes(input).map_err(error)?;
    akl_tsr::io::write_atomic(path, &bytes).map_err(|source| ExecError::Write {
        path: path.to_path_buf(),
        source,
    })
}

fn trace_bytes(input: &TraceInput) -> Result<Vec<u8>, WriteError> {
    let options = mcap::WriteOptions::new().profile("akl");
    let mut writer = McapWriter::new(Cursor::new(Vec::new()), options)?;
    let channels = Channels::new(&mut writer)?;
    let r = input.report;
    let metadata = BTreeMap::from([
        ("task".to_string(), input.spec.task.clone()),
        ("method".to_string(), input.spec.method.clone()),
        ("trial".to_string(), r.trial.to_string()),
        ("seed".to_string(), r.seed.to_string()),
        ("passed".to_string(), r.passed.to_string()),
    ]);
    writer.metadata("akl_trace", metadata)?;
    let mut out = Outbox {
        channels,
        messages: Vec::new(),
    };
    out.push(channels.robot, 0.0, &robot_shapes(input.robot))?;
    if let Some(models) = crate::visual::robot_models(input.robot) {
        out.push(channels.visual, 0.0, &models)?;
    }
    let world_poses: Vec<Pose> = input.world.objects.iter().map(|o| o.pose).collect();
    out.push(
        channels.objects,
        0.0,
        &objects(input.world, 0.0, &world_poses, None),
    )?;
    if let Some(seen) = &input.timeline.perceived {
        let poses: Vec<Pose> = seen.objects.iter().map(|o| o.pose).collect();
        out.push(
            channels.perceived,
            0.0,
            &objects(seen, 0.0, &poses, Some(PERCEIVED)),
        )?;
    }
    if let Some(failure) = &input.timeline.planning_failure {
        failure::planning_failure(input, failure, &mut out)?;
    }
    for frame in &input.timeline.frames {
        let t = frame.t;
        out.push(channels.joints, t, &joint_state(input.robot, frame))?;
        out.push(channels.contacts, t, &contacts(frame))?;
        out.push(channels.tf, t, &transforms(input.robot, t, &frame.links))?;
        out.push(
            channels.objects,
            t,
            &objects(input.world, t, &frame.objects, None),
        )?;
    }
    for (t, update) in keyframes(input) {
        out.push(channels.keyframes, t, &update)?;
    }
    for (t, update) in lines(input) {
        out.push(channels.lines, t, &update)?;
    }
    for (t, line) in events(input) {
        out.push(channels.events, t, &line)?;
    }
    out.messages.sort_by(|a, b| a.t.total_cmp(&b.t));
    for message in &out.messages {
        writer.write_encoded(message)?;
    }
    Ok(writer.finish()?.into_inner())
}

fn robot_shapes(robot: &Robot) -> SceneUpdate {
    let entities = robot
        .links()
        .iter()
        .filter(|l| !l.shapes.is_empty())
        .map(|l| {
            let mut p = Primitives::default();
            for s in &l.shapes {
                p.geometry(&s.geometry, &s.origin, ROBOT);
            }
            p.entity(0.0, &l.name, &l.name, true)
        })
        .collect();
    SceneUpdate::new(entities)
}

fn transforms(robot: &Robot, t: f64, links: &[Pose]) -> FrameTransforms {
    let transforms = robot
        .links()
        .iter()
        .zip(links)
        .map(|(l, p)| FrameTransform {
            timestamp: Time::at(t),
            parent_frame_id: "world".into(),
            child_frame_id: l.name.clone(),
            translation: (&p.translation.vector).into(),
            rotation: (&p.rotation).into(),
        })
        .collect();
    FrameTransforms { transforms }
}

/// The objects of `world` at `poses`, in their usual colours or all in `tint`.
fn objects(world: &World, t: f64, poses: &[Pose], tint: Option<[f64; 4]>) -> SceneUpdate {
    let entities = world
        .objects
        .iter()
        .zip(poses)
        .map(|(o, at)| {
            let mut p = Primitives::default();
            let rgba = tint.unwrap_or(if o.movable { MOVABLE } else { FURNITURE });
            p.shape(&o.shape, at, rgba);
            p.entity(t, "world", &o.name, false)
        })
        .collect();
    SceneUpdate::new(entities)
}

fn joint_state(robot: &Robot, frame: &Frame) -> JointState {
    JointState {
        timestamp: Time::at(frame.t),
        name: robot.joint_names().to_vec(),
        position: frame.joints.clone(),
        gripper_width: frame.width,
    }
}

fn contacts(frame: &Frame) -> SceneUpdate {
    let mut p = Primitives::default();
    for c in &frame.contacts {
        let radius = 0.003 + 0.0002 * c.force.min(100.0);
        let rgba = if c.collision { FAIL } else { PASS };
        p.sphere(
            &Pose::translation(c.point[0], c.point[1], c.point[2]),
            radius,
            [rgba[0], rgba[1], rgba[2], 0.9],
        );
    }
    SceneUpdate::new(vec![p.entity(frame.t, "world", "contacts", false)])
}

/// Each keyframe's TSR grounded where the simulation reached it, and the TCP reached.
fn keyframes(input: &TraceInput) -> Vec<(f64, SceneUpdate)> {
    input
        .report
        .keyframes
        .iter()
        .filter_map(|c| {
            let kf = input.spec.keyframes.get(c.keyframe)?;
            let reference = c.grounded_on.to_pose().ok()?;
            let tcp = c.tcp.to_pose().ok()?;
            let mut p = Primitives::default();
            let rgba = if c.reached { PASS } else { FAIL };
            let nominal = p.tsr_region(&reference, &kf.tsr, rgba);
            p.arrow(&tcp, 0.06, opaque(rgba));
            p.text(
                &(Translation3::new(0.0, 0.0, 0.04) * nominal),
                &format!("keyframe {} ({}, {})", c.keyframe, kf.kind, kf.gripper),
            );
            let id = format!("keyframe {}", c.keyframe);
            Some((
                c.t,
                SceneUpdate::new(vec![p.entity(c.t, "world", &id, false)]),
            ))
        })
        .collect()
}

/// Each `move_in_line` segment's line and the path the TCP took along it.
fn lines(input: &TraceInput) -> Vec<(f64, SceneUpdate)> {
    let tcp = input.robot.tcp_link();
    input
        .report
        .lines
        .iter()
        .map(|l| {
            let mut p = Primitives::default();
            p.polyline(&[Vector3::from(l.from), Vector3::from(l.to)], 0.003, LINE);
            let path: Vec<Vector3<f64>> = input
                .timeline
                .frames
                .iter()
                .filter(|f| f.t >= l.start - 1e-9 && f.t <= l.end + 1e-9)
                .filter_map(|f| f.links.get(tcp).map(|p| p.translation.vector))
                .collect();
            let rgba = if l.within { PASS } else { FAIL };
            p.polyline(&path, 0.002, opaque(rgba));
            let id = format!("line to keyframe {}", l.keyframe);
            (
                l.end,
                SceneUpdate::new(vec![p.entity(l.end, "world", &id, false)]),
            )
        })
        .collect()
}

/// Releases, grasps, collisions, failed grasps and the verdict, as log lines.
fn events(input: &TraceInput) -> Vec<(f64, Log)> {
    use LogLevel::{Error, Info};
    let r = input.report;
    let mut out = Vec::new();
    let mut say = |t: f64, level: LogLevel, message: String| {
        out.push((t, Log::new(t, level, LOG_NAME, message)));
    };
    if let Some(plan) = &input.timeline.plan {
        for e in plan
            .events
            .iter()
            .filter(|e| e.action == GripperAction::Open)
        {
            say(
                e.t,
                Info,
                format!("release {} (keyframe {})", e.object, e.keyframe),
            );
        }
    }
    for g in &r.grasps {
        let (level, message) = match &g.grasped {
            Some(n) if *n == g.planned => (Info, format!("grasped {n} (keyframe {})", g.keyframe)),
            Some(n) => (
                Error,
                format!(
                    "grasped {n} instead of {} (keyframe {})",
                    g.planned, g.keyframe
                ),
            ),
            None => (
                Error,
                format!(
                    "closed on nothing; {} is not between the fingers (keyframe {})",
                    g.planned, g.keyframe
                ),
            ),
        };
        say(g.t, level, message);
    }
    for c in &r.collisions {
        say(c.t, Error, format!("collision: {}", c.describe()));
    }
    for f in r
        .failures
        .iter()
        .filter(|f| f.cause == crate::report::Cause::GraspFailed)
    {
        say(r.simulated_seconds, Error, f.detail.clone());
    }
    let verdict = if r.passed {
        format!("trial {} passed", r.trial)
    } else {
        let failures: Vec<String> = r
            .failures
            .iter()
            .map(|f| format!("{}: {}", f.cause, f.detail))
            .collect();
        format!("trial {} failed: {}", r.trial, failures.join("; "))
    };
    say(
        r.simulated_seconds,
        if r.passed { Info } else { Error },
        verdict,
    );
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::batch::{Batch, BatchOptions};
    use crate::options::ExecOptions;

    /// A trial traced and read back.
    struct Traced {
        report: TrialReport,
        timeline: Timeline,
        /// Each topic's messages in time order.
        topics: BTreeMap<String, Vec<Value>>,
    }

    /// Runs one randomized trial of `spec` on inspection (seed 3), writes its trace to a
    /// scratch file named after `name`, checks every message against the schema written for
    /// its channel, and reads it back.
    fn traced(spec: &TaskSpec, name: &str) -> Traced {
        let robot = Robot::panda().unwrap();
        let task = akl_scene::builtin::task("inspection").unwrap().unwrap();
        let exec = ExecOptions::default();
        let options = BatchOptions {
            trials: 1,
            randomize: true,
            seed: 3,
            jobs: 1,
        };
        let batch = Batch::new(&robot, &task, spec, &exec, options).unwrap();
        let (report, timeline) = batch.record(0, TRACE_RATE).unwrap();
        let dir = std::env::temp_dir().join(format!("akl-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("trace.mcap");
        let input = TraceInput {
            robot: &robot,
            world: batch.world(0).unwrap(),
            spec,
            report: &report,
            timeline: &timeline,
        };
        write_trace(&path, &input).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
        let checked = akl_foxglove::check_mcap(&bytes).unwrap();
        let mut topics: BTreeMap<String, Vec<Value>> = BTreeMap::new();
        let mut last = 0;
        for m in mcap::MessageStream::new(&bytes).unwrap() {
            let m = m.unwrap();
            assert!(m.log_time >= last, "messages in time order");
            last = m.log_time;
            let value: Value = serde_json::from_slice(&m.data).unwrap();
            topics
                .entry(m.channel.topic.clone())
                .or_default()
                .push(value);
        }
        let counts: BTreeMap<String, usize> =
            topics.iter().map(|(t, m)| (t.clone(), m.len())).collect();
        assert_eq!(checked, counts, "every message was checked");
        Traced {
            report,
            timeline,
            topics,
        }
    }

    fn xyz(v: &Value) -> Vector3<f64> {
        Vector3::new(
            v["x"].as_f64().unwrap(),
            v["y"].as_f64().unwrap(),
            v["z"].as_f64().unwrap(),
        )
    }

    fn seconds(stamp: &Value) -> f64 {
        stamp["sec"].as_f64().unwrap() + stamp["nsec"].as_f64().unwrap() * 1e-9
    }

    #[test]
    fn a_trace_shows_the_simulated_trial() {
        let task = akl_scene::builtin::task("inspection").unwrap().unwrap();
        let spec = task.truth.clone().unwrap();
        let Traced {
            report,
            timeline,
            topics,
        } = traced(&spec, "trace");
        let robot = Robot::panda().unwrap();
        let frames = &timeline.frames;
        let count = |t: &str| topics.get(t).map_or(0, Vec::len);
        assert!(report.passed);
        assert_eq!(count("/robot"), 1);
        assert_eq!(count("/perceived"), 1);
        assert_eq!(count("/rejected"), 0);
        // The real arm's look: one model per link with a visual mesh, locked to its frame,
        // its binary STL embedded (base64 in JSON).
        assert_eq!(count("/robot/visual"), 1);
        let models = topics["/robot/visual"][0]["entities"].as_array().unwrap();
        assert_eq!(models.len(), 11);
        for e in models {
            let m = &e["models"][0];
            assert_eq!(m["media_type"], "model/stl");
            assert!(e["frame_locked"].as_bool().unwrap());
            assert!(m["data"].as_str().unwrap().len() > 1000);
        }
        // The collision model that was checked: a hull per meshed link, drawn as triangles.
        let hulls = topics["/robot"][0]["entities"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|e| !e["triangles"].as_array().unwrap().is_empty())
            .count();
        assert_eq!(hulls, 11);

        // Each frame's links, joints and objects are the simulated ones, at the frame's time.
        assert!(frames.len() > 100);
        assert_eq!(count("/tf"), frames.len());
        assert_eq!(count("/joint_states"), frames.len());
        assert_eq!(count("/contacts"), frames.len());
        assert_eq!(count("/objects"), frames.len() + 1);
        let tcp = robot.tcp_link();
        for (n, frame) in frames.iter().enumerate().step_by(37) {
            let tf = &topics["/tf"][n]["transforms"];
            assert_eq!(tf.as_array().unwrap().len(), robot.links().len());
            assert_eq!(tf[tcp]["child_frame_id"], robot.links()[tcp].name.as_str());
            assert!((seconds(&tf[tcp]["timestamp"]) - frame.t).abs() < 1e-9);
            let at = xyz(&tf[tcp]["translation"]);
            assert!((at - frame.links[tcp].translation.vector).norm() < 1e-12);
            let joints = &topics["/joint_states"][n];
            assert_eq!(joints["name"].as_array().unwrap().len(), frame.joints.len());
            assert_eq!(joints["position"][3].as_f64().unwrap(), frame.joints[3]);
            assert_eq!(joints["gripper_width"].as_f64().unwrap(), frame.width);
            // The first message on /objects is the world before the trial.
            let objects = &topics["/objects"][n + 1]["entities"];
            for (k, o) in task.world.objects.iter().enumerate() {
                assert_eq!(objects[k]["id"], o.name.as_str());
                let drawn = &objects[k]["cubes"][0]["pose"]["position"];
                if !drawn.is_null() {
                    let at = xyz(drawn);
                    assert!((at - frame.objects[k].translation.vector).norm() < 1e-12);
                }
            }
        }
        // Some contact was drawn, where the simulation saw it.
        let (n, frame) = frames
            .iter()
            .enumerate()
            .find(|(_, f)| !f.contacts.is_empty())
            .expect("the part is grasped: the pads touch it");
        let spheres = &topics["/contacts"][n]["entities"][0]["spheres"];
        assert_eq!(spheres.as_array().unwrap().len(), frame.contacts.len());
        let p = frame.contacts[0].point;
        assert!((xyz(&spheres[0]["pose"]["position"]) - Vector3::from(p)).norm() < 1e-12);

        // One TSR box per keyframe, green where reached, and the line drawn from its report.
        assert_eq!(count("/keyframes"), spec.keyframes.len());
        for k in &topics["/keyframes"] {
            let cubes = k["entities"][0]["cubes"].as_array().unwrap();
            assert_eq!(cubes.len(), 1);
            assert_eq!(cubes[0]["color"]["g"].as_f64().unwrap(), PASS[1]);
            assert!(k["entities"][0]["texts"][0]["text"]
                .as_str()
                .unwrap()
                .starts_with("keyframe "));
        }
        assert_eq!(count("/lines"), report.lines.len());
        let line = &topics["/lines"][0]["entities"][0]["lines"];
        let ends = &line[0]["points"];
        assert!((xyz(&ends[0]) - Vector3::from(report.lines[0].from)).norm() < 1e-12);
        assert!((xyz(&ends[1]) - Vector3::from(report.lines[0].to)).norm() < 1e-12);
        assert!(
            line[1]["points"].as_array().unwrap().len() > 2,
            "the path taken"
        );

        // The log: a grasp, then the verdict last.
        let said: Vec<&str> = topics["/events"]
            .iter()
            .map(|e| e["message"].as_str().unwrap())
            .collect();
        assert!(said.iter().any(|m| m.starts_with("grasped ")), "{said:?}");
        assert_eq!(said.last(), Some(&"trial 0 passed"));
        assert_eq!(topics["/events"].last().unwrap()["level"], 2);
    }

    #[test]
    fn a_planning_failure_shows_the_worlds_the_tsrs_and_the_rejected_arms() {
        let task = akl_scene::builtin::task("inspection").unwrap().unwrap();
        let mut spec = task.truth.clone().unwrap();
        let last = spec.keyframes.len() - 1;
        // The part put 3 cm into the shelf: every solution presses it in.
        spec.keyframes[last].tsr.tw_e.translation.vector.z -= 0.03;
        let Traced {
            report,
            timeline,
            topics,
        } = traced(&spec, "trace-plan");
        assert!(!report.passed && timeline.frames.is_empty());
        assert_eq!(topics["/objects"].len(), 1);
        assert_eq!(topics["/perceived"].len(), 1);
        assert_eq!(topics["/keyframes"].len(), spec.keyframes.len());
        // The failed keyframe is red, the others green.
        for (k, update) in topics["/keyframes"].iter().enumerate() {
            let colour = &update["entities"][0]["cubes"][0]["color"];
            let expected = if k == last { FAIL } else { PASS };
            assert_eq!(colour["r"].as_f64().unwrap(), expected[0], "keyframe {k}");
        }
        let ghosts = topics["/rejected"][0]["entities"].as_array().unwrap();
        assert!(!ghosts.is_empty());
        let label = ghosts[0]["texts"][0]["text"].as_str().unwrap();
        assert!(label.starts_with("IK 0: "), "{label}");
        let said = &topics["/events"][0];
        let message = said["message"].as_str().unwrap();
        assert!(
            message.starts_with("planning failed: keyframe 3"),
            "{message}"
        );
        assert_eq!(said["level"], 4);
    }
}
