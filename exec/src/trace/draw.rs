//! Drawing a trace: the colours, and the primitives of one scene entity built from poses,
//! shapes and TSRs.

use akl_foxglove::{
    Arrow, Color, Cylinder, Line, LineType, SceneEntity, Solid, Text, TriangleList,
};
use akl_planner::Geometry;
use akl_scene::Shape;
use akl_tsr::nalgebra::{Translation3, UnitQuaternion, Vector3};
use akl_tsr::Pose;

/// Furniture.
pub(crate) const FURNITURE: [f64; 4] = [0.6, 0.6, 0.62, 1.0];
/// Movable objects.
pub(crate) const MOVABLE: [f64; 4] = [0.95, 0.55, 0.15, 1.0];
/// The robot's collision model.
pub(crate) const ROBOT: [f64; 4] = [0.85, 0.85, 0.9, 0.9];
/// What passed: a keyframe reached, a line kept, a contact allowed.
pub(crate) const PASS: [f64; 4] = [0.2, 0.8, 0.3, 0.35];
/// What failed.
pub(crate) const FAIL: [f64; 4] = [0.9, 0.15, 0.15, 0.5];
/// A `move_in_line` segment's line.
pub(crate) const LINE: [f64; 4] = [0.2, 0.4, 1.0, 1.0];
/// The objects where the planner perceived them.
pub(crate) const PERCEIVED: [f64; 4] = [0.3, 0.8, 0.9, 0.35];
/// The arm at a rejected IK solution.
pub(crate) const GHOST: [f64; 4] = [0.9, 0.2, 0.2, 0.25];

/// `rgba` made opaque.
pub(crate) fn opaque(rgba: [f64; 4]) -> [f64; 4] {
    [rgba[0], rgba[1], rgba[2], 1.0]
}

/// The primitives of one entity being drawn.
#[derive(Default)]
pub(crate) struct Primitives {
    cubes: Vec<Solid>,
    spheres: Vec<Solid>,
    cylinders: Vec<Cylinder>,
    arrows: Vec<Arrow>,
    lines: Vec<Line>,
    texts: Vec<Text>,
    triangles: Vec<TriangleList>,
}

impl Primitives {
    fn cube(&mut self, at: &Pose, size: Vector3<f64>, rgba: [f64; 4]) {
        self.cubes.push(Solid {
            pose: at.into(),
            size: (&size).into(),
            color: rgba.into(),
        });
    }

    /// A sphere of `radius` centred at `at`.
    pub(crate) fn sphere(&mut self, at: &Pose, radius: f64, rgba: [f64; 4]) {
        self.spheres.push(Solid {
            pose: at.into(),
            size: akl_foxglove::Vector3::uniform(2.0 * radius),
            color: rgba.into(),
        });
    }

    fn cylinder(&mut self, at: &Pose, radius: f64, length: f64, rgba: [f64; 4]) {
        let d = 2.0 * radius;
        self.cylinders.push(Cylinder {
            pose: at.into(),
            size: (&Vector3::new(d, d, length)).into(),
            bottom_scale: 1.0,
            top_scale: 1.0,
            color: rgba.into(),
        });
    }

    /// A task object's shape at `at`.
    pub(crate) fn shape(&mut self, shape: &Shape, at: &Pose, rgba: [f64; 4]) {
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

    /// A robot link's collision shape at `at`.
    pub(crate) fn geometry(&mut self, geometry: &Geometry, at: &Pose, rgba: [f64; 4]) {
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
                let points = hull
                    .triangles
                    .iter()
                    .flat_map(|t| t.map(|i| (&hull.vertices[i as usize].coords).into()))
                    .collect();
                self.triangles.push(TriangleList {
                    pose: at.into(),
                    points,
                    color: rgba.into(),
                    colors: Vec::new(),
                    indices: Vec::new(),
                });
            }
        }
    }

    /// A line through `points` (in the entity's frame).
    pub(crate) fn polyline(&mut self, points: &[Vector3<f64>], thickness: f64, rgba: [f64; 4]) {
        self.lines.push(Line {
            kind: LineType::Strip,
            pose: (&Pose::identity()).into(),
            thickness,
            scale_invariant: false,
            points: points.iter().map(Into::into).collect(),
            color: rgba.into(),
            colors: Vec::new(),
            indices: Vec::new(),
        });
    }

    /// An arrow along the z axis of `at`.
    pub(crate) fn arrow(&mut self, at: &Pose, length: f64, rgba: [f64; 4]) {
        let along_z =
            at * UnitQuaternion::from_axis_angle(&-Vector3::y_axis(), std::f64::consts::FRAC_PI_2);
        self.arrows.push(Arrow {
            pose: (&along_z).into(),
            shaft_length: 0.7 * length,
            shaft_diameter: 0.004,
            head_length: 0.3 * length,
            head_diameter: 0.01,
            color: rgba.into(),
        });
    }

    /// The TCP positions of `tsr` grounded on `reference`: its bounds' box, in the reference's
    /// axes, around the nominal TCP position; returns that nominal pose.
    pub(crate) fn tsr_region(
        &mut self,
        reference: &Pose,
        tsr: &akl_tsr::Tsr,
        rgba: [f64; 4],
    ) -> Pose {
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

    /// White text facing the camera at `at`.
    pub(crate) fn text(&mut self, at: &Pose, text: &str) {
        self.texts.push(Text {
            pose: at.into(),
            billboard: true,
            font_size: 14.0,
            scale_invariant: true,
            color: Color::from([1.0, 1.0, 1.0, 1.0]),
            text: text.to_string(),
        });
    }

    /// The entity `id` in `frame` at `t` with these primitives; `locked` to its frame or not.
    pub(crate) fn entity(self, t: f64, frame: &str, id: &str, locked: bool) -> SceneEntity {
        SceneEntity {
            frame_locked: locked,
            arrows: self.arrows,
            cubes: self.cubes,
            spheres: self.spheres,
            cylinders: self.cylinders,
            lines: self.lines,
            triangles: self.triangles,
            texts: self.texts,
            ..SceneEntity::new(t, frame, id)
        }
    }
}
