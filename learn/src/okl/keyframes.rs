//! Algorithm 1, lines 12, 15 and 16: constraint keyframes, interaction keyframes at the gripper
//! commands, and combining the two where they coincide.

use super::segment::{gripper_changes, Segment};
use akl_tsr::nalgebra::Vector3;
use akl_tsr::{Constraint, Gripper, KeyframeKind};

/// A keyframe before grounding: where in the demo it is and what it commands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct RawKeyframe {
    /// Demonstration frame.
    pub frame: usize,
    /// Interaction, constraint or combined.
    pub kind: KeyframeKind,
    /// Gripper state commanded once reached.
    pub gripper: Gripper,
    /// Constraint on the segment ending here.
    pub constraint: Constraint,
}

/// A learned straight-line constraint: frames `start..=end` of one interaction segment.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct LineConstraint {
    /// The segment it lies in.
    pub segment: Segment,
    /// First frame of the line.
    pub start: usize,
    /// Last frame of the line.
    pub end: usize,
}

/// Line 15, `AddInteractionKFs`: one keyframe per gripper command, at the frame the state
/// changes, commanding the new state.
pub(crate) fn interaction_keyframes(gripper: &[Gripper]) -> Vec<RawKeyframe> {
    gripper_changes(gripper)
        .into_iter()
        .map(|k| RawKeyframe {
            frame: k,
            kind: KeyframeKind::Interaction,
            gripper: gripper[k],
            constraint: Constraint::None,
        })
        .collect()
}

/// Line 12, `ConstraintKF`: the two keyframes bounding a line; the gripper keeps the segment's
/// state and the second keyframe carries the move-in-line constraint.
pub(crate) fn constraint_keyframes(line: &LineConstraint) -> [RawKeyframe; 2] {
    let kf = |frame, constraint| RawKeyframe {
        frame,
        kind: KeyframeKind::Constraint,
        gripper: line.segment.gripper,
        constraint,
    };
    [
        kf(line.start, Constraint::None),
        kf(line.end, Constraint::MoveInLine),
    ]
}

/// Line 16, `CombineKF`: merges interaction and constraint keyframes into one ordered list.
///
/// `interactions` and `lines` are in frame order; the merge bisects instead of scanning, so
/// it costs O(K log K) for K keyframes, not O(K²).
///
/// A line boundary coincides with an interaction when it lies in the segment that interaction
/// opens (line start) or closes (line end) and the hand gets from the one to the other without
/// leaving the line: the end-effector positions at the two frames are at most `tolerance`
/// metres apart, or every frame between them lies within `tolerance` of the line (the hand
/// went straight from the grasp into the line, or straight on from the line to the release).
/// The second case matters for a teacher who starts a slide slowly after a grasp: the
/// threshold places the boundary where the motion becomes clearly straight, a centimetre or
/// two into the slide, although the line starts at the grasp. The boundary then moves to the
/// interaction's frame and the two become one combined keyframe (the interaction's gripper
/// command, the line's constraint flag). Lines in one segment that overlap are cut so the
/// later one starts where the earlier one ends (one keyframe between them).
///
/// The check walks the frames between a boundary and its interaction once, so the merge stays
/// linear in the number of frames.
pub(crate) fn combine(
    interactions: &[RawKeyframe],
    lines: &[LineConstraint],
    positions: &[Vector3<f64>],
    tolerance: f64,
) -> Vec<RawKeyframe> {
    let is_interaction = |k: usize| interactions.binary_search_by_key(&k, |i| i.frame).is_ok();
    let joins = |l: &LineConstraint, a: usize, b: usize| {
        (positions[a] - positions[b]).norm() <= tolerance
            || stays_on_line(positions, l, a.min(b)..=a.max(b), tolerance)
    };
    let mut snapped: Vec<LineConstraint> = Vec::with_capacity(lines.len());
    for line in lines {
        let mut l = *line;
        if is_interaction(l.segment.start) && joins(line, l.start, l.segment.start) {
            l.start = l.segment.start;
        }
        if is_interaction(l.segment.end) && joins(line, l.end, l.segment.end) {
            l.end = l.segment.end;
        }
        if let Some(prev) = snapped.last() {
            if l.start < prev.end {
                l.start = prev.end;
            }
        }
        if l.end > l.start {
            snapped.push(l);
        }
    }
    let mut out: Vec<RawKeyframe> = interactions.to_vec();
    let mut boundaries: Vec<RawKeyframe> = Vec::with_capacity(2 * snapped.len());
    for l in &snapped {
        for c in constraint_keyframes(l) {
            let existing = match out.binary_search_by_key(&c.frame, |k| k.frame) {
                Ok(i) => Some(&mut out[i]),
                Err(_) => boundaries.last_mut().filter(|b| b.frame == c.frame),
            };
            match existing {
                Some(existing) => {
                    if existing.kind == KeyframeKind::Interaction {
                        existing.kind = KeyframeKind::Combined;
                    }
                    if c.constraint == Constraint::MoveInLine {
                        existing.constraint = Constraint::MoveInLine;
                    }
                }
                None => boundaries.push(c),
            }
        }
    }
    out.extend(boundaries);
    out.sort_by_key(|k| k.frame);
    out
}

/// Whether every position of `frames` lies within `tolerance` of the straight line through the
/// two boundaries of `line`.
fn stays_on_line(
    positions: &[Vector3<f64>],
    line: &LineConstraint,
    frames: std::ops::RangeInclusive<usize>,
    tolerance: f64,
) -> bool {
    let origin = positions[line.start];
    let Some(direction) = (positions[line.end] - origin).try_normalize(1e-9) else {
        return false;
    };
    positions[frames].iter().all(|p| {
        let v = p - origin;
        (v - direction * v.dot(&direction)).norm() <= tolerance
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use Gripper::{Closed as C, Open as O};

    fn positions(n: usize) -> Vec<Vector3<f64>> {
        (0..n)
            .map(|i| Vector3::new(i as f64 * 0.001, 0.0, 0.0))
            .collect()
    }

    /// [`positions`] lifted 1 mm off the x axis outside frames `on`: straight only there.
    fn bent(n: usize, on: std::ops::RangeInclusive<usize>) -> Vec<Vector3<f64>> {
        let mut p = positions(n);
        for (k, v) in p.iter_mut().enumerate() {
            v.y = if on.contains(&k) { 0.0 } else { 0.001 };
        }
        p
    }

    #[test]
    fn interactions_at_each_command() {
        let g = [O, O, C, C, O];
        let k = interaction_keyframes(&g);
        assert_eq!(k.len(), 2);
        assert_eq!((k[0].frame, k[0].gripper), (2, C));
        assert_eq!((k[1].frame, k[1].gripper), (4, O));
    }

    #[test]
    fn a_line_inside_a_segment_gives_two_constraint_keyframes() {
        let g = [O, O, C, C, C, C, C, C, C, C, O];
        let inter = interaction_keyframes(&g);
        let seg = Segment {
            start: 2,
            end: 10,
            gripper: C,
        };
        let line = LineConstraint {
            segment: seg,
            start: 5,
            end: 7,
        };
        let out = combine(&inter, &[line], &bent(11, 5..=7), 0.0005);
        let kinds: Vec<_> = out
            .iter()
            .map(|k| (k.frame, k.kind, k.constraint))
            .collect();
        assert_eq!(
            kinds,
            vec![
                (2, KeyframeKind::Interaction, Constraint::None),
                (5, KeyframeKind::Constraint, Constraint::None),
                (7, KeyframeKind::Constraint, Constraint::MoveInLine),
                (10, KeyframeKind::Interaction, Constraint::None),
            ]
        );
        assert!(out[1..3].iter().all(|k| k.gripper == C));
    }

    #[test]
    fn boundaries_near_interactions_combine() {
        let g = [O, O, C, C, C, C, C, C, C, C, O];
        let inter = interaction_keyframes(&g);
        let seg = Segment {
            start: 2,
            end: 10,
            gripper: C,
        };
        let line = LineConstraint {
            segment: seg,
            start: 3,
            end: 9,
        };
        // 1 mm per frame: within 1.5 mm both ends snap to the interactions.
        let out = combine(&inter, &[line], &positions(11), 0.0015);
        let kinds: Vec<_> = out
            .iter()
            .map(|k| (k.frame, k.kind, k.gripper, k.constraint))
            .collect();
        assert_eq!(
            kinds,
            vec![
                (2, KeyframeKind::Combined, C, Constraint::None),
                (10, KeyframeKind::Combined, O, Constraint::MoveInLine),
            ]
        );
        // With a tighter tolerance they stay apart, unless the hand went along the line.
        assert_eq!(combine(&inter, &[line], &bent(11, 3..=9), 0.0005).len(), 4);
        assert_eq!(combine(&inter, &[line], &positions(11), 0.0005).len(), 2);
    }

    #[test]
    fn consecutive_lines_share_a_keyframe() {
        let seg = Segment {
            start: 0,
            end: 20,
            gripper: O,
        };
        let a = LineConstraint {
            segment: seg,
            start: 2,
            end: 8,
        };
        let b = LineConstraint {
            segment: seg,
            start: 6,
            end: 15,
        };
        let out = combine(&[], &[a, b], &positions(21), 0.0);
        let frames: Vec<_> = out.iter().map(|k| (k.frame, k.constraint)).collect();
        assert_eq!(
            frames,
            vec![
                (2, Constraint::None),
                (8, Constraint::MoveInLine),
                (15, Constraint::MoveInLine)
            ]
        );
    }
}
