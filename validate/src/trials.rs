//! Randomized trials as validation runs them: goals drawn across every TSR, either a fixed
//! number of them ([`run_trials`]) or as many as the deployment gate needs to decide
//! ([`run_gated`]).

use akl_exec::batch::{trial_seed, worker_pool, Batch, BatchOptions};
use akl_exec::report::{BatchReport, Cause, TrialReport};
use akl_exec::{ExecError, ExecOptions};
use akl_planner::GoalStrategy;
use akl_planner::{PlanBudget, Robot};
use akl_scene::Task;
use akl_stats::{Decision, Gate, PassRate};
use akl_tsr::TaskSpec;
use rayon::prelude::*;
use serde::Serialize;
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};

/// Which randomized trials to run: trial i places the objects and plans with seed
/// `seed + i`, as `akl execute --randomize` does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Trials {
    /// Number of trials (at least 1).
    pub count: usize,
    /// Seed of the first.
    pub seed: u64,
    /// Trials run in parallel (at least 1).
    pub jobs: usize,
}

impl Trials {
    /// The seeds of the trials, in order.
    pub fn seeds(&self) -> Vec<u64> {
        (0..self.count).map(|i| trial_seed(self.seed, i)).collect()
    }

    /// Checks the counts.
    pub fn check(&self) -> Result<(), ExecError> {
        if self.count == 0 {
            return Err(ExecError::Options("needs at least one trial".into()));
        }
        if self.jobs == 0 {
            return Err(ExecError::Options("needs at least one job".into()));
        }
        Ok(())
    }
}

/// The first failed trial of a run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrialFailure {
    /// Its seed.
    pub seed: u64,
    /// Its root cause (its earliest failure's cause).
    pub cause: Cause,
    /// What failed.
    pub detail: String,
}

/// What a run of trials gave.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Outcome {
    /// Trials run (fewer than asked when the run stopped early).
    pub run: usize,
    /// Trials that passed.
    pub passed: usize,
    /// The pass rate with its 95 % confidence interval.
    pub pass_rate: PassRate,
    /// For each cause, the failed trials it was the root cause of (these add up to the
    /// failed trials).
    pub failures: BTreeMap<Cause, usize>,
    /// The first trial that failed, if any.
    pub first_failure: Option<TrialFailure>,
    /// The seeds of the trials that failed, in order.
    pub failed_seeds: Vec<u64>,
    /// Configurations the planner probed for collisions, over every trial read.
    pub plan_probes: u64,
}

impl Default for Outcome {
    fn default() -> Self {
        Outcome {
            run: 0,
            passed: 0,
            pass_rate: PassRate::new(0, 0),
            failures: BTreeMap::new(),
            first_failure: None,
            failed_seeds: Vec::new(),
            plan_probes: 0,
        }
    }
}

impl Outcome {
    /// Whether trials ran and every one passed.
    pub fn all_passed(&self) -> bool {
        self.run > 0 && self.passed == self.run
    }

    /// The first failure in words (`cause (seed S): detail`), if any.
    pub fn first_failure_text(&self) -> Option<String> {
        self.first_failure
            .as_ref()
            .map(|f| format!("{} (seed {}): {}", f.cause, f.seed, f.detail))
    }

    /// Mean collision probes of planning per trial read (0 when none was).
    pub fn probes_per_trial(&self) -> f64 {
        self.plan_probes as f64 / self.run.max(1) as f64
    }

    /// Counts one more trial.
    fn record(&mut self, trial: &TrialReport) {
        self.run += 1;
        self.plan_probes += trial.plan_probes;
        if trial.passed {
            self.passed += 1;
        } else {
            self.failed_seeds.push(trial.seed);
            if let Some(root) = trial.root() {
                *self.failures.entry(root.cause).or_default() += 1;
                self.first_failure.get_or_insert_with(|| TrialFailure {
                    seed: trial.seed,
                    cause: root.cause,
                    detail: root.detail.clone(),
                });
            }
        }
        self.pass_rate = PassRate::new(self.passed, self.run);
    }

    fn add(&mut self, report: &BatchReport) {
        for trial in &report.reports {
            self.record(trial);
        }
    }
}

/// Whole-spec draws a verification plan may take: the first that plans is executed (see
/// [`akl_planner::plan_best`]). Measured on the inspection specs AKL and mACL learn from the
/// default teacher: with 4 draws the AKL spec failed 1 of 20 trials for `no collision-free
/// goal` (a grasp drawn high on the part and every release pose drawn for it pressing the part
/// into the shelf); with 8 both passed 100 of 100. Only a draw that fails to plan costs another.
pub const DRAWS: usize = 8;

/// `exec` as verification runs it: every keyframe's goal drawn at random within its TSR
/// ([`GoalStrategy::Sampled`]), the first of [`DRAWS`] whole-spec draws that plans executed.
///
/// With the planner's default goals a keyframe is reached at its TSR's nominal pose whenever
/// that is reachable, so a spec would be judged on its centre alone: a region twice as wide
/// would pass the same trials, and a trial would never show that part of a region fails. A spec
/// claims that any pose of its regions will do; goals drawn across the regions (from the
/// trial's seed, so runs stay reproducible) test that claim. The first draw that plans is
/// kept, never the quickest of several (which would prefer some poses to others); a draw that
/// cannot be planned is drawn again, as a planner searching the regions would do.
pub fn verifying(exec: &ExecOptions) -> ExecOptions {
    let mut options = exec.clone();
    options.plan.goals.strategy = GoalStrategy::Sampled;
    options.plan.budget = PlanBudget::candidates(DRAWS);
    options
}

/// Runs `spec`'s randomized `trials` on `task`, planned as [`verifying`] plans them, every one
/// of them (`jobs` at a time; the same seeds give the same outcome whatever `jobs` is).
pub fn run_trials(
    robot: &Robot,
    task: &Task,
    spec: &TaskSpec,
    exec: &ExecOptions,
    trials: &Trials,
) -> Result<Outcome, ExecError> {
    trials.check()?;
    let exec = verifying(exec);
    let batch = Batch::new(
        robot,
        task,
        spec,
        &exec,
        BatchOptions {
            trials: trials.count,
            randomize: true,
            seed: trials.seed,
            jobs: trials.jobs.min(trials.count),
        },
    )?;
    let mut outcome = Outcome::default();
    outcome.add(&batch.run(&|_| {})?);
    Ok(outcome)
}

/// Runs trial `seed` of each `(spec, seed)` of `trials` on its own, `jobs` at a time, in the
/// order a pool of workers takes them, until `stop` says so of a finished trial; `exec` is used
/// as given (pass [`verifying`]'s to plan as verification does). A search screening or
/// replaying single trials of different specs keeps every core busy this way, where batches
/// of `jobs` trials would wait for their slowest. Returns each trial's report in the order
/// asked, or `None` for one that had not started when `stop` (or `exec.interrupt`) was raised:
/// which trials ran may depend on timing, what each gives never does.
pub fn run_each(
    robot: &Robot,
    task: &Task,
    exec: &ExecOptions,
    trials: &[(&TaskSpec, u64)],
    jobs: usize,
    stop: &(dyn Fn(&TrialReport) -> bool + Sync),
) -> Result<Vec<Option<TrialReport>>, ExecError> {
    if jobs == 0 {
        return Err(ExecError::Options("needs at least one job".into()));
    }
    let stopped = AtomicBool::new(false);
    worker_pool(jobs)?.install(|| {
        trials
            .par_iter()
            .with_max_len(1)
            .map(|&(spec, seed)| {
                if stopped.load(Ordering::SeqCst) {
                    return Ok(None);
                }
                let batch = Batch::new(
                    robot,
                    task,
                    spec,
                    exec,
                    BatchOptions {
                        trials: 1,
                        randomize: true,
                        seed,
                        jobs: 1,
                    },
                )?;
                let report = batch.run(&|_| {})?.reports.pop();
                if report.as_ref().is_some_and(stop) {
                    stopped.store(true, Ordering::SeqCst);
                }
                Ok(report)
            })
            .collect()
    })
}

/// A spec's trials judged by the deployment gate ([`akl_stats::gate`]).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Gated {
    /// The gate's decision; `None` when the run was interrupted (Ctrl-C) before it decided.
    pub decision: Option<Decision>,
    /// The trials the gate read, in seed order up to its decision (trials a batch ran past
    /// it are left out, so the decision and these counts do not depend on `jobs`).
    pub outcome: Outcome,
    /// Those trials' reports, when asked for (see [`run_gated`]).
    #[serde(skip)]
    pub reports: Vec<TrialReport>,
}

/// Largest batch the gate runs at once (per job): later batches grow to it, so a spec that
/// fails at once costs a trial or two per core, and one that passes runs in few batches.
const LARGEST_BATCH_PER_JOB: usize = 32;

/// Runs `spec`'s trials from seed `seed` (planned as [`verifying`] plans them), `jobs` at a
/// time in batches that double in size, and feeds them to `gate` in seed order until it
/// decides. Keeps the trials' reports when `keep_reports`; `progress` is called after each
/// batch with the trials judged so far. Stops, without a decision, once `exec.interrupt` is
/// raised.
#[allow(clippy::too_many_arguments)]
pub fn run_gated(
    robot: &Robot,
    task: &Task,
    spec: &TaskSpec,
    exec: &ExecOptions,
    gate: &Gate,
    seed: u64,
    jobs: usize,
    keep_reports: bool,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Gated, ExecError> {
    let run = GateRun {
        seed,
        jobs,
        keep_reports,
        give_up: false,
    };
    gate_trials(robot, task, spec, exec, gate, &run, progress)
}

/// [`run_gated`] for a search that keeps only what passes: it also stops, *undecided*, once
/// so many trials failed that the gate can no longer pass within its trials
/// ([`Gate::can_still_pass`]). A widening that fails 1.5 % of its trials then costs a few
/// hundred trials instead of the 1,500 its gate would take to fail it.
pub fn run_gated_to_pass(
    robot: &Robot,
    task: &Task,
    spec: &TaskSpec,
    exec: &ExecOptions,
    gate: &Gate,
    seed: u64,
    jobs: usize,
) -> Result<Gated, ExecError> {
    let run = GateRun {
        seed,
        jobs,
        keep_reports: false,
        give_up: true,
    };
    gate_trials(robot, task, spec, exec, gate, &run, &|_| {})
}

/// How [`gate_trials`] runs.
struct GateRun {
    seed: u64,
    jobs: usize,
    keep_reports: bool,
    /// Stop once the gate can no longer pass.
    give_up: bool,
}

fn gate_trials(
    robot: &Robot,
    task: &Task,
    spec: &TaskSpec,
    exec: &ExecOptions,
    gate: &Gate,
    run: &GateRun,
    progress: &(dyn Fn(usize) + Sync),
) -> Result<Gated, ExecError> {
    let &GateRun {
        seed,
        jobs,
        keep_reports,
        give_up,
    } = run;
    if jobs == 0 {
        return Err(ExecError::Options("needs at least one job".into()));
    }
    let exec = verifying(exec);
    let max = gate.options().max_trials;
    let mut gated = Gated {
        decision: None,
        outcome: Outcome::default(),
        reports: Vec::new(),
    };
    let mut failed = 0;
    let mut size = jobs;
    while gated.decision.is_none() && gated.outcome.run < max {
        if exec.interrupt.raised() {
            return Ok(gated);
        }
        let count = size.min(max - gated.outcome.run);
        let batch = Batch::new(
            robot,
            task,
            spec,
            &exec,
            BatchOptions {
                trials: count,
                randomize: true,
                seed: trial_seed(seed, gated.outcome.run),
                jobs: jobs.min(count),
            },
        )?;
        let report = batch.run(&|_| {})?;
        for trial in report.reports {
            gated.outcome.record(&trial);
            failed += usize::from(!trial.passed);
            if keep_reports {
                gated.reports.push(trial);
            }
            gated.decision = gate.decide(gated.outcome.run, failed);
            if gated.decision.is_none() && give_up && !gate.can_still_pass(failed) {
                gated.decision = Some(Decision::Undecided);
            }
            if gated.decision.is_some() {
                break;
            }
        }
        progress(gated.outcome.run);
        if report.interrupted {
            return Ok(gated);
        }
        size = (2 * size).min(LARGEST_BATCH_PER_JOB * jobs);
    }
    Ok(gated)
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_scene::builtin;

    #[test]
    fn a_failing_spec_is_rejected_by_the_gate_at_its_first_trial_whatever_the_jobs() {
        let robot = Robot::panda().unwrap();
        let task = builtin::task("pick_place").unwrap().unwrap();
        let mut wrong = task.truth.clone().unwrap();
        // The first block is never put down: every trial fails.
        wrong.keyframes.truncate(1);
        let exec = ExecOptions::default();
        let trials = Trials {
            count: 4,
            seed: 0,
            jobs: 1,
        };
        let all = run_trials(&robot, &task, &wrong, &exec, &trials).unwrap();
        assert_eq!((all.run, all.passed), (4, 0));
        assert_eq!(all.failures.values().sum::<usize>(), 4);
        let first = all.first_failure.clone().unwrap();
        assert_eq!(first.seed, 0);
        assert_eq!(all.failed_seeds, vec![0, 1, 2, 3]);
        assert!(all.pass_rate.upper < 0.61, "{:?}", all.pass_rate);
        let gate = Gate::new(akl_stats::GateOptions::default()).unwrap();
        for jobs in [1, 2] {
            let gated =
                run_gated(&robot, &task, &wrong, &exec, &gate, 0, jobs, true, &|_| {}).unwrap();
            assert_eq!(gated.decision, Some(Decision::Fails));
            assert_eq!((gated.outcome.run, gated.reports.len()), (1, 1));
            assert_eq!(gated.outcome.first_failure, Some(first.clone()));
        }
    }

    #[test]
    fn trials_run_each_alone_give_what_a_batch_gives_and_stop_when_asked() {
        let robot = Robot::panda().unwrap();
        let task = builtin::task("pick_place").unwrap().unwrap();
        let truth = task.truth.clone().unwrap();
        let mut wrong = truth.clone();
        wrong.keyframes.truncate(1);
        let exec = verifying(&ExecOptions::default());
        let asked = [(&truth, 5), (&wrong, 6), (&truth, 6)];
        let ran = run_each(&robot, &task, &exec, &asked, 2, &|_| false).unwrap();
        let passed: Vec<bool> = ran.iter().map(|r| r.as_ref().unwrap().passed).collect();
        assert_eq!(passed, [true, false, true]);
        let batch = Batch::new(
            &robot,
            &task,
            &truth,
            &exec,
            BatchOptions {
                trials: 2,
                randomize: true,
                seed: 5,
                jobs: 2,
            },
        )
        .unwrap()
        .run(&|_| {})
        .unwrap();
        let alone = ran[0].as_ref().unwrap();
        assert_eq!(
            (alone.seed, alone.plan_probes),
            (5, batch.reports[0].plan_probes)
        );
        assert_eq!(
            ran[2].as_ref().unwrap().plan_probes,
            batch.reports[1].plan_probes
        );
        // One job takes the trials in order: a stop after the failure runs nothing after it.
        let stopped = run_each(&robot, &task, &exec, &asked[1..], 1, &|t| !t.passed).unwrap();
        assert!(!stopped[0].as_ref().unwrap().passed && stopped[1].is_none());
        assert!(run_each(&robot, &task, &exec, &asked, 0, &|_| false).is_err());
    }

    #[test]
    fn verification_draws_goals_across_the_regions() {
        let exec = ExecOptions {
            plan: akl_planner::PlanOptions {
                budget: PlanBudget::candidates(9),
                ..Default::default()
            },
            ..ExecOptions::default()
        };
        let v = verifying(&exec);
        assert_eq!(v.plan.goals.strategy, GoalStrategy::Sampled);
        assert_eq!(v.plan.budget, PlanBudget::candidates(DRAWS));
        assert_eq!(v.noise, exec.noise);
    }

    #[test]
    fn trials_run_on_consecutive_seeds() {
        let trials = Trials {
            count: 3,
            seed: 7,
            jobs: 2,
        };
        assert_eq!(trials.seeds(), vec![7, 8, 9]);
    }

    #[test]
    fn no_trials_is_refused() {
        let trials = Trials {
            count: 0,
            seed: 0,
            jobs: 1,
        };
        assert!(trials.check().is_err());
    }
}
