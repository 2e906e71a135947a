//! The world as the checks see it: its objects, grown where the rules say, and the robot's base.

use super::cull::BoxLanes;
use super::spheres::Target;
use crate::parry_convert;
use akl_scene::World;
use akl_tsr::Pose;
use parry3d_f64::shape::SharedShape;

/// A scene object prepared for checking.
#[derive(Debug, Clone)]
pub(super) struct Obstacle {
    pub(super) name: String,
    pub(super) shape: SharedShape,
    pub(super) pose: Pose,
    /// The object for closed-form distances from points, with its world-axis-aligned box.
    pub(super) target: Target,
    /// Whether it is movable: placed where it was perceived, not where it is known to be.
    pub(super) movable: bool,
}

/// The world as the checker sees it: exact object shapes with bounding boxes, the robot's
/// base pose, and the object the robot stands on.
#[derive(Debug, Clone)]
pub struct Scene {
    pub(super) obstacles: Vec<Obstacle>,
    /// The obstacles' world-axis-aligned boxes, in the same order, four to a group.
    pub(super) boxes: Vec<BoxLanes>,
    pub(super) base: Pose,
    pub(super) mount: Option<usize>,
}

impl Scene {
    /// The objects of `world` except those named in `without` (e.g. a held object).
    pub fn new(world: &World, without: &[&str]) -> Scene {
        let mut obstacles = Vec::new();
        for o in world
            .objects
            .iter()
            .filter(|o| !without.contains(&o.name.as_str()))
        {
            let (shape, fix) = parry_convert::object_shape(&o.shape, 0.0);
            obstacles.push(Obstacle {
                name: o.name.clone(),
                shape,
                pose: o.pose * fix,
                target: Target::of(&o.shape, &o.pose),
                movable: o.movable,
            });
        }
        let base = world.robot_base;
        let origin = base.translation.vector;
        let mount = obstacles.iter().position(|o| {
            let (min, max) = (&o.target.min, &o.target.max);
            let inside = |i: usize| origin[i] >= min[i] - 1e-9 && origin[i] <= max[i] + 1e-9;
            inside(0) && inside(1) && (max.z - origin.z).abs() <= akl_scene::SUPPORT_GAP
        });
        let corners: Vec<_> = obstacles
            .iter()
            .map(|o| [o.target.min, o.target.max])
            .collect();
        let boxes = BoxLanes::of(&corners);
        Scene {
            obstacles,
            boxes,
            base,
            mount,
        }
    }

    /// Name of the object the robot is mounted on, if any.
    pub fn mount(&self) -> Option<&str> {
        self.mount.map(|i| self.obstacles[i].name.as_str())
    }
}
