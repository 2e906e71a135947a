//! The online detector on the simulated teacher's demonstrations: a query on every required
//! line of the built-in tasks, on at least 9 of 10 unintended straight lines, and on no curved
//! free motion, over 10 seeds; required lines of 10 and 12 cm (shorter than any built-in one)
//! asked about and learned as lines; no more queries on curved motion than the thesis's 5 cm
//! sampling makes; and the survey that chose the sampling and the calibration's settings.

use akl_learn::calibration::{Calibration, Motion, Sampling, TankRule, SAMPLING};
use akl_learn::{learn_spec, Demo, Detector, DialogueKind, LearnOptions, Method};

use akl_learn::okl::runs;
use akl_learn::okl::OklParams;
use akl_learn::teach::{oracle, oracle_for, run_session, teach_simulated, Pace};
use akl_learn::teacher::{calibration_demos_with, demonstrate, SimulatedDemo, TeacherProfile};
use akl_scene::{builtin, Task};
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
    tally_taught(sim, &demo)
}

/// Tallies the queries of `demo`, the session's recording of `sim`.
fn tally_taught(sim: &SimulatedDemo, demo: &Demo) -> Tally {
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
            .filter(|r| asked.iter().any(|&q| covers(demo, r, q)))
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
            .filter(|&&q| !straight_runs.iter().any(|r| covers(demo, r, q)))
            .count(),
    }
}

#[test]
fn every_required_line_is_asked_about_and_curved_motion_never() {
    for name in builtin::names() {
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

/// A sampling at the thesis's 5 cm filter step, eq. 3.2 on consecutive points, no smoothing
/// (each filtered point the mean of its step's samples, as at every sampling here).
const FIVE_CM: Sampling = Sampling {
    filter_distance: 0.05,
    window: 1,
    smoothing: 0.0,
};

/// A calibration at `sampling` with `rule`, fitted to the default teacher's line and circle as
/// the shipped one is.
fn fitted(sampling: Sampling, rule: &TankRule) -> Calibration {
    let (line, circle) = calibration_demos_with(&TeacherProfile::careful(), 0, 0.3).unwrap();
    Calibration::fit_with(&Motion::of(&line), &Motion::of(&circle), sampling, rule).unwrap()
}

/// Queries on curved motion when the detector before this sampling (D_F = 5 cm, each filtered
/// point the first sample of its step, eq. 3.2 on consecutive points) taught the built-in tasks
/// live with the first-time teacher, 10 seeds each (measured on commit d71aad3 as
/// [`survey_builtin`] does): 3 on `pick_place`, 3 on `assembly`, 5 on `bottles`.
const QUERIES_ON_CURVES_BEFORE: usize = 11;

/// The first-time teacher shakes twice as much and bows its reaches less: its free motion is
/// asked about now and then, but no more often than before the detector sampled finer, and the
/// calibration circles (of the default and the first-time teacher) never.
#[test]
fn curved_motion_is_asked_about_no_more_than_before() {
    let now = survey_builtin(&TeacherProfile::novice(), Calibration::default()).stray;
    assert!(
        now <= QUERIES_ON_CURVES_BEFORE,
        "{now} queries on curves, {QUERIES_ON_CURVES_BEFORE} before"
    );
    for profile in [TeacherProfile::careful(), TeacherProfile::novice()] {
        for seed in 0..10 {
            let (_, circle) = calibration_demos_with(&profile, seed, 0.3).unwrap();
            let (states, _) = Detector::replay(Calibration::default(), &Motion::of(&circle));
            assert!(!states.iter().any(|c| *c), "seed {seed}");
        }
    }
}

/// A task whose one required line is `length` metres long: `descend`, a peg lowered straight
/// into a fixture after a free reach above it, or `pull`, a handle pulled straight out of a
/// cabinet (off the stand it rests on) right after it is grasped.
fn short_line_task(kind: &str, length: f64) -> Task {
    let table = r#"{"name": "table", "shape": {"type": "box", "size": [1.2, 1.4, 0.04]},
        "pose": {"p": [0.35, 0, -0.02], "q": [0, 0, 0, 1]}, "movable": false, "mass": 0.0, "friction": 0.6}"#;
    let home = r#"{"action": "move", "to": {"p": [0.307, 0.0, 0.487], "q": [1, 0, 0, 0]}, "relative_to": "world"}"#;
    let (objects, steps) = match kind {
        "descend" => (
            r#"{"name": "peg", "shape": {"type": "cylinder", "radius": 0.01, "length": 0.08},
                "pose": {"p": [0.45, 0.3, 0.04], "q": [0, 0, 0, 1]}, "movable": true, "mass": 0.05, "friction": 0.6},
               {"name": "fixture", "shape": {"type": "box", "size": [0.08, 0.08, 0.06]},
                "pose": {"p": [0.5, -0.25, 0.03], "q": [0, 0, 0, 1]}, "movable": false, "mass": 0.0, "friction": 0.6}"#
                .to_string(),
            format!(
                r#"{{"action": "grasp", "object": "peg", "tcp": {{"p": [0, 0, 0.03], "q": [1, 0, 0, 0]}}}},
                   {{"action": "move", "to": {{"p": [0, 0, {above}], "q": [1, 0, 0, 0]}}, "relative_to": "fixture"}},
                   {{"action": "line", "to": {{"p": [0, 0, 0.06], "q": [1, 0, 0, 0]}}, "relative_to": "fixture"}},
                   {{"action": "release", "on": "fixture", "place": {{"p": [0, 0, 0.03], "q": [0, 0, 0, 1]}}}}"#,
                above = 0.06 + length
            ),
        ),
        _ => (
            r#"{"name": "cabinet", "shape": {"type": "box", "size": [0.3, 0.4, 0.3]},
                "pose": {"p": [0.77, 0.0, 0.15], "q": [0, 0, 0, 1]}, "movable": false, "mass": 0.0, "friction": 0.6},
               {"name": "stand", "shape": {"type": "box", "size": [0.04, 0.12, 0.19]},
                "pose": {"p": [0.59, 0.0, 0.095], "q": [0, 0, 0, 1]}, "movable": false, "mass": 0.0, "friction": 0.6},
               {"name": "handle", "shape": {"type": "box", "size": [0.02, 0.1, 0.02]},
                "pose": {"p": [0.59, 0.0, 0.2], "q": [0, 0, 0, 1]}, "movable": true, "mass": 0.05, "friction": 0.6}"#
                .to_string(),
            format!(
                r#"{{"action": "grasp", "object": "handle", "tcp": {{"p": [0, 0, 0.01], "q": [1, 0, 0, 0]}}}},
                   {{"action": "line", "to": {{"p": [{x}, 0, 0.21], "q": [1, 0, 0, 0]}}, "relative_to": "world"}},
                   {{"action": "release", "on": "table", "place": {{"p": [{on_table}, 0.0, 0.22], "q": [0, 0, 0, 1]}}}}"#,
                x = 0.59 - length,
                on_table = 0.24 - length
            ),
        ),
    };
    let text = format!(
        r#"{{"akl_task": 1, "name": "{kind}", "description": "A short required line.",
            "world": {{"robot_base": {{"p": [0, 0, 0], "q": [0, 0, 0, 1]}}, "objects": [{table}, {objects}]}},
            "goals": [],
            "teaching": {{"start": {{"p": [0.307, 0.0, 0.487], "q": [1, 0, 0, 0]}}, "steps": [{steps}, {home}]}}}}"#
    );
    Task::from_json(&text).unwrap()
}

/// What teaching `task` live with the oracle gave: the tally and whether AKL learned a line.
fn teach_short(
    task: &Task,
    profile: &TeacherProfile,
    seed: u64,
    cal: Calibration,
) -> (Tally, bool) {
    let mut answers = oracle(profile, seed);
    let taught = teach_simulated(
        task,
        &task.world,
        profile,
        seed,
        (cal, None),
        &mut answers,
        None,
        &Pace::default(),
    )
    .unwrap();
    let options = LearnOptions {
        okl: OklParams::for_calibration(&cal),
        ..LearnOptions::default()
    };
    let spec = learn_spec(Method::Akl, &taught.demo, Some(&task.world), &options).unwrap();
    let t = tally_taught(&taught.sim, &taught.demo);
    (t, spec.line_count() == 1)
}

/// Required lines of 10 and 12 cm — a descent into a fixture and the pull of a handle — are
/// asked about while they are made, and learned as one `move_in_line`, for the default teacher
/// and a first-time teacher who answers right, over 10 seeds each.
#[test]
fn short_required_lines_are_asked_about_and_learned() {
    let novice = TeacherProfile {
        wrong_answer_rate: 0.0,
        unknown_answer_rate: 0.0,
        unintended_line_chance: 0.0,
        ..TeacherProfile::novice()
    };
    for kind in ["descend", "pull"] {
        for length in [0.10, 0.12] {
            let task = short_line_task(kind, length);
            for profile in [TeacherProfile::careful(), novice] {
                for seed in 0..10 {
                    let (t, line) = teach_short(&task, &profile, seed, Calibration::default());
                    let at = format!("{kind} {length} m, seed {seed}: {t:?}");
                    assert_eq!((t.required, t.required_asked, t.stray), (1, 1, 0), "{at}");
                    assert!(line, "{at}: no line learned");
                }
            }
        }
    }
}

/// The measurement behind the detector's sampling ([`SAMPLING`]) and tank rule: for each
/// sampling, fitted to the default teacher's calibration motions, the queries on curved motion
/// (default, first-time and straight-moving teachers on the built-in tasks, and the calibration
/// circles), the required and unintended lines asked about, and per short line (descend or pull,
/// 8–15 cm) how many of 10 seeds were asked about / learned as a line, for the default teacher
/// and a first-time teacher who answers right.
#[test]
#[ignore = "a survey that prints a table (seconds in release): run with --release --ignored --nocapture"]
fn detector_survey() {
    let candidates = [
        (FIVE_CM, 2.0),
        (
            Sampling {
                smoothing: 0.0,
                ..SAMPLING
            },
            2.0,
        ),
        (
            Sampling {
                smoothing: 0.06,
                ..SAMPLING
            },
            2.0,
        ),
        (SAMPLING, 2.0),
        (SAMPLING, 3.0),
        (
            Sampling {
                window: 2,
                ..SAMPLING
            },
            2.0,
        ),
        (
            Sampling {
                window: 4,
                ..SAMPLING
            },
            2.0,
        ),
        (
            Sampling {
                filter_distance: 0.008,
                window: 4,
                ..SAMPLING
            },
            2.0,
        ),
        (
            Sampling {
                filter_distance: 0.012,
                ..SAMPLING
            },
            2.0,
        ),
        (
            Sampling {
                filter_distance: 0.006,
                window: 5,
                ..SAMPLING
            },
            2.0,
        ),
    ];
    let novice = TeacherProfile {
        wrong_answer_rate: 0.0,
        unknown_answer_rate: 0.0,
        unintended_line_chance: 0.0,
        ..TeacherProfile::novice()
    };
    for (sampling, switch_points) in candidates {
        let rule = TankRule {
            switch_points,
            ..TankRule::default()
        };
        let cal = fitted(sampling, &rule);
        let careful = survey_builtin(&TeacherProfile::careful(), cal);
        let first_time = survey_builtin(&TeacherProfile::novice(), cal);
        let straight = survey_builtin(&TeacherProfile::straight(), cal);
        let mut circle = 0;
        for profile in [TeacherProfile::careful(), TeacherProfile::novice()] {
            for seed in 0..10 {
                let (_, c) = calibration_demos_with(&profile, seed, 0.3).unwrap();
                let (_, switches) = Detector::replay(cal, &Motion::of(&c));
                circle += switches.iter().filter(|(_, s)| s.constrained).count();
            }
        }
        println!(
            "D_F {} m, window {}, smoothing {} s, {switch_points} switch points: queries on curves \
             {} (default) {} (first-time) {} (straight), circles {circle}; required {}/{}, \
             unintended {}/{}",
            sampling.filter_distance,
            sampling.window,
            sampling.smoothing,
            careful.stray,
            first_time.stray,
            straight.stray,
            careful.required_asked + first_time.required_asked,
            careful.required + first_time.required,
            first_time.unintended_asked + straight.unintended_asked,
            first_time.unintended + straight.unintended,
        );
        let mut row = String::new();
        for kind in ["descend", "pull"] {
            for length in [0.08, 0.10, 0.12, 0.15] {
                let task = short_line_task(kind, length);
                let cells: Vec<String> = [TeacherProfile::careful(), novice]
                    .iter()
                    .map(|profile| {
                        let (mut asked, mut learned) = (0, 0);
                        for seed in 0..10 {
                            let (t, line) = teach_short(&task, profile, seed, cal);
                            asked += t.required_asked;
                            learned += usize::from(line);
                        }
                        format!("{asked}/{learned}")
                    })
                    .collect();
                row += &format!(" {kind} {:.0} cm {}", length * 100.0, cells.join(" "));
            }
        }
        println!("   {row}");
    }
}

/// [`Tally`] over 10 seeds of every built-in task taught live by `profile`.
fn survey_builtin(profile: &TeacherProfile, cal: Calibration) -> Tally {
    let mut total = Tally::default();
    for name in builtin::names() {
        let task = builtin::resolve(name).unwrap();
        for seed in 0..10 {
            let mut answers = oracle(profile, seed);
            let taught = teach_simulated(
                &task,
                &task.world,
                profile,
                seed,
                (cal, None),
                &mut answers,
                None,
                &Pace::default(),
            )
            .unwrap();
            let t = tally_taught(&taught.sim, &taught.demo);
            total.required += t.required;
            total.required_asked += t.required_asked;
            total.unintended += t.unintended;
            total.unintended_asked += t.unintended_asked;
            total.stray += t.stray;
        }
    }
    total
}
