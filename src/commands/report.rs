//! `akl report merge PARTS... -o FILE`: the shards of a run joined into its report.

use super::execute::{print_executed, Executed};
use super::{check_output, print_json};
use crate::cli::{MergeArgs, ReportCommand};
use crate::exit::{CliError, CliResult};
use akl_exec::merge;
use akl_exec::{junit, Suite};
use serde::Serialize;

pub(super) fn run(cmd: ReportCommand) -> CliResult {
    match cmd {
        ReportCommand::Merge(args) => merge_parts(&args),
    }
}

/// What `akl report merge --json` prints: the merged report without its trials.
#[derive(Serialize)]
struct Merged<'a> {
    output: String,
    junit: Option<String>,
    parts: usize,
    trials: usize,
    passed: usize,
    pass_rate: akl_stats::PassRate,
    failures: &'a std::collections::BTreeMap<akl_exec::report::Cause, usize>,
    secondary: &'a std::collections::BTreeMap<akl_exec::report::Cause, usize>,
    identity: &'a Option<akl_exec::report::Identity>,
}

fn merge_parts(args: &MergeArgs) -> CliResult {
    check_output(&args.output, "merged report")?;
    if let Some(p) = &args.junit {
        check_output(p, "JUnit file")?;
    }
    let parts = args
        .parts
        .iter()
        .map(|p| merge::read(p).map(|r| (p.clone(), r)))
        .collect::<Result<Vec<_>, _>>()
        .map_err(CliError::input)?;
    let merged = merge::merge(&parts).map_err(CliError::input)?;
    merged
        .save(&args.output)
        .map_err(|e| CliError::internal(format!("{}: {e}", args.output.display())))?;
    if let Some(p) = &args.junit {
        let name = format!("{} on {}", merged.method, merged.task);
        let class = format!("akl.{}", merged.task);
        let suite = Suite {
            name: &name,
            class: &class,
            properties: Vec::new(),
        };
        akl_tsr::io::write_atomic(p, junit(&merged, &suite).as_bytes())
            .map_err(|e| CliError::internal(format!("{}: {e}", p.display())))?;
    }
    if args.json {
        return print_json(&Merged {
            output: args.output.display().to_string(),
            junit: args.junit.as_ref().map(|p| p.display().to_string()),
            parts: parts.len(),
            trials: merged.trials,
            passed: merged.passed,
            pass_rate: merged.pass_rate,
            failures: &merged.failures,
            secondary: &merged.secondary,
            identity: &merged.identity,
        });
    }
    let spec = format!("spec {}", short_hash(&merged));
    let output = args.output.display().to_string();
    let junit_file = args.junit.as_ref().map(|p| p.display().to_string());
    print_executed(&Executed {
        spec,
        report_file: Some(output.clone()),
        trace_file: None,
        trace_trial: None,
        report: merged,
    });
    println!("merged {} part(s) into {output}", parts.len());
    if let Some(f) = junit_file {
        println!("JUnit: {f}");
    }
    Ok(())
}

/// The first 12 hex digits of the merged run's spec hash, to name the spec in the summary.
fn short_hash(r: &merge::StoredReport) -> String {
    r.identity
        .as_ref()
        .map_or_else(String::new, |i| i.spec_hash.chars().take(12).collect())
}
