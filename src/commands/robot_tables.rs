//! `akl robot tables`: the robot's self-collision tables computed ahead, written to a file.

use super::print_json;
use super::robot::load;
use crate::cli::RobotArg;
use crate::exit::{CliError, CliResult};
use akl_planner::collision::RobotCollision;
use akl_planner::STORED_TABLES_FILE;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(Serialize)]
struct Written {
    file: PathBuf,
    tables: usize,
    nodes: usize,
    bytes: usize,
    seconds: f64,
}

pub(super) fn run(
    arg: &RobotArg,
    output: Option<&Path>,
    jobs: Option<usize>,
    json: bool,
) -> CliResult {
    let file = match (output, &arg.robot) {
        (Some(path), _) => path.to_path_buf(),
        (None, Some(dir)) => dir.join(STORED_TABLES_FILE),
        (None, None) => {
            return Err(CliError::input(
                "--output: the built-in Panda's tables go to a file named here (robots/panda/self_tables.bin in the source tree)",
            ))
        }
    };
    let threads = super::execute::jobs(jobs)?;
    let robot = load(arg)?;
    let model = RobotCollision::new(&robot);
    let started = Instant::now();
    let stored = model.fill_tables(&robot, threads);
    let bytes = stored.to_bytes();
    akl_tsr::io::write_atomic(&file, &bytes)
        .map_err(|e| CliError::input(format!("{}: cannot write: {e}", file.display())))?;
    let written = Written {
        file,
        tables: stored.len(),
        nodes: stored.nodes(),
        bytes: bytes.len(),
        seconds: started.elapsed().as_secs_f64(),
    };
    if json {
        return print_json(&written);
    }
    println!(
        "{} self-collision table(s), {} nodes, computed in {:.2} s: {} ({} bytes)",
        written.tables,
        written.nodes,
        written.seconds,
        written.file.display(),
        written.bytes
    );
    Ok(())
}
