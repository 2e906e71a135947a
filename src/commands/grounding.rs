//! `akl execute SPEC --task T --grounding-check`: which references the task's randomization can
//! tell apart from each keyframe's own.

use super::print_json;
use crate::exit::{CliError, CliResult};
use crate::progress::Progress;
use crate::table::Table;
use akl_exec::{ExecError, ExecOptions};
use akl_planner::Robot;
use akl_scene::Task;
use akl_stats::percent;
use akl_tsr::{FileError, TaskSpec};
use akl_validate::grounding::{check_groundings, GroundingOptions, Groundings, Verdict};
use std::path::Path;

/// Runs the check, each alternative judged by the gate of `options`, and prints it;
/// interrupted (`exec.interrupt`), it prints what it measured and exits 130.
#[allow(clippy::too_many_arguments)]
pub(super) fn run(
    robot: &Robot,
    task: &Task,
    spec: &TaskSpec,
    spec_path: &Path,
    exec: &ExecOptions,
    options: &GroundingOptions,
    json: bool,
) -> CliResult {
    let alternatives = spec.keyframes.len() * task.world.objects.len();
    let progress = Progress::new(&format!("re-grounding on `{}`", task.name), alternatives);
    let measured = check_groundings(robot, task, spec, exec, options, &|done, _| {
        progress.set(done);
    });
    progress.finish();
    let measured = measured.map_err(|e| match e {
        ExecError::Spec(source) => CliError::input(FileError {
            path: spec_path.to_path_buf(),
            source,
        }),
        other => CliError::input(other),
    })?;
    if json {
        print_json(&measured)?;
    } else {
        print_groundings(spec_path, task, options, &measured);
    }
    if measured.interrupted {
        let done: usize = measured
            .keyframes
            .iter()
            .map(|k| k.alternatives.len())
            .sum();
        return Err(CliError::interrupted(format!(
            "interrupted: {done} of {alternatives} alternatives measured"
        )));
    }
    Ok(())
}

fn print_groundings(
    spec_path: &Path,
    task: &Task,
    options: &GroundingOptions,
    measured: &Groundings,
) {
    let g = &options.gate;
    println!(
        "{}: each keyframe re-grounded on every other object of `{}`, judged by the deployment \
         gate (success {} at confidence {}, at most {} trials from seed {}, goals drawn across \
         the TSRs); distinguished when the gate fails it",
        spec_path.display(),
        task.name,
        g.min_success,
        g.confidence,
        g.max_trials,
        options.seed
    );
    if measured.interrupted {
        println!(
            "interrupted: only the alternatives measured are listed, the last possibly undecided"
        );
    }
    for k in &measured.keyframes {
        println!("keyframe {} (on {}):", k.keyframe, k.reference);
        let mut table = Table::new(["  re-grounded on", "failed", "verdict"]);
        for a in &k.alternatives {
            let (failed, verdict) = match &a.verdict {
                Verdict::Equivalent { because } => {
                    ("-".to_string(), format!("equivalent: {because}"))
                }
                v => {
                    let causes: Vec<String> =
                        a.causes.iter().map(|(c, n)| format!("{c} {n}")).collect();
                    let word = match v {
                        Verdict::Distinguished => "distinguished",
                        Verdict::NotDistinguished => "NOT distinguished",
                        _ => "undecided",
                    };
                    let why = if causes.is_empty() {
                        String::new()
                    } else {
                        format!(" ({})", causes.join(", "))
                    };
                    let failed = match a.pass_rate {
                        Some(r) => format!(
                            "{}/{} (95 % CI {}–{})",
                            a.failed,
                            a.trials,
                            percent(1.0 - r.upper),
                            percent(1.0 - r.lower)
                        ),
                        None => format!("{}/{}", a.failed, a.trials),
                    };
                    (failed, format!("{word}{why}"))
                }
            };
            table.row(vec![format!("  {}", a.reference), failed, verdict]);
        }
        print!("{}", table.render());
    }
    let undecided = measured
        .keyframes
        .iter()
        .flat_map(|k| &k.alternatives)
        .filter(|a| a.verdict == Verdict::Undecided)
        .count();
    if undecided > 0 {
        println!("{undecided} alternative(s) undecided: the gate could not tell within its trials");
    }
    let weak: Vec<String> = measured
        .keyframes
        .iter()
        .flat_map(|k| {
            k.not_distinguished()
                .map(move |a| format!("keyframe {} on {}", k.keyframe, a.reference))
        })
        .collect();
    if !weak.is_empty() {
        println!(
            "the randomization cannot tell these from the spec's references: {}",
            weak.join(", ")
        );
    } else if undecided == 0 {
        let measured = if measured.interrupted {
            " measured"
        } else {
            ""
        };
        println!("every other reference{measured} is distinguished or equivalent");
    }
}
