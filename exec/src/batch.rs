//! Batches of trials: one spec executed in N worlds, in parallel, reproducibly.
//!
//! Trial i places the objects with seed `seed + i` (or leaves them where the task file has
//! them) and plans with the same seed. Each trial builds its own rapier world and runs
//! single-threaded, so a batch gives the same reports whatever the number of threads.
//!
//! Once the options' [`crate::interrupt::Interrupt`] is raised no trial starts; those under
//! way finish, and the report covers the trials that finished, in trial order.

use crate::error::ExecError;
use crate::options::{ExecOptions, Setup};
use crate::report::{BatchReport, Settings, TrialReport};
use crate::timeline::Timeline;
use crate::trace::{write_trace, TraceInput, TRACE_RATE};
use crate::trial::{run_trial, trial_world};
use akl_planner::Robot;
use akl_scene::{Task, World};
use akl_tsr::TaskSpec;
use rayon::prelude::*;
use sha2::{Digest, Sha256};
use std::path::Path;
use std::time::Instant;

/// Which trials a batch runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BatchOptions {
    /// Number of trials (at least 1).
    pub trials: usize,
    /// Whether objects are moved within the task's ranges (else every trial uses the task's
    /// own placements).
    pub randomize: bool,
    /// Seed of the first trial.
    pub seed: u64,
    /// Worker threads (at least 1).
    pub jobs: usize,
}

/// A spec ready to be executed on a task: references checked, worlds placed.
pub struct Batch<'a> {
    setup: Setup<'a>,
    options: BatchOptions,
    worlds: Vec<World>,
}

impl<'a> Batch<'a> {
    /// Checks the spec against the task and places the objects of every trial.
    pub fn new(
        robot: &'a Robot,
        task: &'a Task,
        spec: &'a TaskSpec,
        exec: &'a ExecOptions,
        options: BatchOptions,
    ) -> Result<Batch<'a>, ExecError> {
        if options.trials == 0 {
            return Err(ExecError::Options(
                "a batch needs at least one trial".into(),
            ));
        }
        if options.jobs == 0 {
            return Err(ExecError::Options("a batch needs at least one job".into()));
        }
        spec.validate()?;
        spec.check_references(task.world.names())?;
        exec.plan
            .check()
            .map_err(|e| ExecError::Options(e.to_string()))?;
        let worlds = (0..options.trials)
            .map(|i| {
                trial_world(
                    task,
                    options.randomize,
                    trial_seed(options.seed, i),
                    &exec.physics,
                )
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Batch {
            setup: Setup {
                robot,
                task,
                spec,
                options: exec,
            },
            options,
            worlds,
        })
    }

    /// Runs every trial on [`BatchOptions::jobs`] threads, calling `progress` after each
    /// (from the worker that ran it). Once [`ExecOptions::interrupt`] is raised no more trials
    /// start: the report then holds the trials that finished (in trial order, each the same as
    /// in an uninterrupted run) and is [`BatchReport::interrupted`] if any trial did not run.
    pub fn run(&self, progress: &(dyn Fn(&TrialReport) + Sync)) -> Result<BatchReport, ExecError> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(self.options.jobs)
            .build()
            .map_err(|e| {
                ExecError::Options(format!("cannot start {} jobs: {e}", self.options.jobs))
            })?;
        let started = Instant::now();
        let interrupt = self.setup.options.interrupt;
        let reports: Vec<TrialReport> = pool.install(|| {
            (0..self.options.trials)
                .into_par_iter()
                .filter_map(|i| {
                    if interrupt.raised() {
                        return None;
                    }
                    let r = self.trial(i, None);
                    progress(&r);
                    Some(r)
                })
                .collect()
        });
        let interrupted = reports.len() < self.options.trials;
        let mut report = BatchReport::new(
            &self.setup.task.name,
            &self.setup.spec.method,
            self.options.seed,
            self.options.randomize,
            reports,
            self.options.jobs,
            started.elapsed().as_secs_f64(),
            settings(self.setup.robot, self.setup.options, self.setup.spec),
        );
        report.interrupted = interrupted;
        Ok(report)
    }

    /// Runs trial `i` alone (it gives the same report as in the batch), recording its frames
    /// at `rate` per simulated second for a trace.
    pub fn record(&self, i: usize, rate: f64) -> (TrialReport, Timeline) {
        let mut timeline = Timeline::new(rate);
        let report = self.trial(i, Some(&mut timeline));
        (report, timeline)
    }

    /// Runs again trial `trial` of this batch, or the trial of `report` (this batch's report)
    /// that a trace should show by default (see [`trial_to_trace`]), recording it at
    /// [`TRACE_RATE`], and writes it as an MCAP trace to `path`. Returns that trial's index.
    pub fn write_trace(
        &self,
        report: &BatchReport,
        trial: Option<usize>,
        path: &Path,
    ) -> Result<usize, ExecError> {
        let i = trial
            .unwrap_or_else(|| trial_to_trace(report))
            .min(self.worlds.len() - 1);
        let (trial, timeline) = self.record(i, TRACE_RATE);
        let input = TraceInput {
            robot: self.setup.robot,
            world: &self.worlds[i],
            spec: self.setup.spec,
            report: &trial,
            timeline: &timeline,
        };
        write_trace(path, &input)?;
        Ok(i)
    }

    fn trial(&self, i: usize, timeline: Option<&mut Timeline>) -> TrialReport {
        let seed = trial_seed(self.options.seed, i);
        run_trial(&self.setup, i, seed, &self.worlds[i], timeline)
    }

    /// The world trial `i` runs in.
    pub fn world(&self, i: usize) -> Option<&World> {
        self.worlds.get(i)
    }

    /// The robot, task, spec and settings.
    pub fn setup(&self) -> &Setup<'a> {
        &self.setup
    }
}

/// The settings of a batch executing `spec` with `options`, for its report.
pub fn settings(robot: &Robot, options: &ExecOptions, spec: &TaskSpec) -> Settings {
    let slack = crate::checks::keyframe::KeyframeSlack::of(options);
    Settings {
        version: env!("CARGO_PKG_VERSION").to_string(),
        spec_hash: spec_hash(spec),
        pose_noise_position: options.noise.position,
        pose_noise_yaw: options.noise.yaw,
        servo_frequency: options.drives.frequency,
        servo_damping_ratio: options.drives.damping_ratio,
        torque_limits: options.drives.torque_limits_of(robot),
        grasp_force: options.drives.grasp_force,
        step: options.physics.dt,
        solver_iterations: options.physics.solver_iterations,
        line_tolerance: options.line_tolerance,
        keyframe_position_slack: slack.position,
        keyframe_angle_slack: slack.angle,
        slip_limit: options.slip_limit,
        drop_limit: options.drop_limit,
        grasp_centre_offset: options.grasp.max_centre_offset,
        grasp_overlap: options.grasp.min_overlap,
        contacts: options.contacts,
        settle: options.settle,
        settle_max: options.settle_max,
        speed_scale: options.plan.speed_scale,
    }
}

/// SHA-256 (hex) of the spec's canonical JSON: the same spec gives the same hash whatever its
/// file's layout.
pub fn spec_hash(spec: &TaskSpec) -> String {
    let text = spec.to_json();
    Sha256::digest(text.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// The seed of trial `i` of a batch seeded `seed`.
pub fn trial_seed(seed: u64, i: usize) -> u64 {
    seed.wrapping_add(i as u64)
}

/// The trial a trace should show: the first that failed, else the first.
pub fn trial_to_trace(report: &BatchReport) -> usize {
    report
        .reports
        .iter()
        .find(|r| !r.passed)
        .map_or(0, |r| r.trial)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::atomic::{AtomicUsize, Ordering};

    fn strip(mut r: TrialReport) -> TrialReport {
        r.plan_seconds = 0.0;
        r.sim_seconds = 0.0;
        r
    }

    #[test]
    fn trials_are_reproducible_whatever_the_threads() {
        let robot = Robot::panda().unwrap();
        let task = akl_scene::builtin::task("inspection").unwrap().unwrap();
        let spec = task.truth.clone().unwrap();
        let exec = ExecOptions::default();
        let options = |jobs| BatchOptions {
            trials: 3,
            randomize: true,
            seed: 11,
            jobs,
        };
        let one = Batch::new(&robot, &task, &spec, &exec, options(1)).unwrap();
        let two = Batch::new(&robot, &task, &spec, &exec, options(2)).unwrap();
        let seen = AtomicUsize::new(0);
        let a = one.run(&|_| {
            seen.fetch_add(1, Ordering::Relaxed);
        });
        let a = a.unwrap();
        let b = two.run(&|_| {}).unwrap();
        assert_eq!(seen.load(Ordering::Relaxed), 3);
        assert_eq!(a.passed, 3, "{:?}", a.reports[0].failures);
        for (x, y) in a.reports.into_iter().zip(b.reports) {
            assert_eq!(strip(x.clone()), strip(y));
            let (again, timeline) = one.record(x.trial, 30.0);
            assert_eq!(strip(again), strip(x));
            assert!(timeline.frames.len() > 30 && timeline.plan.is_some());
        }
    }

    #[test]
    fn an_interrupted_batch_reports_the_trials_that_finished() {
        use crate::interrupt::Interrupt;
        use std::sync::atomic::AtomicBool;
        static STOP: AtomicBool = AtomicBool::new(false);
        let robot = Robot::panda().unwrap();
        let task = akl_scene::builtin::task("inspection").unwrap().unwrap();
        let spec = task.truth.clone().unwrap();
        let exec = ExecOptions {
            interrupt: Interrupt::on(&STOP),
            ..ExecOptions::default()
        };
        let options = BatchOptions {
            trials: 5,
            randomize: true,
            seed: 11,
            jobs: 1,
        };
        let batch = Batch::new(&robot, &task, &spec, &exec, options).unwrap();
        // Raised while trial 1 finishes: trials 0 and 1 are kept, 2 to 4 never start.
        let report = batch
            .run(&|r| {
                if r.trial == 1 {
                    STOP.store(true, Ordering::SeqCst);
                }
            })
            .unwrap();
        assert!(report.interrupted);
        assert_eq!(report.trials, 2);
        let kept: Vec<usize> = report.reports.iter().map(|r| r.trial).collect();
        assert_eq!(kept, [0, 1]);
        let whole = Batch::new(&robot, &task, &spec, &ExecOptions::default(), options)
            .unwrap()
            .run(&|_| {})
            .unwrap();
        assert!(!whole.interrupted && whole.trials == 5);
        assert_eq!(
            strip(report.reports[1].clone()),
            strip(whole.reports[1].clone())
        );
        let none = batch.run(&|_| {}).unwrap();
        assert!(none.interrupted && none.trials == 0 && none.reports.is_empty());
    }

    #[test]
    fn a_spec_naming_an_unknown_object_is_refused() {
        let robot = Robot::panda().unwrap();
        let task = akl_scene::builtin::task("inspection").unwrap().unwrap();
        let mut spec = task.truth.clone().unwrap();
        spec.keyframes[0].reference = "vase".into();
        let exec = ExecOptions::default();
        let options = BatchOptions {
            trials: 1,
            randomize: false,
            seed: 0,
            jobs: 1,
        };
        let e = Batch::new(&robot, &task, &spec, &exec, options)
            .err()
            .unwrap();
        assert!(e.to_string().contains("vase"), "{e}");
    }
}
