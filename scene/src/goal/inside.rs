//! The `inside` goal: an elongated object lying along a holder's axis, all the way through it.

use super::find;
use crate::shape::Shape;
use crate::world::World;
use akl_tsr::nalgebra::{Point3, Vector3};

/// Checks the values of an `inside` goal; the error names the field.
pub(super) fn validate(
    world: &World,
    object: &str,
    axis: &[[f64; 3]; 2],
    max_offset: f64,
) -> Result<(), (String, String)> {
    if let Some(Shape::Sphere { .. }) = world.object(object).map(|o| &o.shape) {
        return Err((
            "object".into(),
            format!("`{object}` is a sphere, which has no axis; inside needs a cylinder or box"),
        ));
    }
    let [a, b] = axis.map(Vector3::from);
    if a.iter().chain(b.iter()).any(|v| !v.is_finite()) || (a - b).norm() < 1e-6 {
        return Err((
            "axis".into(),
            "must be two finite points at least 1 µm apart".into(),
        ));
    }
    if !max_offset.is_finite() || max_offset <= 0.0 {
        return Err((
            "max_offset".into(),
            format!("must be finite and > 0, got {max_offset}"),
        ));
    }
    Ok(())
}

/// Evaluates an `inside` goal in the settled world `end`.
pub(super) fn evaluate(
    end: &World,
    object: &str,
    holder: &str,
    axis: &[[f64; 3]; 2],
    max_offset: f64,
) -> Result<String, String> {
    let o = find(end, object)?;
    let h = find(end, holder)?;
    let centre = o.pose.translation.vector;
    let direction = o.pose.rotation * Vector3::z();
    let half_length = o.shape.half_extents().z;
    let mut offset: f64 = 0.0;
    let mut beyond_end = f64::NEG_INFINITY;
    for end_point in axis {
        let e = (h.pose * Point3::from(*end_point)).coords - centre;
        let along = e.dot(&direction);
        offset = offset.max((e - direction * along).norm());
        beyond_end = beyond_end.max(along.abs() - half_length);
    }
    if offset > max_offset {
        return Err(format!(
            "{object}'s axis is {:.1} mm from {holder}'s axis (at most {:.1} mm allowed)",
            offset * 1e3,
            max_offset * 1e3
        ));
    }
    if beyond_end > 0.0 {
        return Err(format!(
            "{object} does not reach through {holder}: its end stops {:.1} mm short of the far end of {holder}'s axis",
            beyond_end * 1e3
        ));
    }
    Ok(format!(
        "axis within {:.1} mm of {holder}'s along its whole length; {:.0} mm of {object} beyond it at the nearer end",
        offset * 1e3,
        -beyond_end * 1e3
    ))
}

#[cfg(test)]
mod tests {
    use crate::builtin;
    use crate::paths::ObjectPaths;
    use crate::{Goal, Task, World};
    use akl_tsr::pose::{pose_from_xyz, pose_from_xyz_rpy};

    fn task() -> Task {
        builtin::task("assembly").unwrap().unwrap()
    }

    fn inside_goal(t: &Task) -> &Goal {
        t.goals.iter().find(|g| g.kind() == "inside").unwrap()
    }

    /// The world with the pipe where the teaching releases it: through the clamp.
    fn through(world: &World) -> World {
        let mut w = world.clone();
        let rail = w.object("rail").unwrap().pose;
        w.object_mut("pipe").unwrap().pose =
            rail * pose_from_xyz_rpy([0.0, -0.13, 0.045], [std::f64::consts::FRAC_PI_2, 0.0, 0.0]);
        w
    }

    fn check(t: &Task, w: &World) -> crate::GoalCheck {
        inside_goal(t).check(w, &ObjectPaths::new(), &t.world)
    }

    fn shifted(w: &World, by: [f64; 3]) -> World {
        let mut w = w.clone();
        let pipe = w.object_mut("pipe").unwrap();
        pipe.pose = pose_from_xyz(by) * pipe.pose;
        w
    }

    #[test]
    fn a_pipe_through_the_clamp_holds_even_off_centre_within_the_clearance() {
        let t = task();
        let w = through(&t.world);
        let c = check(&t, &w);
        assert!(c.holds, "{}", c.detail);
        // 6 mm to the side, as far as the tunnel lets it, and 10 cm further along.
        let c = check(&t, &shifted(&w, [0.006, -0.1, 0.0]));
        assert!(c.holds, "{}", c.detail);
    }

    #[test]
    fn a_pipe_beside_the_clamp_fails() {
        let t = task();
        let c = check(&t, &shifted(&through(&t.world), [0.06, 0.0, 0.0]));
        assert!(
            !c.holds && c.detail.contains("60.1 mm from clamp_top's axis"),
            "{}",
            c.detail
        );
    }

    #[test]
    fn a_pipe_only_half_in_the_clamp_fails() {
        let t = task();
        // Its front end at the clamp's middle: 3 cm of the clamp's axis is left uncovered.
        let c = check(&t, &shifted(&through(&t.world), [0.0, 0.15, 0.0]));
        assert!(
            !c.holds && c.detail.contains("30.0 mm short"),
            "{}",
            c.detail
        );
    }

    #[test]
    fn a_pipe_across_the_clamp_axis_fails() {
        let t = task();
        let mut w = through(&t.world);
        let pipe = w.object_mut("pipe").unwrap();
        pipe.pose *= pose_from_xyz_rpy([0.0; 3], [0.3, 0.0, 0.0]);
        let c = check(&t, &w);
        assert!(
            !c.holds && c.detail.contains("from clamp_top's axis"),
            "{}",
            c.detail
        );
    }

    #[test]
    fn the_goal_follows_the_clamp_when_it_moves() {
        let t = task();
        let mut moved = t.world.clone();
        let shift = pose_from_xyz_rpy([0.02, -0.03, 0.0], [0.0, 0.0, 0.08]);
        for name in ["rail", "clamp_left", "clamp_right", "clamp_top"] {
            let o = moved.object_mut(name).unwrap();
            o.pose = shift * o.pose;
        }
        let c = check(&t, &through(&moved));
        assert!(c.holds, "{}", c.detail);
        // Where the clamp was in the task file is no longer inside it.
        let stale = through(&t.world);
        let mut w = moved.clone();
        w.object_mut("pipe").unwrap().pose = stale.object("pipe").unwrap().pose;
        assert!(!check(&t, &w).holds);
    }
}
