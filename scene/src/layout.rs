//! Feasible layouts: the rules a placement of a task's objects must meet for the task to be
//! doable at all, so that a randomized trial blames the spec and never an impossible scene.

use crate::overlap::{penetration, CONTACT_TOLERANCE};
use crate::task::Task;
use crate::world::World;
use akl_tsr::nalgebra::Vector3;

/// How far (metres) an object's footprint may reach further beyond its support's outline than
/// it does in the task file (rounding, and the 1 mm contact tolerance of the format).
pub(crate) const OVERHANG_TOLERANCE: f64 = 1e-3;

/// Why a layout is not one the task can be done in.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum Infeasible {
    /// Two objects interpenetrate.
    #[error("{a} and {b} interpenetrate by {:.1} mm", depth * 1e3)]
    Overlap {
        /// One object.
        a: String,
        /// The other.
        b: String,
        /// How deep (metres).
        depth: f64,
    },
    /// Two movable objects are closer than the task's hand clearance.
    #[error("{a} and {b} are {:.1} mm apart, less than min_gap {:.1} mm", gap * 1e3, min_gap * 1e3)]
    TooClose {
        /// One object.
        a: String,
        /// The other.
        b: String,
        /// Their gap (metres).
        gap: f64,
        /// The task's `min_gap`.
        min_gap: f64,
    },
    /// An object no longer rests on what it stood on in the task file.
    #[error("{object} no longer rests on {support}")]
    OffSupport {
        /// The object.
        object: String,
        /// Its support in the task file.
        support: String,
    },
    /// An object's footprint reaches further beyond its support than in the task file.
    #[error("{object} overhangs {support} by {:.1} mm", overhang * 1e3)]
    Overhang {
        /// The object.
        object: String,
        /// Its support.
        support: String,
        /// How far its footprint reaches beyond the support's outline (metres).
        overhang: f64,
    },
    /// A TCP target of the teaching intent is out of the robot's reach.
    #[error(
        "teaching step {step}'s target is {distance:.3} m from the shoulder, beyond reach {max} m"
    )]
    OutOfReach {
        /// Index of the teaching step.
        step: usize,
        /// Its distance from the shoulder (metres).
        distance: f64,
        /// [`Reach::max`].
        max: f64,
    },
    /// A TCP target of the teaching intent is too close to the robot's base axis.
    #[error(
        "teaching step {step}'s target is {radial:.3} m from the base's axis, nearer than {min} m"
    )]
    TooNearBase {
        /// Index of the teaching step.
        step: usize,
        /// Its distance from the base's vertical axis (metres).
        radial: f64,
        /// [`Reach::min_radial`].
        min: f64,
    },
    /// The teaching intent cannot be followed in the layout.
    #[error("{0}")]
    Teaching(String),
    /// The layout does not stand still when simulated untouched (see
    /// [`crate::randomize::randomize_layout_with`]).
    #[error("{0}")]
    Unsettled(String),
}

/// Checks that `task` can be done in the layout `world` (the task's world with objects moved):
/// nothing interpenetrates; movable objects keep `min_gap` from each other (the gap between
/// bounding boxes, [`penetration`]'s negative); every object still rests on what it stood on
/// in the task file and overhangs it no further than there; every TCP target of the teaching
/// intent is within [`Reach`].
pub(crate) fn check_layout(task: &Task, world: &World) -> Result<(), Infeasible> {
    let objects = &world.objects;
    for (i, a) in objects.iter().enumerate() {
        for b in &objects[i + 1..] {
            let depth = penetration(&a.shape, &a.pose, &b.shape, &b.pose);
            if depth > CONTACT_TOLERANCE {
                return Err(Infeasible::Overlap {
                    a: a.name.clone(),
                    b: b.name.clone(),
                    depth,
                });
            }
            if a.movable && b.movable && -depth < task.min_gap {
                return Err(Infeasible::TooClose {
                    a: a.name.clone(),
                    b: b.name.clone(),
                    gap: -depth,
                    min_gap: task.min_gap,
                });
            }
        }
    }
    for nominal in &task.world.objects {
        let Some(support) = task.world.support_of(&nominal.name) else {
            continue;
        };
        let (Some(now), Some(under)) = (world.object(&nominal.name), world.object(&support.name))
        else {
            continue;
        };
        if world.support_of(&now.name).map(|s| &s.name) != Some(&support.name) {
            return Err(Infeasible::OffSupport {
                object: now.name.clone(),
                support: support.name.clone(),
            });
        }
        let allowed = support
            .shape
            .overhang(&support.pose, &nominal.shape, &nominal.pose)
            .max(0.0)
            + OVERHANG_TOLERANCE;
        let overhang = under.shape.overhang(&under.pose, &now.shape, &now.pose);
        if overhang > allowed {
            return Err(Infeasible::Overhang {
                object: now.name.clone(),
                support: support.name.clone(),
                overhang,
            });
        }
    }
    let targets = task
        .teaching
        .targets(world)
        .map_err(|e| Infeasible::Teaching(e.to_string()))?;
    let base_inverse = world.robot_base.inverse();
    let shoulder = Vector3::from(task.reach.shoulder);
    for (step, target) in targets.iter().enumerate() {
        let p = (base_inverse * target).translation.vector;
        let distance = (p - shoulder).norm();
        if distance > task.reach.max {
            return Err(Infeasible::OutOfReach {
                step,
                distance,
                max: task.reach.max,
            });
        }
        let radial = p.x.hypot(p.y);
        if radial < task.reach.min_radial {
            return Err(Infeasible::TooNearBase {
                step,
                radial,
                min: task.reach.min_radial,
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtin;
    use crate::reach::Reach;
    use akl_tsr::pose::pose_from_xyz;

    fn moved(world: &World, name: &str, by: [f64; 3]) -> World {
        let mut w = world.clone();
        let o = w.object_mut(name).unwrap();
        o.pose = pose_from_xyz(by) * o.pose;
        w
    }

    #[test]
    fn the_built_in_layouts_are_feasible() {
        for name in builtin::names() {
            let t = builtin::task(name).unwrap().unwrap();
            assert_eq!(check_layout(&t, &t.world), Ok(()), "{name}");
        }
    }

    #[test]
    fn blocks_too_close_for_the_hand_are_rejected() {
        let t = builtin::task("pick_place").unwrap().unwrap();
        // The layout the old randomizer allowed: 9.4 cm between centres, 8 cm of it along the
        // fingers' closing direction (the blocks' y): a 3 cm gap.
        let a = t.world.object("block_a").unwrap().pose.translation.vector;
        let b = t.world.object("block_b").unwrap().pose.translation.vector;
        let target = a + Vector3::new(0.05, 0.08, 0.0);
        let w = moved(&t.world, "block_b", (target - b).into());
        match check_layout(&t, &w) {
            Err(Infeasible::TooClose { gap, .. }) => assert!((gap - 0.03).abs() < 1e-9),
            other => panic!("{other:?}"),
        }
    }

    #[test]
    fn an_object_off_or_over_the_edge_of_its_support_is_rejected() {
        let t = builtin::task("pick_place").unwrap().unwrap();
        // block_b is 4.5 cm from shelf_1's edge along x: 5 cm more puts it over the edge.
        let w = moved(&t.world, "block_b", [0.05, 0.0, 0.0]);
        assert!(matches!(
            check_layout(&t, &w),
            Err(Infeasible::Overhang { ref object, .. }) if object == "block_b"
        ));
        let w = moved(&t.world, "block_b", [0.2, 0.0, 0.0]);
        assert!(matches!(
            check_layout(&t, &w),
            Err(Infeasible::OffSupport { ref object, .. }) if object == "block_b"
        ));
    }

    #[test]
    fn furniture_out_of_reach_is_rejected() {
        let t = builtin::task("pick_place").unwrap().unwrap();
        let shelf_2 = |by: [f64; 3]| {
            ["shelf_2", "mat_a", "mat_b"]
                .iter()
                .fold(t.world.clone(), |w, name| moved(&w, name, by))
        };
        let w = shelf_2([0.3, 0.0, 0.0]);
        assert!(
            matches!(
                check_layout(&t, &w),
                Err(Infeasible::OutOfReach { step: 1, .. })
            ),
            "{:?}",
            check_layout(&t, &w)
        );
        let w = shelf_2([-0.35, 0.2, 0.0]);
        assert!(
            matches!(check_layout(&t, &w), Err(Infeasible::TooNearBase { .. })),
            "{:?}",
            check_layout(&t, &w)
        );
    }

    #[test]
    fn reach_values_are_checked_by_field() {
        let r = Reach {
            min_radial: 0.9,
            ..Reach::default()
        };
        assert_eq!(r.validate().unwrap_err().0, "min_radial");
        let r = Reach {
            max: f64::NAN,
            ..Reach::default()
        };
        assert_eq!(r.validate().unwrap_err().0, "max");
    }
}
