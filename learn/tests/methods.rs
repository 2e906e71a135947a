//! The three learning methods on the simulated teacher's demonstrations of the built-in tasks,
//! through the real online detector and dialogue, scored against the ground truths.

use akl_learn::calibration::Calibration;
use akl_learn::dialogue::{AllYes, AnswerSource, ListedAnswers};
use akl_learn::okl::runs;
use akl_learn::okl::synth::DemoBuilder;
use akl_learn::teach::{oracle_for, run_session};
use akl_learn::teacher::{demonstrate, SimulatedDemo, TeacherProfile};
use akl_learn::{learn_spec, score, Answer, Demo, LearnOptions, Method, Tolerance};
use akl_scene::{builtin, Task};
use akl_tsr::{Constraint, KeyframeKind, TaskSpec};

fn teach(task: &Task, profile: &TeacherProfile, seed: u64) -> (SimulatedDemo, Demo) {
    let sim = demonstrate(task, &task.world, profile, seed).unwrap();
    let mut oracle = oracle_for(&sim, profile, seed);
    let demo = run_session(&sim, Calibration::default(), &mut oracle, None).unwrap();
    (sim, demo)
}

fn learn(method: Method, demo: &Demo, task: &Task) -> TaskSpec {
    learn_spec(method, demo, Some(&task.world), &LearnOptions::default()).unwrap()
}

fn count(spec: &TaskSpec, pred: impl Fn(KeyframeKind, Constraint) -> bool) -> usize {
    spec.keyframes
        .iter()
        .filter(|k| pred(k.kind, k.constraint))
        .count()
}

#[test]
fn akl_learns_every_builtin_task_from_the_default_teacher() {
    for name in builtin::names() {
        let task = builtin::resolve(name).unwrap();
        let truth = task.truth.clone().unwrap();
        let mut failures = Vec::new();
        for seed in 0..10 {
            let (_, demo) = teach(&task, &TeacherProfile::careful(), seed);
            let spec = learn(Method::Akl, &demo, &task);
            let s = score(&spec, &truth, &Tolerance::default());
            if !s.success {
                failures.push(format!("seed {seed}: {:?}", s.differences));
            }
        }
        assert!(failures.len() <= 1, "{name}: {failures:#?}");
    }
}

/// A careful teacher who makes exactly one free motion in a straight line, and the frames of
/// that line.
fn one_unintended_line() -> (Task, SimulatedDemo) {
    let task = builtin::resolve("pick_place").unwrap();
    let profile = TeacherProfile {
        unintended_line_chance: 0.25,
        ..TeacherProfile::careful()
    };
    (0..100)
        .map(|seed| demonstrate(&task, &task.world, &profile, seed).unwrap())
        .find(|sim| runs(&sim.unintended_line).len() == 1)
        .map(|sim| (task, sim))
        .expect("a seed with one unintended line")
}

#[test]
fn an_unintended_line_answered_no_leaves_nothing_and_yes_two_constraint_keyframes() {
    let (task, sim) = one_unintended_line();
    let answer = |answers: &mut dyn AnswerSource| {
        let demo = run_session(&sim, Calibration::default(), answers, None).unwrap();
        learn(Method::Akl, &demo, &task)
    };
    let no = answer(&mut ListedAnswers::parse("no").unwrap());
    assert_eq!(no.keyframes.len(), 4);
    assert_eq!(count(&no, |k, _| k != KeyframeKind::Interaction), 0);
    // Kept, the line is bounded by two keyframes: constraint keyframes, or combined ones where
    // a boundary coincides with a grasp or release.
    let yes = answer(&mut AllYes);
    assert_eq!(
        count(&yes, |k, _| k != KeyframeKind::Interaction),
        2,
        "{yes:#?}"
    );
    assert_eq!(count(&yes, |_, c| c == Constraint::MoveInLine), 1);
    let combined = count(&yes, |k, _| k == KeyframeKind::Combined);
    assert_eq!(yes.keyframes.len(), 6 - combined);
}

#[test]
fn macl_cannot_combine_and_kd_learns_no_constraints() {
    let task = builtin::resolve("assembly").unwrap();
    for seed in 0..10 {
        let (_, demo) = teach(&task, &TeacherProfile::careful(), seed);
        let macl = learn(Method::Macl, &demo, &task);
        assert_eq!(
            macl.keyframes.len(),
            6,
            "seed {seed}: {:#?}",
            macl.keyframes
        );
        assert_eq!(count(&macl, |k, _| k == KeyframeKind::Combined), 0);
        assert_eq!(count(&macl, |k, _| k == KeyframeKind::Constraint), 2);
    }
    for name in builtin::names() {
        let task = builtin::resolve(name).unwrap();
        for seed in 0..3 {
            let (_, demo) = teach(&task, &TeacherProfile::novice(), seed);
            let kd = learn(Method::Kd, &demo, &task);
            assert_eq!(count(&kd, |_, c| c == Constraint::MoveInLine), 0, "{name}");
            assert_eq!(kd.method, "kd");
        }
    }
}

#[test]
fn degenerate_demos_give_a_spec_or_a_clear_error_with_every_method() {
    let straight = DemoBuilder::new("t", [0.3, 0.0, 0.5], 100.0, 0.0005, 0)
        .line([0.3, 0.4, 0.5], 0.2, Some(Answer::Yes))
        .build();
    let demos = [
        DemoBuilder::new("t", [0.3, 0.0, 0.5], 100.0, 0.0, 0).build(),
        DemoBuilder::new("t", [0.3, 0.0, 0.5], 100.0, 0.0, 0)
            .pause(1.0)
            .build(),
        DemoBuilder::new("t", [0.3, 0.0, 0.5], 100.0, 0.0005, 0)
            .curve([0.5, 0.2, 0.3], 0.2)
            .build(),
        straight,
    ];
    for demo in &demos {
        for method in Method::ALL {
            match learn_spec(method, demo, None, &LearnOptions::default()) {
                Ok(spec) => spec.validate().unwrap(),
                Err(e) => assert!(!e.to_string().is_empty()),
            }
        }
    }
}
