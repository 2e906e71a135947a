//! `akl plan SPEC --task T`.

use super::print_json;
use super::robot::load as load_robot;
use crate::cli::PlanArgs;
use crate::exit::{CliError, CliResult};
use crate::table::{vec3, Table};
use akl_planner::{plan_best, GripperAction, PlanBudget, PlanOptions};
use serde::Serialize;

#[derive(Serialize)]
struct SegmentSummary {
    kind: &'static str,
    keyframe: usize,
    start: f64,
    duration: f64,
    planning_time: f64,
    waypoints: usize,
    holding: Option<String>,
}

#[derive(Serialize)]
struct EventSummary {
    t: f64,
    action: &'static str,
    keyframe: usize,
    object: String,
    support: Option<String>,
    width: f64,
}

#[derive(Serialize)]
struct PlanSummary {
    spec: String,
    task: String,
    robot: String,
    seed: u64,
    budget_ms: u64,
    speed_scale: f64,
    candidates: usize,
    candidates_planned: usize,
    chosen_candidate: usize,
    nominal_duration: Option<f64>,
    duration: f64,
    planning_time: f64,
    segments: Vec<SegmentSummary>,
    events: Vec<EventSummary>,
    output: Option<String>,
}

pub(super) fn run(args: PlanArgs) -> CliResult {
    if let Some(out) = &args.output {
        super::check_output(out, "plan")?;
    }
    let robot = load_robot(&args.robot)?;
    let task = super::load_task(&args.task)?;
    let spec = super::load_spec_for(&args.spec, &task, args.fit)?;
    let options = PlanOptions {
        seed: args.seed,
        budget: PlanBudget::from_millis(args.budget, spec.keyframes.len()),
        speed_scale: args.speed.speed_scale,
        ..PlanOptions::default()
    };
    let started = std::time::Instant::now();
    let best = plan_best(&robot, &spec, &task.world, &options).map_err(|e| {
        CliError::internal(format!(
            "cannot plan {} in task `{}`: {e}",
            args.spec.display(),
            task.name
        ))
    })?;
    let planning_time = started.elapsed().as_secs_f64();
    let plan = &best.plan;
    if let Some(out) = &args.output {
        plan.save(out).map_err(|e| {
            CliError::internal(format!("{}: cannot write the plan: {e}", out.display()))
        })?;
    }
    let summary = PlanSummary {
        spec: args.spec.display().to_string(),
        task: task.name.clone(),
        robot: robot.name().to_string(),
        seed: args.seed,
        budget_ms: args.budget,
        speed_scale: args.speed.speed_scale,
        candidates: best.candidates.len(),
        candidates_planned: best.candidates.iter().filter(|c| c.result.is_ok()).count(),
        chosen_candidate: best.chosen,
        nominal_duration: best.nominal_duration(),
        duration: plan.duration,
        planning_time,
        segments: plan
            .segments
            .iter()
            .map(|s| SegmentSummary {
                kind: s.kind.name(),
                keyframe: s.keyframe,
                start: s.start,
                duration: s.end - s.start,
                planning_time: s.planning_time,
                waypoints: s.waypoints.len(),
                holding: s.holding.clone(),
            })
            .collect(),
        events: plan
            .events
            .iter()
            .map(|e| EventSummary {
                t: e.t,
                action: match e.action {
                    GripperAction::Close => "close",
                    GripperAction::Open => "open",
                },
                keyframe: e.keyframe,
                object: e.object.clone(),
                support: e.support.clone(),
                width: e.width,
            })
            .collect(),
        output: args.output.as_ref().map(|p| p.display().to_string()),
    };
    if args.json {
        return print_json(&summary);
    }
    println!(
        "{}: planned for task `{}` with {} (seed {}): {} segments, {:.2} s of motion, {:.1} ms of planning",
        summary.spec,
        summary.task,
        summary.robot,
        summary.seed,
        summary.segments.len(),
        summary.duration,
        summary.planning_time * 1e3
    );
    let nominal = summary
        .nominal_duration
        .map_or("failed".to_string(), |d| format!("{d:.2} s"));
    println!(
        "budget {} ms: {} candidates ({} planned), kept candidate {}; the nominal-first candidate: {nominal}; speed scale {}",
        summary.budget_ms,
        summary.candidates,
        summary.candidates_planned,
        summary.chosen_candidate,
        summary.speed_scale
    );
    let mut table = Table::new([
        "#",
        "kind",
        "keyframe",
        "start (s)",
        "duration (s)",
        "planning (ms)",
        "waypoints",
        "holding",
    ]);
    for (i, s) in summary.segments.iter().enumerate() {
        table.row(vec![
            i.to_string(),
            s.kind.to_string(),
            s.keyframe.to_string(),
            format!("{:.2}", s.start),
            format!("{:.2}", s.duration),
            format!("{:.2}", s.planning_time * 1e3),
            s.waypoints.to_string(),
            s.holding.clone().unwrap_or_else(|| "-".into()),
        ]);
    }
    print!("{}", table.render());
    println!("gripper events:");
    for (e, planned) in summary.events.iter().zip(&plan.events) {
        let place = match planned.action {
            GripperAction::Close => {
                format!("lifted from {}", e.support.as_deref().unwrap_or("nothing"))
            }
            GripperAction::Open => format!(
                "placed on {} at {}",
                e.support.as_deref().unwrap_or("nothing"),
                vec3(&planned.object_pose.translation.vector)
            ),
        };
        println!(
            "  {:6.2} s  keyframe {}: {} on {} ({place}), fingers {:.3} m",
            e.t, e.keyframe, e.action, e.object, e.width
        );
    }
    if let Some(out) = &summary.output {
        println!("wrote {out}");
    }
    Ok(())
}
