//! Batches of trials: one spec executed in N worlds, in parallel, reproducibly.
//!
//! Trial i places the objects with seed `seed + i` (or leaves them where the task file has
//! them) and plans with the same seed. Each trial builds its own rapier world and runs
//! single-threaded, so a batch gives the same reports whatever the number of threads.
//!
//! Once the options' [`crate::interrupt::Interrupt`] is raised no trial starts; those under
//! way finish, and the report covers the trials that finished, in trial order.

use crate::error::ExecError;
use crate::interrupt::Interrupt;
use crate::options::{ExecOptions, Setup};
use crate::report::{BatchReport, Identity, Settings, TrialOutcome, TrialReport};
use crate::shard::Shard;
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
    /// The shard of the run this batch is, if it is one.
    shard: Option<Shard>,
    /// The indices of the trials this batch runs (all of the run's, a shard's block, or
    /// those a resumed run still lacks), in order.
    indices: Vec<usize>,
    /// The world of each of them.
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
        let setup = Setup {
            robot,
            task,
            spec,
            options: exec,
        };
        Batch::only(setup, options, None, (0..options.trials).collect())
    }

    /// The batch of shard `shard` of the run `options` describes: only the trials of its
    /// block ([`Shard::trials`]), each with the seed, layout and outcome it has in the whole
    /// run. Refused when the block is empty.
    pub fn shard(
        setup: Setup<'a>,
        options: BatchOptions,
        shard: Shard,
    ) -> Result<Batch<'a>, ExecError> {
        let block = shard.nonempty_trials(options.trials)?;
        Batch::only(setup, options, Some(shard), block.collect())
    }

    /// The batch of the trials `indices` (each below `options.trials`, in increasing order)
    /// of the run `options` describes (of its shard `shard`, if given): what a resumed run
    /// still has to run.
    pub fn only(
        setup: Setup<'a>,
        options: BatchOptions,
        shard: Option<Shard>,
        indices: Vec<usize>,
    ) -> Result<Batch<'a>, ExecError> {
        if options.trials == 0 || indices.is_empty() {
            return Err(ExecError::Options(
                "a batch needs at least one trial".into(),
            ));
        }
        if options.jobs == 0 {
            return Err(ExecError::Options("a batch needs at least one job".into()));
        }
        if indices.windows(2).any(|w| w[0] >= w[1]) || indices.iter().any(|&i| i >= options.trials)
        {
            return Err(ExecError::Options(format!(
                "the trials of a batch must be distinct, in order and below {}",
                options.trials
            )));
        }
        let Setup {
            task,
            spec,
            options: exec,
            ..
        } = setup;
        spec.validate()?;
        spec.check_references(task.world.names())?;
        exec.plan
            .check()
            .map_err(|e| ExecError::Options(e.to_string()))?;
        let worlds = indices
            .iter()
            .map(|&i| {
                trial_world(
                    task,
                    options.randomize,
                    trial_seed(options.seed, i),
                    &exec.physics,
                )
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Batch {
            setup,
            options,
            shard,
            indices,
            worlds,
        })
    }

    /// Runs every trial of the batch on [`BatchOptions::jobs`] threads, calling `progress`
    /// after each (from the worker that ran it). Once [`ExecOptions::interrupt`] is raised no
    /// more trials start: the report then holds the trials that finished (in trial order, each
    /// the same as in an uninterrupted run) and is [`BatchReport::interrupted`] if any trial
    /// did not run.
    ///
    /// With one job the trials run on the calling thread, so a batch run from a worker of
    /// another pool (a search running many one-trial batches) keeps to that pool's threads.
    pub fn run(&self, progress: &(dyn Fn(&TrialReport) + Sync)) -> Result<BatchReport, ExecError> {
        let started = Instant::now();
        let interrupt = self.setup.options.interrupt;
        let run_one = |k: usize| {
            if interrupt.raised() {
                return None;
            }
            let r = self.trial(k, None);
            progress(&r);
            Some(r)
        };
        let reports: Vec<TrialReport> = if self.options.jobs == 1 {
            (0..self.indices.len()).map_while(run_one).collect()
        } else {
            worker_pool(self.options.jobs)?.install(|| {
                (0..self.indices.len())
                    .into_par_iter()
                    .filter_map(run_one)
                    .collect()
            })
        };
        let interrupted = reports.len() < self.indices.len();
        let Setup {
            robot,
            task,
            spec,
            options,
        } = self.setup;
        let mut report = BatchReport::new(
            &task.name,
            &spec.method,
            self.options.seed,
            self.options.randomize,
            reports,
            self.options.jobs,
            started.elapsed().as_secs_f64(),
            settings(robot, options, spec),
        );
        report.interrupted = interrupted;
        report.shard = self.shard;
        report.identity = Some(identity(&self.setup, self.options.trials));
        Ok(report)
    }

    /// Runs trial `i` of the run alone (it gives the same report as in the batch), recording
    /// its frames at `rate` per simulated second for a trace. Refused when trial `i` is not
    /// one of this batch's.
    pub fn record(&self, i: usize, rate: f64) -> Result<(TrialReport, Timeline), ExecError> {
        let k = self.position(i)?;
        let mut timeline = Timeline::new(rate);
        let report = self.trial(k, Some(&mut timeline));
        Ok((report, timeline))
    }

    /// Runs again trial `trial` of this batch, or the trial of `report` (this batch's report)
    /// that a trace should show by default (the first that failed, else the first), recording it at
    /// [`TRACE_RATE`], and writes it as an MCAP trace to `path`. Returns that trial's index.
    pub fn write_trace(
        &self,
        report: &BatchReport,
        trial: Option<usize>,
        path: &Path,
    ) -> Result<usize, ExecError> {
        let i = trial.unwrap_or_else(|| trial_to_trace(report).unwrap_or(self.indices[0]));
        let (trial, timeline) = self.record(i, TRACE_RATE)?;
        let input = TraceInput {
            robot: self.setup.robot,
            world: &self.worlds[self.position(i)?],
            spec: self.setup.spec,
            report: &trial,
            timeline: &timeline,
        };
        write_trace(path, &input)?;
        Ok(i)
    }

    /// Where trial `i` of the run is in this batch.
    fn position(&self, i: usize) -> Result<usize, ExecError> {
        self.indices.binary_search(&i).map_err(|_| {
            let (first, last) = (self.indices[0], self.indices[self.indices.len() - 1]);
            ExecError::Options(format!(
                "trial {i} is not one of this batch's (trials {first} to {last})"
            ))
        })
    }

    fn trial(&self, k: usize, timeline: Option<&mut Timeline>) -> TrialReport {
        let i = self.indices[k];
        let seed = trial_seed(self.options.seed, i);
        run_trial(&self.setup, i, seed, &self.worlds[k], timeline)
    }

    /// The world trial `i` of the run runs in, if it is one of this batch's.
    pub fn world(&self, i: usize) -> Option<&World> {
        self.position(i).ok().map(|k| &self.worlds[k])
    }

    /// The indices of the trials this batch runs, in order.
    pub fn indices(&self) -> &[usize] {
        &self.indices
    }

    /// The robot, task, spec and settings.
    pub fn setup(&self) -> &Setup<'a> {
        &self.setup
    }
}

/// What makes reports of `setup` in a run of `trials` trials comparable ([`Identity`]).
pub fn identity(setup: &Setup, trials: usize) -> Identity {
    let Setup {
        robot,
        task,
        spec,
        options,
    } = *setup;
    // The interrupt flag changes which trials run, never what one gives.
    let settings = ExecOptions {
        interrupt: Interrupt::NEVER,
        ..options.clone()
    };
    Identity {
        version: env!("CARGO_PKG_VERSION").to_string(),
        platform: format!("{}-{}", std::env::consts::ARCH, std::env::consts::OS),
        spec_hash: spec_hash(spec),
        task_hash: sha256(&format!("{task:?}")),
        robot_hash: robot.digest().to_string(),
        settings_hash: sha256(&format!("{settings:?}")),
        trials,
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
pub(crate) fn spec_hash(spec: &TaskSpec) -> String {
    sha256(&spec.to_json())
}

/// SHA-256 of `text`, hex.
fn sha256(text: &str) -> String {
    Sha256::digest(text.as_bytes())
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// A pool of `jobs` threads to run trials on: every part of a run that runs trials side by
/// side takes its threads from here.
pub fn worker_pool(jobs: usize) -> Result<rayon::ThreadPool, ExecError> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .build()
        .map_err(|e| ExecError::Options(format!("cannot start {jobs} jobs: {e}")))
}

/// The seed of trial `i` of a batch seeded `seed`.
pub fn trial_seed(seed: u64, i: usize) -> u64 {
    seed.wrapping_add(i as u64)
}

/// The trial a trace should show: the first that failed, else the first (`None` when the
/// report holds no trial).
pub(crate) fn trial_to_trace<T: TrialOutcome>(report: &BatchReport<T>) -> Option<usize> {
    report
        .reports
        .iter()
        .find(|r| !r.passed())
        .or(report.reports.first())
        .map(TrialOutcome::index)
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
            let (again, timeline) = one.record(x.trial, 30.0).unwrap();
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
