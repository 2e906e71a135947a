//! One module per top-level command.

mod bench;
mod calibrate;
mod compare;
mod demo;
mod eval;
mod execute;
mod flexibility;
mod grounding;
mod learn;
mod plan;
mod relax;
mod report;
mod robot;
mod robot_check;
mod robot_init;
mod robot_tables;
mod score;
mod spec;
mod task;
mod teach;
mod validate;

use crate::cli::{AnyTaskArg, Cli, Command};
use crate::exit::{CliError, CliResult};
use akl_exec::{check_settles, Physics};
use akl_learn::calibration::Calibration;
use akl_learn::teacher::TeacherProfile;
use akl_scene::Task;
use akl_tsr::{FileError, TaskSpec};
use std::path::Path;

/// Runs the parsed command line.
pub(crate) fn run(cli: Cli) -> CliResult {
    match cli.command {
        Command::Task(cmd) => task::run(cmd),
        Command::Spec(cmd) => spec::run(cmd),
        Command::Calibrate(args) => calibrate::run(args),
        Command::Teach(args) => teach::run(args),
        Command::Learn(args) => learn::run(args),
        Command::Score(args) => score::run(args),
        Command::Robot(cmd) => robot::run(cmd),
        Command::Plan(args) => plan::run(args),
        Command::Execute(args) => execute::run(args),
        Command::Flexibility(args) => flexibility::run(args),
        Command::Validate(args) => validate::run(args),
        Command::Relax(args) => relax::run(args),
        Command::Compare(args) => compare::run(args),
        Command::Demo(args) => demo::run(args),
        Command::Eval(args) => eval::run(args),
        Command::Bench(cmd) => bench::run(cmd),
        Command::Report(cmd) => report::run(cmd),
    }
}

/// A simulated teacher profile by name; the error lists the names.
pub(crate) fn profile(name: &str) -> Result<TeacherProfile, CliError> {
    TeacherProfile::named(name).ok_or_else(|| {
        CliError::input(format!(
            "unknown teacher profile `{name}` (use {})",
            TeacherProfile::NAMES.join(", ")
        ))
    })
}

/// The calibration in `path`, or the shipped default; with the label a recording names it by.
pub(crate) fn load_calibration(path: Option<&Path>) -> Result<(Calibration, String), CliError> {
    match path {
        Some(p) => Ok((
            Calibration::load(p).map_err(CliError::input)?,
            p.display().to_string(),
        )),
        None => Ok((Calibration::default(), "default".into())),
    }
}

/// Checks, before any work, that an output the user named can be written: its folder exists
/// and it is not a folder itself (bad input, exit 2, rather than a failure after the work).
pub(crate) fn check_output(path: &Path, what: &str) -> Result<(), CliError> {
    if path.is_dir() {
        return Err(CliError::input(format!(
            "{}: is a folder; give the {what} a file name",
            path.display()
        )));
    }
    let folder = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    if path.file_name().is_none() || !folder.is_dir() {
        return Err(CliError::input(format!(
            "{}: cannot write the {what} there (no such folder)",
            path.display()
        )));
    }
    Ok(())
}

/// The task `name_or_path` names (a built-in name or a task file), its world checked to stand
/// still when simulated untouched ([`akl_exec::check_settles`]): a scene that only the
/// simulation shows to be wrong (an object in the air, one over an edge) is bad input naming the
/// object.
pub(crate) fn load_task(name_or_path: &str) -> Result<Task, CliError> {
    let task = akl_scene::builtin::resolve(name_or_path).map_err(CliError::input)?;
    check_settles(&task.world, &Physics::default())
        .map_err(|e| CliError::input(format!("{name_or_path}: world: {e}")))?;
    Ok(task)
}

/// The spec in `path`, checked against `task`: it must be for that task (its `task` field)
/// unless `fit.any_task`, and name only its objects; errors name the file.
pub(crate) fn load_spec_for(
    path: &Path,
    task: &Task,
    fit: AnyTaskArg,
) -> Result<TaskSpec, CliError> {
    let spec = TaskSpec::load(path).map_err(CliError::input)?;
    if spec.task != task.name && !fit.any_task {
        return Err(CliError::input(format!(
            "{}: the spec is for task `{}`, not `{}` (--any-task runs it anyway)",
            path.display(),
            spec.task,
            task.name
        )));
    }
    spec.check_references(task.world.names())
        .map_err(|source| {
            CliError::input(FileError {
                path: path.to_path_buf(),
                source,
            })
        })?;
    Ok(spec)
}

/// Prints a value as pretty JSON on stdout.
pub(crate) fn print_json<T: serde::Serialize>(value: &T) -> CliResult {
    let text = akl_tsr::io::to_readable_json(value).map_err(crate::exit::CliError::internal)?;
    print!("{text}");
    Ok(())
}
