//! `akl flexibility SPEC --task T`.

use super::print_json;
use super::robot::load as load_robot;
use crate::cli::FlexibilityArgs;
use crate::exit::{CliError, CliResult};
use crate::table::Table;
use akl_planner::flexibility::{
    planner_gains, FlexibilityError, Freedom, FreedomOptions, GainOptions, Gains, Workspace,
};
use akl_planner::{PlanBudget, PlanOptions};
use akl_tsr::TaskSpec;
use serde::Serialize;

#[derive(Serialize)]
struct Report {
    spec: String,
    task: String,
    freedom: Freedom,
    budget_ms: u64,
    speed_scale: f64,
    gains: Option<Gains>,
}

fn bits_text(bits: Option<f64>) -> String {
    bits.map_or("no trace".to_string(), |b| format!("{b:.1}"))
}

fn seconds(v: Option<f64>) -> String {
    v.map_or("-".to_string(), |v| format!("{v:.2} s"))
}

pub(super) fn run(args: FlexibilityArgs) -> CliResult {
    let robot = load_robot(&args.robot)?;
    let task = super::load_task(&args.task)?;
    let spec = super::load_spec_for(&args.spec, &task, args.fit)?;
    let in_spec = |e: FlexibilityError| match e {
        FlexibilityError::Scene(_) => CliError::internal(e),
        _ => CliError::input(format!("{}: {e}", args.spec.display())),
    };
    let workspace = Workspace::new(&robot, &task, &FreedomOptions::default())
        .map_err(|e| CliError::input(format!("task `{}`: {e}", task.name)))?;
    let freedom = workspace.freedom(&spec).map_err(in_spec)?;
    let gains = if args.scenes == 0 {
        None
    } else {
        let options = GainOptions {
            scenes: args.scenes,
            seed: args.seed,
            plan: PlanOptions {
                budget: PlanBudget::from_millis(args.budget, spec.keyframes.len()),
                speed_scale: args.speed.speed_scale,
                ..PlanOptions::default()
            },
        };
        Some(planner_gains(&robot, &task, &spec, &options).map_err(in_spec)?)
    };
    let report = Report {
        spec: args.spec.display().to_string(),
        task: task.name.clone(),
        freedom,
        budget_ms: args.budget,
        speed_scale: args.speed.speed_scale,
        gains,
    };
    if args.json {
        return print_json(&report);
    }
    print_report(&report, &spec);
    Ok(())
}

fn print_report(report: &Report, spec: &TaskSpec) {
    let f = &report.freedom;
    println!(
        "{} in task `{}`: {} bits of freedom ({} traces of at most {} steps on a {:.0} cm lattice of {} cells; {} bits with no keyframe)",
        report.spec,
        report.task,
        bits_text(f.bits),
        if f.traces.bits() > 64 {
            format!("about 2^{:.1}", f.bits.unwrap_or(0.0))
        } else {
            f.traces.to_string()
        },
        f.max_steps,
        f.resolution * 100.0,
        f.cells,
        bits_text(f.unconstrained_bits),
    );
    let mut table = Table::new([
        "keyframe",
        "kind",
        "reference",
        "constraint",
        "cells",
        "bits without it",
        "its share",
    ]);
    for share in &f.keyframes {
        let kf = &spec.keyframes[share.keyframe];
        table.row(vec![
            share.keyframe.to_string(),
            kf.kind.to_string(),
            kf.reference.clone(),
            kf.constraint.to_string(),
            share.cells.to_string(),
            bits_text(share.bits_without),
            bits_text(share.share),
        ]);
    }
    for share in &f.lines {
        table.row(vec![
            format!("line to {}", share.keyframe),
            "line".into(),
            "-".into(),
            "move_in_line".into(),
            share.cells.to_string(),
            bits_text(share.bits_without),
            bits_text(share.share),
        ]);
    }
    print!("{}", table.render());
    let Some(g) = &report.gains else {
        return;
    };
    println!(
        "planner over {} randomized scenes (budget {} ms, {} candidates each): planned {}/{} ({:.0} %)",
        g.scenes,
        report.budget_ms,
        g.candidates,
        g.planned,
        g.scenes,
        100.0 * g.success_rate
    );
    println!(
        "  execution time: best {}, median {} (nominal-first candidate: median {}; kept / nominal-first, median {})",
        seconds(g.duration.map(|s| s.best)),
        seconds(g.duration.map(|s| s.median)),
        seconds(g.nominal_duration.map(|s| s.median)),
        g.median_duration_ratio
            .map_or("-".to_string(), |r| format!("{r:.3}"))
    );
    println!(
        "  joint-path length: best {}, median {}",
        g.joint_path_length
            .map_or("-".to_string(), |s| format!("{:.2} rad", s.best)),
        g.joint_path_length
            .map_or("-".to_string(), |s| format!("{:.2} rad", s.median)),
    );
    for failure in &g.failures {
        println!("  scene {}: {}", failure.seed, failure.reason);
    }
}
