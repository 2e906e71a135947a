//! The study's results in the shape of the thesis's tables: success per task and method
//! (Table 4.1, case (a)), constraint errors and what the answers did (Table 4.2), learning
//! runtime per method (§4.6.8) and, when executed, pass rates.

use akl_learn::Method;
use akl_stats::PassRate;
use serde::Serialize;

use crate::study::Trial;

/// Table 4.1 of the thesis, case (a): success rates (%) per task — pick and place,
/// inspection, assembly — and overall, for KD, mACL and AKL.
pub const THESIS_SUCCESS: [(&str, [f64; 3]); 4] = [
    ("pick_place", [50.0, 33.3, 66.7]),
    ("inspection", [0.0, 41.7, 75.0]),
    ("assembly", [0.0, 0.0, 58.3]),
    ("overall", [13.9, 25.0, 66.7]),
];

/// Table 4.2 of the thesis: AKL's constraint errors, those due to answers, those avoided by
/// answers; and mACL's constraint errors (§4.6.4).
pub const THESIS_CONSTRAINT_ERRORS: ConstraintErrors = ConstraintErrors {
    akl_errors: 19,
    akl_errors_from_answers: 14,
    akl_errors_avoided: 20,
    macl_errors: 46,
};

/// The methods in the order the thesis's tables list them.
pub const TABLE_ORDER: [Method; 3] = [Method::Kd, Method::Macl, Method::Akl];

/// Successes out of trials.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Rate {
    /// Successful trials.
    pub successes: usize,
    /// Trials.
    pub trials: usize,
    /// successes / trials in percent (0 without trials).
    pub percent: f64,
}

impl Rate {
    fn from<'a>(trials: impl Iterator<Item = &'a Trial>) -> Rate {
        let (mut successes, mut n) = (0, 0);
        for t in trials {
            n += 1;
            successes += usize::from(t.success);
        }
        Rate {
            successes,
            trials: n,
            percent: if n == 0 {
                0.0
            } else {
                100.0 * successes as f64 / n as f64
            },
        }
    }
}

/// One row of the success table: a task (or `overall`) and each method's rate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SuccessRow {
    /// The task, or `overall`.
    pub task: String,
    /// KD's rate.
    pub kd: Rate,
    /// mACL's rate.
    pub macl: Rate,
    /// AKL's rate.
    pub akl: Rate,
}

impl SuccessRow {
    /// The rate of `method`.
    pub fn rate(&self, method: Method) -> Rate {
        match method {
            Method::Kd => self.kd,
            Method::Macl => self.macl,
            Method::Akl => self.akl,
        }
    }
}

/// Constraint errors (Table 4.2): learned lines that are not true plus true lines not learned.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct ConstraintErrors {
    /// AKL's constraint errors.
    pub akl_errors: usize,
    /// AKL answers that kept a wrong state.
    pub akl_errors_from_answers: usize,
    /// AKL answers "no" to lines the task does not require.
    pub akl_errors_avoided: usize,
    /// mACL's constraint errors.
    pub macl_errors: usize,
}

/// Learning time of one method over its trials (s).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Runtime {
    /// The method.
    pub method: Method,
    /// Trials timed.
    pub trials: usize,
    /// Mean time.
    pub mean_s: f64,
    /// Median time.
    pub median_s: f64,
    /// Longest time.
    pub max_s: f64,
}

/// Execution pass rate of one method's specs on one task (or overall).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PassRow {
    /// The task, or `overall`.
    pub task: String,
    /// Mean pass rate (0–1) of each method's specs, in [`TABLE_ORDER`]; `None` when none ran.
    pub mean_pass_rate: [Option<f64>; 3],
    /// Every execution of each method's specs pooled, with the 95 % interval, in
    /// [`TABLE_ORDER`]. Pooled executions of different specs are not one spec's trials: the
    /// interval says how well the executions measure the method's average over the
    /// participants' specs, not how any one spec does.
    pub pass_rate: [Option<PassRate>; 3],
}

/// Everything the study's tables show.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Summary {
    /// Table 4.1 analog: one row per task, then `overall`.
    pub success: Vec<SuccessRow>,
    /// Table 4.2 analog.
    pub constraint_errors: ConstraintErrors,
    /// Learning time per method, in [`TABLE_ORDER`].
    pub runtime: Vec<Runtime>,
    /// Execution pass rates, when the specs were executed.
    pub pass_rates: Option<Vec<PassRow>>,
}

/// Summarizes `trials` over `tasks` (in table order).
pub fn summarize(trials: &[Trial], tasks: &[String]) -> Summary {
    let row = |task: Option<&str>| SuccessRow {
        task: task.unwrap_or("overall").to_string(),
        kd: Rate::from(of(trials, task, Method::Kd)),
        macl: Rate::from(of(trials, task, Method::Macl)),
        akl: Rate::from(of(trials, task, Method::Akl)),
    };
    let mut success: Vec<SuccessRow> = tasks.iter().map(|n| row(Some(n))).collect();
    success.push(row(None));
    let errors = |m: Method| {
        of(trials, None, m)
            .map(|t| t.missed_constraints + t.incorrect_constraints)
            .sum()
    };
    let akl = || of(trials, None, Method::Akl);
    let constraint_errors = ConstraintErrors {
        akl_errors: errors(Method::Akl),
        akl_errors_from_answers: akl().map(|t| t.errors_from_answers).sum(),
        akl_errors_avoided: akl().map(|t| t.errors_avoided).sum(),
        macl_errors: errors(Method::Macl),
    };
    let runtime = TABLE_ORDER
        .iter()
        .map(|&m| {
            let mut times: Vec<f64> = of(trials, None, m).map(|t| t.runtime_s).collect();
            times.sort_by(f64::total_cmp);
            Runtime {
                method: m,
                trials: times.len(),
                mean_s: mean(&times).unwrap_or(0.0),
                median_s: median(&times),
                max_s: times.last().copied().unwrap_or(0.0),
            }
        })
        .collect();
    let executed = trials.iter().any(|t| t.pass_rate.is_some());
    let pass_rates = executed.then(|| {
        let pass = |task: Option<&str>| PassRow {
            task: task.unwrap_or("overall").to_string(),
            mean_pass_rate: TABLE_ORDER.map(|m| {
                let rates: Vec<f64> = of(trials, task, m).filter_map(|t| t.pass_rate).collect();
                mean(&rates)
            }),
            pass_rate: TABLE_ORDER.map(|m| {
                let (passed, run) = of(trials, task, m)
                    .filter_map(|t| Some((t.passed_executions?, t.executions?)))
                    .fold((0, 0), |(p, n), (tp, tn)| (p + tp, n + tn));
                (run > 0).then(|| PassRate::new(passed, run))
            }),
        };
        let mut rows: Vec<PassRow> = tasks.iter().map(|n| pass(Some(n))).collect();
        rows.push(pass(None));
        rows
    });
    Summary {
        success,
        constraint_errors,
        runtime,
        pass_rates,
    }
}

/// The trials of `m` on `task` (every task when `None`).
fn of<'a>(
    trials: &'a [Trial],
    task: Option<&'a str>,
    m: Method,
) -> impl Iterator<Item = &'a Trial> + 'a {
    trials
        .iter()
        .filter(move |t| t.method == m && task.is_none_or(|n| t.task == n))
}

fn mean(values: &[f64]) -> Option<f64> {
    (!values.is_empty()).then(|| values.iter().sum::<f64>() / values.len() as f64)
}

/// The median of sorted `values` (0 when empty).
fn median(sorted: &[f64]) -> f64 {
    match sorted.len() {
        0 => 0.0,
        n if n % 2 == 1 => sorted[n / 2],
        n => (sorted[n / 2 - 1] + sorted[n / 2]) / 2.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn trial(task: &str, method: Method, success: bool, runtime_s: f64) -> Trial {
        Trial {
            participant: 1,
            experienced: false,
            method,
            position: 1,
            task: task.into(),
            seed: 0,
            frames: 10,
            duration_s: 0.1,
            unintended_line_chance: 0.0,
            unintended_lines: 0,
            queries: 2,
            yes: 1,
            no: 1,
            unknown: 0,
            suggestions: 1,
            errors_from_answers: 1,
            errors_avoided: 1,
            marks: 0,
            learn_error: None,
            learned_keyframes: 4,
            truth_keyframes: 4,
            missed_keyframes: 0,
            incorrect_keyframes: 0,
            keyframe_accuracy: 1.0,
            missed_poses: 0,
            incorrect_poses: 0,
            pose_accuracy: 1.0,
            missed_line_length: 0.0,
            incorrect_line_length: 0.0,
            constraint_accuracy: None,
            missed_constraints: 1,
            incorrect_constraints: usize::from(!success),
            success,
            runtime_s,
            executions: None,
            passed_executions: None,
            pass_rate: None,
            execute_error: None,
            spec: None,
        }
    }

    #[test]
    fn rates_errors_and_runtimes_are_counted_per_task_and_method() {
        let trials = vec![
            trial("a", Method::Akl, true, 0.001),
            trial("a", Method::Akl, false, 0.003),
            trial("b", Method::Akl, true, 0.002),
            trial("a", Method::Macl, false, 0.5),
            trial("b", Method::Kd, true, 0.0001),
        ];
        let s = summarize(&trials, &["a".into(), "b".into()]);
        assert_eq!(s.success.len(), 3);
        assert_eq!(s.success[0].akl.successes, 1);
        assert_eq!(s.success[0].akl.percent, 50.0);
        assert_eq!(s.success[0].kd.trials, 0);
        assert_eq!(s.success[1].kd.percent, 100.0);
        let overall = &s.success[2];
        assert_eq!((overall.akl.successes, overall.akl.trials), (2, 3));
        assert_eq!(overall.macl.percent, 0.0);
        assert_eq!(s.constraint_errors.akl_errors, 4);
        assert_eq!(s.constraint_errors.akl_errors_from_answers, 3);
        assert_eq!(s.constraint_errors.macl_errors, 2);
        let akl = s.runtime.iter().find(|r| r.method == Method::Akl).unwrap();
        assert_eq!((akl.median_s, akl.max_s), (0.002, 0.003));
        assert!((akl.mean_s - 0.002).abs() < 1e-12);
        assert!(s.pass_rates.is_none());
    }
}
