//! `akl score`.

use super::print_json;
use crate::cli::ScoreArgs;
use crate::exit::{CliError, CliResult};
use akl_learn::{score, Tolerance};
use akl_scene::builtin;
use akl_tsr::TaskSpec;
use std::path::Path;

pub(super) fn run(args: ScoreArgs) -> CliResult {
    let learned = TaskSpec::load(&args.spec).map_err(CliError::input)?;
    let truth = load_truth(&args.truth)?;
    let s = score(&learned, &truth, &Tolerance::default());
    if args.json {
        return print_json(&s);
    }
    println!(
        "{} ({} keyframes) against the truth ({} keyframes)",
        args.spec.display(),
        s.learned,
        s.truth
    );
    println!(
        "  keyframe accuracy:   {:.2} ({} paired)",
        s.keyframe_accuracy, s.matched_keyframes
    );
    println!(
        "  pose accuracy:       {:.2} ({} paired)",
        s.pose_accuracy, s.matched_poses
    );
    match s.constraint_accuracy {
        Some(c) => println!(
            "  constraint accuracy: {c:.2} (lines: {:.3} m learned, {:.3} m true, {:.3} m common)",
            s.learned_line_length, s.true_line_length, s.common_line_length
        ),
        None => println!("  constraint accuracy: - (no lines on either side)"),
    }
    if s.success {
        println!("  success: the learned spec equals the ground truth");
    } else {
        println!("  not a success:");
        for d in &s.differences {
            println!("    - {d}");
        }
    }
    Ok(())
}

/// The ground truth of a built-in task by name, or a spec file.
fn load_truth(truth: &str) -> Result<TaskSpec, CliError> {
    match builtin::task(truth) {
        Some(task) => task.map_err(CliError::internal)?.truth.ok_or_else(|| {
            CliError::internal(format!("built-in task `{truth}` has no ground truth"))
        }),
        None => TaskSpec::load(Path::new(truth)).map_err(CliError::input),
    }
}
