//! OKL end to end on synthetic demos with known lines.

use super::synth::DemoBuilder;
use super::*;
use crate::demo::Answer;
use akl_tsr::{Constraint, KeyframeKind};

const NOISE: f64 = 0.0005;

/// Pick the part from shelf_1, carry it in a line over the scanner, put it on shelf_2.
fn inspection(answer: Option<Answer>, seed: u64) -> DemoBuilder {
    DemoBuilder::new("inspection", [0.3, 0.0, 0.5], 100.0, NOISE, seed)
        .object("shelf_1", [0.45, 0.34, 0.07])
        .object("shelf_2", [0.45, -0.36, 0.07])
        .object("part", [0.45, 0.32, 0.19])
        .curve([0.45, 0.32, 0.21], 0.25)
        .pause(0.3)
        .grasp("part")
        .curve([0.55, 0.18, 0.22], 0.25)
        .line([0.55, -0.18, 0.22], 0.15, answer)
        .curve([0.45, -0.36, 0.21], 0.25)
        .pause(0.3)
        .release()
        .curve([0.3, 0.0, 0.5], 0.25)
}

fn summary(spec: &TaskSpec) -> Vec<(KeyframeKind, String, Gripper, Constraint)> {
    spec.keyframes
        .iter()
        .map(|k| (k.kind, k.reference.clone(), k.gripper, k.constraint))
        .collect()
}

#[test]
fn learns_the_inspection_keyframes() {
    for seed in 0..5 {
        let mut b = inspection(Some(Answer::Yes), seed);
        let demo = b.build();
        let spec = learn(&demo, None, &OklParams::default()).unwrap();
        use Gripper::{Closed as C, Open as O};
        use KeyframeKind::{Constraint as K, Interaction as I};
        assert_eq!(
            summary(&spec),
            vec![
                (I, "part".into(), C, Constraint::None),
                (K, "shelf_2".into(), C, Constraint::None),
                (K, "shelf_2".into(), C, Constraint::MoveInLine),
                (I, "shelf_2".into(), O, Constraint::None),
            ],
            "seed {seed}"
        );
        let line = b.lines()[0];
        for (kf, true_frame) in spec.keyframes[1..3].iter().zip([line.start, line.end]) {
            let learned = kf.tsr.nominal().translation.vector;
            let err = (learned - b.exact(true_frame)).norm();
            assert!(err < 0.02, "seed {seed}: boundary {err} m off");
        }
        // The grasp is the tool pose in the part's frame.
        let g = spec.keyframes[0].tsr.tw_e.translation.vector;
        assert!((g - Vector3::new(0.0, 0.0, 0.02)).norm() < 0.003, "{g:?}");
    }
}

#[test]
fn an_unintended_line_answered_no_leaves_no_constraint() {
    let demo = inspection(Some(Answer::No), 1).build();
    let spec = learn(&demo, None, &OklParams::default()).unwrap();
    assert_eq!(spec.keyframes.len(), 2);
    assert!(spec
        .keyframes
        .iter()
        .all(|k| k.kind == KeyframeKind::Interaction && k.constraint == Constraint::None));
    for answer in [Some(Answer::Yes), Some(Answer::Unknown), None] {
        let demo = inspection(answer, 1).build();
        let spec = learn(&demo, None, &OklParams::default()).unwrap();
        let constraint = spec
            .keyframes
            .iter()
            .filter(|k| k.kind == KeyframeKind::Constraint)
            .count();
        assert_eq!(constraint, 2, "answer {answer:?}");
    }
}

#[test]
fn a_line_from_a_grasp_to_a_release_gives_combined_keyframes() {
    let demo = DemoBuilder::new("assembly", [0.3, 0.0, 0.5], 100.0, NOISE, 3)
        .object("rail", [0.55, -0.1, 0.02])
        .object("pipe", [0.55, 0.03, 0.065])
        .curve([0.55, 0.03, 0.165], 0.25)
        .pause(0.3)
        .grasp("pipe")
        .pause(0.2)
        .line([0.55, -0.23, 0.165], 0.1, Some(Answer::Yes))
        .pause(0.2)
        .release()
        .curve([0.3, 0.0, 0.5], 0.25)
        .build();
    let spec = learn(&demo, None, &OklParams::default()).unwrap();
    use KeyframeKind::Combined as X;
    assert_eq!(
        summary(&spec),
        vec![
            (X, "pipe".into(), Gripper::Closed, Constraint::None),
            (X, "rail".into(), Gripper::Open, Constraint::MoveInLine),
        ]
    );
}

#[test]
fn degenerate_demos_give_a_spec_or_a_clear_error() {
    // One frame.
    let one = DemoBuilder::new("t", [0.3, 0.0, 0.5], 100.0, 0.0, 0).build();
    assert_eq!(
        learn(&one, None, &OklParams::default()),
        Err(LearnError::NoKeyframes { frames: 1 })
    );
    // No motion, no gripper change.
    let still = DemoBuilder::new("t", [0.3, 0.0, 0.5], 100.0, 0.0, 0)
        .pause(1.0)
        .build();
    assert!(matches!(
        learn(&still, None, &OklParams::default()),
        Err(LearnError::NoKeyframes { .. })
    ));
    // No gripper change but a curve.
    let curve = DemoBuilder::new("t", [0.3, 0.0, 0.5], 100.0, NOISE, 0)
        .curve([0.5, 0.2, 0.3], 0.2)
        .build();
    assert!(matches!(
        learn(&curve, None, &OklParams::default()),
        Err(LearnError::NoKeyframes { .. })
    ));
    // All straight, no objects: two constraint keyframes on the world frame.
    let straight = DemoBuilder::new("t", [0.3, 0.0, 0.5], 100.0, NOISE, 0)
        .line([0.3, 0.4, 0.5], 0.2, Some(Answer::Yes))
        .build();
    let spec = learn(&straight, None, &OklParams::default()).unwrap();
    assert_eq!(spec.keyframes.len(), 2);
    assert!(spec.keyframes.iter().all(|k| k.reference == WORLD_FRAME));
    assert_eq!(spec.keyframes[1].constraint, Constraint::MoveInLine);
    spec.validate().unwrap();
    // A grasp without any motion or objects.
    let grasp = DemoBuilder::new("t", [0.3, 0.0, 0.5], 100.0, 0.0, 0)
        .grasp("nothing")
        .build();
    let spec = learn(&grasp, None, &OklParams::default()).unwrap();
    assert_eq!(spec.keyframes.len(), 1);
    // No detector states.
    let mut no_detector = inspection(None, 0).build();
    no_detector.detector.clear();
    assert_eq!(
        learn(&no_detector, None, &OklParams::default()),
        Err(LearnError::NoDetectorStates)
    );
}

#[test]
fn bad_columns_are_named() {
    let mut demo = inspection(None, 0).build();
    demo.gripper.pop();
    let e = learn(&demo, None, &OklParams::default()).unwrap_err();
    assert!(e.to_string().contains("`gripper`"), "{e}");
    let mut demo = inspection(None, 0).build();
    demo.ee[17].translation.vector.x = f64::NAN;
    let e = learn(&demo, None, &OklParams::default()).unwrap_err();
    assert!(e.to_string().contains("frame 17"), "{e}");
}
