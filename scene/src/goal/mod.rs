//! Goal predicates: what must hold once a task has been executed.
//!
//! Goals state what a task is for, in terms of the simulated world after the execution has
//! settled and of the paths the objects took; they never mention the spec's keyframes, so a
//! spec passes only if it achieves the task's purpose, whatever keyframes it uses. Furniture
//! moves with randomization, so every goal is stated relative to objects; only `at` is tied
//! to the world frame.

mod inside;
mod rest;
mod scan;

use crate::overlap::CONTACT_TOLERANCE;
use crate::paths::ObjectPaths;
use crate::world::World;
use akl_tsr::pose::serde_pose;
use akl_tsr::Pose;
use serde::{Deserialize, Serialize};

fn default_gap() -> f64 {
    0.01
}
fn default_tilt() -> f64 {
    0.15
}
fn default_depth() -> f64 {
    CONTACT_TOLERANCE
}
fn default_deviation() -> f64 {
    0.005
}
/// 0.1 rad (5.7°): a line whose ends are grounded on the row may still turn from it within
/// its keyframes' bounds: ±5 mm of position and ±0.05 rad of yaw about the reference's origin,
/// which on the built-in scan's ends, 18 cm from `scanner_2`'s centre, is another ±9 mm, so up
/// to 28 mm across over 36 cm (4.5°); goals drawn across the TSRs (`akl validate`) reach that.
fn default_row_angle() -> f64 {
    0.1
}

/// A condition on the end of an execution; written `{"on": {...}}`, `{"scan": {...}}` etc. in
/// task files (see `tasks/README.md`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", deny_unknown_fields)]
pub enum Goal {
    /// `object` rests upright on top of `support`: its bottom within `gap` of the support's
    /// top, its centre above the support's outline, and tilted at most `max_tilt` from how it
    /// stood in the task file.
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
    /// The two `objects` are not pressed into each other: their shapes sink into each other by
    /// at most `max_depth` (touching is allowed).
    Apart {
        /// The two objects.
        objects: [String; 2],
        /// Allowed depth of contact (metres); the contact tolerance of the task format.
        #[serde(default = "default_depth")]
        max_depth: f64,
    },
    /// `object` was carried over the row of `scanners` in a straight line, in their order: some
    /// stretch of its path passed entirely over every scanner (its outline seen from above
    /// inside the scanner's) with its bottom between `height[0]` and `height[1]` above the
    /// scanner's top, and that stretch stayed within `max_deviation` of a straight line which,
    /// seen from above, heads from the first scanner towards the last (within `max_angle` of
    /// the direction from the first scanner's centre to the last's), as a row of scanners
    /// scans. The stretch judged is a shortest one that crosses them all, so a free motion over
    /// one scanner before or after the pass is not part of it.
    Scan {
        /// The object scanned.
        object: String,
        /// The scanners, each of which it must pass over.
        scanners: Vec<String>,
        /// Scan height: the band `[min, max]` (metres) the object's bottom must be in above a
        /// scanner's top while it is over it.
        height: [f64; 2],
        /// How far (metres) the object's path over the row may leave a straight line.
        #[serde(default = "default_deviation")]
        max_deviation: f64,
        /// How far (radians) that line may turn from the row's direction, seen from above.
        #[serde(default = "default_row_angle")]
        max_angle: f64,
    },
    /// `object` (a cylinder or box, its axis the frame's z axis) lies inside `holder`: the
    /// holder's axis, the segment `axis` given in the holder's frame, is covered by the
    /// object's length from end to end, and the object's axis passes within `max_offset` of
    /// both of its ends.
    Inside {
        /// The object that must be inside, e.g. a pipe.
        object: String,
        /// The object whose frame gives the axis, e.g. a clamp.
        holder: String,
        /// The two ends of the holder's axis, in the holder's frame (metres).
        axis: [[f64; 3]; 2],
        /// Allowed distance (metres) of the object's axis from the holder's axis ends.
        max_offset: f64,
    },
    /// `object` is at `pose` in the world frame within the tolerances. The pose is fixed in the
    /// world: randomized furniture does not carry it, so use it only for places tied to the
    /// robot's base. Rotation about a cylinder's own axis and any rotation of a sphere are
    /// ignored: they are not visible in the result.
    At {
        /// The object.
        object: String,
        /// Where it must be (world frame).
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
    /// The short name of the predicate, as the task format spells it (`on`, `scan`, ...).
    pub fn kind(&self) -> &'static str {
        match self {
            Goal::On { .. } => "on",
            Goal::Apart { .. } => "apart",
            Goal::Scan { .. } => "scan",
            Goal::Inside { .. } => "inside",
            Goal::At { .. } => "at",
        }
    }

    /// The objects the goal mentions.
    pub fn objects(&self) -> Vec<&str> {
        match self {
            Goal::On {
                object, support, ..
            } => vec![object, support],
            Goal::Apart { objects, .. } => objects.iter().map(String::as_str).collect(),
            Goal::Scan {
                object, scanners, ..
            } => std::iter::once(object)
                .chain(scanners)
                .map(String::as_str)
                .collect(),
            Goal::Inside { object, holder, .. } => vec![object, holder],
            Goal::At { object, .. } => vec![object],
        }
    }

    /// The goal in words, e.g. `on(part, shelf_2)`.
    pub fn describe(&self) -> String {
        match self {
            Goal::On {
                object, support, ..
            } => format!("on({object}, {support})"),
            Goal::Apart {
                objects: [a, b], ..
            } => format!("apart({a}, {b})"),
            Goal::Scan {
                object, scanners, ..
            } => format!("scan({object} over {})", scanners.join(", ")),
            Goal::Inside { object, holder, .. } => format!("inside({object}, {holder})"),
            Goal::At { object, pose, .. } => {
                let p = pose.translation.vector;
                format!("at({object}, [{:.3}, {:.3}, {:.3}])", p.x, p.y, p.z)
            }
        }
    }

    /// Checks the values the JSON shape cannot: every length and angle finite and in range,
    /// every named object present in `world` (and of a fitting shape). The error is the field
    /// at fault (relative to the goal, e.g. `height`) and what is wrong.
    pub fn validate(&self, world: &World) -> Result<(), (String, String)> {
        for name in self.objects() {
            if world.object(name).is_none() {
                return Err(("".into(), format!("unknown object `{name}`")));
            }
        }
        match self {
            Goal::On { gap, max_tilt, .. } => {
                non_negative("gap", *gap)?;
                non_negative("max_tilt", *max_tilt)
            }
            Goal::Apart {
                objects: [a, b],
                max_depth,
            } => {
                if a == b {
                    return Err(("objects".into(), format!("names `{a}` twice")));
                }
                non_negative("max_depth", *max_depth)
            }
            Goal::Scan {
                scanners,
                height,
                max_deviation,
                max_angle,
                object,
            } => scan::validate(object, scanners, *height, *max_deviation, *max_angle),
            Goal::Inside {
                object,
                axis,
                max_offset,
                ..
            } => inside::validate(world, object, axis, *max_offset),
            Goal::At {
                position_tolerance,
                angle_tolerance,
                ..
            } => {
                non_negative("position_tolerance", *position_tolerance)?;
                non_negative("angle_tolerance", *angle_tolerance)
            }
        }
    }

    /// Checks the goal at the end of an execution: `end` is the settled world, `paths` the
    /// sampled paths of the objects that moved, `nominal` the task file's world (which says
    /// which way up each object stands).
    pub fn check(&self, end: &World, paths: &ObjectPaths, nominal: &World) -> GoalCheck {
        let (holds, detail) = match self.evaluate(end, paths, nominal) {
            Ok(detail) => (true, detail),
            Err(detail) => (false, detail),
        };
        GoalCheck {
            goal: self.describe(),
            holds,
            detail,
        }
    }

    fn evaluate(
        &self,
        end: &World,
        paths: &ObjectPaths,
        nominal: &World,
    ) -> Result<String, String> {
        match self {
            Goal::On {
                object,
                support,
                gap,
                max_tilt,
            } => rest::on(end, nominal, object, support, *gap, *max_tilt),
            Goal::Apart { objects, max_depth } => rest::apart(end, objects, *max_depth),
            Goal::Scan {
                object,
                scanners,
                height,
                max_deviation,
                max_angle,
            } => scan::evaluate(
                end,
                paths,
                &scan::Scan {
                    object,
                    scanners,
                    height: *height,
                    max_deviation: *max_deviation,
                    max_angle: *max_angle,
                },
            ),
            Goal::Inside {
                object,
                holder,
                axis,
                max_offset,
            } => inside::evaluate(end, object, holder, axis, *max_offset),
            Goal::At {
                object,
                pose,
                position_tolerance,
                angle_tolerance,
            } => rest::at(end, object, pose, *position_tolerance, *angle_tolerance),
        }
    }
}

/// The object `name` of `world`, or why it is missing.
fn find<'w>(world: &'w World, name: &str) -> Result<&'w crate::Object, String> {
    world
        .object(name)
        .ok_or_else(|| format!("no object `{name}` in the world"))
}

fn non_negative(field: &str, value: f64) -> Result<(), (String, String)> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err((
            field.into(),
            format!("must be finite and >= 0, got {value}"),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn goals_name_their_objects_and_read_as_predicates() {
        let scan: Goal = serde_json::from_str(
            r#"{"scan": {"object": "part", "scanners": ["s1", "s2"], "height": [0.02, 0.08]}}"#,
        )
        .unwrap();
        assert_eq!(scan.objects(), ["part", "s1", "s2"]);
        assert_eq!(scan.describe(), "scan(part over s1, s2)");
        assert_eq!(scan.kind(), "scan");
        let apart: Goal = serde_json::from_str(r#"{"apart": {"objects": ["a", "b"]}}"#).unwrap();
        assert_eq!(apart.describe(), "apart(a, b)");
        assert!(matches!(apart, Goal::Apart { max_depth, .. } if max_depth == CONTACT_TOLERANCE));
    }

    #[test]
    fn validation_names_the_field_at_fault() {
        let t = crate::builtin::task("pick_place").unwrap().unwrap();
        let bad = Goal::Apart {
            objects: ["block_a".into(), "block_a".into()],
            max_depth: 0.001,
        };
        assert_eq!(bad.validate(&t.world).unwrap_err().0, "objects");
        let bad = Goal::On {
            object: "block_a".into(),
            support: "shelf_2".into(),
            gap: 0.01,
            max_tilt: -0.1,
        };
        assert_eq!(bad.validate(&t.world).unwrap_err().0, "max_tilt");
        let bad = Goal::On {
            object: "block_c".into(),
            support: "shelf_2".into(),
            gap: 0.01,
            max_tilt: 0.1,
        };
        assert!(bad.validate(&t.world).unwrap_err().1.contains("block_c"));
    }
}
