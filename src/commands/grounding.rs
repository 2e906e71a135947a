//! `akl execute SPEC --task T --grounding-check`: which references the task's randomization can
//! tell apart from each keyframe's own.

use super::print_json;
use crate::exit::{CliError, CliResult};
use crate::progress::Progress;
use crate::table::Table;
use akl_exec::error::ExecError;
use akl_exec::grounding::{check_groundings, GroundingOptions, Groundings, Verdict};
use akl_exec::trial::ExecOptions;
use akl_planner::Robot;
use akl_scene::Task;
use akl_tsr::{FileError, TaskSpec};
use std::path::Path;

/// Runs the check with `trials` randomized trials per alternative and prints it; interrupted
/// (`exec.interrupt`), it prints what it measured and exits 130.
#[allow(clippy::too_many_arguments)]
pub fn run(
    robot: &Robot,
    task: &Task,
    spec: &TaskSpec,
    spec_path: &Path,
    exec: &ExecOptions,
    options: &GroundingOptions,
    json: bool,
) -> CliResult {
    let alternatives = spec.keyframes.len() * task.world.objects.len();
    let progress = Progress::new(
        &format!("re-grounding on `{}`", task.name),
        alternatives * options.trials,
    );
    let measured = check_groundings(robot, task, spec, exec, options, &|done, total| {
        let _ = total;
        progress.set(done * options.trials);
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
    println!(
        "{}: each keyframe re-grounded on every other object of `{}`, {} randomized trials each \
         (seeds {}..); distinguished when at least {:.0} % fail",
        spec_path.display(),
        task.name,
        options.trials,
        options.seed,
        options.share * 100.0
    );
    if measured.interrupted {
        println!(
            "interrupted: only the alternatives measured are listed, the last possibly on fewer trials"
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
                    let word = if *v == Verdict::Distinguished {
                        "distinguished"
                    } else {
                        "NOT distinguished"
                    };
                    let why = if causes.is_empty() {
                        String::new()
                    } else {
                        format!(" ({})", causes.join(", "))
                    };
                    (format!("{}/{}", a.failed, a.trials), format!("{word}{why}"))
                }
            };
            table.row(vec![format!("  {}", a.reference), failed, verdict]);
        }
        print!("{}", table.render());
    }
    let weak: Vec<String> = measured
        .keyframes
        .iter()
        .flat_map(|k| {
            k.not_distinguished()
                .map(move |a| format!("keyframe {} on {}", k.keyframe, a.reference))
        })
        .collect();
    if weak.is_empty() {
        let measured = if measured.interrupted {
            " measured"
        } else {
            ""
        };
        println!("every other reference{measured} is distinguished or equivalent");
    } else {
        println!(
            "the randomization cannot tell these from the spec's references: {}",
            weak.join(", ")
        );
    }
}
