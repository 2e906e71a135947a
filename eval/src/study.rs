//! Running the study: every participant calibrates, then teaches every task with every method
//! in its Latin-square order, and every learned spec is scored (thesis §4.2, §4.4).

use std::ops::Range;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use akl_learn::calibration::{Calibration, Motion};
use akl_learn::okl::OklParams;
use akl_learn::teach::{oracle, teach_simulated, Pace, ORACLE_MEMORY};
use akl_learn::teacher::{calibration_demos, demonstrate, SimulatedDemo, TeacherProfile};
use akl_learn::{learn_spec, score, Answer, Demo, DialogueKind, LearnOptions, Method, Tolerance};
use akl_scene::Task;
use akl_tsr::TaskSpec;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::population::{Participant, Population};

/// Runs a learned spec in simulation: the pass rate of `trials` randomized executions. The
/// study knows no robot (learning never does); the caller plugs the executor in.
pub trait Executor: Sync {
    /// How many of `trials` randomized executions of `spec` on `task` (seeds from `seed`)
    /// pass, or why none could run.
    fn passes(
        &self,
        spec: &TaskSpec,
        task: &Task,
        trials: usize,
        seed: u64,
    ) -> Result<usize, String>;
}

/// What a study runs.
pub struct StudyOptions<'a> {
    /// Number of participants.
    pub participants: usize,
    /// Seed of the draw of participants and of everything they do.
    pub seed: u64,
    /// The tasks, in the order each participant teaches them within a method.
    pub tasks: &'a [Task],
    /// Executes each learned spec this many times when an executor is given.
    pub execute: Option<(&'a dyn Executor, usize)>,
    /// Run only these participants (0-based, a contiguous block of the `participants` drawn),
    /// each exactly as in the whole study: one shard of it. `None`: all.
    pub only: Option<Range<usize>>,
    /// Raised to stop part-way (Ctrl-C): once it is, no participant starts another trial; the
    /// trials under way (their executions included) finish, and the study holds those that
    /// did ([`Study::interrupted`]). `None`: never stopped.
    pub stop: Option<&'a AtomicBool>,
}

/// Why a study could not run.
#[derive(Debug, thiserror::Error, PartialEq)]
#[non_exhaustive]
pub enum StudyError {
    /// No participants or no tasks.
    #[error("a study needs at least one participant and one task")]
    Empty,
    /// The block of participants to run is empty or beyond those drawn.
    #[error("participants {start} to {end} (from 0) are not a block of the {drawn} drawn")]
    Block {
        /// First of the block.
        start: usize,
        /// Past its last.
        end: usize,
        /// Participants drawn.
        drawn: usize,
    },
    /// A task has no ground truth to score against.
    #[error("task `{0}` has no ground truth to score against")]
    NoTruth(String),
    /// The simulated teacher cannot demonstrate a task.
    #[error("participant {participant}, task `{task}`: {message}")]
    Teaching {
        /// The participant.
        participant: usize,
        /// The task.
        task: String,
        /// What went wrong.
        message: String,
    },
}

/// One participant teaching one task with one method, and how the learned spec scored.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Trial {
    /// The participant (1-based).
    pub participant: usize,
    /// Whether the participant has handled robots before.
    pub experienced: bool,
    /// The method.
    pub method: Method,
    /// When the participant used this method: 1, 2 or 3.
    pub position: usize,
    /// The task.
    pub task: String,
    /// Seed of the demonstration.
    pub seed: u64,
    /// Frames recorded.
    pub frames: usize,
    /// Length of the demonstration (s).
    pub duration_s: f64,
    /// The participant's chance of an unintended line when the demonstration began.
    pub unintended_line_chance: f64,
    /// Free motions made in a straight line.
    pub unintended_lines: usize,
    /// Queries the learner asked (AKL).
    pub queries: usize,
    /// Answers "yes", "no" and "I don't know" (AKL).
    pub yes: usize,
    /// "no" answers.
    pub no: usize,
    /// "I don't know" answers.
    pub unknown: usize,
    /// Suggestions made (AKL).
    pub suggestions: usize,
    /// Answers that kept a wrong state: "no" to a required line, "yes" or "I don't know" to a
    /// line the task does not require (Table 4.2: constraint errors due to feedback).
    pub errors_from_answers: usize,
    /// "no" to lines the task does not require (Table 4.2: errors avoided by feedback).
    pub errors_avoided: usize,
    /// Keyframes the teacher marked (KD).
    pub marks: usize,
    /// Whether learning failed outright (no spec), with why.
    pub learn_error: Option<String>,
    /// Keyframes learned.
    pub learned_keyframes: usize,
    /// Keyframes in the ground truth.
    pub truth_keyframes: usize,
    /// Truth keyframes with no learned match (Figure 4-2b).
    pub missed_keyframes: usize,
    /// Learned keyframes with no truth match (Figure 4-2b).
    pub incorrect_keyframes: usize,
    /// Keyframe accuracy, IoU (§4.2).
    pub keyframe_accuracy: f64,
    /// Truth poses with no learned match (Figure 4-4b).
    pub missed_poses: usize,
    /// Learned poses with no truth match (Figure 4-4b).
    pub incorrect_poses: usize,
    /// Pose accuracy, IoU (§4.2).
    pub pose_accuracy: f64,
    /// Length of true lines not learned (m; Figure 4-6a).
    pub missed_line_length: f64,
    /// Length of learned lines not true (m; Figure 4-6a).
    pub incorrect_line_length: f64,
    /// Constraint accuracy, IoU of line lengths (§4.2); none when neither spec has a line.
    pub constraint_accuracy: Option<f64>,
    /// True lines not learned (Figure 4-6b).
    pub missed_constraints: usize,
    /// Learned lines not true (Figure 4-6b).
    pub incorrect_constraints: usize,
    /// Whether the learned spec equals the ground truth (§4.2).
    pub success: bool,
    /// Learning time (s), from the recording to the spec (Figure 4-9).
    pub runtime_s: f64,
    /// Randomized executions of the learned spec, with `--execute`.
    pub executions: Option<usize>,
    /// How many of them passed.
    pub passed_executions: Option<usize>,
    /// Their share.
    pub pass_rate: Option<f64>,
    /// Why the spec could not be executed, if so.
    pub execute_error: Option<String>,
    /// The learned spec.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spec: Option<TaskSpec>,
}

/// One participant's calibration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Calibrated {
    /// The participant.
    pub participant: usize,
    /// Fitted from the participant's line and circle, or the shipped one when the fit failed.
    pub calibration: Calibration,
    /// Why the fit failed, if it did.
    pub fit_error: Option<String>,
}

/// A whole study: who took part and every trial, in participant, method-order, task order.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Study {
    /// Seed of the study.
    pub seed: u64,
    /// Participants drawn for the whole study (those of every shard).
    #[serde(default)]
    pub drawn: usize,
    /// The participants this study ran (0-based, a contiguous block), when it is one shard of
    /// a study ([`StudyOptions::only`]); absent when it ran all of them.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub block: Option<Range<usize>>,
    /// Randomized executions of each learned spec (`--execute`), if any.
    #[serde(default)]
    pub executions_per_spec: Option<usize>,
    /// Whether it was stopped (Ctrl-C) before every trial had run: `trials` then holds, for
    /// each participant, the trials it finished, in its order.
    pub interrupted: bool,
    /// The population the participants were drawn from.
    pub population: Population,
    /// The participants.
    pub participants: Vec<Participant>,
    /// Their calibrations.
    pub calibrations: Vec<Calibrated>,
    /// Every trial.
    pub trials: Vec<Trial>,
}

/// Runs the study: the participants of [`Population::study`] drawn with `options.seed`, in
/// parallel (each participant's trials in order, since what a participant learns from the
/// learner's suggestions carries into its later demonstrations); `progress` is called after
/// every trial. The same seed gives the same study (runtimes aside) whatever the threads.
/// Once `options.stop` is raised no trial starts (see [`StudyOptions::stop`]).
pub fn run_study(
    options: &StudyOptions,
    progress: &(dyn Fn(&Trial) + Sync),
) -> Result<Study, StudyError> {
    if options.participants == 0 || options.tasks.is_empty() {
        return Err(StudyError::Empty);
    }
    if let Some(t) = options.tasks.iter().find(|t| t.truth.is_none()) {
        return Err(StudyError::NoTruth(t.name.clone()));
    }
    let population = Population::study();
    let mut participants = population.draw(options.participants, options.seed);
    if let Some(block) = &options.only {
        if block.is_empty() || block.end > participants.len() {
            return Err(StudyError::Block {
                start: block.start,
                end: block.end,
                drawn: participants.len(),
            });
        }
        participants = participants[block.clone()].to_vec();
    }
    let results: Vec<(Calibrated, Vec<Trial>)> = participants
        .par_iter()
        .map(|p| run_participant(p, options, progress))
        .collect::<Result<_, _>>()?;
    let (calibrations, trials) = results.into_iter().unzip::<_, _, Vec<_>, Vec<Vec<_>>>();
    let planned: usize = participants
        .iter()
        .map(|p| p.order.len() * options.tasks.len())
        .sum();
    let trials: Vec<Trial> = trials.into_iter().flatten().collect();
    Ok(Study {
        seed: options.seed,
        drawn: options.participants,
        block: options.only.clone(),
        executions_per_spec: options.execute.map(|(_, n)| n),
        interrupted: trials.len() < planned,
        population,
        participants,
        calibrations,
        trials,
    })
}

/// The participant's calibration from its own line and circle (thesis §4.4).
fn calibrate(p: &Participant) -> Calibrated {
    let fitted = calibration_demos(&p.profile, p.seed)
        .map_err(|e| e.to_string())
        .and_then(|(line, circle)| {
            Calibration::fit(&Motion::of(&line), &Motion::of(&circle)).map_err(|e| e.to_string())
        });
    match fitted {
        Ok(calibration) => Calibrated {
            participant: p.id,
            calibration,
            fit_error: None,
        },
        Err(e) => Calibrated {
            participant: p.id,
            calibration: Calibration::default(),
            fit_error: Some(e),
        },
    }
}

fn run_participant(
    p: &Participant,
    options: &StudyOptions,
    progress: &(dyn Fn(&Trial) + Sync),
) -> Result<(Calibrated, Vec<Trial>), StudyError> {
    let calibrated = calibrate(p);
    let learn_options = LearnOptions {
        okl: OklParams::for_calibration(&calibrated.calibration),
        ..LearnOptions::default()
    };
    let mut teacher = p.profile;
    let mut trials = Vec::with_capacity(3 * options.tasks.len());
    let stopped = || options.stop.is_some_and(|s| s.load(Ordering::SeqCst));
    for (position, method) in p.order.iter().enumerate() {
        for (k, task) in options.tasks.iter().enumerate() {
            if stopped() {
                return Ok((calibrated, trials));
            }
            let seed = trial_seed(p.seed, *method, k);
            let setting = Setting {
                participant: p,
                method: *method,
                position: position + 1,
                task,
                seed,
                calibration: calibrated.calibration,
                options: &learn_options,
            };
            let (trial, after) = run_trial(&setting, &teacher, options.execute)?;
            teacher.unintended_line_chance = after;
            progress(&trial);
            trials.push(trial);
        }
    }
    Ok((calibrated, trials))
}

/// The seed of a participant's demonstration of task `k` with `method`.
fn trial_seed(participant: u64, method: Method, k: usize) -> u64 {
    let m = Method::ALL.iter().position(|x| *x == method).unwrap_or(0) as u64;
    participant
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(m * 1000 + k as u64)
}

/// Everything fixed about one trial.
struct Setting<'a> {
    participant: &'a Participant,
    method: Method,
    position: usize,
    task: &'a Task,
    seed: u64,
    calibration: Calibration,
    options: &'a LearnOptions,
}

/// What a demonstration gave the learner, by method.
struct Taught {
    sim: SimulatedDemo,
    demo: Demo,
    suggestions: usize,
    unintended_line_chance: f64,
}

/// Demonstrates with `teacher` as the method asks: AKL through a live session whose oracle
/// answers as the teacher would, KD with the teacher's marks, mACL as a plain recording.
fn demonstrate_for(s: &Setting, teacher: &TeacherProfile) -> Result<Taught, String> {
    let world = &s.task.world;
    if s.method == Method::Akl {
        let mut answers = oracle(teacher, s.seed);
        let taught = teach_simulated(
            s.task,
            world,
            teacher,
            s.seed,
            (s.calibration, None),
            &mut answers,
            None,
            &Pace::default(),
        )
        .map_err(|e| e.to_string())?;
        return Ok(Taught {
            sim: taught.sim,
            demo: taught.demo,
            suggestions: taught.suggestions,
            unintended_line_chance: taught.unintended_line_chance,
        });
    }
    let sim = demonstrate(s.task, world, teacher, s.seed)?;
    let demo = if s.method == Method::Kd {
        sim.with_marks()
    } else {
        sim.demo.clone()
    };
    Ok(Taught {
        sim,
        demo,
        suggestions: 0,
        unintended_line_chance: teacher.unintended_line_chance,
    })
}

/// One trial; also returns the teacher's chance of an unintended line afterwards.
fn run_trial(
    s: &Setting,
    teacher: &TeacherProfile,
    execute: Option<(&dyn Executor, usize)>,
) -> Result<(Trial, f64), StudyError> {
    let taught = demonstrate_for(s, teacher).map_err(|message| StudyError::Teaching {
        participant: s.participant.id,
        task: s.task.name.clone(),
        message,
    })?;
    let demo = &taught.demo;
    let started = Instant::now();
    let learned = learn_spec(s.method, demo, Some(&s.task.world), s.options);
    let runtime_s = started.elapsed().as_secs_f64();
    let truth = s
        .task
        .truth
        .as_ref()
        .ok_or(StudyError::NoTruth(s.task.name.clone()))?;
    let dialogue = Dialogue::of(&taught.sim, demo, teacher);
    let mut trial = Trial {
        participant: s.participant.id,
        experienced: s.participant.experienced,
        method: s.method,
        position: s.position,
        task: s.task.name.clone(),
        seed: s.seed,
        frames: demo.len(),
        duration_s: demo.times.last().copied().unwrap_or(0.0),
        unintended_line_chance: teacher.unintended_line_chance,
        unintended_lines: akl_learn::okl::runs(&taught.sim.unintended_line).len(),
        queries: dialogue.queries,
        yes: dialogue.yes,
        no: dialogue.no,
        unknown: dialogue.unknown,
        suggestions: taught.suggestions,
        errors_from_answers: dialogue.errors_from_answers,
        errors_avoided: dialogue.errors_avoided,
        marks: taught.sim.marked_keyframes.len(),
        learn_error: learned.as_ref().err().map(|e| e.to_string()),
        learned_keyframes: 0,
        truth_keyframes: truth.keyframes.len(),
        missed_keyframes: truth.keyframes.len(),
        incorrect_keyframes: 0,
        keyframe_accuracy: 0.0,
        missed_poses: truth.keyframes.len(),
        incorrect_poses: 0,
        pose_accuracy: 0.0,
        missed_line_length: 0.0,
        incorrect_line_length: 0.0,
        constraint_accuracy: None,
        missed_constraints: 0,
        incorrect_constraints: 0,
        success: false,
        runtime_s,
        executions: None,
        passed_executions: None,
        pass_rate: None,
        execute_error: None,
        spec: None,
    };
    if let Ok(spec) = learned {
        let scores = score(&spec, truth, &Tolerance::default());
        trial.learned_keyframes = scores.learned;
        trial.missed_keyframes = scores.truth - scores.matched_keyframes;
        trial.incorrect_keyframes = scores.learned - scores.matched_keyframes;
        trial.keyframe_accuracy = scores.keyframe_accuracy;
        trial.missed_poses = scores.truth - scores.matched_poses;
        trial.incorrect_poses = scores.learned - scores.matched_poses;
        trial.pose_accuracy = scores.pose_accuracy;
        trial.missed_line_length = scores.true_line_length - scores.common_line_length;
        trial.incorrect_line_length = scores.learned_line_length - scores.common_line_length;
        trial.constraint_accuracy = scores.constraint_accuracy;
        trial.missed_constraints = scores.missed_lines;
        trial.incorrect_constraints = scores.incorrect_lines;
        trial.success = scores.success;
        if let Some((executor, runs)) = execute {
            match executor.passes(&spec, s.task, runs, s.seed) {
                Ok(passed) => {
                    trial.executions = Some(runs);
                    trial.passed_executions = Some(passed);
                    trial.pass_rate = Some(passed as f64 / runs as f64);
                }
                Err(e) => trial.execute_error = Some(e),
            }
        }
        trial.spec = Some(spec);
    }
    Ok((trial, taught.unintended_line_chance))
}

/// The dialogue of an AKL demonstration, and what the answers did (Table 4.2).
#[derive(Debug, Default)]
struct Dialogue {
    queries: usize,
    yes: usize,
    no: usize,
    unknown: usize,
    errors_from_answers: usize,
    errors_avoided: usize,
}

impl Dialogue {
    /// Each answer is judged against what the teacher was doing when asked: a required line
    /// under way or just ended (within the oracle's memory), or not.
    fn of(sim: &SimulatedDemo, demo: &Demo, teacher: &TeacherProfile) -> Dialogue {
        let window = (ORACLE_MEMORY * teacher.rate).round() as usize;
        let mut d = Dialogue::default();
        for e in &demo.events {
            let answer = match e.kind {
                DialogueKind::Query => {
                    d.queries += 1;
                    continue;
                }
                DialogueKind::Answer(a) => a,
                _ => continue,
            };
            let required = sim.line_required_near(e.frame, window);
            match answer {
                Answer::Yes => d.yes += 1,
                Answer::No => d.no += 1,
                Answer::Unknown => d.unknown += 1,
            }
            match (required, answer) {
                (false, Answer::No) => d.errors_avoided += 1,
                (true, Answer::No) | (false, Answer::Yes | Answer::Unknown) => {
                    d.errors_from_answers += 1
                }
                (true, _) => {}
            }
        }
        d
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_scene::builtin;

    fn tasks() -> Vec<Task> {
        builtin::study_names()
            .into_iter()
            .map(|n| builtin::resolve(n).unwrap())
            .collect()
    }

    #[test]
    fn every_participant_teaches_every_task_with_every_method_in_order() {
        let tasks = tasks();
        let options = StudyOptions {
            participants: 3,
            seed: 5,
            tasks: &tasks,
            execute: None,
            only: None,
            stop: None,
        };
        let count = std::sync::atomic::AtomicUsize::new(0);
        let study = run_study(&options, &|_| {
            count.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        })
        .unwrap();
        assert_eq!(study.trials.len(), 27);
        assert!(!study.interrupted);
        assert_eq!(count.into_inner(), 27);
        for p in &study.participants {
            let mine: Vec<_> = study
                .trials
                .iter()
                .filter(|t| t.participant == p.id)
                .collect();
            let methods: Vec<Method> = mine.iter().map(|t| t.method).collect();
            let expected: Vec<Method> = p.order.iter().flat_map(|m| [*m; 3]).collect();
            assert_eq!(methods, expected);
        }
        for t in &study.trials {
            assert_eq!(t.spec.is_some(), t.learn_error.is_none());
            if t.method != Method::Akl {
                assert_eq!((t.queries, t.suggestions), (0, 0));
            }
            if t.method == Method::Kd {
                assert_eq!(t.incorrect_constraints, 0);
            }
            assert_eq!(t.truth_keyframes, 4);
        }
        let mut again = run_study(&options, &|_| {}).unwrap();
        let mut first = study;
        for t in first.trials.iter_mut().chain(again.trials.iter_mut()) {
            t.runtime_s = 0.0;
        }
        assert_eq!(first, again);
    }

    #[test]
    fn a_stopped_study_keeps_the_trials_that_finished() {
        let tasks = tasks();
        let stop = AtomicBool::new(false);
        let options = StudyOptions {
            participants: 1,
            seed: 5,
            tasks: &tasks,
            execute: None,
            only: None,
            stop: Some(&stop),
        };
        let count = std::sync::atomic::AtomicUsize::new(0);
        let mut stopped = run_study(&options, &|_| {
            if count.fetch_add(1, Ordering::SeqCst) + 1 == 4 {
                stop.store(true, Ordering::SeqCst);
            }
        })
        .unwrap();
        assert!(stopped.interrupted);
        assert_eq!(stopped.trials.len(), 4);
        let mut whole = run_study(
            &StudyOptions {
                stop: None,
                ..options
            },
            &|_| {},
        )
        .unwrap();
        for t in stopped.trials.iter_mut().chain(whole.trials.iter_mut()) {
            t.runtime_s = 0.0;
        }
        assert_eq!(stopped.trials[..], whole.trials[..4]);
    }

    #[test]
    fn a_study_needs_people_tasks_and_truths() {
        let none = StudyOptions {
            participants: 0,
            seed: 0,
            tasks: &[],
            execute: None,
            only: None,
            stop: None,
        };
        assert_eq!(run_study(&none, &|_| {}), Err(StudyError::Empty));
        let mut tasks = tasks();
        tasks[1].truth = None;
        let untrue = StudyOptions {
            participants: 1,
            seed: 0,
            tasks: &tasks,
            execute: None,
            only: None,
            stop: None,
        };
        assert_eq!(
            run_study(&untrue, &|_| {}),
            Err(StudyError::NoTruth("inspection".into()))
        );
    }
}
