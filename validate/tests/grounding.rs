//! Grounding sensitivity of the ground truths: every keyframe re-grounded on every other object
//! (and the world) is either told apart by the randomization (the deployment gate fails it)
//! or equivalent (held in a fixed relation by the task or by an earlier placement). The lists of
//! equivalent groundings are asserted, not just printed: a change that makes the verifier blind
//! to a grounding it used to catch fails this test.
//!
//! What makes every wrong grounding fail: each object is put on a 4 cm mat that moves on its
//! shelf by more than the mat's size (a release grounded on the shelf, the world or anything
//! else lands off the mat), and the scanner row turns freely and must be crossed from its first
//! scanner towards its last (a scan line with an end grounded off the row runs across it).

use akl_exec::ExecOptions;
use akl_planner::Robot;
use akl_scene::builtin;
use akl_validate::grounding::{check_groundings, GroundingOptions, Verdict};

/// Alternatives named by (keyframe, reference).
type Named = Vec<(usize, String)>;

/// The equivalent alternatives of the truth of `task`, and those the gate does not fail
/// (passed or undecided).
fn verdicts(task: &str) -> (Named, Named) {
    let robot = Robot::panda().unwrap();
    let t = builtin::task(task).unwrap().unwrap();
    let spec = t.truth.clone().unwrap();
    let options = GroundingOptions {
        jobs: 2,
        ..GroundingOptions::default()
    };
    let measured = check_groundings(
        &robot,
        &t,
        &spec,
        &ExecOptions::default(),
        &options,
        &|_, _| {},
    )
    .unwrap();
    let mut equivalent = Vec::new();
    let mut not_distinguished = Vec::new();
    assert!(!measured.interrupted);
    for k in &measured.keyframes {
        for a in &k.alternatives {
            match a.verdict {
                Verdict::Equivalent { .. } => equivalent.push((k.keyframe, a.reference.clone())),
                Verdict::NotDistinguished | Verdict::Undecided => {
                    not_distinguished.push((k.keyframe, a.reference.clone()))
                }
                Verdict::Distinguished => {
                    let rate = a.pass_rate.as_ref().unwrap();
                    assert!(a.failed > 0 && rate.upper < 0.99, "{task}: {a:?}")
                }
            }
        }
    }
    (equivalent, not_distinguished)
}

fn pairs(list: &[(usize, &str)]) -> Named {
    list.iter().map(|(k, r)| (*k, r.to_string())).collect()
}

#[test]
fn pick_place_groundings() {
    let (equivalent, not_distinguished) = verdicts("pick_place");
    // The mats move as one group; block_b set down beside block_a, which keyframe 1 put on
    // mat_a.
    assert_eq!(
        equivalent,
        pairs(&[(1, "mat_b"), (3, "mat_a"), (3, "block_a")])
    );
    assert_eq!(not_distinguished, pairs(&[]));
}

#[test]
fn inspection_groundings() {
    let (equivalent, not_distinguished) = verdicts("inspection");
    // The scanners move as one row.
    assert_eq!(
        equivalent,
        pairs(&[
            (1, "scanner_1"),
            (1, "scanner_3"),
            (2, "scanner_1"),
            (2, "scanner_3"),
        ])
    );
    assert_eq!(not_distinguished, pairs(&[]));
}

#[test]
fn assembly_groundings() {
    let (equivalent, not_distinguished) = verdicts("assembly");
    // The rail and the clamp move as one group.
    assert_eq!(
        equivalent,
        pairs(&[(3, "clamp_left"), (3, "clamp_right"), (3, "clamp_top")])
    );
    assert_eq!(not_distinguished, pairs(&[]));
}
