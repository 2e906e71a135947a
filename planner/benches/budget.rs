//! The budgeted planner: what a wider TSR buys and what a candidate costs.
//!
//! For each built-in task, the ground truth and the same spec with every bound widened four
//! times (±5 mm, ±0.05 rad become ±2 cm, ±0.2 rad; the assembly's ±1 mm, ±0.01 rad become
//! ±4 mm, ±0.04 rad) are planned with the same seeds and budget; printed: the median planned
//! duration of each and the per-seed ratio wide / truth (median and worst), and, as the
//! baseline, the nominal-first plan (a budget of one candidate) of the truth.
//! Then the calibration of `MS_PER_KEYFRAME`: the mean planning time of one candidate per
//! keyframe. Criterion times `plan_best` on each ground truth at a 200 ms budget.
//! Run with `cargo bench -p akl-planner --bench budget`.

use akl_planner::{plan_best, PlanBudget, PlanOptions, Robot, MS_PER_KEYFRAME};
use akl_scene::builtin;
use akl_tsr::TaskSpec;
use criterion::{black_box, Criterion};
use std::time::{Duration, Instant};

/// The spec with every bound four times as wide.
fn widened(spec: &TaskSpec) -> TaskSpec {
    let mut wide = spec.clone();
    for k in &mut wide.keyframes {
        for b in &mut k.tsr.bw.0 {
            *b = [4.0 * b[0], 4.0 * b[1]];
        }
    }
    wide
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get((v.len().max(1) - 1) / 2).copied().unwrap_or(f64::NAN)
}

const SEEDS: u64 = 10;
const BUDGET_MS: u64 = 200;

fn main() {
    let robot = Robot::panda().expect("the built-in Panda loads");
    println!(
        "planned duration, {SEEDS} seeds, budget {BUDGET_MS} ms (candidates = 1 + ms / ({MS_PER_KEYFRAME} ms x keyframes)):"
    );
    let mut per_keyframe = Vec::new();
    for name in builtin::names() {
        let task = builtin::task(name).expect("built in").expect("valid");
        let truth = task.truth.clone().expect("truth");
        let wide = widened(&truth);
        let budget = PlanBudget::from_millis(BUDGET_MS, truth.keyframes.len());
        let (mut single, mut narrow, mut broad, mut ratios) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        let mut elapsed = Duration::ZERO;
        for seed in 0..SEEDS {
            let options = PlanOptions {
                seed,
                budget,
                ..PlanOptions::default()
            };
            let t = Instant::now();
            let a = plan_best(&robot, &truth, &task.world, &options);
            elapsed += t.elapsed();
            let b = plan_best(&robot, &wide, &task.world, &options);
            if let (Ok(a), Ok(b)) = (a, b) {
                single.extend(a.nominal_duration());
                ratios.push(b.plan.duration / a.plan.duration);
                narrow.push(a.plan.duration);
                broad.push(b.plan.duration);
            }
        }
        let worst = ratios.iter().copied().fold(f64::NAN, f64::max);
        println!(
            "  {name:<11} {} candidates: nominal-first {:.2} s, truth {:.2} s, wide {:.2} s; wide / truth median {:.3} worst {:.3} ({} seeds planned)",
            budget.candidates,
            median(single.clone()),
            median(narrow.clone()),
            median(broad),
            median(ratios.clone()),
            worst,
            ratios.len()
        );
        let ms = elapsed.as_secs_f64() * 1e3
            / (SEEDS as f64 * budget.candidates as f64 * truth.keyframes.len() as f64);
        per_keyframe.push(ms);
        println!("    {ms:.2} ms per candidate per keyframe");
    }
    let mean = per_keyframe.iter().sum::<f64>() / per_keyframe.len() as f64;
    println!("calibration: {mean:.2} ms per candidate per keyframe (MS_PER_KEYFRAME = {MS_PER_KEYFRAME})");

    let mut c = Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(5))
        .configure_from_args();
    for name in builtin::names() {
        let task = builtin::task(name).expect("built in").expect("valid");
        let truth = task.truth.clone().expect("truth");
        let options = PlanOptions {
            budget: PlanBudget::from_millis(BUDGET_MS, truth.keyframes.len()),
            ..PlanOptions::default()
        };
        c.bench_function(&format!("plan_best/{name}/{BUDGET_MS}ms"), |b| {
            b.iter(|| black_box(plan_best(&robot, &truth, &task.world, &options)))
        });
    }
    c.final_summary();
}
