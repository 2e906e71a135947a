//! Command-line arguments.

use clap::{Parser, Subcommand};
use std::path::PathBuf;

/// Teach a robot arm a multistep task from one demonstration, as the least restrictive
/// sequence of Task Space Region keyframes, and check the learned spec before it runs.
#[derive(Debug, Parser)]
#[command(name = "akl", version, about, long_about = None)]
pub struct Cli {
    /// What to do.
    #[command(subcommand)]
    pub command: Command,
}

/// The top-level commands.
#[derive(Debug, Subcommand)]
pub enum Command {
    /// List and inspect tasks (built-in or from a task file).
    #[command(subcommand)]
    Task(TaskCommand),
    /// Validate and inspect task specifications (spec.json).
    #[command(subcommand)]
    Spec(SpecCommand),
}

/// `akl task ...`
#[derive(Debug, Subcommand)]
pub enum TaskCommand {
    /// List the built-in tasks.
    List {
        /// Print JSON instead of a table.
        #[arg(long)]
        json: bool,
    },
    /// Show a task: its objects, randomization ranges, goals and teaching steps.
    Show {
        /// A built-in task name (see `akl task list`) or the path of a task file.
        task: String,
        /// Print the task file as JSON.
        #[arg(long)]
        json: bool,
    },
}

/// `akl spec ...`
#[derive(Debug, Subcommand)]
pub enum SpecCommand {
    /// Validate a spec and summarize it: keyframes, kinds, references and constraints.
    ///
    /// References are checked against the objects of the task named in the spec when it is a
    /// built-in task, or of the task given with --task. Exits with 2 if the spec is invalid.
    Check {
        /// The spec file.
        file: PathBuf,
        /// Task (built-in name or task file) whose objects the references must name.
        #[arg(long)]
        task: Option<String>,
        /// Print the summary as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Print a spec's keyframes as a table (or JSON).
    Show {
        /// The spec file.
        file: PathBuf,
        /// Print the spec as JSON.
        #[arg(long)]
        json: bool,
    },
}
