//! One module per top-level command.

mod plan;
mod robot;
mod spec;
mod task;

use crate::cli::{Cli, Command};
use crate::exit::CliResult;

/// Runs the parsed command line.
pub fn run(cli: Cli) -> CliResult {
    match cli.command {
        Command::Task(cmd) => task::run(cmd),
        Command::Spec(cmd) => spec::run(cmd),
        Command::Robot(cmd) => robot::run(cmd),
        Command::Plan(args) => plan::run(args),
    }
}

/// Prints a value as pretty JSON on stdout.
pub(crate) fn print_json<T: serde::Serialize>(value: &T) -> CliResult {
    let text = akl_tsr::io::to_readable_json(value).map_err(crate::exit::CliError::internal)?;
    print!("{text}");
    Ok(())
}
