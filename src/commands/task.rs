//! `akl task list` and `akl task show`.

use super::print_json;
use crate::cli::TaskCommand;
use crate::exit::{CliError, CliResult};
use crate::table::{vec3, Table};
use akl_scene::{builtin, Motion, Task};
use akl_tsr::rpy::rpy_from_rotation;
use serde::Serialize;

pub(super) fn run(cmd: TaskCommand) -> CliResult {
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
    super::load_task(name)
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
    let motion = task.motion().map_err(CliError::input)?;
    println!("{}: {}", task.name, task.description);
    println!(
        "robot base at {}",
        vec3(&task.world.robot_base.translation.vector)
    );
    println!();
    let mut objects = Table::new([
        "object", "shape", "position", "yaw", "movable", "mass", "moved by", "rides on",
    ]);
    for o in &task.world.objects {
        let yaw = rpy_from_rotation(&o.pose.rotation)[2];
        let mover = motion.mover_of(&o.name);
        let moved_by = match mover {
            Some(m) if m.range.is_some() && m.group => format!("group {}", m.name),
            Some(m) if m.range.is_some() => "own range".into(),
            _ => "-".into(),
        };
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
            moved_by,
            motion.carrier_of(&o.name).unwrap_or("-").to_string(),
        ]);
    }
    print!("{}", objects.render());
    println!();
    print_randomization(&task, &motion)?;
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

/// The ranges (with what each moves and what carries it), the layout rules and the fixed
/// relations of `task`.
fn print_randomization(task: &Task, motion: &Motion) -> CliResult {
    println!(
        "randomization (offsets along the axes of what carries each; turns about its centre):"
    );
    let mut ranges = Table::new(["  range", "moves", "rides on", "x", "y", "yaw"]);
    for m in motion.movers.iter() {
        let Some(r) = m.range else { continue };
        let interval = |[lo, hi]: [f64; 2]| format!("[{lo}, {hi}]");
        ranges.row(vec![
            format!("  {}", m.name),
            m.members.join(", "),
            m.carrier
                .map_or("-".into(), |c| motion.movers[c].name.clone()),
            interval(r.x),
            interval(r.y),
            interval(r.yaw),
        ]);
    }
    print!("{}", ranges.render());
    println!(
        "  layouts keep movable objects {} m apart (min_gap), on their supports, and the teaching's targets within {} m of the shoulder at {:?} and {} m from the base's axis",
        task.min_gap, task.reach.max, task.reach.shoulder, task.reach.min_radial
    );
    println!("fixed relations (equivalent groundings):");
    for r in task.fixed_relations().map_err(CliError::input)? {
        println!("  {}: {}", r.members.join(", "), r.because);
    }
    Ok(())
}
