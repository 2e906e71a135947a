//! `akl teach`.

use super::{load_calibration, print_json, profile, spec::keyframe_table};
use crate::answers::answer_source;
use crate::cli::{TeachArgs, Teacher};
use crate::exit::{CliError, CliResult};
use crate::stop::on_ctrl_c;
use akl_learn::calibration::Calibration;
use akl_learn::okl::{LearnError, OklParams};
use akl_learn::teach::{
    self as learn_teach, session_header, Clock, Pace, SimulatedTeachingError, WallClock,
};
use akl_learn::{
    learn_spec, prepare_shapes, Answer, Demo, DemoHeader, DialogueKind, LearnOptions, LiveEnd,
    LiveStream, Method, Recording, TeachingSession,
};
use akl_scene::{builtin, Task};
use akl_tsr::TaskSpec;
use serde::Serialize;
use std::path::{Path, PathBuf};

#[derive(Serialize, Default)]
struct AnswerCounts {
    yes: usize,
    no: usize,
    unknown: usize,
}

/// What a teaching session recorded and learned, as `akl teach` prints it.
#[derive(Serialize)]
pub(crate) struct Summary {
    recording: String,
    task: String,
    frames: usize,
    duration_s: f64,
    queries: usize,
    answers: AnswerCounts,
    suggestions: usize,
    keyframe_marks: usize,
    stopped_early: bool,
    spec: Option<String>,
    keyframes: Option<usize>,
    learn_error: Option<String>,
}

pub(super) fn run(args: TeachArgs) -> CliResult {
    let (calibration, label) = load_calibration(args.calibration.as_deref())?;
    let stop = on_ctrl_c();
    let (demo, recording, stopped, task) = match args.teacher {
        Teacher::Sim => {
            let name = args.task.as_deref().ok_or_else(|| {
                CliError::input("--teacher sim needs --task (a built-in task or a task file)")
            })?;
            let task = super::load_task(name)?;
            let teaching = SimulatedTeaching {
                task: &task,
                profile: &args.profile,
                seed: args.seed,
                answers: args.answers.as_deref().unwrap_or("oracle"),
                rate: args.rate,
                realtime: args.realtime,
                output: &args.output,
            };
            let (demo, recording, stopped) =
                teach_simulated(&teaching, calibration, &label, Some(stop))?;
            (demo, recording, stopped, Some(task))
        }
        Teacher::Stdin => teach_live(&args, calibration, &label, stop)?,
    };
    let spec_path = args.output.with_extension("spec.json");
    let (summary, learned) = learn_and_save(
        &demo,
        &recording,
        stopped,
        task.as_ref(),
        &calibration,
        &spec_path,
    )?;
    if args.json {
        print_json(&summary)?;
    } else {
        print_summary(&summary);
        if let Ok(spec) = &learned {
            print!("{}", keyframe_table(spec).render());
        }
    }
    match learned {
        Ok(_) => Ok(()),
        Err(e) => Err(CliError::input(format!(
            "{}: recorded, but no spec could be learned: {e}",
            recording.display()
        ))),
    }
}

/// Learns a spec with AKL from a session's `demo` (recorded to `recording`), writes it to
/// `spec_path` when learning succeeds, and summarizes the session.
pub(crate) fn learn_and_save(
    demo: &Demo,
    recording: &Path,
    stopped: bool,
    task: Option<&Task>,
    calibration: &Calibration,
    spec_path: &Path,
) -> Result<(Summary, Result<TaskSpec, LearnError>), CliError> {
    let options = LearnOptions {
        okl: OklParams::for_calibration(calibration),
        ..LearnOptions::default()
    };
    let learned = learn_spec(Method::Akl, demo, task.map(|t| &t.world), &options);
    let mut summary = summarize(demo, recording, stopped);
    match &learned {
        Ok(spec) => {
            spec.save(spec_path)
                .map_err(|e| CliError::internal(format!("{}: {e}", spec_path.display())))?;
            summary.spec = Some(spec_path.display().to_string());
            summary.keyframes = Some(spec.keyframes.len());
        }
        Err(e) => summary.learn_error = Some(e.to_string()),
    }
    Ok((summary, learned))
}

/// How the simulated teacher demonstrates, as `akl teach --teacher sim` and `akl demo` ask.
pub(crate) struct SimulatedTeaching<'a> {
    /// The task demonstrated.
    pub task: &'a Task,
    /// Teacher profile name.
    pub profile: &'a str,
    /// Seed of the teacher.
    pub seed: u64,
    /// Who answers (see `answer_source`).
    pub answers: &'a str,
    /// Recording rate in Hz, if not the profile's.
    pub rate: Option<f64>,
    /// Play in real time.
    pub realtime: bool,
    /// The recording's file.
    pub output: &'a Path,
}

type Taught = (Demo, PathBuf, bool, Option<Task>);

/// Records the simulated teacher's demonstration through a teaching session (the online
/// detector asks, `t.answers` answers, the teacher heeds the suggestions) under the calibration
/// named `label`. Returns the demo, the recording's path, and whether `stop` (set by Ctrl-C)
/// ended it early.
pub(crate) fn teach_simulated(
    t: &SimulatedTeaching,
    calibration: Calibration,
    label: &str,
    stop: Option<&'static std::sync::atomic::AtomicBool>,
) -> Result<(Demo, PathBuf, bool), CliError> {
    let mut profile = profile(t.profile)?;
    if let Some(rate) = t.rate {
        profile.rate = rate;
    }
    profile
        .validate()
        .map_err(|e| CliError::input(format!("--profile {}: {e}", t.profile)))?;
    let mut answers = answer_source(t.answers, Some((&profile, t.seed)))?;
    let header = session_header(&DemoHeader::new(t.task.name.clone()), Some(label));
    let names: Vec<String> = t
        .task
        .world
        .objects
        .iter()
        .map(|o| o.name.clone())
        .collect();
    let mut recording = Recording::create(t.output, &header, &names).map_err(CliError::input)?;
    let partial = recording.partial_path().to_path_buf();
    let wall = WallClock::new();
    let pace = Pace {
        realtime: t.realtime.then_some(&wall as &dyn Clock),
        stop,
    };
    let taught = learn_teach::teach_simulated(
        t.task,
        &t.task.world,
        &profile,
        t.seed,
        (calibration, Some(label)),
        answers.as_mut(),
        Some(&mut recording),
        &pace,
    )
    .map_err(|e| match e {
        SimulatedTeachingError::Teacher(e) => {
            // Nothing worth keeping was recorded: the task cannot be demonstrated.
            let _ = std::fs::remove_file(&partial);
            CliError::input(format!("task `{}`: {e}", t.task.name))
        }
        other => kept_partial(&partial, other),
    })?;
    let path = recording.finish().map_err(CliError::internal)?;
    Ok((taught.demo, path, taught.stopped))
}

fn teach_live(
    args: &TeachArgs,
    calibration: Calibration,
    label: &str,
    stop: &'static std::sync::atomic::AtomicBool,
) -> Result<Taught, CliError> {
    let stdin = std::io::stdin();
    let mut stream = LiveStream::new(stdin.lock());
    let at_input = |e| CliError::input(format!("standard input: {e}"));
    let mut start = stream.start().map_err(at_input)?;
    // Mesh files of declared shapes are relative to the current folder; the recording names
    // them by their full path, so it reads wherever it is written.
    let here = std::env::current_dir()
        .map_err(|e| CliError::internal(format!("the current folder: {e}")))?;
    prepare_shapes(&mut start.header.shapes, &here, &start.objects)
        .map_err(|e| CliError::input(format!("standard input: line 1: {e}")))?;
    let task = match &args.task {
        Some(name) => Some(super::load_task(name)?),
        None => builtin::task(&start.header.task)
            .transpose()
            .map_err(CliError::internal)?,
    };
    let mut answers = answer_source(args.answers.as_deref().unwrap_or("terminal"), None)?;
    let header = session_header(&start.header, Some(label));
    let objects = start.objects.clone();
    let mut recording =
        Recording::create(&args.output, &header, &objects).map_err(CliError::input)?;
    let partial = recording.partial_path().to_path_buf();
    let mut session = TeachingSession::new(header, &objects, calibration, answers.as_mut())
        .with_sink(&mut recording);
    let end = stream
        .run(start, &mut session, stop)
        .map_err(|e| kept_partial(&partial, format!("standard input: {e}")))?;
    let demo = match end {
        LiveEnd::Finished => session.finish(),
        LiveEnd::Stopped => session.finish_early(),
    }
    .map_err(|e| kept_partial(&partial, e))?;
    let path = recording.finish().map_err(CliError::internal)?;
    Ok((demo, path, end == LiveEnd::Stopped, task))
}

/// A failed session whose recording so far stays in the `.partial` file.
fn kept_partial(partial: &Path, e: impl std::fmt::Display) -> CliError {
    CliError::input(format!(
        "{e}; the recording so far is in {}",
        partial.display()
    ))
}

fn summarize(demo: &Demo, recording: &Path, stopped: bool) -> Summary {
    let mut answers = AnswerCounts::default();
    let (mut queries, mut suggestions, mut marks) = (0, 0, 0);
    for e in &demo.events {
        match e.kind {
            DialogueKind::Query => queries += 1,
            DialogueKind::Answer(Answer::Yes) => answers.yes += 1,
            DialogueKind::Answer(Answer::No) => answers.no += 1,
            DialogueKind::Answer(Answer::Unknown) => answers.unknown += 1,
            DialogueKind::Suggestion => suggestions += 1,
            DialogueKind::Keyframe => marks += 1,
        }
    }
    Summary {
        recording: recording.display().to_string(),
        task: demo.header.task.clone(),
        frames: demo.len(),
        duration_s: demo.times.last().unwrap_or(&0.0) - demo.times.first().unwrap_or(&0.0),
        queries,
        answers,
        suggestions,
        keyframe_marks: marks,
        stopped_early: stopped,
        spec: None,
        keyframes: None,
        learn_error: None,
    }
}

/// Prints a session's summary.
fn print_summary(s: &Summary) {
    print_recorded(s);
    print_learned(s);
}

/// Prints what a session recorded: frames and dialogue.
pub(crate) fn print_recorded(s: &Summary) {
    println!(
        "recorded {}: task `{}`, {} frames, {:.1} s{}",
        s.recording,
        s.task,
        s.frames,
        s.duration_s,
        if s.stopped_early {
            " (stopped early by Ctrl-C)"
        } else {
            ""
        }
    );
    println!(
        "  dialogue: {} queries (yes {}, no {}, I don't know {}), {} suggestions, {} keyframe marks",
        s.queries, s.answers.yes, s.answers.no, s.answers.unknown, s.suggestions, s.keyframe_marks
    );
}

/// Prints what was learned from a session's recording.
pub(crate) fn print_learned(s: &Summary) {
    match (&s.spec, &s.learn_error) {
        (Some(spec), _) => println!(
            "  learned with AKL: {} keyframes, written to {spec}",
            s.keyframes.unwrap_or(0)
        ),
        (None, Some(e)) => println!("  no spec learned: {e}"),
        (None, None) => {}
    }
}
