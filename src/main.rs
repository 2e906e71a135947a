//! `akl`: teach a robot arm a task from one demonstration and verify the learned spec.
//!
//! The binary only parses arguments, calls the library crates and prints; every algorithm
//! lives in a crate.

mod answers;
mod cli;
mod commands;
mod exit;
mod progress;
mod stop;
mod table;
mod tty;

use clap::Parser;
use std::process::ExitCode;

fn main() -> ExitCode {
    stop::end_quietly_on_closed_pipe();
    let args = cli::Cli::parse();
    match commands::run(args) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // A verdict already printed on stdout carries no message.
            if !e.message.is_empty() {
                eprintln!("error: {}", e.message);
            }
            ExitCode::from(e.code)
        }
    }
}
