//! Algorithm 1, lines 2, 3 and 5: interaction segments, the detected constraints kept after the
//! teacher's answers, and the constrained regions of each segment.

use crate::demo::{Answer, DialogueEvent, DialogueKind};
use akl_tsr::Gripper;
use std::ops::RangeInclusive;

/// A stretch of the demonstration between two gripper changes (line 2, `SegmentTrajectory`).
///
/// Frames `start..=end`, both ends included: a segment starts at the frame of the gripper
/// command that opens it and ends at the frame of the command that closes it, so neighbouring
/// segments share that frame and a constraint may end exactly at an interaction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Segment {
    /// First frame (0 or the frame of a gripper change).
    pub start: usize,
    /// Last frame (the next gripper change, or the last frame).
    pub end: usize,
    /// Gripper state held during the segment.
    pub gripper: Gripper,
}

impl Segment {
    /// The frames of the segment.
    pub(crate) fn frames(&self) -> RangeInclusive<usize> {
        self.start..=self.end
    }
}

/// Frames at which the gripper state differs from the frame before: the gripper commands.
pub(crate) fn gripper_changes(gripper: &[Gripper]) -> Vec<usize> {
    (1..gripper.len())
        .filter(|&k| gripper[k] != gripper[k - 1])
        .collect()
}

/// Splits frames `0..n` at the gripper changes (line 2). Empty for an empty demo.
pub(crate) fn segment_trajectory(gripper: &[Gripper]) -> Vec<Segment> {
    let n = gripper.len();
    if n == 0 {
        return Vec::new();
    }
    let mut bounds = vec![0];
    bounds.extend(gripper_changes(gripper));
    bounds.push(n - 1);
    bounds
        .windows(2)
        .map(|w| Segment {
            start: w[0],
            end: w[1],
            gripper: gripper[w[0]],
        })
        .filter(|s| s.end > s.start || n == 1)
        .collect()
}

/// The maximal runs of `true` in `states`, as inclusive frame ranges.
pub fn runs(states: &[bool]) -> Vec<RangeInclusive<usize>> {
    let mut out = Vec::new();
    let mut start = None;
    for (k, &s) in states.iter().enumerate() {
        match (s, start) {
            (true, None) => start = Some(k),
            (false, Some(a)) => {
                out.push(a..=k - 1);
                start = None;
            }
            _ => {}
        }
    }
    if let Some(a) = start {
        out.push(a..=states.len() - 1);
    }
    out
}

/// The answer given to the query a detected run raised: the first answer at or after the run's
/// first frame and before the next run starts (`None` when the teacher gave none). `events`
/// are in time order.
pub(crate) fn answer_for(
    run: &RangeInclusive<usize>,
    next_run_start: Option<usize>,
    events: &[DialogueEvent],
) -> Option<Answer> {
    events
        .iter()
        .skip_while(|e| e.frame < *run.start())
        .take_while(|e| next_run_start.is_none_or(|n| e.frame < n))
        .find_map(|e| match e.kind {
            DialogueKind::Answer(a) => Some(a),
            _ => None,
        })
}

/// Line 3, `ModifyDetectedConstraints`: the detected constrained runs of `detector` without
/// those the teacher answered "no" (answers "yes", "I don't know" and no answer keep a run).
///
/// One pass over the runs and the (time-ordered) events together.
pub(crate) fn modify_detected_constraints(
    detector: &[bool],
    events: &[DialogueEvent],
) -> Vec<RangeInclusive<usize>> {
    let all = runs(detector);
    let mut kept = Vec::with_capacity(all.len());
    let mut from = 0;
    for (i, run) in all.iter().enumerate() {
        from += events[from..].partition_point(|e| e.frame < *run.start());
        let next = all.get(i + 1).map(|r| *r.start());
        if answer_for(run, next, &events[from..]) != Some(Answer::No) {
            kept.push(run.clone());
        }
    }
    kept
}

/// Line 5, `getConstrainedRegions`: the parts of the kept runs inside `segment`, in order.
///
/// `kept` is in frame order (as [`modify_detected_constraints`] returns it), so the runs that
/// can reach into the segment are found by bisection.
pub(crate) fn constrained_regions(
    segment: &Segment,
    kept: &[RangeInclusive<usize>],
) -> Vec<RangeInclusive<usize>> {
    let first = kept.partition_point(|r| *r.end() < segment.start);
    kept[first..]
        .iter()
        .take_while(|r| *r.start() <= segment.end)
        .filter_map(|r| {
            let a = (*r.start()).max(segment.start);
            let b = (*r.end()).min(segment.end);
            (a <= b).then_some(a..=b)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use Gripper::{Closed as C, Open as O};

    fn answer(frame: usize, a: Answer) -> DialogueEvent {
        DialogueEvent {
            t: frame as f64 * 0.01,
            frame,
            kind: DialogueKind::Answer(a),
        }
    }

    #[test]
    fn segments_share_the_gripper_change_frames() {
        let g = [O, O, O, C, C, C, O, O];
        assert_eq!(gripper_changes(&g), vec![3, 6]);
        let s = segment_trajectory(&g);
        assert_eq!(s.len(), 3);
        assert_eq!((s[0].start, s[0].end, s[0].gripper), (0, 3, O));
        assert_eq!((s[1].start, s[1].end, s[1].gripper), (3, 6, C));
        assert_eq!((s[2].start, s[2].end, s[2].gripper), (6, 7, O));
    }

    #[test]
    fn degenerate_gripper_streams() {
        assert!(segment_trajectory(&[]).is_empty());
        assert_eq!(segment_trajectory(&[O]).len(), 1);
        assert_eq!(segment_trajectory(&[O, O, O]).len(), 1);
        // A change on the last frame leaves no empty trailing segment.
        let s = segment_trajectory(&[O, O, C]);
        assert_eq!(s.len(), 1);
        assert_eq!((s[0].start, s[0].end), (0, 2));
    }

    #[test]
    fn runs_of_true() {
        let d = [true, true, false, false, true, false, true];
        assert_eq!(runs(&d), vec![0..=1, 4..=4, 6..=6]);
        assert!(runs(&[false, false]).is_empty());
    }

    #[test]
    fn runs_answered_no_are_dropped() {
        let d = [
            false, true, true, true, false, false, true, true, false, true,
        ];
        let events = [
            answer(2, Answer::No),
            answer(7, Answer::Yes),
            answer(9, Answer::Unknown),
        ];
        assert_eq!(modify_detected_constraints(&d, &events), vec![6..=7, 9..=9]);
        // An answer after the run ended (the detector already flipped back) still counts.
        let events = [answer(4, Answer::No)];
        assert_eq!(modify_detected_constraints(&d, &events), vec![6..=7, 9..=9]);
        // No answer keeps every run.
        assert_eq!(modify_detected_constraints(&d, &[]).len(), 3);
    }

    #[test]
    fn regions_are_clipped_to_the_segment() {
        let seg = Segment {
            start: 3,
            end: 6,
            gripper: C,
        };
        assert_eq!(
            constrained_regions(&seg, &[0..=1, 2..=4, 5..=5, 6..=9, 10..=12]),
            vec![3..=4, 5..=5, 6..=6]
        );
    }
}
