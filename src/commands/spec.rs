//! `akl spec check` and `akl spec show`.

use super::print_json;
use crate::cli::SpecCommand;
use crate::exit::{CliError, CliResult};
use crate::table::{vec3, Table};
use akl_scene::builtin;
use akl_tsr::rpy::rpy_from_rotation;
use akl_tsr::{Constraint, FileError, KeyframeKind, TaskSpec};
use serde::Serialize;
use std::path::Path;

pub(super) fn run(cmd: SpecCommand) -> CliResult {
    match cmd {
        SpecCommand::Check { file, task, json } => check(&file, task.as_deref(), json),
        SpecCommand::Show { file, json } => show(&file, json),
    }
}

fn load(file: &Path) -> Result<TaskSpec, CliError> {
    TaskSpec::load(file).map_err(CliError::input)
}

#[derive(Serialize)]
struct CheckSummary {
    file: String,
    task: String,
    method: String,
    keyframes: usize,
    interaction: usize,
    constraint: usize,
    combined: usize,
    references: Vec<String>,
    references_checked_against: Option<String>,
    move_in_line: Vec<[usize; 2]>,
}

fn check(file: &Path, task: Option<&str>, json: bool) -> CliResult {
    let spec = load(file)?;
    let world_task = match task {
        Some(name) => Some(super::load_task(name)?),
        None => builtin::task(&spec.task)
            .transpose()
            .map_err(CliError::internal)?,
    };
    if let Some(t) = &world_task {
        spec.check_references(t.world.names()).map_err(|source| {
            CliError::input(FileError {
                path: file.to_path_buf(),
                source,
            })
        })?;
    }
    let count = |k: KeyframeKind| spec.keyframes.iter().filter(|kf| kf.kind == k).count();
    let lines: Vec<[usize; 2]> = spec
        .keyframes
        .iter()
        .enumerate()
        .filter(|(_, kf)| kf.constraint == Constraint::MoveInLine)
        .map(|(i, _)| [i - 1, i])
        .collect();
    let summary = CheckSummary {
        file: file.display().to_string(),
        task: spec.task.clone(),
        method: spec.method.clone(),
        keyframes: spec.keyframes.len(),
        interaction: count(KeyframeKind::Interaction),
        constraint: count(KeyframeKind::Constraint),
        combined: count(KeyframeKind::Combined),
        references: spec.references().into_iter().map(String::from).collect(),
        references_checked_against: world_task.as_ref().map(|t| t.name.clone()),
        move_in_line: lines,
    };
    if json {
        return print_json(&summary);
    }
    println!(
        "{}: valid spec for task `{}` (method {})",
        summary.file, summary.task, summary.method
    );
    println!(
        "  keyframes:   {} ({} interaction, {} constraint, {} combined)",
        summary.keyframes, summary.interaction, summary.constraint, summary.combined
    );
    let checked = match &summary.references_checked_against {
        Some(t) => format!("all objects of task `{t}`"),
        None => "not checked: the task is not built in; pass --task".into(),
    };
    println!(
        "  references:  {} ({checked})",
        summary.references.join(", ")
    );
    if summary.move_in_line.is_empty() {
        println!("  constraints: none");
    } else {
        let segs: Vec<String> = summary
            .move_in_line
            .iter()
            .map(|[a, b]| format!("keyframes {a}→{b}"))
            .collect();
        println!("  constraints: move_in_line on {}", segs.join(", "));
    }
    Ok(())
}

fn show(file: &Path, json: bool) -> CliResult {
    let spec = load(file)?;
    if json {
        return print_json(&spec);
    }
    println!(
        "{}: task `{}`, method {}, {} keyframes",
        file.display(),
        spec.task,
        spec.method,
        spec.keyframes.len()
    );
    print!("{}", keyframe_table(&spec).render());
    Ok(())
}

/// The keyframes of `spec`, one row each: kind, reference, gripper, constraint, demo time,
/// the end-effector offset in the reference and the world target.
pub(crate) fn keyframe_table(spec: &TaskSpec) -> Table {
    let mut table = Table::new([
        "#",
        "kind",
        "reference",
        "gripper",
        "constraint",
        "t (s)",
        "offset in reference",
        "rpy (deg)",
        "world target",
    ]);
    for (i, kf) in spec.keyframes.iter().enumerate() {
        let rpy = rpy_from_rotation(&kf.tsr.tw_e.rotation).map(f64::to_degrees);
        table.row(vec![
            i.to_string(),
            kf.kind.to_string(),
            kf.reference.clone(),
            kf.gripper.to_string(),
            kf.constraint.to_string(),
            kf.t.map_or("-".into(), |t| format!("{t:.2}")),
            vec3(&kf.tsr.tw_e.translation.vector),
            format!(
                "[{}, {}, {}]",
                degrees(rpy[0]),
                degrees(rpy[1]),
                degrees(rpy[2])
            ),
            vec3(&kf.tsr.nominal().translation.vector),
        ]);
    }
    table
}

/// Whole degrees, without the "-0" that rounding a tiny negative angle gives.
fn degrees(d: f64) -> String {
    let r = d.round();
    format!("{}", if r == 0.0 { 0.0 } else { r })
}
