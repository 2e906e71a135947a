//! `akl relax SPEC --task T -o relaxed.json`: every TSR widened as far as verification allows.

use super::robot::load as load_robot;
use super::validate::{cli_error, exec_options, trials};
use super::{check_output, load_spec_for, print_json};
use crate::cli::RelaxArgs;
use crate::exit::{CliError, CliResult};
use crate::progress::Progress;
use crate::table::Table;
use akl_scene::builtin;
use akl_validate::relax::{relax, RelaxOptions, Relaxation, Side};
use akl_validate::{Trials, ValidateError};
use serde::Serialize;

/// How far verification seeds start from the search's (`--seed`).
const VERIFY_SEED_OFFSET: u64 = 1_000_000;

#[derive(Serialize)]
struct Relaxed<'a> {
    spec: String,
    task: String,
    output: Option<String>,
    #[serde(flatten)]
    relaxation: &'a Relaxation,
}

pub fn run(args: RelaxArgs) -> CliResult {
    check_output(&args.output, "relaxed spec")?;
    let robot = load_robot(&args.robot)?;
    let task = builtin::resolve(&args.task).map_err(CliError::input)?;
    let spec = load_spec_for(&args.spec, &task)?;
    let search = trials(args.trials, args.seed, &args.run)
        .map_err(|_| CliError::input("--trials: needs at least one trial"))?;
    if args.verify == 0 {
        return Err(CliError::input("--verify: needs at least one trial"));
    }
    let options = RelaxOptions {
        search,
        verify: Trials {
            count: args.verify,
            seed: args.seed.saturating_add(VERIFY_SEED_OFFSET),
            jobs: search.jobs,
        },
        depth: args.depth,
        exec: exec_options(&args.run),
        ..RelaxOptions::default()
    };
    let progress = Progress::new(
        &format!("relaxing on `{}`", task.name),
        options.most_trials(&spec),
    );
    let relaxation = relax(&robot, &task, &spec, &options, &|done, _| {
        progress.set(done)
    });
    progress.finish();
    let relaxation = relaxation.map_err(|e| match e {
        e @ ValidateError::SpecFails(_) => {
            CliError::internal(format!("{}: {e}", args.spec.display()))
        }
        e => cli_error(e, &args.spec, &task),
    })?;
    if let Some(relaxed) = &relaxation.relaxed {
        relaxed
            .save(&args.output)
            .map_err(|e| CliError::internal(format!("{}: {e}", args.output.display())))?;
    }
    let report = Relaxed {
        spec: args.spec.display().to_string(),
        task: task.name.clone(),
        output: relaxation
            .relaxed
            .as_ref()
            .map(|_| args.output.display().to_string()),
        relaxation: &relaxation,
    };
    if args.json {
        print_json(&report)?;
    } else {
        print_relaxation(&report, &options);
    }
    match &relaxation.relaxed {
        Some(_) => Ok(()),
        None => Err(CliError::internal(format!(
            "{}: no relaxation passed its verification; nothing written",
            args.spec.display()
        ))),
    }
}

fn bits(b: Option<f64>) -> String {
    b.map_or("no trace".into(), |b| format!("{b:.1}"))
}

fn print_relaxation(r: &Relaxed, options: &RelaxOptions) {
    let x = r.relaxation;
    println!(
        "{} on task `{}`: {} trials per probe (seeds {}..), bisection depth {}; {} trials in all",
        r.spec, r.task, options.search.count, options.search.seed, options.depth, x.trials
    );
    let widened: Vec<_> = x.bounds.iter().filter(|b| b.widened()).collect();
    if widened.is_empty() {
        println!("no bound could be widened");
    } else {
        let mut table = Table::new(["keyframe", "axis", "bound", "from", "to", "probes"]);
        for b in widened {
            let unit = |v: f64| {
                if matches!(b.axis, "x" | "y" | "z") {
                    format!("{:+.1} mm", v * 1e3)
                } else {
                    format!("{:+.3} rad", v)
                }
            };
            table.row(vec![
                b.keyframe.to_string(),
                b.axis.to_string(),
                match b.side {
                    Side::Max => "max".into(),
                    Side::Min => "min".into(),
                },
                unit(b.from),
                unit(b.to),
                b.probes.to_string(),
            ]);
        }
        print!("{}", table.render());
    }
    for v in &x.verifications {
        println!(
            "verification on fresh seeds {}..: {}/{} passed, {:.0} % of the widening kept{}",
            v.seed,
            v.outcome.passed,
            v.outcome.run,
            v.kept * 100.0,
            v.outcome
                .first_failure_text()
                .map_or(String::new(), |f| format!(" — {f}"))
        );
    }
    let gained = x
        .bits_gained()
        .map_or(String::new(), |g| format!(" ({g:+.1})"));
    println!(
        "bits of freedom: {} before, {} after{gained}",
        bits(x.bits_before),
        bits(x.bits_after)
    );
    if let Some(out) = &r.output {
        println!("wrote {out}");
    }
}
