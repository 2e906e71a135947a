//! `akl task list` and `akl task show`.

use super::print_json;
use crate::cli::TaskCommand;
use crate::exit::{CliError, CliResult};
use crate::table::{vec3, Table};
use akl_scene::{builtin, Task};
use akl_tsr::rpy::rpy_from_rotation;
use serde::Serialize;

pub fn run(cmd: TaskCommand) -> CliResult {
    match cmd {
        TaskCommand::List { json } => list(json),
        TaskCommand::Show { task, json } => show(&task, json),
    }
}

#[derive(Serialize)]
struct TaskSummary {
    name: String,
    description: String,
    objects: usize,
    movable: usize,
    goals: usize,
    truth_keyframes: Option<usize>,
}

fn load(name: &str) -> Result<Task, CliError> {
    builtin::resolve(name).map_err(CliError::input)
}

fn list(json: bool) -> CliResult {
    let mut summaries = Vec::new();
    for name in builtin::names() {
        let t = load(name)?;
        summaries.push(TaskSummary {
            name: t.name.clone(),
            description: t.description.clone(),
            objects: t.world.objects.len(),
            movable: t.world.objects.iter().filter(|o| o.movable).count(),
            goals: t.goals.len(),
            truth_keyframes: t.truth.as_ref().map(|s| s.keyframes.len()),
        });
    }
    if json {
        return print_json(&summaries);
    }
    let mut table = Table::new([
        "task",
        "objects",
        "movable",
        "goals",
        "truth keyframes",
        "description",
    ]);
    for s in &summaries {
        table.row(vec![
            s.name.clone(),
            s.objects.to_string(),
            s.movable.to_string(),
            s.goals.to_string(),
            s.truth_keyframes.map_or("-".into(), |n| n.to_string()),
            s.description.clone(),
        ]);
    }
    print!("{}", table.render());
    Ok(())
}

fn show(name: &str, json: bool) -> CliResult {
    let task = load(name)?;
    if json {
        print!("{}", task.to_json());
        return Ok(());
    }
    println!("{}: {}", task.name, task.description);
    println!(
        "robot base at {}",
        vec3(&task.world.robot_base.translation.vector)
    );
    println!();
    let mut objects = Table::new([
        "object",
        "shape",
        "position",
        "yaw",
        "movable",
        "mass",
        "randomized (dx, dy, dyaw)",
    ]);
    for o in &task.world.objects {
        let yaw = rpy_from_rotation(&o.pose.rotation)[2];
        let range = task.randomize.get(&o.name).map_or("-".into(), |r| {
            format!(
                "[{}, {}] [{}, {}] [{}, {}]",
                r.x[0], r.x[1], r.y[0], r.y[1], r.yaw[0], r.yaw[1]
            )
        });
        objects.row(vec![
            o.name.clone(),
            o.shape.describe(),
            vec3(&o.pose.translation.vector),
            format!("{yaw:.2}"),
            if o.movable { "yes".into() } else { "no".into() },
            if o.movable {
                format!("{} kg", o.mass)
            } else {
                "-".into()
            },
            range,
        ]);
    }
    print!("{}", objects.render());
    println!();
    println!("goals:");
    for g in &task.goals {
        println!("  {}", g.describe());
    }
    println!();
    println!(
        "teaching (starts with the hand at {}):",
        vec3(&task.teaching.start.translation.vector)
    );
    for (i, step) in task.teaching.steps.iter().enumerate() {
        println!("  {}. {}", i + 1, step.describe());
    }
    if let Some(truth) = &task.truth {
        println!();
        println!("ground truth: {} keyframes", truth.keyframes.len());
        for (i, kf) in truth.keyframes.iter().enumerate() {
            println!(
                "  {i}: {} on {}, gripper {}, constraint {}",
                kf.kind, kf.reference, kf.gripper, kf.constraint
            );
        }
    }
    Ok(())
}
