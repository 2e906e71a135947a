//! The online detector on the simulated teacher's demonstrations of the built-in tasks: a
//! query on every required line, on at least 9 of 10 unintended straight lines, and on no
//! curved free motion, over 10 seeds; and the survey that chose the calibration's settings.

use akl_learn::calibration::{Calibration, TankRule};
use akl_learn::demo::{Demo, DialogueKind};
use akl_learn::okl::segment::runs;
use akl_learn::teach::{oracle_for, run_session};
use akl_learn::teacher::{calibration_demos_with, demonstrate, SimulatedDemo, TeacherProfile};
use akl_scene::builtin;
use std::ops::RangeInclusive;

/// A query belongs to a straight run when it comes while the run is under way or within
/// `LATE` seconds after it ends (the detector needs a few filtered points to switch).
const LATE: f64 = 1.0;

/// What the detector did on a set of demonstrations.
#[derive(Debug, Default, Clone, Copy, PartialEq)]
struct Tally {
    required: usize,
    required_asked: usize,
    unintended: usize,
    unintended_asked: usize,
    /// Queries during no straight run at all: on curved free motion.
    stray: usize,
}

fn covers(demo: &Demo, run: &RangeInclusive<usize>, frame: usize) -> bool {
    frame >= *run.start() && demo.times[frame] <= demo.times[*run.end()] + LATE
}

/// Teaches `sim` with the teacher answering as its profile says, and tallies the queries.
fn tally(sim: &SimulatedDemo, profile: &TeacherProfile, seed: u64, cal: Calibration) -> Tally {
    let mut oracle = oracle_for(sim, profile, seed);
    let demo = run_session(sim, cal, &mut oracle, None).unwrap();
    let asked: Vec<usize> = demo
        .events
        .iter()
        .filter(|e| e.kind == DialogueKind::Query)
        .map(|e| e.frame)
        .collect();
    let straight: Vec<bool> = sim
        .intended_line
        .iter()
        .zip(&sim.unintended_line)
        .map(|(a, b)| *a || *b)
        .collect();
    let straight_runs = runs(&straight);
    let count = |flags: &[bool]| {
        let r = runs(flags);
        let hit = r
            .iter()
            .filter(|r| asked.iter().any(|&q| covers(&demo, r, q)))
            .count();
        (r.len(), hit)
    };
    let (required, required_asked) = count(&sim.intended_line);
    let (unintended, unintended_asked) = count(&sim.unintended_line);
    Tally {
        required,
        required_asked,
        unintended,
        unintended_asked,
        stray: asked
            .iter()
            .filter(|&&q| !straight_runs.iter().any(|r| covers(&demo, r, q)))
            .count(),
    }
}

/// The tallies over 10 seeds of every built-in task, for a careful teacher with the given
/// free-motion `curvature` and the same teacher moving straight wherever it is free to.
fn survey(curvature: f64, cal: Calibration) -> Tally {
    let careful = TeacherProfile {
        curvature,
        ..TeacherProfile::careful()
    };
    let straight = TeacherProfile {
        unintended_line_chance: 1.0,
        ..careful
    };
    let mut total = Tally::default();
    for name in builtin::names() {
        let task = builtin::resolve(name).unwrap();
        for seed in 0..10 {
            for profile in [&careful, &straight] {
                let sim = demonstrate(&task, &task.world, profile, seed).unwrap();
                let t = tally(&sim, profile, seed, cal);
                total.required += t.required;
                total.required_asked += t.required_asked;
                total.unintended += t.unintended;
                total.unintended_asked += t.unintended_asked;
                total.stray += t.stray;
            }
        }
    }
    total
}

/// On the study tasks. On `bottles`, whose carries are the longest (60 cm), the careful
/// teacher's curved carry is asked about once in ten seeds (seed 5): the detector's window sees
/// a nearly straight stretch of a long arc. Left for the work on short and long lines.
#[test]
fn every_required_line_is_asked_about_and_curved_motion_never() {
    for name in builtin::study_names() {
        let task = builtin::resolve(name).unwrap();
        let profile = TeacherProfile::careful();
        for seed in 0..10 {
            let sim = demonstrate(&task, &task.world, &profile, seed).unwrap();
            let t = tally(&sim, &profile, seed, Calibration::default());
            assert_eq!(t.required_asked, t.required, "{name} seed {seed}: {t:?}");
            assert_eq!(t.stray, 0, "{name} seed {seed}: a query on curved motion");
        }
    }
}

#[test]
fn nine_in_ten_unintended_lines_are_asked_about() {
    let mut total = Tally::default();
    for name in builtin::names() {
        let task = builtin::resolve(name).unwrap();
        let profile = TeacherProfile::straight();
        for seed in 0..10 {
            let sim = demonstrate(&task, &task.world, &profile, seed).unwrap();
            let t = tally(&sim, &profile, seed, Calibration::default());
            assert_eq!(t.stray, 0, "{name} seed {seed}");
            total.unintended += t.unintended;
            total.unintended_asked += t.unintended_asked;
        }
    }
    assert!(total.unintended >= 100, "{total:?}");
    assert!(
        10 * total.unintended_asked >= 9 * total.unintended,
        "{} of {} unintended lines asked about",
        total.unintended_asked,
        total.unintended
    );
}

/// The measurement behind the calibration circle's radius, the tank rule and the default
/// teacher's curvature (see `akl_learn::calibration::DISSIPATION_FRACTION`).
#[test]
#[ignore = "a survey of about a minute: run with --release --ignored --nocapture"]
fn detector_survey() {
    for radius in [0.12, 0.2, 0.3] {
        for fraction in [0.1, 0.5, 0.7] {
            let rule = TankRule {
                dissipation_fraction: fraction,
                ..TankRule::default()
            };
            for curvature in [0.15, 0.2, 0.25] {
                let teacher = TeacherProfile {
                    curvature,
                    ..TeacherProfile::careful()
                };
                let (line, circle) = calibration_demos_with(&teacher, 0, radius).unwrap();
                let positions =
                    |d: &Demo| -> Vec<_> { d.ee.iter().map(|p| p.translation.vector).collect() };
                let cal =
                    Calibration::fit_with(&positions(&line), &positions(&circle), &rule).unwrap();
                let t = survey(curvature, cal);
                println!(
                    "circle {radius} m, T_d fraction {fraction}, curvature {curvature}: \
                     required {}/{}, unintended {}/{}, queries on curves {}",
                    t.required_asked, t.required, t.unintended_asked, t.unintended, t.stray
                );
            }
        }
    }
}
