//! Goals on where objects came to rest: `on`, `apart` and `at`.

use super::find;
use crate::overlap::penetration;
use crate::shape::Shape;
use crate::world::World;
use akl_tsr::nalgebra::Vector3;
use akl_tsr::pose::position_distance;
use akl_tsr::Pose;

/// `object` rests upright on `support` in `end` (see [`super::Goal::On`]).
pub(super) fn on(
    end: &World,
    nominal: &World,
    object: &str,
    support: &str,
    gap: f64,
    max_tilt: f64,
) -> Result<String, String> {
    let o = find(end, object)?;
    let s = find(end, support)?;
    let dz = o.shape.bottom(&o.pose) - s.shape.top(&s.pose);
    let local = s
        .pose
        .inverse_transform_point(&o.pose.translation.vector.into());
    let tilt = nominal
        .object(object)
        .map(|n| tilt_from(&n.pose, &o.pose))
        .unwrap_or(0.0);
    if dz.abs() > gap {
        return Err(format!("{object} is {dz:+.3} m from the top of {support}"));
    }
    if !s.shape.outline_contains(local.x, local.y, 0.0) {
        let beyond = s
            .shape
            .outline_excess_of(&s.pose, &[o.pose.translation.vector.into()]);
        return Err(format!(
            "{object}'s centre is not above {support}: {:.1} mm beyond its outline",
            beyond * 1e3
        ));
    }
    if tilt > max_tilt {
        return Err(format!(
            "{object} is tilted {tilt:.2} rad (at most {max_tilt:.2} allowed)"
        ));
    }
    Ok(format!("gap {dz:+.3} m, tilt {tilt:.2} rad"))
}

/// The two objects sink into each other by at most `max_depth` (see [`super::Goal::Apart`]).
pub(super) fn apart(end: &World, [a, b]: &[String; 2], max_depth: f64) -> Result<String, String> {
    let oa = find(end, a)?;
    let ob = find(end, b)?;
    let depth = penetration(&oa.shape, &oa.pose, &ob.shape, &ob.pose);
    if depth > max_depth {
        return Err(format!(
            "{a} and {b} are pressed {:.1} mm into each other (at most {:.1} mm allowed)",
            depth * 1e3,
            max_depth * 1e3
        ));
    }
    if depth > 0.0 {
        Ok(format!("touching, {:.1} mm deep", depth * 1e3))
    } else {
        Ok(format!("at least {:.3} m apart", -depth))
    }
}

/// `object` is at the world pose `pose` (see [`super::Goal::At`]).
pub(super) fn at(
    end: &World,
    object: &str,
    pose: &Pose,
    position_tolerance: f64,
    angle_tolerance: f64,
) -> Result<String, String> {
    let o = find(end, object)?;
    let dp = position_distance(&o.pose, pose);
    let da = visible_rotation(&o.shape, &o.pose, pose);
    if dp > position_tolerance {
        return Err(format!("{object} is {dp:.3} m from its goal pose"));
    }
    if da > angle_tolerance {
        return Err(format!("{object} is turned {da:.2} rad from its goal pose"));
    }
    Ok(format!("{dp:.3} m, {da:.2} rad from the goal pose"))
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
        Shape::Cylinder { .. } | Shape::Capsule { .. } => {
            let za = a.rotation * Vector3::z();
            let zb = b.rotation * Vector3::z();
            za.dot(&zb).clamp(-1.0, 1.0).acos()
        }
        Shape::Box { .. } | Shape::Mesh { .. } => a.rotation.angle_to(&b.rotation),
    }
}

#[cfg(test)]
mod tests {
    use crate::builtin;
    use crate::paths::ObjectPaths;
    use crate::{Goal, World};
    use akl_tsr::pose::{pose_from_xyz, pose_from_xyz_rpy};

    /// pick_place's end state as intended: both blocks where the teaching puts them, on
    /// their mats.
    fn placed() -> (crate::Task, World) {
        let t = builtin::task("pick_place").unwrap().unwrap();
        let mut w = t.world.clone();
        for (block, mat) in [("block_a", "mat_a"), ("block_b", "mat_b")] {
            let mat = w.object(mat).unwrap().pose;
            w.object_mut(block).unwrap().pose = mat * pose_from_xyz([0.0, 0.0, 0.0405]);
        }
        (t, w)
    }

    fn failing(t: &crate::Task, w: &World) -> Vec<String> {
        t.goals
            .iter()
            .map(|g| g.check(w, &ObjectPaths::new(), &t.world))
            .filter(|c| !c.holds)
            .map(|c| format!("{}: {}", c.goal, c.detail))
            .collect()
    }

    #[test]
    fn pick_place_holds_with_both_blocks_upright_on_their_mats() {
        let (t, w) = placed();
        assert!(failing(&t, &w).is_empty(), "{:?}", failing(&t, &w));
        // Turned about the vertical is still upright.
        let mut turned = w.clone();
        let b = turned.object_mut("block_b").unwrap();
        b.pose *= pose_from_xyz_rpy([0.0; 3], [0.0, 0.0, 0.7]);
        assert!(failing(&t, &turned).is_empty());
    }

    #[test]
    fn a_tilted_block_fails_for_its_tilt() {
        let (t, mut w) = placed();
        let b = w.object_mut("block_b").unwrap();
        // Leaning 0.3 rad on an edge: the bottom still touches the mat.
        b.pose *= pose_from_xyz_rpy([0.0; 3], [0.3, 0.0, 0.0]);
        b.pose.translation.z = 0.141 + b.shape.world_half_extents(&b.pose).z;
        let f = failing(&t, &w);
        assert_eq!(f.len(), 1, "{f:?}");
        assert!(
            f[0].starts_with("on(block_b, mat_b)") && f[0].contains("tilted"),
            "{f:?}"
        );
    }

    #[test]
    fn a_block_beside_its_mat_or_on_the_wrong_shelf_fails() {
        let (t, mut w) = placed();
        let shelf_1 = t.world.object("shelf_1").unwrap().pose;
        w.object_mut("block_a").unwrap().pose = shelf_1 * pose_from_xyz([0.0, 0.0, 0.11]);
        // On the right shelf, 3 cm from its mat: its centre is off the 4 cm mat.
        let mat_b = t.world.object("mat_b").unwrap().pose;
        w.object_mut("block_b").unwrap().pose = mat_b * pose_from_xyz([0.03, 0.0, 0.0405]);
        let f = failing(&t, &w);
        assert!(
            f.len() == 2
                && f[0].starts_with("on(block_a, mat_a)")
                && f[1].starts_with("on(block_b, mat_b)")
                && f.iter().all(|f| f.contains("not above")),
            "{f:?}"
        );
    }

    #[test]
    fn blocks_pressed_into_each_other_fail_and_touching_ones_pass() {
        let (t, mut w) = placed();
        let a = w.object("block_a").unwrap().pose;
        let apart = |w: &World| -> Vec<String> {
            failing(&t, w)
                .into_iter()
                .filter(|f| f.starts_with("apart"))
                .collect()
        };
        // Side by side along x, faces touching: allowed.
        w.object_mut("block_b").unwrap().pose = pose_from_xyz([0.05, 0.0, 0.0]) * a;
        assert!(apart(&w).is_empty(), "{:?}", apart(&w));
        // 3 mm into each other: the goal names the depth.
        w.object_mut("block_b").unwrap().pose = pose_from_xyz([0.047, 0.0, 0.0]) * a;
        let f = apart(&w);
        assert!(
            f.len() == 1 && f[0].starts_with("apart(block_a, block_b)") && f[0].contains("3.0 mm"),
            "{f:?}"
        );
    }

    #[test]
    fn at_is_fixed_in_the_world() {
        let (t, w) = placed();
        let target = w.object("block_a").unwrap().pose;
        let g = Goal::At {
            object: "block_a".into(),
            pose: target,
            position_tolerance: 0.01,
            angle_tolerance: 0.1,
        };
        assert!(g.check(&w, &ObjectPaths::new(), &t.world).holds);
        let mut moved = w.clone();
        moved.object_mut("block_a").unwrap().pose = pose_from_xyz([0.0, 0.02, 0.0]) * target;
        let c = g.check(&moved, &ObjectPaths::new(), &t.world);
        assert!(!c.holds && c.detail.contains("0.020 m"), "{c:?}");
    }
}
