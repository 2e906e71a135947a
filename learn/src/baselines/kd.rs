//! Keyframe demonstrations (KD, thesis §4.1): the teacher marks the keyframes while
//! demonstrating; the learner adds a keyframe at every gripper command and learns no
//! constraints.
//!
//! A mark within [`KdParams::merge_distance`] of a gripper command's end-effector position
//! (the teacher marking the grasp pose, then closing the gripper) is the same keyframe as the
//! command. Any other mark bounds a stretch of free motion: it becomes a keyframe of kind
//! `constraint` whose constraint is `none` — a segment boundary with no line, which is all KD
//! can express between interactions.

use crate::demo::{Demo, DialogueKind};
use crate::okl::keyframes::{interaction_keyframes, RawKeyframe};
use crate::okl::{check_demo, ground, task_name, LearnError};
use akl_scene::World;
use akl_tsr::{Bounds, Constraint, KeyframeKind, TaskSpec};

/// Tuning of KD.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KdParams {
    /// A mark this close (metres) to a gripper command is that command's keyframe: 0.01 m,
    /// the same tolerance OKL combines keyframes with.
    pub merge_distance: f64,
    /// Bounds of every TSR: the same defaults as OKL's.
    pub bounds: Bounds,
}

impl Default for KdParams {
    fn default() -> Self {
        let okl = crate::okl::OklParams::default();
        KdParams {
            merge_distance: okl.combine_distance,
            bounds: okl.bounds,
        }
    }
}

/// The frames the teacher marked as keyframes, in order, without repeats.
pub fn marked_frames(demo: &Demo) -> Vec<usize> {
    let mut frames: Vec<usize> = demo
        .events
        .iter()
        .filter(|e| e.kind == DialogueKind::Keyframe)
        .map(|e| e.frame.min(demo.len().saturating_sub(1)))
        .collect();
    frames.dedup();
    frames
}

/// Learns a spec from the teacher's marks and gripper commands.
pub fn learn_kd(
    demo: &Demo,
    world: Option<&World>,
    params: &KdParams,
) -> Result<TaskSpec, LearnError> {
    let positions = check_demo(demo)?;
    let mut keyframes = interaction_keyframes(&demo.gripper);
    let commands: Vec<usize> = keyframes.iter().map(|k| k.frame).collect();
    for frame in marked_frames(demo) {
        let is_command = commands
            .iter()
            .any(|&c| (positions[c] - positions[frame]).norm() <= params.merge_distance);
        if !is_command {
            keyframes.push(RawKeyframe {
                frame,
                kind: KeyframeKind::Constraint,
                gripper: demo.gripper[frame],
                constraint: Constraint::None,
            });
        }
    }
    keyframes.sort_by_key(|k| k.frame);
    keyframes.dedup_by_key(|k| k.frame);
    let grounded = ground(&keyframes, demo, world, params.bounds)?;
    Ok(TaskSpec::new(task_name(demo), "kd", grounded))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::okl::synth::DemoBuilder;
    use akl_tsr::Gripper;

    fn pick_and_place(marks_between: bool) -> Demo {
        let mut b = DemoBuilder::new("pick", [0.3, 0.0, 0.5], 100.0, 0.0005, 1)
            .object("shelf_1", [0.45, 0.34, 0.07])
            .object("shelf_2", [0.45, -0.36, 0.07])
            .object("part", [0.45, 0.32, 0.19])
            .curve([0.45, 0.32, 0.21], 0.25)
            .mark()
            .pause(0.3)
            .grasp("part")
            .curve([0.55, 0.0, 0.3], 0.25);
        if marks_between {
            b = b.mark();
        }
        b.curve([0.45, -0.36, 0.21], 0.25)
            .mark()
            .pause(0.3)
            .release()
            .build()
    }

    #[test]
    fn marks_at_gripper_commands_merge_and_others_stay() {
        let spec = learn_kd(&pick_and_place(false), None, &KdParams::default()).unwrap();
        let kinds: Vec<_> = spec.keyframes.iter().map(|k| (k.kind, k.gripper)).collect();
        assert_eq!(
            kinds,
            vec![
                (KeyframeKind::Interaction, Gripper::Closed),
                (KeyframeKind::Interaction, Gripper::Open)
            ]
        );
        let spec = learn_kd(&pick_and_place(true), None, &KdParams::default()).unwrap();
        assert_eq!(spec.keyframes.len(), 3);
        assert_eq!(spec.keyframes[1].kind, KeyframeKind::Constraint);
        assert_eq!(spec.keyframes[1].reference, "shelf_2");
        assert!(spec
            .keyframes
            .iter()
            .all(|k| k.constraint == Constraint::None));
        assert_eq!(spec.method, "kd");
    }

    #[test]
    fn no_marks_and_no_commands_is_a_clear_error() {
        let demo = DemoBuilder::new("still", [0.3, 0.0, 0.5], 100.0, 0.0, 1)
            .pause(1.0)
            .build();
        assert!(matches!(
            learn_kd(&demo, None, &KdParams::default()),
            Err(LearnError::NoKeyframes { .. })
        ));
    }
}
