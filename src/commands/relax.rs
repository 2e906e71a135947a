//! `akl relax SPEC --task T -o relaxed.json`: every TSR widened as far as the deployment gate
//! allows, each probe and gate printed as it ends.

use super::execute::jobs;
use super::robot::load as load_robot;
use super::validate::{cli_error, exec_options, gate_options};
use super::{check_output, load_spec_for, print_json};
use crate::cli::RelaxArgs;
use crate::exit::{CliError, CliResult};
use akl_validate::relax::{relax, Event, GateRound, Probe, RelaxOptions, Relaxation};
use akl_validate::ValidateError;
use serde::Serialize;

/// How far the gates' seeds start from the search's (`--seed`).
const GATE_SEED_OFFSET: u64 = 1_000_000;

#[derive(Serialize)]
struct Relaxed<'a> {
    spec: String,
    task: String,
    output: Option<String>,
    speed_scale: f64,
    #[serde(flatten)]
    relaxation: &'a Relaxation,
}

pub(super) fn run(args: RelaxArgs) -> CliResult {
    check_output(&args.output, "relaxed spec")?;
    let robot = load_robot(&args.robot)?;
    let task = super::load_task(&args.task)?;
    let spec = load_spec_for(&args.spec, &task, args.fit)?;
    let options = RelaxOptions {
        seed: args.seed,
        gate_seed: args.seed.saturating_add(GATE_SEED_OFFSET),
        jobs: jobs(args.run.jobs)?,
        screen: args.screen,
        max_effort: args.max_effort,
        gate: gate_options(&args.gate, RelaxOptions::default().gate.max_trials)?,
        exec: exec_options(&args.run),
        ..RelaxOptions::default()
    };
    if !args.json {
        println!(
            "{} on task `{}`: screening up to {} trials per widening (seeds {}..), planning at most {}× the spec's collision probes; what screening kept gated on fresh seeds (from {}): success {} at {:.0} % confidence",
            args.spec.display(),
            task.name,
            options.screen,
            options.seed,
            options.max_effort,
            options.gate_seed,
            options.gate.min_success,
            100.0 * options.gate.confidence
        );
    }
    let relaxation = relax(&robot, &task, &spec, &options, &|event| {
        if !args.json {
            match event {
                Event::Probe(p) => println!("{}", probe_line(p)),
                Event::Gate(g) => println!("{}", gate_line(g)),
            }
        }
    });
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
        speed_scale: args.run.speed.speed_scale,
        relaxation: &relaxation,
    };
    if args.json {
        print_json(&report)?;
    } else {
        print_summary(&report);
    }
    match (&relaxation.relaxed, relaxation.interrupted) {
        (_, true) => Err(CliError::interrupted(format!(
            "interrupted after {} trials{}",
            relaxation.trials,
            if relaxation.relaxed.is_some() {
                "; the widest gated spec was written"
            } else {
                "; nothing was gated, nothing written"
            }
        ))),
        (Some(_), false) => Ok(()),
        (None, false) => Err(CliError::internal(format!(
            "{}: no widening passed its gate; nothing written",
            args.spec.display()
        ))),
    }
}

/// A bound in its unit: millimetres for x, y and z, radians for the turns.
fn bound(axis: &str, v: f64) -> String {
    if matches!(axis, "x" | "y" | "z") {
        format!("{:+.1} mm", v * 1e3)
    } else {
        format!("{:+.3} rad", v)
    }
}

fn probe_line(p: &Probe) -> String {
    let verdict = match (&p.rejected_by, p.kept) {
        (_, true) => "screened, kept".to_string(),
        (Some(why), _) => format!("rejected: {why}"),
        (None, false) => "interrupted".to_string(),
    };
    format!(
        "  keyframe {} {:<5} [{}, {}] → [{}, {}]: {} trial(s), effort {:.1}×, {verdict}",
        p.keyframe,
        p.axis,
        bound(p.axis, p.from[0]),
        bound(p.axis, p.from[1]),
        bound(p.axis, p.to[0]),
        bound(p.axis, p.to[1]),
        p.trials,
        p.effort
    )
}

fn gate_line(g: &GateRound) -> String {
    let what = if g.shares.is_empty() {
        "the spec as given".to_string()
    } else {
        let widened: Vec<String> = g
            .shares
            .iter()
            .enumerate()
            .filter(|(_, s)| **s > 0.0)
            .map(|(k, s)| format!("keyframe {k} at {:.0} %", 100.0 * s))
            .collect();
        format!("the widenings kept ({})", widened.join(", "))
    };
    let blamed = if g.blamed.is_empty() {
        String::new()
    } else {
        let names: Vec<String> = g.blamed.iter().map(usize::to_string).collect();
        format!("; blamed on keyframe(s) {}", names.join(", "))
    };
    format!(
        "gate on {what} (seeds {}..): {} — passed {}{}{blamed}",
        g.seed,
        g.decision.map_or("interrupted", |d| d.label()),
        g.outcome.pass_rate,
        g.outcome
            .first_failure_text()
            .map_or(String::new(), |f| format!("; first failure: {f}"))
    )
}

fn bits(b: Option<f64>) -> String {
    b.map_or("no trace".into(), |b| format!("{b:.1}"))
}

fn print_summary(r: &Relaxed) {
    let x = r.relaxation;
    let gains: Vec<String> = x
        .volume_gain
        .iter()
        .enumerate()
        .map(|(k, g)| format!("keyframe {k} {g:+.1}"))
        .collect();
    println!(
        "TSR volume gained: {:+.1} bits ({}); {} trials in all",
        x.volume_gained(),
        gains.join(", "),
        x.trials
    );
    let gained = x
        .bits_gained()
        .map_or(String::new(), |g| format!(" ({g:+.1})"));
    println!(
        "bits of execution traces: {} before, {} after{gained}",
        bits(x.bits_before),
        bits(x.bits_after)
    );
    if let Some(out) = &r.output {
        println!("wrote {out}");
    }
}
