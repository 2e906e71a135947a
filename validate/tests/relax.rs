//! Relaxation on a built-in task: what it returns passes fresh seeds, never narrows a bound,
//! and widens the turn a square block's placement leaves free (pick_place, keyframe 3).

use akl_exec::trial::ExecOptions;
use akl_planner::Robot;
use akl_scene::builtin;
use akl_tsr::pose::pose_from_xyz;
use akl_validate::relax::{relax, RelaxOptions};
use akl_validate::trials::{run_trials, Stop};
use akl_validate::{Trials, ValidateError};

fn options() -> RelaxOptions {
    RelaxOptions {
        search: Trials {
            count: 4,
            seed: 0,
            jobs: 2,
        },
        verify: Trials {
            count: 12,
            seed: 1_000_000,
            jobs: 2,
        },
        depth: 2,
        exec: ExecOptions::default(),
        ..RelaxOptions::default()
    }
}

#[test]
fn the_relaxed_spec_passes_fresh_seeds_and_only_widens() {
    let robot = Robot::panda().unwrap();
    let task = builtin::task("pick_place").unwrap().unwrap();
    let truth = task.truth.clone().unwrap();
    let options = options();
    let r = relax(&robot, &task, &truth, &options, &|_, _| {}).unwrap();
    let relaxed = r.relaxed.clone().expect("a verified relaxation");
    let last = r.verifications.last().unwrap();
    assert!(last.outcome.all_passed(), "{:?}", last.outcome);
    for earlier in &r.verifications[..r.verifications.len() - 1] {
        assert!(!earlier.outcome.all_passed());
    }
    // Every verification seed lies outside the search's.
    let search = options.search.seeds();
    assert!(r.verifications.iter().all(|v| !search.contains(&v.seed)));

    // Rerun independently on the seeds that verified it: all pass again. On seeds neither step
    // used, 12 passing trials bound the failure rate only loosely (one in five at 95 %
    // confidence), so one failure in 12 is allowed there.
    let rerun = |seed: u64| {
        let fresh = Trials {
            count: options.verify.count,
            seed,
            jobs: 2,
        };
        run_trials(&robot, &task, &relaxed, &options.exec, &fresh, Stop::Never).unwrap()
    };
    let again = rerun(last.seed);
    assert!(again.all_passed(), "seed {}: {again:?}", last.seed);
    let fresh = rerun(2_000_000);
    assert!(fresh.passed + 1 >= fresh.run, "{fresh:?}");

    // Some bound widened, and none narrowed.
    let widened = truth
        .keyframes
        .iter()
        .zip(&relaxed.keyframes)
        .flat_map(|(a, b)| a.tsr.bw.0.iter().zip(b.tsr.bw.0))
        .filter(|([lo0, hi0], [lo, hi])| lo < lo0 || hi > hi0)
        .count();
    assert!(widened > 0);
    for (k, (a, b)) in truth.keyframes.iter().zip(&relaxed.keyframes).enumerate() {
        for (axis, ([lo0, hi0], [lo, hi])) in a.tsr.bw.0.iter().zip(b.tsr.bw.0).enumerate() {
            assert!(
                lo <= *lo0 && hi >= *hi0,
                "keyframe {k} axis {axis} narrowed"
            );
        }
    }
    assert!(r.bits_gained().unwrap() > 0.0, "{:?}", r.bits_gained());
    assert_eq!(relaxed.method, "truth+relaxed");
}

#[test]
fn a_spec_that_fails_its_own_trials_is_not_relaxed() {
    let robot = Robot::panda().unwrap();
    let task = builtin::task("pick_place").unwrap().unwrap();
    let mut spec = task.truth.clone().unwrap();
    spec.keyframes[3].tsr.tw_e = pose_from_xyz([0.0, 0.3, 0.0]) * spec.keyframes[3].tsr.tw_e;
    let e = relax(&robot, &task, &spec, &options(), &|_, _| {}).unwrap_err();
    assert!(matches!(e, ValidateError::SpecFails(_)), "{e}");
}

/// How the search's trial count and bisection depth were chosen: for each setting, relaxing
/// each ground truth, the trials it took, whether the search's result passed its first
/// fresh-seed verification (30 trials) and the share of the widening kept, and the bits
/// gained. Run with
/// `cargo test --release -p akl-validate --test relax relax_survey -- --ignored --nocapture`.
#[test]
#[ignore = "a survey of minutes; prints the table behind RelaxOptions::default"]
fn relax_survey() {
    let robot = Robot::panda().unwrap();
    println!(
        "task        trials  depth  trials run  seconds  first verification  kept  bits gained"
    );
    for (count, depth) in [(5, 2), (5, 4), (10, 2), (10, 4), (20, 4)] {
        for name in builtin::names() {
            let task = builtin::task(name).unwrap().unwrap();
            let truth = task.truth.clone().unwrap();
            let options = RelaxOptions {
                search: Trials {
                    count,
                    seed: 0,
                    jobs: 2,
                },
                verify: Trials {
                    count: 30,
                    seed: 1_000_000,
                    jobs: 2,
                },
                depth,
                ..RelaxOptions::default()
            };
            let start = std::time::Instant::now();
            let r = relax(&robot, &task, &truth, &options, &|_, _| {}).unwrap();
            let first = &r.verifications[0].outcome;
            let kept = r
                .verifications
                .iter()
                .find(|v| v.outcome.all_passed())
                .map_or(0.0, |v| v.kept);
            println!(
                "{name:<11} {count:>6}  {depth:>5}  {:>10}  {:>7.1}  {:>18}  {:>4.2}  {:>11.1}",
                r.trials,
                start.elapsed().as_secs_f64(),
                if first.all_passed() {
                    "passed"
                } else {
                    "failed"
                },
                kept,
                r.bits_gained().unwrap_or(0.0)
            );
        }
    }
}
