//! Grasp check: the pads closed on the object the spec closes on, and held it soundly
//! (see [`crate::grasp`] for what sound means).

use crate::report::{Cause, Failure, GraspCheck};
use crate::simulate::observations::GraspEvent;

/// One check per closing of the gripper; a failure for each that did not hold the intended
/// object soundly, at the time the closing ended.
pub(crate) fn check(grasps: &[GraspEvent]) -> (Vec<GraspCheck>, Vec<Failure>) {
    let mut checks = Vec::with_capacity(grasps.len());
    let mut failures = Vec::new();
    for g in grasps {
        let grasped = match &g.pads {
            [Some(a), Some(b)] if a == b => Some(a.clone()),
            _ => None,
        };
        let why = match (&g.pads, &grasped) {
            (_, Some(o)) if *o != g.intended => {
                Some(format!("the pads closed on {o} instead of {}", g.intended))
            }
            (_, Some(_)) => g
                .unsound
                .as_ref()
                .map(|u| format!("{} is not held soundly: {u}", g.intended)),
            ([None, None], None) => Some(format!(
                "the pads closed on nothing ({} is not between them)",
                g.intended
            )),
            ([Some(a), Some(b)], None) => {
                Some(format!("the pads closed on two objects, {a} and {b}"))
            }
            ([Some(o), None] | [None, Some(o)], None) => Some(format!(
                "only one pad touched {o}: the other closed on nothing"
            )),
        };
        if let Some(why) = why {
            failures.push(
                Failure::new(
                    Cause::GraspFailed,
                    format!("keyframe {}: {why}", g.keyframe),
                )
                .at(g.keyframe)
                .at_time(g.t),
            );
        }
        checks.push(GraspCheck {
            keyframe: g.keyframe,
            t: g.t,
            planned: g.intended.clone(),
            grasped,
            pads: g.pads.clone(),
            offset_from_pads: g.measure.as_ref().map(|m| m.offset_from_pads),
            centre_offset: g.measure.as_ref().map(|m| m.centre_offset),
            overlap: g.measure.as_ref().map(|m| m.overlap),
            held: g.welded,
            squared: g.squared,
            slip: g.slip,
            peak_load: g.peak_load,
            broke_at: g.broke_at,
        });
    }
    (checks, failures)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn event(pads: [Option<&str>; 2], unsound: Option<&str>) -> GraspEvent {
        GraspEvent {
            keyframe: 0,
            t: 1.0,
            intended: "part".into(),
            pads: pads.map(|p| p.map(String::from)),
            measure: None,
            unsound: unsound.map(String::from),
            welded: unsound.is_none() && pads == [Some("part"); 2],
            squared: 0.0,
            broke_at: None,
            broke_by: None,
            slip: 0.0,
            slipped_at: None,
            peak_load: 0.0,
        }
    }

    #[test]
    fn every_way_a_closing_goes_wrong_is_a_failed_grasp() {
        let ok = check(&[event([Some("part"); 2], None)]);
        assert!(ok.1.is_empty() && ok.0[0].held);
        for (e, says) in [
            (event([None, None], None), "closed on nothing"),
            (
                event([Some("block"); 2], None),
                "closed on block instead of part",
            ),
            (event([Some("part"), Some("block")], None), "two objects"),
            (event([Some("part"), None], None), "only one pad"),
            (
                event([Some("part"); 2], Some("too little overlap")),
                "not held soundly",
            ),
        ] {
            let (_, f) = check(&[e]);
            assert_eq!(f.len(), 1);
            assert_eq!(f[0].cause, Cause::GraspFailed);
            assert!(f[0].detail.contains(says), "{}", f[0].detail);
        }
    }
}
