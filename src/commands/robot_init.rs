//! `akl robot init`: guess a robot folder from a stock URDF, write it, load it back and print
//! what was guessed.

use super::print_json;
use crate::cli::RobotInitArgs;
use crate::exit::{CliError, CliResult};
use akl_planner::robot_init::{guess, write, Guess, InitOptions};
use akl_planner::Robot;
use serde::Serialize;

#[derive(Serialize)]
struct Output<'a> {
    folder: String,
    #[serde(flatten)]
    guess: &'a Guess,
    /// Why the written folder does not load, if it does not.
    load_error: Option<String>,
}

pub(super) fn run(args: &RobotInitArgs) -> CliResult {
    let options = InitOptions {
        samples: args.samples,
        ..InitOptions::default()
    };
    let g =
        guess(&args.urdf, &args.package_path, &args.output, &options).map_err(CliError::input)?;
    write(&g, &args.output).map_err(CliError::input)?;
    let load_error = Robot::load_with(&args.output, &args.package_path)
        .err()
        .map(|e| e.to_string());
    let folder = args.output.display().to_string();
    if args.json {
        print_json(&Output {
            folder: folder.clone(),
            guess: &g,
            load_error: load_error.clone(),
        })?;
    } else {
        print_guess(&folder, &g);
    }
    match load_error {
        None => Ok(()),
        Some(e) => Err(CliError::input(format!(
            "{folder} was written but does not load (edit it and run `akl robot info --robot {folder}`): {e}"
        ))),
    }
}

fn print_guess(folder: &str, g: &Guess) {
    let s = &g.structure;
    let c = &g.config;
    println!(
        "wrote {folder}/robot.toml and {folder}/{} from {}",
        c.urdf,
        g.urdf_path.display()
    );
    println!(
        "arm: {} joints from root `{}` ({}), flange `{}`",
        s.arm_joints.len(),
        s.root,
        s.arm_joints.join(", "),
        c.flange_link
    );
    let kind = match s.gripper {
        akl_planner::robot_init::GripperKind::Parallel => "parallel (two prismatic fingers)",
        akl_planner::robot_init::GripperKind::Linkage => "linkage (a knuckle with mimic joints)",
        akl_planner::robot_init::GripperKind::None => "none",
    };
    println!(
        "gripper: {kind} on `{}`, driven by {} (moves {}), opens {} m",
        s.palm,
        list(&c.gripper.joints),
        list(&s.finger_joints),
        c.gripper.open_width
    );
    let t = &g.tcp;
    println!(
        "tcp: `{}`{} at xyz {:?}, rpy {:?} in `{}`",
        t.link,
        if t.added.is_some() {
            " (added to the URDF)"
        } else {
            " (in the URDF)"
        },
        t.xyz,
        t.rpy,
        s.palm
    );
    println!("ik solver: {:?}", c.ik.solver);
    println!("ready: {:?}", c.ready);
    println!("velocity limits (URDF): {:?}", c.velocity_limits);
    println!("acceleration limits: {:?}", c.acceleration_limits);
    println!(
        "hand links: {}; mount links: {}",
        list(&c.gripper.hand_links),
        list(&c.collision.mount_links)
    );
    let p = &g.pairs;
    println!(
        "link pairs never checked: {} ({} adjacent or fingers, {} never meeting and {} always meeting in {} random configurations); {} checked",
        c.collision.allowed_pairs.len(),
        p.adjacent,
        p.never.len(),
        p.always.len(),
        p.samples,
        p.checked.len()
    );
    for note in &g.notes {
        println!("note: {note}");
    }
}

fn list(items: &[String]) -> String {
    if items.is_empty() {
        "none".into()
    } else {
        items.join(", ")
    }
}
