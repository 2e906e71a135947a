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
//! - `/joint_states` (JSON): the simulated joint positions and gripper opening;
//! - `/contacts` (`foxglove.SceneUpdate`): contact points of the arm and the held object, red
//!   where they are collisions, sized by their force.

use crate::error::ExecError;
use crate::report::TrialReport;
use crate::timeline::{Frame, Timeline};
use akl_planner::collision::{Checker, RobotCollision, Scene};
use akl_planner::contact_rules::Step;
use akl_planner::{Geometry, GripperAction, PlanError, Robot};
use akl_scene::{Shape, World};
use akl_tsr::nalgebra::{Translation3, UnitQuaternion, Vector3};
use akl_tsr::{Pose, TaskSpec};
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::Path;

/// Frames per simulated second a trace records.
pub const TRACE_RATE: f64 = 30.0;

fn nanos(t: f64) -> u64 {
    (t.max(0.0) * 1e9).round() as u64
}

pub(crate) fn stamp(t: f64) -> Value {
    let ns = nanos(t);
    json!({"sec": ns / 1_000_000_000, "nsec": ns % 1_000_000_000})
}

fn vec3(v: &Vector3<f64>) -> Value {
    json!({"x": v.x, "y": v.y, "z": v.z})
}

pub(crate) fn pose(p: &Pose) -> Value {
    let q = p.rotation.quaternion().coords;
    json!({"position": vec3(&p.translation.vector),
           "orientation": {"x": q.x, "y": q.y, "z": q.z, "w": q.w}})
}

pub(crate) fn color(rgba: [f64; 4]) -> Value {
    json!({"r": rgba[0], "g": rgba[1], "b": rgba[2], "a": rgba[3]})
}

const FURNITURE: [f64; 4] = [0.6, 0.6, 0.62, 1.0];
const MOVABLE: [f64; 4] = [0.95, 0.55, 0.15, 1.0];
const ROBOT: [f64; 4] = [0.85, 0.85, 0.9, 0.9];
const PASS: [f64; 4] = [0.2, 0.8, 0.3, 0.35];
const FAIL: [f64; 4] = [0.9, 0.15, 0.15, 0.5];
const LINE: [f64; 4] = [0.2, 0.4, 1.0, 1.0];
const PERCEIVED: [f64; 4] = [0.3, 0.8, 0.9, 0.35];
const GHOST: [f64; 4] = [0.9, 0.2, 0.2, 0.25];

/// IK solutions of a failed keyframe drawn in a planning-failure trace.
const GHOSTS: usize = 6;

/// Primitives of one entity, by Foxglove field name.
#[derive(Default)]
struct Primitives {
    cubes: Vec<Value>,
    spheres: Vec<Value>,
    cylinders: Vec<Value>,
    arrows: Vec<Value>,
    lines: Vec<Value>,
    texts: Vec<Value>,
    triangles: Vec<Value>,
}

impl Primitives {
    fn cube(&mut self, at: &Pose, size: Vector3<f64>, rgba: [f64; 4]) {
        self.cubes
            .push(json!({"pose": pose(at), "size": vec3(&size), "color": color(rgba)}));
    }

    fn sphere(&mut self, at: &Pose, radius: f64, rgba: [f64; 4]) {
        let d = 2.0 * radius;
        self.spheres.push(
            json!({"pose": pose(at), "size": {"x": d, "y": d, "z": d}, "color": color(rgba)}),
        );
    }

    fn cylinder(&mut self, at: &Pose, radius: f64, length: f64, rgba: [f64; 4]) {
        let d = 2.0 * radius;
        self.cylinders.push(
            json!({"pose": pose(at), "size": {"x": d, "y": d, "z": length},
            "bottom_scale": 1.0, "top_scale": 1.0, "color": color(rgba)}),
        );
    }

    fn shape(&mut self, shape: &Shape, at: &Pose, rgba: [f64; 4]) {
        match *shape {
            Shape::Box { size } => self.cube(at, Vector3::from(size), rgba),
            Shape::Cylinder { radius, length } => self.cylinder(at, radius, length, rgba),
            Shape::Capsule { radius, length } => {
                self.cylinder(at, radius, length, rgba);
                for end in [-0.5 * length, 0.5 * length] {
                    self.sphere(&(at * Pose::translation(0.0, 0.0, end)), radius, rgba);
                }
            }
            Shape::Sphere { radius } => self.sphere(at, radius, rgba),
            // A mesh is drawn as its bounding box.
            Shape::Mesh { .. } => self.cube(at, 2.0 * shape.half_extents(), rgba),
        }
    }

    fn geometry(&mut self, geometry: &Geometry, at: &Pose, rgba: [f64; 4]) {
        match *geometry {
            Geometry::Capsule { radius, length } => {
                self.cylinder(at, radius, length, rgba);
                for end in [-0.5 * length, 0.5 * length] {
                    self.sphere(&(at * Translation3::new(0.0, 0.0, end)), radius, rgba);
                }
            }
            Geometry::Box { size } => self.cube(at, Vector3::from(size), rgba),
            Geometry::Cylinder { radius, length } => self.cylinder(at, radius, length, rgba),
            Geometry::Sphere { radius } => self.sphere(at, radius, rgba),
            // A grown hull is drawn as its hull.
            Geometry::RoundHull(ref hull) => {
                let points: Vec<Value> = hull
                    .triangles
                    .iter()
                    .flat_map(|t| t.map(|i| vec3(&hull.vertices[i as usize].coords)))
                    .collect();
                self.triangles
                    .push(json!({"pose": pose(at), "points": points,
                    "color": color(rgba), "colors": [], "indices": []}));
            }
        }
    }

    fn polyline(&mut self, points: &[Vector3<f64>], thickness: f64, rgba: [f64; 4]) {
        let points: Vec<Value> = points.iter().map(vec3).collect();
        self.lines
            .push(json!({"type": 0, "pose": pose(&Pose::identity()),
            "thickness": thickness, "scale_invariant": false, "points": points,
            "color": color(rgba), "colors": [], "indices": []}));
    }

    /// An arrow along the z axis of `at`.
    fn arrow(&mut self, at: &Pose, length: f64, rgba: [f64; 4]) {
        let along_z =
            at * UnitQuaternion::from_axis_angle(&-Vector3::y_axis(), std::f64::consts::FRAC_PI_2);
        self.arrows
            .push(json!({"pose": pose(&along_z), "shaft_length": 0.7 * length,
            "shaft_diameter": 0.004, "head_length": 0.3 * length, "head_diameter": 0.01,
            "color": color(rgba)}));
    }

    /// The TCP positions of `tsr` grounded on `reference`: its bounds' box, in the reference's
    /// axes, around the nominal TCP position; returns that nominal pose.
    fn tsr_region(&mut self, reference: &Pose, tsr: &akl_tsr::Tsr, rgba: [f64; 4]) -> Pose {
        let bw = tsr.bw.0;
        let centre = Vector3::from_fn(|i, _| 0.5 * (bw[i][0] + bw[i][1]));
        let size = Vector3::from_fn(|i, _| (bw[i][1] - bw[i][0]).max(1e-3));
        let nominal = reference * tsr.tw_e;
        let region = Pose::from_parts(
            Translation3::from(nominal.translation.vector + reference.rotation * centre),
            reference.rotation,
        );
        self.cube(&region, size, rgba);
        nominal
    }

    fn text(&mut self, at: &Pose, text: &str) {
        self.texts.push(
            json!({"pose": pose(at), "billboard": true, "font_size": 14.0,
            "scale_invariant": true, "color": color([1.0, 1.0, 1.0, 1.0]), "text": text}),
        );
    }

    fn entity(self, t: f64, frame: &str, id: &str, locked: bool) -> Value {
        json!({"timestamp": stamp(t), "frame_id": frame, "id": id,
               "lifetime": {"sec": 0, "nsec": 0}, "frame_locked": locked, "metadata": [],
               "arrows": self.arrows, "cubes": self.cubes, "spheres": self.spheres,
               "cylinders": self.cylinders, "lines": self.lines, "triangles": self.triangles,
               "texts": self.texts, "models": []})
    }
}

pub(crate) fn scene_update(entities: Vec<Value>) -> Value {
    json!({"deletions": [], "entities": entities})
}

fn log(t: f64, level: u8, message: &str) -> Value {
    json!({"timestamp": stamp(t), "level": level, "message": message, "name": "akl.execute",
           "file": "", "line": 0})
}

/// JSON schemas of the Foxglove messages written (the fields this writer uses).
mod schema {
    use serde_json::{json, Value};

    fn object(props: Value) -> Value {
        json!({"type": "object", "properties": props})
    }

    fn array(items: Value) -> Value {
        json!({"type": "array", "items": items})
    }

    fn number() -> Value {
        json!({"type": "number"})
    }

    fn string() -> Value {
        json!({"type": "string"})
    }

    fn time() -> Value {
        object(json!({"sec": {"type": "integer"}, "nsec": {"type": "integer"}}))
    }

    fn vec3() -> Value {
        object(json!({"x": number(), "y": number(), "z": number()}))
    }

    fn quat() -> Value {
        object(json!({"x": number(), "y": number(), "z": number(), "w": number()}))
    }

    fn color() -> Value {
        object(json!({"r": number(), "g": number(), "b": number(), "a": number()}))
    }

    fn pose() -> Value {
        object(json!({"position": vec3(), "orientation": quat()}))
    }

    fn sized() -> Value {
        object(json!({"pose": pose(), "size": vec3(), "color": color()}))
    }

    fn titled(title: &str, mut value: Value) -> Value {
        value["title"] = json!(title);
        value
    }

    /// `foxglove.FrameTransforms`.
    pub(super) fn frame_transforms() -> Value {
        titled(
            "foxglove.FrameTransforms",
            object(json!({"transforms": array(object(json!({
                "timestamp": time(), "parent_frame_id": string(), "child_frame_id": string(),
                "translation": vec3(), "rotation": quat()})))})),
        )
    }

    /// `foxglove.SceneUpdate`.
    pub(super) fn scene_update() -> Value {
        let cylinder = object(
            json!({"pose": pose(), "size": vec3(), "bottom_scale": number(),
            "top_scale": number(), "color": color()}),
        );
        let arrow = object(json!({"pose": pose(), "shaft_length": number(),
            "shaft_diameter": number(), "head_length": number(), "head_diameter": number(),
            "color": color()}));
        let line = object(
            json!({"type": {"type": "integer", "enum": [0, 1, 2]}, "pose": pose(),
            "thickness": number(), "scale_invariant": {"type": "boolean"},
            "points": array(vec3()), "color": color(), "colors": array(color()),
            "indices": array(json!({"type": "integer"}))}),
        );
        let text = object(json!({"pose": pose(), "billboard": {"type": "boolean"},
            "font_size": number(), "scale_invariant": {"type": "boolean"}, "color": color(),
            "text": string()}));
        let entity = object(
            json!({"timestamp": time(), "frame_id": string(), "id": string(),
            "lifetime": time(), "frame_locked": {"type": "boolean"},
            "metadata": array(object(json!({"key": string(), "value": string()}))),
            "arrows": array(arrow), "cubes": array(sized()), "spheres": array(sized()),
            "cylinders": array(cylinder), "lines": array(line), "triangles": array(object(json!({}))),
            "texts": array(text), "models": array(object(json!({})))}),
        );
        let deletion =
            object(json!({"timestamp": time(), "type": {"type": "integer"}, "id": string()}));
        titled(
            "foxglove.SceneUpdate",
            object(json!({"deletions": array(deletion), "entities": array(entity)})),
        )
    }

    /// The simulated joints: names, positions and the gripper opening.
    pub(super) fn joint_state() -> Value {
        titled(
            "akl.JointState",
            object(json!({"timestamp": time(), "name": array(string()),
                "position": array(number()), "gripper_width": number()})),
        )
    }

    /// `foxglove.Log`.
    pub(super) fn log() -> Value {
        titled(
            "foxglove.Log",
            object(json!({"timestamp": time(), "level": {"type": "integer"},
                "message": string(), "name": string(), "file": string(),
                "line": {"type": "integer"}})),
        )
    }
}

fn mcap_error(path: &Path) -> impl Fn(mcap::McapError) -> ExecError + '_ {
    move |e| ExecError::Write {
        path: path.to_path_buf(),
        source: std::io::Error::other(e.to_string()),
    }
}

/// The channels of a trace being written.
struct Channels {
    tf: u16,
    robot: u16,
    visual: u16,
    objects: u16,
    perceived: u16,
    keyframes: u16,
    rejected: u16,
    lines: u16,
    joints: u16,
    contacts: u16,
    events: u16,
}

/// One trial and what it needs to be drawn.
pub struct TraceInput<'a> {
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
pub fn write_trace(path: &Path, input: &TraceInput) -> Result<(), ExecError> {
    let bytes = trace_bytes(path, input)?;
    akl_tsr::io::write_atomic(path, &bytes).map_err(|source| ExecError::Write {
        path: path.to_path_buf(),
        source,
    })
}

fn trace_bytes(path: &Path, input: &TraceInput) -> Result<Vec<u8>, ExecError> {
    let err = mcap_error(path);
    let mut writer = mcap::WriteOptions::new()
        .profile("akl")
        .create(Cursor::new(Vec::new()))
        .map_err(&err)?;
    let none = BTreeMap::new();
    let mut schema = |name: &str, value: Value| {
        writer.add_schema(name, "jsonschema", value.to_string().as_bytes())
    };
    let tf_schema = schema("foxglove.FrameTransforms", schema::frame_transforms()).map_err(&err)?;
    let scene_schema = schema("foxglove.SceneUpdate", schema::scene_update()).map_err(&err)?;
    let log_schema = schema("foxglove.Log", schema::log()).map_err(&err)?;
    let joint_schema = schema("akl.JointState", schema::joint_state()).map_err(&err)?;
    let mut channel = |schema: u16, topic: &str| writer.add_channel(schema, topic, "json", &none);
    let channels = Channels {
        tf: channel(tf_schema, "/tf").map_err(&err)?,
        robot: channel(scene_schema, "/robot").map_err(&err)?,
        visual: channel(scene_schema, "/robot/visual").map_err(&err)?,
        objects: channel(scene_schema, "/objects").map_err(&err)?,
        perceived: channel(scene_schema, "/perceived").map_err(&err)?,
        keyframes: channel(scene_schema, "/keyframes").map_err(&err)?,
        rejected: channel(scene_schema, "/rejected").map_err(&err)?,
        lines: channel(scene_schema, "/lines").map_err(&err)?,
        joints: channel(joint_schema, "/joint_states").map_err(&err)?,
        contacts: channel(scene_schema, "/contacts").map_err(&err)?,
        events: channel(log_schema, "/events").map_err(&err)?,
    };
    let r = input.report;
    let metadata = BTreeMap::from([
        ("task".to_string(), input.spec.task.clone()),
        ("method".to_string(), input.spec.method.clone()),
        ("trial".to_string(), r.trial.to_string()),
        ("seed".to_string(), r.seed.to_string()),
        ("passed".to_string(), r.passed.to_string()),
    ]);
    writer
        .write_metadata(&mcap::records::Metadata {
            name: "akl_trace".into(),
            metadata,
        })
        .map_err(&err)?;
    let mut messages: Vec<(f64, u16, Value)> = Vec::new();
    messages.push((0.0, channels.robot, robot_shapes(input.robot)));
    if let Some(models) = crate::visual::robot_models(input.robot) {
        messages.push((0.0, channels.visual, models));
    }
    let world_poses: Vec<Pose> = input.world.objects.iter().map(|o| o.pose).collect();
    messages.push((
        0.0,
        channels.objects,
        objects(input.world, 0.0, &world_poses, None),
    ));
    if let Some(seen) = &input.timeline.perceived {
        let poses: Vec<Pose> = seen.objects.iter().map(|o| o.pose).collect();
        messages.push((
            0.0,
            channels.perceived,
            objects(seen, 0.0, &poses, Some(PERCEIVED)),
        ));
    }
    if let Some(failure) = &input.timeline.planning_failure {
        messages.extend(planning_failure(input, failure, &channels));
    }
    for frame in &input.timeline.frames {
        messages.push((frame.t, channels.joints, joint_state(input.robot, frame)));
        messages.push((frame.t, channels.contacts, contacts(frame)));
        messages.push((
            frame.t,
            channels.tf,
            transforms(input.robot, frame.t, &frame.links),
        ));
        messages.push((
            frame.t,
            channels.objects,
            objects(input.world, frame.t, &frame.objects, None),
        ));
    }
    messages.extend(keyframes(input, channels.keyframes));
    messages.extend(lines(input, channels.lines));
    messages.extend(events(input, channels.events));
    messages.sort_by(|a, b| a.0.total_cmp(&b.0));
    for (sequence, (t, channel, value)) in messages.into_iter().enumerate() {
        let header = mcap::records::MessageHeader {
            channel_id: channel,
            sequence: sequence as u32,
            log_time: nanos(t),
            publish_time: nanos(t),
        };
        writer
            .write_to_known_channel(&header, value.to_string().as_bytes())
            .map_err(&err)?;
    }
    writer.finish().map_err(&err)?;
    Ok(writer.into_inner().into_inner())
}

fn robot_shapes(robot: &Robot) -> Value {
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
    scene_update(entities)
}

fn transforms(robot: &Robot, t: f64, links: &[Pose]) -> Value {
    let transforms: Vec<Value> = robot
        .links()
        .iter()
        .zip(links)
        .map(|(l, p)| {
            let q = p.rotation.quaternion().coords;
            json!({"timestamp": stamp(t), "parent_frame_id": "world", "child_frame_id": l.name,
                   "translation": vec3(&p.translation.vector),
                   "rotation": {"x": q.x, "y": q.y, "z": q.z, "w": q.w}})
        })
        .collect();
    json!({ "transforms": transforms })
}

/// The objects of `world` at `poses`, in their usual colours or all in `tint`.
fn objects(world: &World, t: f64, poses: &[Pose], tint: Option<[f64; 4]>) -> Value {
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
    scene_update(entities)
}

fn joint_state(robot: &Robot, frame: &Frame) -> Value {
    json!({"timestamp": stamp(frame.t), "name": robot.joint_names(), "position": frame.joints,
           "gripper_width": frame.width})
}

fn contacts(frame: &Frame) -> Value {
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
    scene_update(vec![p.entity(frame.t, "world", "contacts", false)])
}

/// Where planning failed: every keyframe's TSR grounded on the perceived world, and for the
/// keyframe that failed, the arm at rejected IK solutions with what each collides with.
fn planning_failure(
    input: &TraceInput,
    failure: &PlanError,
    channels: &Channels,
) -> Vec<(f64, u16, Value)> {
    let seen = input.timeline.perceived.as_ref().unwrap_or(input.world);
    let poses = seen.object_poses();
    let failed = failure.keyframe();
    let mut out = vec![(
        0.0,
        channels.events,
        log(0.0, 4, &format!("planning failed: {failure}")),
    )];
    let Ok(grounded) = input.spec.ground(&poses) else {
        return out;
    };
    for (k, kf) in grounded.keyframes.iter().enumerate() {
        let mut p = Primitives::default();
        let rgba = if Some(k) == failed { FAIL } else { PASS };
        let nominal = p.tsr_region(&kf.tsr.t0_w, &kf.tsr, rgba);
        p.text(
            &(Translation3::new(0.0, 0.0, 0.04) * nominal),
            &format!("keyframe {k}"),
        );
        let id = format!("keyframe {k}");
        out.push((
            0.0,
            channels.keyframes,
            scene_update(vec![p.entity(0.0, "world", &id, false)]),
        ));
    }
    if let Some(kf) = failed.and_then(|k| grounded.keyframes.get(k)) {
        out.push((0.0, channels.rejected, rejected(input.robot, seen, kf)));
    }
    out
}

/// The arm at IK solutions of `kf`'s nominal pose in `world`, each with its first collision.
fn rejected(robot: &Robot, world: &World, kf: &akl_tsr::Keyframe) -> Value {
    let model = RobotCollision::new(robot);
    let scene = Scene::new(world, &[]);
    let checker = Checker::new(robot, &model, &scene);
    let grasping = (kf.gripper == akl_tsr::Gripper::Closed).then_some(kf.reference.as_str());
    let allow = Step {
        grasping,
        ..Step::default()
    }
    .allowances();
    let target = world.robot_base.inverse() * kf.tsr.nominal();
    let mut entities = Vec::new();
    for (n, q) in robot
        .ik_solutions(&target, robot.ready(), GHOSTS)
        .iter()
        .enumerate()
    {
        let hit = checker.check(q, robot.open_width(), None, &allow);
        let mut p = Primitives::default();
        let links = robot.link_poses(q, robot.open_width());
        for (link, at) in robot.links().iter().zip(&links) {
            for s in &link.shapes {
                p.geometry(&s.geometry, &(world.robot_base * at * s.origin), GHOST);
            }
        }
        let tcp = world.robot_base * links[robot.tcp_link()];
        let what = hit.map_or_else(|| "free".to_string(), |h| h.to_string());
        p.text(
            &(Translation3::new(0.0, 0.0, 0.08 + 0.03 * n as f64) * tcp),
            &format!("IK {n}: {what}"),
        );
        entities.push(p.entity(0.0, "world", &format!("rejected {n}"), false));
    }
    scene_update(entities)
}

fn keyframes(input: &TraceInput, channel: u16) -> Vec<(f64, u16, Value)> {
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
            p.arrow(&tcp, 0.06, [rgba[0], rgba[1], rgba[2], 1.0]);
            p.text(
                &(Translation3::new(0.0, 0.0, 0.04) * nominal),
                &format!("keyframe {} ({}, {})", c.keyframe, kf.kind, kf.gripper),
            );
            let id = format!("keyframe {}", c.keyframe);
            Some((
                c.t,
                channel,
                scene_update(vec![p.entity(c.t, "world", &id, false)]),
            ))
        })
        .collect()
}

fn lines(input: &TraceInput, channel: u16) -> Vec<(f64, u16, Value)> {
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
            p.polyline(&path, 0.002, [rgba[0], rgba[1], rgba[2], 1.0]);
            let id = format!("line to keyframe {}", l.keyframe);
            (
                l.end,
                channel,
                scene_update(vec![p.entity(l.end, "world", &id, false)]),
            )
        })
        .collect()
}

fn events(input: &TraceInput, channel: u16) -> Vec<(f64, u16, Value)> {
    const INFO: u8 = 2;
    const ERROR: u8 = 4;
    let r = input.report;
    let mut out = Vec::new();
    if let Some(plan) = &input.timeline.plan {
        for e in plan
            .events
            .iter()
            .filter(|e| e.action == GripperAction::Open)
        {
            let message = format!("release {} (keyframe {})", e.object, e.keyframe);
            out.push((e.t, channel, log(e.t, INFO, &message)));
        }
    }
    for g in &r.grasps {
        let (level, message) = match &g.grasped {
            Some(n) if *n == g.planned => (INFO, format!("grasped {n} (keyframe {})", g.keyframe)),
            Some(n) => (
                ERROR,
                format!(
                    "grasped {n} instead of {} (keyframe {})",
                    g.planned, g.keyframe
                ),
            ),
            None => (
                ERROR,
                format!(
                    "closed on nothing; {} is not between the fingers (keyframe {})",
                    g.planned, g.keyframe
                ),
            ),
        };
        out.push((g.t, channel, log(g.t, level, &message)));
    }
    for c in &r.collisions {
        let message = format!("collision: {}", c.describe());
        out.push((c.t, channel, log(c.t, ERROR, &message)));
    }
    for f in r
        .failures
        .iter()
        .filter(|f| f.cause == crate::report::Cause::GraspFailed)
    {
        out.push((
            r.simulated_seconds,
            channel,
            log(r.simulated_seconds, ERROR, &f.detail),
        ));
    }
    let end = r.simulated_seconds;
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
    out.push((
        end,
        channel,
        log(end, if r.passed { INFO } else { ERROR }, &verdict),
    ));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::batch::{Batch, BatchOptions};
    use crate::options::ExecOptions;

    /// Runs one randomized trial of `spec` on inspection (seed 3), writes its trace to a
    /// scratch file named after `name`, and reads it back: the report, the frames recorded, and
    /// each topic's messages in time order.
    fn traced(spec: &TaskSpec, name: &str) -> (TrialReport, usize, BTreeMap<String, Vec<Value>>) {
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
        std::fs::remove_dir_all(&dir).unwrap();
        (report, timeline.frames.len(), topics)
    }

    #[test]
    fn a_trace_holds_every_channel_and_reads_back() {
        let task = akl_scene::builtin::task("inspection").unwrap().unwrap();
        let spec = task.truth.clone().unwrap();
        let (_, frames, topics) = traced(&spec, "trace");
        let count = |t: &str| topics.get(t).map_or(0, Vec::len);
        for k in &topics["/keyframes"] {
            assert_eq!(k["entities"][0]["cubes"].as_array().unwrap().len(), 1);
        }
        assert_eq!(count("/robot"), 1);
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
        assert_eq!(count("/keyframes"), spec.keyframes.len());
        assert_eq!(count("/lines"), 1);
        assert!(frames > 100 && count("/tf") == frames && count("/objects") == frames + 1);
        assert_eq!(count("/joint_states"), frames);
        assert_eq!(count("/contacts"), frames);
        assert_eq!(count("/perceived"), 1);
        assert_eq!(count("/rejected"), 0);
        assert!(count("/events") >= 3);
    }

    #[test]
    fn a_planning_failure_shows_the_worlds_the_tsrs_and_the_rejected_arms() {
        let task = akl_scene::builtin::task("inspection").unwrap().unwrap();
        let mut spec = task.truth.clone().unwrap();
        let last = spec.keyframes.len() - 1;
        // The part put 3 cm into the shelf: every solution presses it in.
        spec.keyframes[last].tsr.tw_e.translation.vector.z -= 0.03;
        let (report, frames, topics) = traced(&spec, "trace-plan");
        assert!(!report.passed && frames == 0);
        assert_eq!(topics["/objects"].len(), 1);
        assert_eq!(topics["/perceived"].len(), 1);
        assert_eq!(topics["/keyframes"].len(), spec.keyframes.len());
        let ghosts = topics["/rejected"][0]["entities"].as_array().unwrap();
        assert!(!ghosts.is_empty());
        let label = ghosts[0]["texts"][0]["text"].as_str().unwrap();
        assert!(label.starts_with("IK 0: "), "{label}");
        let said = topics["/events"][0]["message"].as_str().unwrap();
        assert!(said.starts_with("planning failed: keyframe 3"), "{said}");
    }
}
