//! `akl robot check`: one configuration against a task's world or a file of obstacles, with
//! the planner's collision model.

use super::print_json;
use super::robot::{joints, load};
use crate::cli::RobotCheckArgs;
use crate::exit::{CliError, CliResult, INTERNAL};
use crate::table::Table;
use akl_planner::collision::{CheckReport, Checker, Margins, RobotCollision, Scene};
use akl_scene::World;
use serde::Serialize;

#[derive(Serialize)]
struct Output<'a> {
    joints: &'a [f64],
    gripper: f64,
    margins: Margins,
    free: bool,
    #[serde(flatten)]
    report: &'a CheckReport,
}

pub(super) fn run(args: &RobotCheckArgs) -> CliResult {
    let robot = load(&args.robot)?;
    let q = joints(&args.joints, "--joints", &robot)?;
    let width = match args.gripper {
        Some(w) if !(w.is_finite() && (0.0..=robot.open_width()).contains(&w)) => {
            return Err(CliError::input(format!(
                "--gripper: {w} is not an opening between 0 and {} m",
                robot.open_width()
            )))
        }
        Some(w) => w,
        None => robot.open_width(),
    };
    let world = match (&args.task, &args.obstacles) {
        (Some(task), _) => super::load_task(task)?.world,
        (None, Some(path)) => akl_scene::load_obstacles(path).map_err(CliError::input)?,
        (None, None) => World {
            robot_base: akl_tsr::Pose::identity(),
            objects: Vec::new(),
        },
    };
    let model = match args.margin {
        Some(m) if !(m.is_finite() && m >= 0.0) => {
            return Err(CliError::input(format!(
                "--margin: {m} is not a clearance of 0 m or more"
            )))
        }
        Some(m) => RobotCollision::with_margins(
            &robot,
            Margins {
                arm: m,
                hand: m,
                held: m,
                self_: m,
            },
        ),
        None => RobotCollision::new(&robot),
    };
    let scene = Scene::new(&world, &[]);
    let report = Checker::new(&robot, &model, &scene).report(&q, width);
    let free = report.collisions.is_empty();
    if args.json {
        print_json(&Output {
            joints: &q,
            gripper: width,
            margins: model.margins(),
            free,
            report: &report,
        })?;
    } else {
        print_text(&report, &model.margins());
    }
    if free {
        Ok(())
    } else {
        // The verdict is on stdout already.
        Err(CliError::verdict(INTERNAL, ""))
    }
}

fn print_text(report: &CheckReport, m: &Margins) {
    println!(
        "margins: arm {} m, hand {} m, between links {} m",
        m.arm, m.hand, m.self_
    );
    if report.collisions.is_empty() {
        println!("free: no collision");
    } else {
        println!("in collision:");
        for c in &report.collisions {
            let other = c
                .other_link
                .as_deref()
                .or(c.object.as_deref())
                .unwrap_or("?");
            println!("  {} with {}", c.link, other);
        }
    }
    if !report.clearances.is_empty() {
        let mut table = Table::new(["object", "distance (m)", "nearest link", ""]);
        for c in &report.clearances {
            table.row(vec![
                c.object.clone(),
                format!("{:.4}", c.distance),
                c.link.clone(),
                if c.unchecked {
                    "not checked (robot stands on it)".into()
                } else {
                    String::new()
                },
            ]);
        }
        print!("{}", table.render());
    }
}
