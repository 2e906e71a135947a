//! Bits of freedom: the time of a whole `akl flexibility` bits report per built-in task (the
//! lattice, the ground truth's count, the unconstrained count and every keyframe's and line's
//! share), and of one count. Baseline in the same run: planning the same ground truth once
//! (`plan_task`, one candidate), so a report's cost reads as a number of plans.
//! Before criterion, one run per task prints the figures and the shares.
//! Run with `cargo bench -p akl-planner --bench flexibility`.

use akl_planner::flexibility::{FreedomOptions, Workspace};
use akl_planner::{plan_task, PlanOptions, Robot};
use akl_scene::builtin;
use criterion::{black_box, Criterion};
use std::time::{Duration, Instant};

fn main() {
    let robot = Robot::panda().expect("the built-in Panda loads");
    let options = FreedomOptions::default();
    println!(
        "lattice {} m, slack {} (one run each):",
        options.resolution, options.slack
    );
    for name in builtin::names() {
        let task = builtin::task(name).expect("built in").expect("valid");
        let truth = task.truth.clone().expect("truth");
        let t = Instant::now();
        let ws = Workspace::new(&robot, &task, &options).expect("workspace");
        let report = ws.freedom(&truth).expect("report");
        let full = t.elapsed();
        let t = Instant::now();
        black_box(ws.traces(&truth).expect("count"));
        let one = t.elapsed();
        let shares: Vec<String> = report
            .keyframes
            .iter()
            .chain(&report.lines)
            .map(|s| format!("{:.1}", s.share.unwrap_or(f64::NAN)))
            .collect();
        println!(
            "  {name:<11} {} cells, {} steps: {:.1} bits ({:.1} unconstrained); report {full:.2?}, one count {one:.2?}; shares (keyframes, then lines) {}",
            ws.lattice().len(),
            ws.max_steps(),
            report.bits.unwrap_or(f64::NAN),
            report.unconstrained_bits.unwrap_or(f64::NAN),
            shares.join(", ")
        );
    }

    let mut c = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(4))
        .configure_from_args();
    for name in builtin::names() {
        let task = builtin::task(name).expect("built in").expect("valid");
        let truth = task.truth.clone().expect("truth");
        c.bench_function(&format!("flexibility/{name}/report"), |b| {
            b.iter(|| {
                let ws = Workspace::new(&robot, &task, &options).expect("workspace");
                black_box(ws.freedom(&truth).expect("report"))
            })
        });
        let ws = Workspace::new(&robot, &task, &options).expect("workspace");
        c.bench_function(&format!("flexibility/{name}/count"), |b| {
            b.iter(|| black_box(ws.traces(&truth)))
        });
        c.bench_function(&format!("flexibility/{name}/plan_task (baseline)"), |b| {
            b.iter(|| {
                black_box(plan_task(
                    &robot,
                    &truth,
                    &task.world,
                    &PlanOptions::default(),
                ))
            })
        });
    }
    c.final_summary();
}
