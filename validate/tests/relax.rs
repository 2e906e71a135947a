//! Relaxation on a built-in task: what it returns passed the gate on seeds the search never
//! used and passes it again on others, it never narrows a bound, it gains TSR volume, and a
//! spec that fails its own gate is not relaxed.

use akl_planner::Robot;
use akl_scene::builtin;
use akl_stats::{Decision, Gate, GateOptions};
use akl_tsr::pose::pose_from_xyz;
use akl_validate::relax::{relax, RelaxOptions};
use akl_validate::trials::run_gated;
use akl_validate::ValidateError;

/// A gate lighter than the default (success 0.95 shown at 0.9 confidence: 45 clean trials
/// pass) and short screenings keep the test quick; the defaults are measured in
/// BENCHMARKS.md. (At 0.8, a widening failing 17 % of trials passed its gate.)
fn options() -> RelaxOptions {
    RelaxOptions {
        jobs: 2,
        screen: 8,
        levels: vec![1.0, 0.25],
        gate: GateOptions {
            min_success: 0.95,
            confidence: 0.9,
            max_trials: 300,
        },
        ..RelaxOptions::default()
    }
}

#[test]
fn the_relaxed_spec_passed_fresh_seeds_and_only_widens() {
    let robot = Robot::panda().unwrap();
    let task = builtin::task("pick_place").unwrap().unwrap();
    let truth = task.truth.clone().unwrap();
    let options = options();
    let r = relax(&robot, &task, &truth, &options, &|_| {}).unwrap();
    let relaxed = r.relaxed.clone().expect("a gated relaxation");
    assert!(!r.interrupted);
    // The spec was gated first, and the last gate that passed is the spec returned.
    assert!(r.gates[0].shares.is_empty());
    let last = r.gates.last().unwrap();
    assert!(last.shares.iter().any(|s| *s > 0.0));
    assert_eq!(last.decision, Some(Decision::Passes));
    // Every gate ran on seeds no probe screened on.
    let search_end = options.seed + (options.most_probes(&truth) * options.screen) as u64;
    assert!(r.gates.iter().all(|g| g.seed >= search_end));
    // Gated again, independently, on seeds neither step used: it passes.
    let gate = Gate::new(options.gate).unwrap();
    let again = run_gated(
        &robot,
        &task,
        &relaxed,
        &options.exec,
        &gate,
        5_000_000,
        2,
        false,
        &|_| {},
    )
    .unwrap();
    assert_eq!(
        again.decision,
        Some(Decision::Passes),
        "{:?}",
        again.outcome
    );
    // Some bound widened, none narrowed, and the TSR volume grew.
    for (k, (a, b)) in truth.keyframes.iter().zip(&relaxed.keyframes).enumerate() {
        for (axis, ([lo0, hi0], [lo, hi])) in a.tsr.bw.0.iter().zip(b.tsr.bw.0).enumerate() {
            assert!(
                lo <= *lo0 && hi >= *hi0,
                "keyframe {k} axis {axis} narrowed"
            );
        }
    }
    assert!(r.volume_gained() >= 1.0, "{:?}", r.volume_gain);
    assert_eq!(relaxed.method, "truth+relaxed");
    assert!(r.probes.iter().any(|p| p.kept));
}

#[test]
fn a_spec_that_fails_its_own_gate_is_not_relaxed() {
    let robot = Robot::panda().unwrap();
    let task = builtin::task("pick_place").unwrap().unwrap();
    let mut spec = task.truth.clone().unwrap();
    spec.keyframes[3].tsr.tw_e = pose_from_xyz([0.0, 0.3, 0.0]) * spec.keyframes[3].tsr.tw_e;
    let e = relax(&robot, &task, &spec, &options(), &|_| {}).unwrap_err();
    assert!(matches!(e, ValidateError::SpecFails(_)), "{e}");
}

#[test]
fn a_widening_that_multiplies_planning_work_is_rejected_for_it() {
    let robot = Robot::panda().unwrap();
    let task = builtin::task("pick_place").unwrap().unwrap();
    let truth = task.truth.clone().unwrap();
    // Planning may take no more collision probes than the truth's own: the widest widenings,
    // whose regions hold poses the planner must try and reject, cannot be kept.
    let tight = RelaxOptions {
        max_effort: 1.0,
        levels: vec![1.0],
        ..options()
    };
    let r = relax(&robot, &task, &truth, &tight, &|_| {}).unwrap();
    let for_effort: Vec<_> = r
        .probes
        .iter()
        .filter(|p| {
            p.rejected_by
                .as_deref()
                .is_some_and(|why| why.contains("collision probes"))
        })
        .collect();
    assert!(!for_effort.is_empty(), "{:#?}", r.probes);
    assert!(for_effort.iter().all(|p| p.effort > 1.0), "{for_effort:#?}");
    assert!(
        r.probes.iter().filter(|p| p.kept).all(|p| p.effort <= 1.0),
        "{:#?}",
        r.probes
    );
    let tight_gates = RelaxOptions {
        max_effort: 0.5,
        ..options()
    };
    assert!(tight_gates.check(&truth).is_err());
}
