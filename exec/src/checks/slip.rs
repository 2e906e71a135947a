//! Slip check: an object the hand holds moves in the hand by no more than the slip limit
//! while carried (until the gripper opens).

use crate::report::{Cause, Failure};
use crate::simulate::observations::GraspEvent;

/// A failure for each held object that slipped further than `limit` (metres).
pub fn check(grasps: &[GraspEvent], limit: f64) -> Vec<Failure> {
    grasps
        .iter()
        .filter(|g| g.welded && g.slip > limit)
        .map(|g| {
            let why = match g.broke_at {
                Some(t) => format!(
                    " after the load ({:.0} N) exceeded what friction holds at {t:.2} s",
                    g.peak_load
                ),
                None => String::new(),
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
        })
        .collect()
}
