//! The checks of a trial that compare what was executed with the spec and the task: keyframes
//! within their TSRs grounded on the reference's current pose, lines within tolerance, goals.

use crate::report::{KeyframeCheck, LineCheck};
use akl_planner::line::distance_to_segment;
use akl_scene::{GoalCheck, ObjectPaths, Task, World};
use akl_tsr::nalgebra::Vector3;
use akl_tsr::{Bounds, Keyframe, Pose, PoseJson};

/// Slack added to every position bound of a keyframe's TSR when checking it (metres): the
/// reference object rests up to a tenth of a millimetre from where the planner saw it, and
/// the simulation runs in single precision.
pub const POSITION_SLACK: f64 = 5e-4;
/// Slack added to every angular bound of a keyframe's TSR when checking it (radians).
pub const ANGLE_SLACK: f64 = 5e-3;

/// Checks that `tcp` lies in keyframe `index`'s TSR grounded on `reference` (the reference
/// object's pose at time `t`), its bounds widened by [`POSITION_SLACK`] and [`ANGLE_SLACK`].
pub fn check_keyframe(
    kf: &Keyframe,
    index: usize,
    reference: &Pose,
    tcp: &Pose,
    t: f64,
) -> KeyframeCheck {
    let mut bw = kf.tsr.bw.0;
    for (i, [lo, hi]) in bw.iter_mut().enumerate() {
        let slack = if i < 3 { POSITION_SLACK } else { ANGLE_SLACK };
        *lo -= slack;
        *hi += slack;
    }
    let grounded = akl_tsr::Tsr::new(*reference, kf.tsr.tw_e, Bounds(bw));
    let distance = grounded.distance(tcp);
    KeyframeCheck {
        keyframe: index,
        t,
        reference: kf.reference.clone(),
        grounded_on: PoseJson::from_pose(reference),
        tcp: PoseJson::from_pose(tcp),
        distance,
        reached: distance == 0.0,
    }
}

/// The largest distance of `path` from the segment `from`–`to`, as a [`LineCheck`] of the line
/// ending at keyframe `keyframe`, run from `start` to `end`.
pub fn check_line(
    keyframe: usize,
    (start, end): (f64, f64),
    from: &Vector3<f64>,
    to: &Vector3<f64>,
    path: &[Vector3<f64>],
    tolerance: f64,
) -> LineCheck {
    let deviation = path
        .iter()
        .map(|p| distance_to_segment(p, from, to))
        .fold(0.0, f64::max);
    LineCheck {
        keyframe,
        start,
        end,
        from: [from.x, from.y, from.z],
        to: [to.x, to.y, to.z],
        deviation,
        within: deviation <= tolerance,
    }
}

/// The task's goal predicates on the settled world `now` and the objects' sampled `paths`.
pub fn check_goals(task: &Task, now: &World, paths: &ObjectPaths) -> Vec<GoalCheck> {
    task.check_goals(now, paths)
}

/// The rest check: every movable object slower than `max_speed` (m/s, and 10 × that in rad/s)
/// once settled; `speeds` are (name, linear, angular) per movable object.
pub fn check_rest(speeds: &[(String, f64, f64)], max_speed: f64) -> GoalCheck {
    let moving: Vec<String> = speeds
        .iter()
        .filter(|(_, v, w)| *v > max_speed || *w > 10.0 * max_speed)
        .map(|(n, v, w)| format!("{n} ({v:.3} m/s, {w:.2} rad/s)"))
        .collect();
    GoalCheck {
        goal: "at rest".into(),
        holds: moving.is_empty(),
        detail: if moving.is_empty() {
            "every object at rest".into()
        } else {
            format!("still moving: {}", moving.join(", "))
        },
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_tsr::pose::pose_from_xyz;

    #[test]
    fn a_keyframe_is_checked_against_the_current_reference_pose() {
        let task = akl_scene::builtin::task("inspection").unwrap().unwrap();
        let kf = &task.truth.as_ref().unwrap().keyframes[0];
        let moved = pose_from_xyz([0.02, 0.01, 0.0]) * task.world.object("part").unwrap().pose;
        let at_moved = moved * kf.tsr.tw_e;
        let c = check_keyframe(kf, 0, &moved, &at_moved, 1.0);
        assert!(c.reached && c.distance == 0.0);
        let stale = kf.tsr.nominal();
        let c = check_keyframe(kf, 0, &moved, &stale, 1.0);
        assert!(!c.reached && c.distance > 0.015, "{c:?}");
        let within_slack = pose_from_xyz([0.0052, 0.0, 0.0]) * at_moved;
        assert!(check_keyframe(kf, 0, &moved, &within_slack, 1.0).reached);
    }

    #[test]
    fn a_line_check_reports_the_largest_deviation() {
        let a = Vector3::new(0.0, 0.0, 0.0);
        let b = Vector3::new(1.0, 0.0, 0.0);
        let path = [
            a,
            Vector3::new(0.5, 0.004, 0.0),
            Vector3::new(0.7, 0.0, 0.006),
            b,
        ];
        let c = check_line(2, (0.0, 1.0), &a, &b, &path, 0.005);
        assert!((c.deviation - 0.006).abs() < 1e-12 && !c.within);
        assert!(check_line(2, (0.0, 1.0), &a, &b, &path[..2], 0.005).within);
    }

    #[test]
    fn moving_objects_fail_the_rest_check() {
        let ok = check_rest(&[("a".into(), 0.001, 0.01)], 0.01);
        assert!(ok.holds);
        let bad = check_rest(&[("a".into(), 0.001, 0.01), ("b".into(), 0.2, 0.0)], 0.01);
        assert!(!bad.holds && bad.detail.contains('b'), "{}", bad.detail);
    }
}
