//! Release checks: every object grasped is let go of by the end, and none falls further than
//! the drop limit when it is (the height of its bottom when let go above where it came to
//! rest).

use crate::report::{Cause, Failure, ReleaseCheck};
use crate::simulate::observations::ReleaseEvent;

/// One check per release; a failure for each object still in the hand at the end (`end`, the
/// simulated seconds of the run) and each that fell further than `drop_limit` (metres), at its
/// release.
pub(crate) fn check(
    releases: &[ReleaseEvent],
    still_held: &[String],
    drop_limit: f64,
    end: f64,
) -> (Vec<ReleaseCheck>, Vec<Failure>) {
    let mut failures: Vec<Failure> = still_held
        .iter()
        .map(|o| {
            Failure::new(
                Cause::GoalNotMet,
                format!("{o} is still in the hand at the end: the spec never releases it"),
            )
            .at_time(end)
        })
        .collect();
    let checks = releases
        .iter()
        .map(|r| {
            let fall = r
                .bottom_at_rest
                .map_or(0.0, |rest| r.bottom_at_release - rest);
            if fall > drop_limit {
                failures.push(
                    Failure::new(
                        Cause::Dropped,
                        format!(
                            "keyframe {}: {} fell {:.1} cm when let go (limit {:.1} cm)",
                            r.keyframe,
                            r.object,
                            fall * 1e2,
                            drop_limit * 1e2
                        ),
                    )
                    .at(r.keyframe)
                    .at_time(r.t),
                );
            }
            ReleaseCheck {
                keyframe: r.keyframe,
                object: r.object.clone(),
                t: r.t,
                fall,
            }
        })
        .collect();
    (checks, failures)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn release(at: f64, rest: f64) -> ReleaseEvent {
        ReleaseEvent {
            keyframe: 3,
            object: "part".into(),
            t: 2.0,
            bottom_at_release: at,
            bottom_at_rest: Some(rest),
        }
    }

    #[test]
    fn a_fall_beyond_the_limit_is_a_drop_and_a_kept_object_is_no_release() {
        let (checks, failures) = check(&[release(0.1405, 0.14)], &[], 0.02, 9.0);
        assert!(failures.is_empty() && (checks[0].fall - 0.0005).abs() < 1e-9);
        let (_, failures) = check(&[release(0.21, 0.14)], &[], 0.02, 9.0);
        assert_eq!(failures[0].cause, Cause::Dropped);
        assert_eq!(failures[0].t, Some(2.0), "at the release");
        assert!(
            failures[0].detail.contains("fell 7.0 cm"),
            "{}",
            failures[0].detail
        );
        let (_, failures) = check(&[], &["part".into()], 0.02, 9.0);
        assert_eq!(failures[0].cause, Cause::GoalNotMet);
        assert_eq!(failures[0].t, Some(9.0), "at the end");
        assert!(failures[0].detail.contains("never releases"));
    }
}
