//! Keyframe check: when the plan reaches a keyframe, the simulated TCP lies in the keyframe's
//! TSR grounded on the reference object's simulated (true) pose.
//!
//! The TSR's bounds are widened by a slack ([`KeyframeSlack`]): what the single-precision
//! simulation and the servos' residual lag add, plus four standard deviations of the
//! perception error, since the planner grounded the keyframe on what it perceived. Four, not
//! three: `akl validate` draws goals up to a region's edge, and there 3σ per axis failed 1 of
//! 300 pick_place truth trials (a perception error of about 7 mm, 3.5σ, along one axis). A keyframe
//! grounded on the wrong object misses by the distance that object moved, centimetres under
//! the task's randomization.

use crate::options::ExecOptions;
use crate::report::{Cause, Failure, KeyframeCheck};
use crate::simulate::observations::KeyframeReach;
use akl_tsr::{Bounds, PoseJson, TaskSpec, Tsr};

/// How much wider than a TSR's bounds a reached keyframe may be.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub(crate) struct KeyframeSlack {
    /// Added to each position bound (metres).
    pub position: f64,
    /// Added to each angle bound (radians).
    pub angle: f64,
}

/// Slack of the simulation itself: 0.5 mm and 5 mrad.
pub(crate) const SIMULATION_SLACK: KeyframeSlack = KeyframeSlack {
    position: 5e-4,
    angle: 5e-3,
};

impl KeyframeSlack {
    /// The simulation's slack plus four standard deviations of a perception error of
    /// `position` metres and `yaw` radians.
    pub(crate) fn with_perception(position: f64, yaw: f64) -> KeyframeSlack {
        KeyframeSlack {
            position: SIMULATION_SLACK.position + 4.0 * position,
            angle: SIMULATION_SLACK.angle + 4.0 * yaw,
        }
    }

    /// The slack trials run with `options` are judged with: the simulation's plus four
    /// standard deviations of their perception error.
    pub(crate) fn of(options: &ExecOptions) -> KeyframeSlack {
        KeyframeSlack::with_perception(options.noise.position, options.noise.yaw)
    }
}

/// One check per keyframe the plan reached; a failure for each missed (at its reach time) or
/// never reached (with no time).
pub(crate) fn check(
    spec: &TaskSpec,
    reaches: &[KeyframeReach],
    slack: &KeyframeSlack,
) -> (Vec<KeyframeCheck>, Vec<Failure>) {
    let mut checks = Vec::with_capacity(reaches.len());
    let mut failures = Vec::new();
    for k in 0..spec.keyframes.len() {
        if !reaches.iter().any(|r| r.keyframe == k) {
            failures.push(
                Failure::new(
                    Cause::KeyframeMissed,
                    format!("keyframe {k}: the plan never reaches it"),
                )
                .at(k),
            );
        }
    }
    for r in reaches {
        let kf = &spec.keyframes[r.keyframe];
        let Some(reference) = r.reference else {
            failures.push(
                Failure::new(
                    Cause::KeyframeMissed,
                    format!(
                        "keyframe {}: its reference {} is not in the simulation",
                        r.keyframe, kf.reference
                    ),
                )
                .at(r.keyframe)
                .at_time(r.t),
            );
            continue;
        };
        let mut bw = kf.tsr.bw.0;
        for (i, [lo, hi]) in bw.iter_mut().enumerate() {
            let s = if i < 3 { slack.position } else { slack.angle };
            *lo -= s;
            *hi += s;
        }
        let distance = Tsr::new(reference, kf.tsr.tw_e, Bounds(bw)).distance(&r.tcp);
        let reached = distance == 0.0;
        if !reached {
            failures.push(Failure::new(
                Cause::KeyframeMissed,
                format!(
                    "keyframe {}: the simulated TCP is {:.1} mm from its TSR grounded on {}'s simulated pose",
                    r.keyframe,
                    distance * 1e3,
                    kf.reference
                ),
            ).at(r.keyframe).at_time(r.t));
        }
        checks.push(KeyframeCheck {
            keyframe: r.keyframe,
            t: r.t,
            reference: kf.reference.clone(),
            grounded_on: PoseJson::from_pose(&reference),
            tcp: PoseJson::from_pose(&r.tcp),
            distance,
            reached,
        });
    }
    (checks, failures)
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_tsr::pose::pose_from_xyz;

    fn reach(k: usize, tcp: akl_tsr::Pose, reference: akl_tsr::Pose) -> KeyframeReach {
        KeyframeReach {
            keyframe: k,
            t: 1.0,
            tcp,
            reference: Some(reference),
        }
    }

    #[test]
    fn a_keyframe_is_judged_on_the_reference_where_it_truly_is() {
        let task = akl_scene::builtin::task("inspection").unwrap().unwrap();
        let spec = task.truth.clone().unwrap();
        let part = task.world.object("part").unwrap().pose;
        let moved = pose_from_xyz([0.02, 0.01, 0.0]) * part;
        let kf = &spec.keyframes[0];
        let slack = KeyframeSlack::with_perception(0.002, 0.0);
        let on_moved = moved * kf.tsr.tw_e;
        let (checks, failures) = check(&spec, &[reach(0, on_moved, moved)], &slack);
        assert!(checks[0].reached && checks[0].distance == 0.0);
        assert_eq!(
            failures.len(),
            spec.keyframes.len() - 1,
            "the others were never reached"
        );
        let stale = kf.tsr.nominal();
        let (checks, failures) = check(&spec, &[reach(0, stale, moved)], &slack);
        assert!(!checks[0].reached && checks[0].distance > 0.006);
        assert!(failures
            .iter()
            .any(|f| f.detail.starts_with("keyframe 0: the simulated TCP")));
        let within = pose_from_xyz([0.005 + 0.0084, 0.0, 0.0]) * on_moved;
        assert!(check(&spec, &[reach(0, within, moved)], &slack).0[0].reached);
        let beyond = pose_from_xyz([0.005 + 0.0088, 0.0, 0.0]) * on_moved;
        assert!(!check(&spec, &[reach(0, beyond, moved)], &slack).0[0].reached);
    }
}
