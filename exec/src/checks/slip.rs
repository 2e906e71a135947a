//! Slip check: an object the hand holds moves in the hand by no more than the slip limit
//! while carried (until the gripper opens).

use crate::report::{Cause, Failure};
use crate::simulate::observations::GraspEvent;

/// A failure for each held object that slipped further than `limit` (metres), at the time it
/// first moved beyond the limit (else when its weld broke, else the grasp's time).
pub(crate) fn check(grasps: &[GraspEvent], limit: f64) -> Vec<Failure> {
    grasps
        .iter()
        .filter(|g| g.welded && g.slip > limit)
        .map(|g| {
            let why = match (g.broke_at, &g.broke_by) {
                (Some(t), Some(by)) => format!(" after {by} at {t:.2} s"),
                (Some(t), None) => format!(" after the grasp came loose at {t:.2} s"),
                _ => String::new(),
            };
            Failure::new(
                Cause::Slipped,
                format!(
                    "keyframe {}: {} moved {:.1} mm in the hand (limit {:.1} mm){why}",
                    g.keyframe,
                    g.intended,
                    g.slip * 1e3,
                    limit * 1e3
                ),
            )
            .at(g.keyframe)
            .at_time(g.slipped_at.or(g.broke_at).unwrap_or(g.t))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn held(slip: f64, slipped_at: Option<f64>, broke_at: Option<f64>) -> GraspEvent {
        GraspEvent {
            keyframe: 1,
            t: 1.0,
            intended: "tube".into(),
            pads: [Some("tube".into()), Some("tube".into())],
            measure: None,
            unsound: None,
            welded: true,
            squared: 0.0,
            broke_at,
            broke_by: broke_at.map(|_| {
                "a force of 25 N along the pads, more than the 20 N friction holds".into()
            }),
            slip,
            slipped_at,
            peak_load: 25.0,
        }
    }

    #[test]
    fn a_slip_beyond_the_limit_fails_when_it_first_went_beyond() {
        assert!(check(&[held(0.004, None, None)], 0.005).is_empty());
        let f = check(&[held(0.012, Some(2.26), Some(2.24))], 0.005);
        assert_eq!((f[0].cause, f[0].t), (Cause::Slipped, Some(2.26)));
        assert!(
            f[0].detail
                .contains("after a force of 25 N along the pads, more than the 20 N"),
            "{}",
            f[0].detail
        );
        let f = check(&[held(0.012, None, Some(2.24))], 0.005);
        assert_eq!(
            f[0].t,
            Some(2.24),
            "the weld's break when no time was noted"
        );
    }
}
