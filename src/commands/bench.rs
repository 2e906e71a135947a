//! `akl bench planning`: the planner on a shared problem file, and beside another planner's
//! records of it.

use super::print_json;
use super::robot::load;
use crate::cli::{BenchCommand, BenchPlanningArgs};
use crate::exit::{CliError, CliResult, INTERNAL};
use crate::progress::Progress;
use crate::table::{seconds, Table};
use akl_planner::benchmark::{
    compare, run_problem, summarize, BenchSettings, ProblemFile, ProblemOutcome, ProblemRecord,
    Times,
};
use akl_planner::collision::RobotCollision;
use akl_planner::{DynamicDomain, RrtOptions, HALVE_STEP_AFTER};
use std::path::Path;

/// Runs `akl bench ...`.
pub(super) fn run(cmd: BenchCommand) -> CliResult {
    match cmd {
        BenchCommand::Planning(args) => planning(&args),
    }
}

fn planning(args: &BenchPlanningArgs) -> CliResult {
    if args.seeds == 0 {
        return Err(CliError::input("--seeds: at least one run per problem"));
    }
    if args.max_iterations == 0 {
        return Err(CliError::input("--max-iterations: at least one sample"));
    }
    let robot = load(&args.robot)?;
    let file = ProblemFile::load(&args.problems, robot.dof()).map_err(CliError::input)?;
    for set in &args.set {
        if !file.problems.iter().any(|p| &p.set == set) {
            return Err(CliError::input(format!(
                "--set {set}: {} has no problem of that set",
                args.problems.display()
            )));
        }
    }
    let peer = args.against.as_deref().map(read_records).transpose()?;
    let chosen: Vec<_> = file
        .problems
        .iter()
        .filter(|p| args.set.is_empty() || args.set.contains(&p.set))
        .collect();
    let model = RobotCollision::new(&robot);
    let settings = BenchSettings {
        seeds: args.seeds,
        rrt: RrtOptions {
            max_iterations: args.max_iterations,
            dynamic_domain: (!args.no_dynamic_domain).then(DynamicDomain::default),
            balance: !args.no_balance,
            halve_step_after: (!args.no_step_halving).then_some(HALVE_STEP_AFTER),
            ..RrtOptions::default()
        },
    };
    let progress = Progress::counting("planning", chosen.len(), "problems");
    let outcomes: Vec<ProblemOutcome> = chosen
        .iter()
        .map(|p| {
            let outcome = run_problem(&robot, &model, &file, p, &settings);
            progress.tick(outcome.record.runs.iter().all(|r| r.found));
            outcome
        })
        .collect();
    progress.finish();
    let records: Vec<ProblemRecord> = outcomes.iter().map(|o| o.record.clone()).collect();
    if args.json {
        print_json(&records)?;
    } else {
        print_text(&outcomes, &records, peer.as_deref());
    }
    let failed = records
        .iter()
        .flat_map(|r| &r.runs)
        .filter(|r| !r.found)
        .count();
    if failed == 0 {
        Ok(())
    } else {
        Err(CliError::verdict(
            INTERNAL,
            format!(
                "{failed} run(s) found no path within {} samples",
                args.max_iterations
            ),
        ))
    }
}

/// Another planner's records: a JSON array of problem records.
fn read_records(path: &Path) -> Result<Vec<ProblemRecord>, CliError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| CliError::input(format!("{}: cannot read: {e}", path.display())))?;
    serde_json::from_str(&text).map_err(|e| {
        CliError::input(format!(
            "{}: not a JSON array of problem records: {e}",
            path.display()
        ))
    })
}

fn print_text(
    outcomes: &[ProblemOutcome],
    records: &[ProblemRecord],
    peer: Option<&[ProblemRecord]>,
) {
    let mut table = Table::new([
        "set",
        "problems",
        "valid",
        "solved",
        "median",
        "p95",
        "iterations",
    ]);
    for s in summarize(records) {
        let mut row = vec![s.set, s.problems.to_string(), s.valid.to_string()];
        row.extend(times_cells(s.times));
        table.row(row);
    }
    print!("{}", table.render());
    let invalid: Vec<_> = outcomes
        .iter()
        .filter(|o| o.start_hit.is_some() || o.goal_hit.is_some())
        .collect();
    if !invalid.is_empty() {
        println!("\ninvalid under the collision model and margins:");
        for o in invalid {
            let mut why = Vec::new();
            if let Some(hit) = &o.start_hit {
                why.push(format!("start: {hit}"));
            }
            if let Some(hit) = &o.goal_hit {
                why.push(format!("goal: {hit}"));
            }
            println!("  {}  {}", o.record.id, why.join("; "));
        }
    }
    let unsolved: Vec<_> = records
        .iter()
        .flat_map(|r| {
            r.runs
                .iter()
                .filter(|run| !run.found)
                .map(move |run| (r, run))
        })
        .collect();
    if !unsolved.is_empty() {
        println!("\nno path found:");
        for (r, run) in unsolved {
            println!("  {} seed {} ({} samples)", r.id, run.seed, run.iterations);
        }
    }
    if let Some(peer) = peer {
        let mut table = Table::new([
            "set",
            "both valid",
            "only ours",
            "only peer",
            "ours median",
            "peer median",
            "ratio",
            "ours p95",
            "peer p95",
            "ratio p95",
        ]);
        for c in compare(records, peer) {
            let time =
                |t: Option<Times>, f: fn(&Times) -> f64| t.map_or("-".into(), |t| duration(f(&t)));
            let ratio = |r: Option<f64>| r.map_or("-".into(), |r| format!("{r:.1}×"));
            table.row(vec![
                c.set.clone(),
                c.both_valid.to_string(),
                c.only_ours.to_string(),
                c.only_peer.to_string(),
                time(c.ours, |t| t.median_ns),
                time(c.peer, |t| t.median_ns),
                ratio(c.median_ratio()),
                time(c.ours, |t| t.p95_ns),
                time(c.peer, |t| t.p95_ns),
                ratio(c.p95_ratio()),
            ]);
        }
        println!("\nbeside the other planner (problems both call valid):");
        print!("{}", table.render());
    }
}

fn times_cells(times: Option<Times>) -> Vec<String> {
    match times {
        Some(t) => vec![
            format!("{}/{}", t.solved, t.runs),
            duration(t.median_ns),
            duration(t.p95_ns),
            format!("{:.0}", t.median_iterations),
        ],
        None => vec!["-".into(); 4],
    }
}

/// A time in nanoseconds as [`seconds`] writes it.
fn duration(ns: f64) -> String {
    seconds(ns / 1e9)
}
