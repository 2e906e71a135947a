//! Accuracy measures of a learned spec against a ground truth (thesis §4.2).
//!
//! How keyframes are compared:
//! - The learned spec is first grounded on the truth's object poses: every learned keyframe
//!   whose reference object also appears in the truth gets the truth's `t0_w` for it. A demo
//!   recorded with objects moved is then compared by where the hand is relative to the
//!   objects, not in the world.
//! - A **keyframe matches** a truth keyframe when kind, reference, gripper command and
//!   constraint flag are all equal.
//! - A **pose matches** when the nominal poses (`t0_w · tw_e`) are within
//!   [`Tolerance::position`] metres and [`Tolerance::rotation`] radians. TSR bounds are not
//!   compared: learned bounds are defaults, not learned.
//! - Keyframes are paired in order: the largest order-preserving pairing (longest common
//!   subsequence) under each predicate. Accuracy = IoU = paired / (learned + truth − paired).
//! - **Constraint accuracy** is the IoU of line lengths: each `move_in_line` keyframe and the
//!   one before it span a segment in space; a learned and a true segment overlap by the length
//!   of their common part along the true line, counted when they are parallel within
//!   [`Tolerance::rotation`] and the learned ends lie within [`Tolerance::position`] of the true
//!   line. With no line on either side the measure is undefined (`None`).
//! - **Success**: the learned spec equals the truth — as many keyframes, each matching the
//!   truth keyframe at its position in both senses.

use akl_tsr::nalgebra::Vector3;
use akl_tsr::pose::{position_distance, rotation_distance};
use akl_tsr::{Constraint, Keyframe, TaskSpec};
use serde::Serialize;

/// How close poses must be to count as the same.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Tolerance {
    /// Metres: 0.02, about the spread of where demonstrated lines start (the thesis reports a
    /// 1.6 cm standard deviation), well under the ≥ 5 cm between distinct keyframes of the
    /// built-in tasks.
    pub position: f64,
    /// Radians: 0.2.
    pub rotation: f64,
}

impl Default for Tolerance {
    fn default() -> Self {
        Tolerance {
            position: 0.02,
            rotation: 0.2,
        }
    }
}

/// The measures of one learned spec.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Scores {
    /// Keyframes in the learned spec.
    pub learned: usize,
    /// Keyframes in the ground truth.
    pub truth: usize,
    /// Keyframes paired by kind, reference, gripper and constraint.
    pub matched_keyframes: usize,
    /// Keyframe accuracy (IoU).
    pub keyframe_accuracy: f64,
    /// Keyframes paired by pose.
    pub matched_poses: usize,
    /// Pose accuracy (IoU).
    pub pose_accuracy: f64,
    /// Total length of the learned lines (metres).
    pub learned_line_length: f64,
    /// Total length of the true lines (metres).
    pub true_line_length: f64,
    /// Length common to both (metres).
    pub common_line_length: f64,
    /// Constraint accuracy (IoU of line lengths); `None` when neither spec has a line.
    pub constraint_accuracy: Option<f64>,
    /// True lines no learned line overlaps (missed constraints, Figure 4-6b).
    pub missed_lines: usize,
    /// Learned lines that overlap no true line (incorrect constraints, Figure 4-6b).
    pub incorrect_lines: usize,
    /// Whether the learned spec equals the ground truth.
    pub success: bool,
    /// Why it is not a success, one entry per difference.
    pub differences: Vec<String>,
}

/// Scores `learned` against `truth` (see the module docs).
pub fn score(learned: &TaskSpec, truth: &TaskSpec, tol: &Tolerance) -> Scores {
    let learned = ground_on_truth(learned, truth);
    let (l, t) = (&learned.keyframes, &truth.keyframes);
    let matched_keyframes = lcs(l, t, same_keyframe);
    let matched_poses = lcs(l, t, |a, b| same_pose(a, b, tol));
    let iou = |m: usize| {
        let union = l.len() + t.len() - m;
        if union == 0 {
            1.0
        } else {
            m as f64 / union as f64
        }
    };
    let (ll, tl) = (lines(l), lines(t));
    let learned_line_length = total(ll.iter().map(|(a, b)| (b - a).norm()));
    let true_line_length = total(tl.iter().map(|(a, b)| (b - a).norm()));
    let common_line_length = total(
        tl.iter()
            .flat_map(|tr| ll.iter().map(move |lr| common_length(lr, tr, tol))),
    );
    let constraint_accuracy = if ll.is_empty() && tl.is_empty() {
        None
    } else {
        let union = learned_line_length + true_line_length - common_line_length;
        Some(if union > 0.0 {
            (common_line_length / union).clamp(0.0, 1.0)
        } else {
            0.0
        })
    };
    let overlaps = |a: &(Vector3<f64>, Vector3<f64>), b: &(Vector3<f64>, Vector3<f64>)| {
        common_length(a, b, tol) > 0.0
    };
    let missed_lines = tl
        .iter()
        .filter(|tr| !ll.iter().any(|lr| overlaps(lr, tr)))
        .count();
    let incorrect_lines = ll
        .iter()
        .filter(|lr| !tl.iter().any(|tr| overlaps(lr, tr)))
        .count();
    let differences = differences(l, t, tol);
    Scores {
        missed_lines,
        incorrect_lines,
        learned: l.len(),
        truth: t.len(),
        matched_keyframes,
        keyframe_accuracy: iou(matched_keyframes),
        matched_poses,
        pose_accuracy: iou(matched_poses),
        learned_line_length,
        true_line_length,
        common_line_length,
        constraint_accuracy,
        success: differences.is_empty(),
        differences,
    }
}

/// A sum of lengths that is +0 when empty (`Iterator::sum` gives −0, which prints as "-0").
fn total(lengths: impl Iterator<Item = f64>) -> f64 {
    lengths.fold(0.0, |a, b| a + b)
}

/// `learned` with each keyframe's `t0_w` replaced by the truth's pose of the same reference.
pub(crate) fn ground_on_truth(learned: &TaskSpec, truth: &TaskSpec) -> TaskSpec {
    let mut out = learned.clone();
    for kf in &mut out.keyframes {
        if let Some(t) = truth.keyframes.iter().find(|t| t.reference == kf.reference) {
            kf.tsr = kf.tsr.rebased(t.tsr.t0_w);
        }
    }
    out
}

fn same_keyframe(a: &Keyframe, b: &Keyframe) -> bool {
    a.kind == b.kind
        && a.reference == b.reference
        && a.gripper == b.gripper
        && a.constraint == b.constraint
}

fn same_pose(a: &Keyframe, b: &Keyframe, tol: &Tolerance) -> bool {
    let (pa, pb) = (a.tsr.nominal(), b.tsr.nominal());
    position_distance(&pa, &pb) <= tol.position && rotation_distance(&pa, &pb) <= tol.rotation
}

/// Length of the longest order-preserving pairing of `a` with `b` under `eq`.
fn lcs(a: &[Keyframe], b: &[Keyframe], eq: impl Fn(&Keyframe, &Keyframe) -> bool) -> usize {
    let mut row = vec![0usize; b.len() + 1];
    for x in a {
        let mut diag = 0;
        for (j, y) in b.iter().enumerate() {
            let up = row[j + 1];
            row[j + 1] = if eq(x, y) { diag + 1 } else { up.max(row[j]) };
            diag = up;
        }
    }
    row[b.len()]
}

/// The straight-line segments of a keyframe sequence (start and end positions).
fn lines(kfs: &[Keyframe]) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    (1..kfs.len())
        .filter(|&i| kfs[i].constraint == Constraint::MoveInLine)
        .map(|i| {
            (
                kfs[i - 1].tsr.nominal().translation.vector,
                kfs[i].tsr.nominal().translation.vector,
            )
        })
        .collect()
}

fn common_length(
    learned: &(Vector3<f64>, Vector3<f64>),
    truth: &(Vector3<f64>, Vector3<f64>),
    tol: &Tolerance,
) -> f64 {
    let (t0, t1) = truth;
    let (l0, l1) = learned;
    let length = (t1 - t0).norm();
    let ll = (l1 - l0).norm();
    if length == 0.0 || ll == 0.0 {
        return 0.0;
    }
    let d = (t1 - t0) / length;
    let angle = ((l1 - l0) / ll).dot(&d).abs().min(1.0).acos();
    let off_line = |p: &Vector3<f64>| {
        let v = p - t0;
        (v - d * v.dot(&d)).norm()
    };
    if angle > tol.rotation || off_line(l0) > tol.position || off_line(l1) > tol.position {
        return 0.0;
    }
    let (s0, s1) = ((l0 - t0).dot(&d), (l1 - t0).dot(&d));
    let (lo, hi) = (s0.min(s1).max(0.0), s0.max(s1).min(length));
    (hi - lo).max(0.0)
}

fn differences(l: &[Keyframe], t: &[Keyframe], tol: &Tolerance) -> Vec<String> {
    let mut out = Vec::new();
    if l.len() != t.len() {
        out.push(format!(
            "{} keyframes learned, {} in the truth",
            l.len(),
            t.len()
        ));
    }
    for (i, (a, b)) in l.iter().zip(t).enumerate() {
        let mut fields = Vec::new();
        if a.kind != b.kind {
            fields.push(format!("kind {} ≠ {}", a.kind, b.kind));
        }
        if a.reference != b.reference {
            fields.push(format!("reference {} ≠ {}", a.reference, b.reference));
        }
        if a.gripper != b.gripper {
            fields.push(format!("gripper {} ≠ {}", a.gripper, b.gripper));
        }
        if a.constraint != b.constraint {
            fields.push(format!("constraint {} ≠ {}", a.constraint, b.constraint));
        }
        if !same_pose(a, b, tol) {
            let (pa, pb) = (a.tsr.nominal(), b.tsr.nominal());
            fields.push(format!(
                "pose {:.3} m / {:.3} rad away",
                position_distance(&pa, &pb),
                rotation_distance(&pa, &pb)
            ));
        }
        if !fields.is_empty() {
            out.push(format!("keyframe {i}: {}", fields.join(", ")));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_scene::builtin;
    use akl_tsr::KeyframeKind;

    fn truths() -> Vec<TaskSpec> {
        builtin::names()
            .into_iter()
            .map(|n| builtin::task(n).unwrap().unwrap().truth.unwrap())
            .collect()
    }

    #[test]
    fn every_truth_scores_as_a_success_against_itself() {
        for t in truths() {
            let s = score(&t, &t, &Tolerance::default());
            assert!(s.success, "{}: {:?}", t.task, s.differences);
            assert_eq!(s.keyframe_accuracy, 1.0);
            assert_eq!(s.pose_accuracy, 1.0);
            let has_lines = t
                .keyframes
                .iter()
                .any(|k| k.constraint == Constraint::MoveInLine);
            assert_eq!(s.constraint_accuracy.is_some(), has_lines, "{}", t.task);
            if has_lines {
                assert!((s.constraint_accuracy.unwrap() - 1.0).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn perturbed_truths_are_not_successes() {
        for t in truths() {
            let tol = Tolerance::default();
            let mut moved = t.clone();
            moved.keyframes[1].tsr.tw_e.translation.vector.x += 0.05;
            let s = score(&moved, &t, &tol);
            assert!(!s.success && s.pose_accuracy < 1.0 && s.keyframe_accuracy == 1.0);
            assert!(
                s.differences[0].contains("keyframe 1: pose"),
                "{:?}",
                s.differences
            );

            let mut fewer = t.clone();
            fewer.keyframes.pop();
            let s = score(&fewer, &t, &tol);
            let n = t.keyframes.len() as f64;
            assert!(!s.success);
            assert!((s.keyframe_accuracy - (n - 1.0) / n).abs() < 1e-12);

            let mut other_ref = t.clone();
            other_ref.keyframes[0].reference = "table".into();
            assert!(!score(&other_ref, &t, &tol).success);

            let mut kind = t.clone();
            kind.keyframes[0].kind = KeyframeKind::Constraint;
            let s = score(&kind, &t, &tol);
            assert!(!s.success && s.keyframe_accuracy < 1.0);
        }
    }

    #[test]
    fn moved_objects_do_not_change_the_score() {
        for t in truths() {
            let mut shifted = t.clone();
            for kf in &mut shifted.keyframes {
                kf.tsr.t0_w.translation.vector.y += 0.03;
            }
            assert!(
                score(&shifted, &t, &Tolerance::default()).success,
                "{}",
                t.task
            );
        }
    }

    #[test]
    fn line_overlap_is_measured_along_the_true_line() {
        let inspection = builtin::task("inspection").unwrap().unwrap().truth.unwrap();
        let mut half = inspection.clone();
        // Move the line's start halfway along (0.36 m line → 0.18 m learned).
        half.keyframes[1].tsr.tw_e.translation.vector.y -= 0.18;
        let s = score(&half, &inspection, &Tolerance::default());
        assert!((s.true_line_length - 0.36).abs() < 1e-9);
        assert!((s.learned_line_length - 0.18).abs() < 1e-9);
        assert!((s.constraint_accuracy.unwrap() - 0.5).abs() < 1e-9);
        assert_eq!((s.missed_lines, s.incorrect_lines), (0, 0));
        // No learned line at all.
        let mut none = inspection.clone();
        none.keyframes[2].constraint = Constraint::None;
        let s = score(&none, &inspection, &Tolerance::default());
        assert_eq!(s.constraint_accuracy, Some(0.0));
        assert_eq!((s.missed_lines, s.incorrect_lines), (1, 0));
        // A line where there is none (the carry to the part) and none where there is one.
        let mut wrong = inspection.clone();
        wrong.keyframes[1].constraint = Constraint::MoveInLine;
        wrong.keyframes[2].constraint = Constraint::None;
        let s = score(&wrong, &inspection, &Tolerance::default());
        assert_eq!((s.missed_lines, s.incorrect_lines), (1, 1));
    }
}
