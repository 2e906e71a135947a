//! What validation and relaxation cost, against the spec's own randomized trials measured in
//! the same run (the part of `akl validate` that `akl execute --randomize N` would do too).
//!
//! For each built-in ground truth, on one core: 20 trials of the spec alone (baseline), then
//! `validate` on the same 20 trials (the spec's trials plus every removal's, each stopped at
//! its first failure). Relaxation takes tens of seconds, too long to repeat for criterion: it
//! runs once per task with the defaults of `akl relax` and its wall time is printed beside the
//! number of trials it ran. Run with `cargo bench -p akl-validate --bench validation`.

use akl_exec::trial::ExecOptions;
use akl_planner::Robot;
use akl_scene::builtin;
use akl_validate::relax::{relax, RelaxOptions};
use akl_validate::trials::{run_trials, Stop};
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
    let options = ValidateOptions {
        trials,
        exec: ExecOptions::default(),
    };
    let mut c = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(8))
        .configure_from_args();
    for name in builtin::names() {
        let task = builtin::task(name).expect("built in").expect("valid");
        let truth = task.truth.clone().expect("a ground truth");
        c.bench_function(&format!("validation/{name}/trials_only"), |b| {
            b.iter(|| run_trials(&robot, &task, &truth, &options.exec, &trials, Stop::Never))
        });
        c.bench_function(&format!("validation/{name}/validate"), |b| {
            b.iter(|| validate(&robot, &task, &truth, &options, None, &|_, _| {}))
        });
    }
    for name in builtin::names() {
        let task = builtin::task(name).expect("built in").expect("valid");
        let truth = task.truth.clone().expect("a ground truth");
        let start = Instant::now();
        let relaxed = relax(&robot, &task, &truth, &RelaxOptions::default(), &|_, _| {});
        let seconds = start.elapsed().as_secs_f64();
        match relaxed {
            Ok(r) => println!(
                "relax/{name}: {seconds:.1} s for {} trials ({:.1} ms per trial), {} bounds widened, {:+.1} bits, verified: {}",
                r.trials,
                1e3 * seconds / r.trials.max(1) as f64,
                r.bounds.iter().filter(|b| b.widened()).count(),
                r.bits_gained().unwrap_or(0.0),
                r.relaxed.is_some()
            ),
            Err(e) => println!("relax/{name}: {seconds:.1} s, failed: {e}"),
        }
    }
    c.final_summary();
}
