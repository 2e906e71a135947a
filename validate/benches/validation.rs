//! What validation and relaxation cost, against the spec's own randomized trials measured in
//! the same run.
//!
//! For each built-in ground truth, on one core: criterion times 20 trials of the spec alone
//! (the baseline, per trial). `validate` (the sequential gate on the spec, then on the spec
//! without each keyframe and line) and `relax` take seconds to minutes, too long to repeat for
//! criterion: each runs once per task with its defaults, and its wall time is printed beside
//! the trials it ran and their cost in baseline trials. Run with
//! `cargo bench -p akl-validate --bench validation`.

use akl_exec::ExecOptions;
use akl_planner::Robot;
use akl_scene::builtin;
use akl_stats::GateOptions;
use akl_validate::relax::{relax, RelaxOptions};
use akl_validate::trials::run_trials;
use akl_validate::{validate, Trials, ValidateOptions};
use criterion::Criterion;
use std::time::{Duration, Instant};

fn main() {
    let robot = Robot::panda().expect("the built-in Panda loads");
    let trials = Trials {
        count: 20,
        seed: 0,
        jobs: 1,
    };
    let exec = ExecOptions::default();
    let mut c = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(8))
        .configure_from_args();
    let mut per_trial = Vec::new();
    for name in builtin::names() {
        let task = builtin::task(name).expect("built in").expect("valid");
        let truth = task.truth.clone().expect("a ground truth");
        c.bench_function(&format!("validation/{name}/trials_only"), |b| {
            b.iter(|| run_trials(&robot, &task, &truth, &exec, &trials))
        });
        let start = Instant::now();
        run_trials(&robot, &task, &truth, &exec, &trials).expect("trials run");
        per_trial.push(start.elapsed().as_secs_f64() / trials.count as f64);
    }
    for (name, baseline) in builtin::names().iter().zip(per_trial) {
        let task = builtin::task(name).expect("built in").expect("valid");
        let truth = task.truth.clone().expect("a ground truth");
        let options = ValidateOptions {
            seed: 0,
            jobs: 1,
            gate: GateOptions::default(),
            exec: exec.clone(),
        };
        let start = Instant::now();
        let v = validate(&robot, &task, &truth, &options, None, &|_, _| {}).expect("validates");
        let seconds = start.elapsed().as_secs_f64();
        let ran = v.spec.outcome.run
            + v.removals
                .iter()
                .filter_map(|r| r.outcome.as_ref())
                .map(|o| o.run)
                .sum::<usize>();
        println!(
            "validate/{name}: {seconds:.1} s, {ran} trials ({} of the spec), {:.0} baseline trials, verdict {:?}",
            v.spec.outcome.run,
            seconds / baseline,
            v.verdict
        );
        let start = Instant::now();
        let relaxed = relax(&robot, &task, &truth, &RelaxOptions::default(), &|_| {});
        let seconds = start.elapsed().as_secs_f64();
        match relaxed {
            Ok(r) => println!(
                "relax/{name}: {seconds:.1} s for {} trials ({:.1} ms per trial), {} widenings kept, {:+.1} bits of TSR volume, {:+.1} bits of traces, gated: {}",
                r.trials,
                1e3 * seconds / r.trials.max(1) as f64,
                r.probes.iter().filter(|p| p.kept).count(),
                r.volume_gained(),
                r.bits_gained().unwrap_or(0.0),
                r.relaxed.is_some()
            ),
            Err(e) => println!("relax/{name}: {seconds:.1} s, failed: {e}"),
        }
    }
    c.final_summary();
}
