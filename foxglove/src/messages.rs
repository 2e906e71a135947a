//! The Foxglove message types AKL writes, as serde structs.
//!
//! Field names and their order are Foxglove's (a `foxglove.SceneEntity` lists `arrows` before
//! `cubes`, ...), so the JSON written is what Foxglove's own schemas describe. Each type's JSON
//! schema is its [`Schema`] implementation, in [`crate::schema`].

use serde::{Serialize, Serializer};

use crate::writer::nanos;

/// A time stamp: whole seconds and nanoseconds (`time` in Foxglove's schemas).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct Time {
    /// Whole seconds.
    pub sec: u64,
    /// Nanoseconds past `sec`, below 10⁹.
    pub nsec: u32,
}

impl Time {
    /// The time stamp of `t` seconds (rounded to the nanosecond; negative times are 0).
    pub fn at(t: f64) -> Time {
        let ns = nanos(t);
        Time {
            sec: ns / 1_000_000_000,
            nsec: (ns % 1_000_000_000) as u32,
        }
    }
}

/// `foxglove.Vector3`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

impl From<&akl_tsr::nalgebra::Vector3<f64>> for Vector3 {
    fn from(v: &akl_tsr::nalgebra::Vector3<f64>) -> Self {
        Vector3 {
            x: v.x,
            y: v.y,
            z: v.z,
        }
    }
}

impl Vector3 {
    /// The same length `s` along every axis (a sphere's size, a model's scale).
    pub fn uniform(s: f64) -> Vector3 {
        Vector3 { x: s, y: s, z: s }
    }
}

/// `foxglove.Quaternion`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl From<&akl_tsr::nalgebra::UnitQuaternion<f64>> for Quaternion {
    fn from(q: &akl_tsr::nalgebra::UnitQuaternion<f64>) -> Self {
        let c = q.quaternion().coords;
        Quaternion {
            x: c.x,
            y: c.y,
            z: c.z,
            w: c.w,
        }
    }
}

/// `foxglove.Pose`: a position and an orientation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Pose {
    /// Position.
    pub position: Vector3,
    /// Orientation.
    pub orientation: Quaternion,
}

impl From<&akl_tsr::Pose> for Pose {
    fn from(p: &akl_tsr::Pose) -> Self {
        Pose {
            position: Vector3::from(&p.translation.vector),
            orientation: Quaternion::from(&p.rotation),
        }
    }
}

/// `foxglove.Color`: red, green, blue and opacity, each in [0, 1].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Color {
    /// Red.
    pub r: f64,
    /// Green.
    pub g: f64,
    /// Blue.
    pub b: f64,
    /// Opacity.
    pub a: f64,
}

impl From<[f64; 4]> for Color {
    fn from(rgba: [f64; 4]) -> Self {
        Color {
            r: rgba[0],
            g: rgba[1],
            b: rgba[2],
            a: rgba[3],
        }
    }
}

/// `foxglove.PoseInFrame`: a time-stamped pose in a named frame.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PoseInFrame {
    /// When.
    pub timestamp: Time,
    /// The frame the pose is in.
    pub frame_id: String,
    /// The pose.
    pub pose: Pose,
}

/// A `foxglove.Log` level (the ones AKL writes).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LogLevel {
    /// `INFO` (2).
    Info,
    /// `ERROR` (4).
    Error,
}

impl Serialize for LogLevel {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_u8(match self {
            LogLevel::Info => 2,
            LogLevel::Error => 4,
        })
    }
}

/// `foxglove.Log`: a line of text at a time.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Log {
    /// When.
    pub timestamp: Time,
    /// How serious.
    pub level: LogLevel,
    /// The text.
    pub message: String,
    /// Who said it (AKL writes `akl.<what>`).
    pub name: String,
    /// Source file (AKL writes none: empty).
    pub file: String,
    /// Source line (AKL writes 0).
    pub line: u32,
}

impl Log {
    /// A line `message` from `name` at `t` seconds, with no source location.
    pub fn new(t: f64, level: LogLevel, name: &str, message: String) -> Log {
        Log {
            timestamp: Time::at(t),
            level,
            message,
            name: name.to_string(),
            file: String::new(),
            line: 0,
        }
    }
}

/// `foxglove.FrameTransform`: where a child frame is in its parent.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameTransform {
    /// When.
    pub timestamp: Time,
    /// The parent frame.
    pub parent_frame_id: String,
    /// The child frame.
    pub child_frame_id: String,
    /// The child's origin in the parent.
    pub translation: Vector3,
    /// The child's axes in the parent.
    pub rotation: Quaternion,
}

/// `foxglove.FrameTransforms`: several transforms in one message.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FrameTransforms {
    /// The transforms.
    pub transforms: Vec<FrameTransform>,
}

/// `foxglove.CubePrimitive` and `foxglove.SpherePrimitive`, which have the same fields: a
/// solid of `size` (a sphere's diameters) centred at `pose`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Solid {
    /// Centre and axes.
    pub pose: Pose,
    /// Extent along each axis.
    pub size: Vector3,
    /// Colour.
    pub color: Color,
}

/// `foxglove.CylinderPrimitive`: a cylinder along the z axis of `pose`, or a cone when the
/// scales differ.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Cylinder {
    /// Centre and axes.
    pub pose: Pose,
    /// Diameters along x and y, length along z.
    pub size: Vector3,
    /// The bottom face's diameter as a fraction of `size`.
    pub bottom_scale: f64,
    /// The top face's diameter as a fraction of `size`.
    pub top_scale: f64,
    /// Colour.
    pub color: Color,
}

/// `foxglove.ArrowPrimitive`: an arrow along the x axis of `pose`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Arrow {
    /// The tail and the arrow's axes.
    pub pose: Pose,
    /// Length of the shaft.
    pub shaft_length: f64,
    /// Diameter of the shaft.
    pub shaft_diameter: f64,
    /// Length of the head.
    pub head_length: f64,
    /// Diameter of the head's base.
    pub head_diameter: f64,
    /// Colour.
    pub color: Color,
}

/// How a `foxglove.LinePrimitive` joins its points (the kinds AKL draws).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LineType {
    /// `LINE_STRIP` (0): each point joined to the next.
    Strip,
}

impl Serialize for LineType {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_u8(match self {
            LineType::Strip => 0,
        })
    }
}

/// `foxglove.LinePrimitive`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Line {
    /// How the points are joined.
    #[serde(rename = "type")]
    pub kind: LineType,
    /// The frame the points are in, relative to the entity's.
    pub pose: Pose,
    /// Thickness.
    pub thickness: f64,
    /// Whether `thickness` is in pixels rather than metres.
    pub scale_invariant: bool,
    /// The points.
    pub points: Vec<Vector3>,
    /// Colour of the whole line (when `colors` is empty).
    pub color: Color,
    /// One colour per point, or none.
    pub colors: Vec<Color>,
    /// Indices into `points` to draw, or none for all in order.
    pub indices: Vec<u32>,
}

/// `foxglove.TriangleListPrimitive`: triangles, three points each.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TriangleList {
    /// The frame the points are in, relative to the entity's.
    pub pose: Pose,
    /// The corners, three per triangle.
    pub points: Vec<Vector3>,
    /// Colour of every triangle (when `colors` is empty).
    pub color: Color,
    /// One colour per point, or none.
    pub colors: Vec<Color>,
    /// Indices into `points` to draw, or none for all in order.
    pub indices: Vec<u32>,
}

/// `foxglove.TextPrimitive`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Text {
    /// Where.
    pub pose: Pose,
    /// Whether it always faces the camera.
    pub billboard: bool,
    /// Size.
    pub font_size: f64,
    /// Whether `font_size` is in pixels rather than metres.
    pub scale_invariant: bool,
    /// Colour.
    pub color: Color,
    /// The text.
    pub text: String,
}

/// `foxglove.ModelPrimitive` with the model's file embedded.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Model {
    /// Where the model's origin is.
    pub pose: Pose,
    /// Scale along each axis.
    pub scale: Vector3,
    /// Colour (used when `override_color`).
    pub color: Color,
    /// Whether `color` replaces the model's own materials.
    pub override_color: bool,
    /// Where to load the model from (empty: `data` holds it).
    pub url: String,
    /// The type of `data`, e.g. `model/stl`.
    pub media_type: String,
    /// The model file, base64-encoded.
    pub data: String,
}

/// `foxglove.KeyValuePair`.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct KeyValuePair {
    /// Key.
    pub key: String,
    /// Value.
    pub value: String,
}

/// `foxglove.SceneEntity`: primitives drawn together in one frame, replaced by the next
/// entity of the same `id`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SceneEntity {
    /// When.
    pub timestamp: Time,
    /// The frame the primitives are in.
    pub frame_id: String,
    /// Identifies the entity across messages.
    pub id: String,
    /// How long it is shown (zero: until replaced).
    pub lifetime: Time,
    /// Whether it moves with its frame after `timestamp`.
    pub frame_locked: bool,
    /// Key-value metadata.
    pub metadata: Vec<KeyValuePair>,
    /// Arrows.
    pub arrows: Vec<Arrow>,
    /// Cubes.
    pub cubes: Vec<Solid>,
    /// Spheres.
    pub spheres: Vec<Solid>,
    /// Cylinders.
    pub cylinders: Vec<Cylinder>,
    /// Lines.
    pub lines: Vec<Line>,
    /// Triangle lists.
    pub triangles: Vec<TriangleList>,
    /// Texts.
    pub texts: Vec<Text>,
    /// Models.
    pub models: Vec<Model>,
}

impl SceneEntity {
    /// An entity `id` in `frame_id` at `t` seconds with no primitives, shown until replaced,
    /// not locked to its frame.
    pub fn new(t: f64, frame_id: &str, id: &str) -> SceneEntity {
        SceneEntity {
            timestamp: Time::at(t),
            frame_id: frame_id.to_string(),
            id: id.to_string(),
            lifetime: Time::default(),
            frame_locked: false,
            metadata: Vec::new(),
            arrows: Vec::new(),
            cubes: Vec::new(),
            spheres: Vec::new(),
            cylinders: Vec::new(),
            lines: Vec::new(),
            triangles: Vec::new(),
            texts: Vec::new(),
            models: Vec::new(),
        }
    }
}

/// `foxglove.SceneEntityDeletion` (AKL deletes nothing, but the field is Foxglove's).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SceneEntityDeletion {
    /// When.
    pub timestamp: Time,
    /// 0: the entity `id`; 1: all entities.
    #[serde(rename = "type")]
    pub kind: u8,
    /// The entity deleted.
    pub id: String,
}

/// `foxglove.SceneUpdate`: entities added or replaced.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SceneUpdate {
    /// Entities deleted.
    pub deletions: Vec<SceneEntityDeletion>,
    /// Entities added or replaced.
    pub entities: Vec<SceneEntity>,
}

impl SceneUpdate {
    /// An update adding or replacing `entities`, deleting none.
    pub fn new(entities: Vec<SceneEntity>) -> SceneUpdate {
        SceneUpdate {
            deletions: Vec::new(),
            entities,
        }
    }
}
