//! The world as the checks see it: its objects, grown where the rules say, and the robot's base.

use super::spheres::{Placement, Solid, Target};
use crate::parry_convert;
use akl_scene::World;
use akl_tsr::nalgebra::Vector3;
use akl_tsr::Pose;
use parry3d::shape::SharedShape;

/// A scene object prepared for checking.
#[derive(Debug, Clone)]
pub(super) struct Obstacle {
    pub(super) name: String,
    pub(super) shape: SharedShape,
    pub(super) pose: Pose,
    pub(super) min: Vector3<f64>,
    pub(super) max: Vector3<f64>,
    /// The object for closed-form distances from points.
    pub(super) target: Target,
}

/// The world as the checker sees it: exact object shapes with bounding boxes, the robot's
/// base pose, and the object the robot stands on.
#[derive(Debug, Clone)]
pub struct Scene {
    pub(super) obstacles: Vec<Obstacle>,
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
            let h = o.shape.world_half_extents(&o.pose);
            let c = o.pose.translation.vector;
            obstacles.push(Obstacle {
                name: o.name.clone(),
                shape,
                pose: o.pose * fix,
                min: c - h,
                max: c + h,
                target: Target {
                    solid: Solid::of(&o.shape),
                    inverse: Placement::of(&o.pose.inverse()),
                    min: c - h,
                    max: c + h,
                },
            });
        }
        let base = world.robot_base;
        let origin = base.translation.vector;
        let mount = obstacles.iter().position(|o| {
            let inside = |i: usize| origin[i] >= o.min[i] - 1e-9 && origin[i] <= o.max[i] + 1e-9;
            inside(0) && inside(1) && (o.max.z - origin.z).abs() <= akl_scene::SUPPORT_GAP
        });
        Scene {
            obstacles,
            base,
            mount,
        }
    }

    /// The robot base pose in the world.
    pub fn base(&self) -> &Pose {
        &self.base
    }

    /// Name of the object the robot is mounted on, if any.
    pub fn mount(&self) -> Option<&str> {
        self.mount.map(|i| self.obstacles[i].name.as_str())
    }
}
