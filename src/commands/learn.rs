//! `akl learn`.

use super::{load_calibration, print_json, spec::keyframe_table};
use crate::answers::answer_source;
use crate::cli::LearnArgs;
use crate::exit::{CliError, CliResult};
use akl_learn::dialogue::AnswerSource;
use akl_learn::okl::OklParams;
use akl_learn::{
    import_ros2, learn_spec, needs_replay, prepare, read_demo_file, read_shapes_file,
    recorded_answers, without_dialogue, Demo, LearnOptions, Method, PoseSource, Ros2Topics,
};
use akl_scene::builtin;
use akl_tsr::{Bounds, TaskSpec};
use serde::Serialize;
use std::time::Instant;

#[derive(Serialize)]
struct Learned<'a> {
    demo: String,
    method: Method,
    frames: usize,
    replayed_detector: bool,
    /// Whose answers the replay took: `the answers given` or `the recording's answers`.
    replayed_with: Option<&'static str>,
    runtime_s: f64,
    output: Option<String>,
    spec: &'a TaskSpec,
}

pub(super) fn run(args: LearnArgs) -> CliResult {
    let method: Method = args.method.parse().map_err(CliError::input)?;
    let bounds = parse_bounds(&args.bounds)?;
    if let Some(out) = &args.output {
        super::check_output(out, "spec")?;
    }
    let mut demo = read_demo(&args)?;
    let task = match &args.task {
        Some(name) => Some(super::load_task(name)?),
        None => builtin::task(&demo.header.task)
            .transpose()
            .map_err(CliError::internal)?,
    };
    let (calibration, _) = load_calibration(args.calibration.as_deref())?;
    // Given answers replace the recording's: the detector is replayed with them. Without, a
    // recording that kept its answers but not the detector's states is replayed with its own.
    let replayed = match (&args.answers, method) {
        (Some(spec), Method::Akl) => {
            demo = without_dialogue(demo);
            Some((answer_source(spec, None)?, "the answers given"))
        }
        _ if needs_replay(method, &demo) => {
            let recorded = recorded_answers(&demo).ok_or_else(|| {
                CliError::input(format!(
                    "{}: recorded without the online detector or any answer; pass --answers (all-yes, terminal or a list such as yes,no) to replay it",
                    args.demo.display()
                ))
            })?;
            Some((
                Box::new(recorded) as Box<dyn AnswerSource>,
                "the recording's answers",
            ))
        }
        _ => None,
    };
    let replayed = match replayed {
        Some((mut answers, with)) => {
            demo = prepare(method, demo, calibration, answers.as_mut())
                .map_err(|e| CliError::input(format!("{}: {e}", args.demo.display())))?;
            Some(with)
        }
        None => None,
    };
    let mut options = LearnOptions {
        okl: OklParams::for_calibration(&calibration),
        ..LearnOptions::default()
    };
    options.okl.bounds = bounds;
    options.kd.bounds = bounds;
    options.macl.bounds = bounds;
    let started = Instant::now();
    let spec = learn_spec(method, &demo, task.as_ref().map(|t| &t.world), &options)
        .map_err(|e| CliError::input(format!("{}: {e}", args.demo.display())))?;
    let runtime = started.elapsed().as_secs_f64();
    if let Some(out) = &args.output {
        spec.save(out)
            .map_err(|e| CliError::internal(format!("{}: {e}", out.display())))?;
    }
    let learned = Learned {
        demo: args.demo.display().to_string(),
        method,
        frames: demo.len(),
        replayed_detector: replayed.is_some(),
        replayed_with: replayed,
        runtime_s: runtime,
        output: args.output.as_ref().map(|p| p.display().to_string()),
        spec: &spec,
    };
    if args.json {
        return print_json(&learned);
    }
    println!(
        "{}: {} frames, learned with {} in {:.2} ms{}",
        learned.demo,
        learned.frames,
        method,
        runtime * 1e3,
        replayed
            .map(|with| format!(" (after replaying the online detector with {with})"))
            .unwrap_or_default()
    );
    print!("{}", keyframe_table(&spec).render());
    if let Some(out) = &learned.output {
        println!("wrote {out}");
    }
    Ok(())
}

/// The demonstration: a recording, or a ROS 2 bag read through the named topics (with the
/// shapes of `--ros-shapes`).
fn read_demo(args: &LearnArgs) -> Result<Demo, CliError> {
    let Some(ee) = &args.ros_ee else {
        let loaded = read_demo_file(&args.demo).map_err(CliError::input)?;
        if let Some(t) = &loaded.truncation {
            eprintln!("warning: {}: {t}", args.demo.display());
        }
        return Ok(loaded.demo);
    };
    let mut objects = Vec::with_capacity(args.ros_objects.len());
    for spec in &args.ros_objects {
        let (name, source) = spec.split_once('=').ok_or_else(|| {
            CliError::input(format!(
                "--ros-object `{spec}`: expected NAME=TOPIC or NAME=tf:FRAME"
            ))
        })?;
        objects.push((name.to_string(), PoseSource::parse(source)));
    }
    let topics = Ros2Topics {
        task: args.task.clone().unwrap_or_else(|| "unnamed".into()),
        frame: args.ros_frame.clone(),
        ee: PoseSource::parse(ee),
        objects,
        gripper: args.ros_gripper.clone(),
        closed_below: args.ros_closed_below,
    };
    let bytes = std::fs::read(&args.demo)
        .map_err(|e| CliError::input(format!("{}: {e}", args.demo.display())))?;
    let mut demo = import_ros2(&bytes, &topics)
        .map_err(|e| CliError::input(format!("{}: {e}", args.demo.display())))?;
    if let Some(file) = &args.ros_shapes {
        let tracked: Vec<String> = demo.objects.iter().map(|o| o.name.clone()).collect();
        demo.header.shapes = read_shapes_file(file, &tracked).map_err(CliError::input)?;
    }
    Ok(demo)
}

/// `METRES,RADIANS` as symmetric TSR bounds.
fn parse_bounds(text: &str) -> Result<Bounds, CliError> {
    let bad = || {
        CliError::input(format!(
            "--bounds `{text}`: expected two non-negative numbers METRES,RADIANS such as 0.005,0.05"
        ))
    };
    let values: Vec<f64> = text
        .split(',')
        .map(|v| v.trim().parse::<f64>().map_err(|_| bad()))
        .collect::<Result<_, _>>()?;
    match values[..] {
        [p, r] if p.is_finite() && r.is_finite() && p >= 0.0 && r >= 0.0 => {
            Ok(Bounds::symmetric(p, r))
        }
        _ => Err(bad()),
    }
}
