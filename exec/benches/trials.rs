//! Trial throughput: one randomized trial of each built-in task's ground truth (plan, simulate
//! in rapier3d, verify) on one core, cycling through 20 randomized placements.
//!
//! Baseline, measured in the same run on the same placements and seeds: planning alone
//! (`plan_task`), the part of a trial that does not depend on the simulation; the difference
//! is what simulating and verifying cost. Trials per second per core = 1 / time per trial.
//! Run with `cargo bench -p akl-exec --bench trials`.

use akl_exec::{run_trial, trial_world, ExecOptions, Setup};
use akl_planner::{plan_task, PlanOptions, Robot};
use akl_scene::builtin;
use criterion::{black_box, Criterion};
use std::time::Duration;

/// Randomized placements per task.
const PLACEMENTS: u64 = 20;

fn main() {
    let robot = Robot::panda().expect("the built-in Panda loads");
    let options = ExecOptions::default();
    let mut c = Criterion::default()
        .sample_size(15)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(10))
        .configure_from_args();
    for name in builtin::names() {
        let task = builtin::task(name).expect("built in").expect("valid");
        let spec = task.truth.clone().expect("a ground truth");
        let worlds: Vec<_> = (0..PLACEMENTS)
            .map(|seed| trial_world(&task, true, seed, &options.physics).expect("placeable"))
            .collect();
        let setup = Setup {
            robot: &robot,
            task: &task,
            spec: &spec,
            options: &options,
        };
        let passed = worlds
            .iter()
            .zip(0..)
            .filter(|(w, seed)| run_trial(&setup, 0, *seed, w, None).passed)
            .count();
        println!("{name}: the ground truth passes {passed} of {PLACEMENTS} placements");
        let mut i = 0;
        c.bench_function(&format!("trials/{name}/plan_only"), |b| {
            b.iter(|| {
                i = (i + 1) % worlds.len();
                let plan_options = PlanOptions {
                    seed: i as u64,
                    ..options.plan.clone()
                };
                plan_task(&robot, &spec, black_box(&worlds[i]), &plan_options).is_ok()
            })
        });
        let mut j = 0;
        c.bench_function(&format!("trials/{name}/plan_simulate_verify"), |b| {
            b.iter(|| {
                j = (j + 1) % worlds.len();
                run_trial(&setup, j, j as u64, black_box(&worlds[j]), None).passed
            })
        });
    }
    c.final_summary();
}
