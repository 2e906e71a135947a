//! Goal predicates: what must hold once a task has been executed.

use crate::shape::Shape;
use crate::world::World;
use akl_tsr::nalgebra::Vector3;
use akl_tsr::pose::{position_distance, serde_pose};
use akl_tsr::Pose;
use serde::{Deserialize, Serialize};

fn default_gap() -> f64 {
    0.01
}
fn default_tilt() -> f64 {
    0.15
}

/// A condition on the final world; `{"on": {...}}` or `{"at": {...}}` in task files.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Goal {
    /// `object` rests on top of `support`: its bottom within `gap` of the support's top, its
    /// centre above the support's outline, and tilted at most `max_tilt` from how it stood in
    /// the task file.
    On {
        /// The object that must rest.
        object: String,
        /// What it must rest on.
        support: String,
        /// Allowed vertical gap between bottom and top (metres).
        #[serde(default = "default_gap")]
        gap: f64,
        /// Allowed tilt from the object's orientation in the task file (radians).
        #[serde(default = "default_tilt")]
        max_tilt: f64,
    },
    /// `object` is at `pose` (world frame) within the tolerances. Rotation about a cylinder's
    /// own axis and any rotation of a sphere are ignored: they are not visible in the result.
    At {
        /// The object.
        object: String,
        /// Where it must be.
        #[serde(with = "serde_pose")]
        pose: Pose,
        /// Allowed position error (metres).
        position_tolerance: f64,
        /// Allowed rotation error (radians).
        angle_tolerance: f64,
    },
}

/// The outcome of checking one goal.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GoalCheck {
    /// The goal, in words.
    pub goal: String,
    /// Whether it holds.
    pub holds: bool,
    /// What was measured.
    pub detail: String,
}

impl Goal {
    /// The objects the goal mentions.
    pub fn objects(&self) -> Vec<&str> {
        match self {
            Goal::On {
                object, support, ..
            } => vec![object, support],
            Goal::At { object, .. } => vec![object],
        }
    }

    /// The goal in words, e.g. `on(part, shelf_2)`.
    pub fn describe(&self) -> String {
        match self {
            Goal::On {
                object, support, ..
            } => format!("on({object}, {support})"),
            Goal::At { object, pose, .. } => {
                let p = pose.translation.vector;
                format!("at({object}, [{:.3}, {:.3}, {:.3}])", p.x, p.y, p.z)
            }
        }
    }

    /// Checks the goal in `world`; `nominal` is the task file's world, which says which way up
    /// each object stands.
    pub fn check(&self, world: &World, nominal: &World) -> GoalCheck {
        let (holds, detail) = match self.evaluate(world, nominal) {
            Ok(detail) => (true, detail),
            Err(detail) => (false, detail),
        };
        GoalCheck {
            goal: self.describe(),
            holds,
            detail,
        }
    }

    fn evaluate(&self, world: &World, nominal: &World) -> Result<String, String> {
        let find = |name: &str| {
            world
                .object(name)
                .ok_or_else(|| format!("no object `{name}` in the world"))
        };
        match self {
            Goal::On {
                object,
                support,
                gap,
                max_tilt,
            } => {
                let o = find(object)?;
                let s = find(support)?;
                let dz = o.shape.bottom(&o.pose) - s.shape.top(&s.pose);
                let local = s
                    .pose
                    .inverse_transform_point(&o.pose.translation.vector.into());
                let tilt = nominal
                    .object(object)
                    .map(|n| tilt_from(&n.pose, &o.pose))
                    .unwrap_or(0.0);
                if dz.abs() > *gap {
                    return Err(format!("{object} is {dz:+.3} m from the top of {support}"));
                }
                if !s.shape.outline_contains(local.x, local.y, 0.0) {
                    return Err(format!("{object}'s centre is not above {support}"));
                }
                if tilt > *max_tilt {
                    return Err(format!("{object} is tilted {tilt:.2} rad"));
                }
                Ok(format!("gap {dz:+.3} m, tilt {tilt:.2} rad"))
            }
            Goal::At {
                object,
                pose,
                position_tolerance,
                angle_tolerance,
            } => {
                let o = find(object)?;
                let dp = position_distance(&o.pose, pose);
                let da = visible_rotation(&o.shape, &o.pose, pose);
                if dp > *position_tolerance {
                    return Err(format!("{object} is {dp:.3} m from its goal pose"));
                }
                if da > *angle_tolerance {
                    return Err(format!("{object} is turned {da:.2} rad from its goal pose"));
                }
                Ok(format!("{dp:.3} m, {da:.2} rad from the goal pose"))
            }
        }
    }
}

/// Angle between the world "up" direction as the object carried it at `nominal` and where that
/// direction points at `now`.
fn tilt_from(nominal: &Pose, now: &Pose) -> f64 {
    let up = Vector3::z();
    let up_in_object = nominal.rotation.inverse() * up;
    (now.rotation * up_in_object)
        .dot(&up)
        .clamp(-1.0, 1.0)
        .acos()
}

/// The rotation between two poses of a shape that an observer can tell apart.
fn visible_rotation(shape: &Shape, a: &Pose, b: &Pose) -> f64 {
    match shape {
        Shape::Sphere { .. } => 0.0,
        Shape::Cylinder { .. } => {
            let za = a.rotation * Vector3::z();
            let zb = b.rotation * Vector3::z();
            za.dot(&zb).clamp(-1.0, 1.0).acos()
        }
        Shape::Box { .. } => a.rotation.angle_to(&b.rotation),
    }
}
