//! Worlds: the robot base and named objects.

use crate::overlap::{shapes_overlap, CONTACT_TOLERANCE};
use crate::shape::Shape;
use akl_tsr::pose::serde_pose;
use akl_tsr::Pose;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};

/// A named rigid object of the scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Object {
    /// Unique name; keyframes refer to objects by it.
    pub name: String,
    /// Geometry, centred on the object frame.
    pub shape: Shape,
    /// Pose of the object frame in the world.
    #[serde(with = "serde_pose")]
    pub pose: Pose,
    /// Whether the robot may pick the object up (dynamic in simulation); fixed objects are
    /// furniture.
    pub movable: bool,
    /// Mass in kilograms (used for movable objects).
    pub mass: f64,
    /// Coulomb friction coefficient.
    pub friction: f64,
}

/// The robot base pose and the objects around it; all poses in the world frame.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct World {
    /// Pose of the robot's base frame in the world.
    #[serde(with = "serde_pose")]
    pub robot_base: Pose,
    /// The objects, in file order.
    pub objects: Vec<Object>,
}

/// How far (metres) an object's bottom may be from a support's top for it to rest on it.
pub const SUPPORT_GAP: f64 = 2e-3;

impl World {
    /// The object named `name`.
    pub fn object(&self, name: &str) -> Option<&Object> {
        self.objects.iter().find(|o| o.name == name)
    }

    /// Mutable access to the object named `name`.
    pub fn object_mut(&mut self, name: &str) -> Option<&mut Object> {
        self.objects.iter_mut().find(|o| o.name == name)
    }

    /// Every object's current pose by name, as grounding needs them.
    pub fn object_poses(&self) -> BTreeMap<String, Pose> {
        self.objects
            .iter()
            .map(|o| (o.name.clone(), o.pose))
            .collect()
    }

    /// The names of all objects.
    pub fn names(&self) -> impl Iterator<Item = &str> {
        self.objects.iter().map(|o| o.name.as_str())
    }

    /// The object `name` rests on: the one whose top is within [`SUPPORT_GAP`] of `name`'s
    /// bottom and whose outline seen from above contains `name`'s centre; the highest such.
    pub fn support_of(&self, name: &str) -> Option<&Object> {
        let object = self.object(name)?;
        self.support_under(&object.shape, &object.pose, name)
    }

    /// The object a shape at `pose` would rest on (see [`World::support_of`]), ignoring `skip`.
    pub fn support_under(&self, shape: &Shape, pose: &Pose, skip: &str) -> Option<&Object> {
        let bottom = shape.bottom(pose);
        let centre = pose.translation.vector;
        self.objects
            .iter()
            .filter(|s| s.name != skip)
            .filter(|s| (s.shape.top(&s.pose) - bottom).abs() <= SUPPORT_GAP)
            .filter(|s| {
                let local = s.pose.inverse_transform_point(&centre.into());
                s.shape.outline_contains(local.x, local.y, 0.0)
            })
            .max_by(|a, b| a.shape.top(&a.pose).total_cmp(&b.shape.top(&b.pose)))
    }

    /// Pairs of objects that interpenetrate (deeper than resting contact).
    pub fn overlapping_pairs(&self) -> Vec<(&str, &str)> {
        let mut pairs = Vec::new();
        for (i, a) in self.objects.iter().enumerate() {
            for b in &self.objects[i + 1..] {
                if shapes_overlap(&a.shape, &a.pose, &b.shape, &b.pose) {
                    pairs.push((a.name.as_str(), b.name.as_str()));
                }
            }
        }
        pairs
    }

    /// Checks names, sizes and physical properties; errors name the object.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let mut seen = BTreeSet::new();
        for (i, o) in self.objects.iter().enumerate() {
            let at = |f: &str| format!("world.objects[{i}] ({}).{f}", o.name);
            if o.name.trim().is_empty() {
                return Err((format!("world.objects[{i}].name"), "is empty".into()));
            }
            if o.name == akl_tsr::WORLD_FRAME {
                return Err((at("name"), "`world` is reserved for the world frame".into()));
            }
            if !seen.insert(o.name.as_str()) {
                return Err((at("name"), "is used by more than one object".into()));
            }
            o.shape
                .validate()
                .map_err(|p| (at("shape"), p.to_string()))?;
            if !o.mass.is_finite() || o.mass < 0.0 || (o.movable && o.mass == 0.0) {
                return Err((
                    at("mass"),
                    format!(
                        "must be finite, >= 0, and > 0 for a movable object; got {}",
                        o.mass
                    ),
                ));
            }
            if !o.friction.is_finite() || o.friction < 0.0 {
                return Err((
                    at("friction"),
                    format!("must be finite and >= 0, got {}", o.friction),
                ));
            }
        }
        if let Some((a, b)) = self.overlapping_pairs().first() {
            return Err((
                "world.objects".into(),
                format!("`{a}` and `{b}` interpenetrate by more than {CONTACT_TOLERANCE} m"),
            ));
        }
        Ok(())
    }
}
