//! The built-in tasks, embedded in the binary so they work from any directory: the three study
//! tasks of the thesis (§4.4) and `bottles`, with round objects standing among others.

use crate::error::SceneError;
use crate::task::Task;
use akl_tsr::TaskSpec;
use std::path::Path;

/// (name, task file, ground-truth spec) of each built-in task, the study's first.
const BUILTIN: [(&str, &str, &str); 4] = [
    (
        "pick_place",
        include_str!("../../tasks/pick_place.json"),
        include_str!("../../tasks/pick_place.truth.json"),
    ),
    (
        "inspection",
        include_str!("../../tasks/inspection.json"),
        include_str!("../../tasks/inspection.truth.json"),
    ),
    (
        "assembly",
        include_str!("../../tasks/assembly.json"),
        include_str!("../../tasks/assembly.truth.json"),
    ),
    (
        "bottles",
        include_str!("../../tasks/bottles.json"),
        include_str!("../../tasks/bottles.truth.json"),
    ),
];

/// How many of the built-in tasks are the thesis's study tasks (the first ones).
const STUDY_TASKS: usize = 3;

/// Names of the built-in tasks, the study's first, in study order.
pub fn names() -> Vec<&'static str> {
    BUILTIN.iter().map(|(name, _, _)| *name).collect()
}

/// Names of the thesis's study tasks (§4.4), in study order: what the simulated study runs.
pub fn study_names() -> Vec<&'static str> {
    names().into_iter().take(STUDY_TASKS).collect()
}

/// The built-in task `name` with its ground truth, if there is one by that name.
pub fn task(name: &str) -> Option<Result<Task, SceneError>> {
    let (_, text, truth) = BUILTIN.iter().find(|(n, _, _)| *n == name)?;
    Some(parse(name, text, truth))
}

fn parse(name: &str, text: &str, truth: &str) -> Result<Task, SceneError> {
    let task_path = format!("tasks/{name}.json");
    let truth_path = format!("tasks/{name}.truth.json");
    let mut task = Task::from_json(text).map_err(|source| SceneError::Invalid {
        location: task_path,
        problem: source.to_string(),
    })?;
    let spec = TaskSpec::from_json(truth).map_err(|source| {
        SceneError::Truth(akl_tsr::FileError {
            path: truth_path.clone().into(),
            source,
        })
    })?;
    task.set_truth(spec, Path::new(&truth_path))?;
    Ok(task)
}

/// A built-in task by name, or a task file by path (anything with a `/` or ending in `.json`).
pub fn resolve(name_or_path: &str) -> Result<Task, SceneError> {
    if let Some(task) = task(name_or_path) {
        return task;
    }
    let path = Path::new(name_or_path);
    if name_or_path.contains('/') || name_or_path.ends_with(".json") || path.exists() {
        return Task::load(path).map_err(|e| SceneError::Invalid {
            location: e.path.display().to_string(),
            problem: e.source.to_string(),
        });
    }
    Err(SceneError::UnknownTask {
        name: name_or_path.to_string(),
        known: names().into_iter().map(String::from).collect(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::intent::TeachStep;
    use crate::{ObjectPaths, World};
    use akl_tsr::pose::{position_distance, rotation_distance};
    use akl_tsr::{Gripper, KeyframeKind, Pose};

    fn all() -> Vec<Task> {
        names()
            .into_iter()
            .map(|n| task(n).unwrap().unwrap())
            .collect()
    }

    #[test]
    fn the_study_tasks_and_bottles_load_with_their_truth() {
        assert_eq!(names(), ["pick_place", "inspection", "assembly", "bottles"]);
        assert_eq!(study_names(), ["pick_place", "inspection", "assembly"]);
        for t in all() {
            assert!(t.truth.is_some(), "{} has no truth", t.name);
        }
    }

    #[test]
    fn truth_specs_have_the_keyframes_of_the_study() {
        let kinds = |name: &str| -> Vec<KeyframeKind> {
            let t = task(name).unwrap().unwrap();
            t.truth.unwrap().keyframes.iter().map(|k| k.kind).collect()
        };
        use KeyframeKind::*;
        assert_eq!(kinds("pick_place"), [Interaction; 4]);
        assert_eq!(
            kinds("inspection"),
            [Interaction, Constraint, Constraint, Interaction]
        );
        assert_eq!(
            kinds("assembly"),
            [Interaction, Interaction, Combined, Combined]
        );
    }

    /// Each truth keyframe sits where the teaching intent puts the hand: interactions at the
    /// grasp and release targets, a line's two boundaries at its start and end.
    #[test]
    fn truth_keyframes_match_the_teaching_intent() {
        for t in all() {
            let targets = t.teaching.targets(&t.world).unwrap();
            let mut expected = Vec::new();
            let mut previous = t.teaching.start;
            for (step, target) in t.teaching.steps.iter().zip(&targets) {
                match step {
                    TeachStep::Grasp { .. } => expected.push((*target, Gripper::Closed)),
                    TeachStep::Release { .. } => expected.push((*target, Gripper::Open)),
                    TeachStep::Line { .. } => {
                        expected.push((previous, Gripper::Closed));
                        expected.push((*target, Gripper::Closed));
                    }
                    TeachStep::Move { .. } => {}
                }
                previous = *target;
            }
            // Coinciding boundaries are one (combined) keyframe in the truth.
            expected.dedup_by(|b, a| {
                position_distance(&a.0, &b.0) < 1e-6 && {
                    a.1 = if a.1 == Gripper::Open || b.1 == Gripper::Open {
                        Gripper::Open
                    } else {
                        a.1
                    };
                    true
                }
            });
            let truth = t
                .truth
                .as_ref()
                .unwrap()
                .ground(&t.world.object_poses())
                .unwrap();
            assert_eq!(truth.keyframes.len(), expected.len(), "{}", t.name);
            for (i, (kf, (pose, _))) in truth.keyframes.iter().zip(&expected).enumerate() {
                let nominal = kf.tsr.nominal();
                assert!(
                    position_distance(&nominal, pose) < 1e-6,
                    "{} keyframe {i}",
                    t.name
                );
                assert!(
                    rotation_distance(&nominal, pose) < 1e-6,
                    "{} keyframe {i}",
                    t.name
                );
                assert!(kf.tsr.bw.contains_zero());
            }
            let lines = truth.line_count();
            let line_steps = t
                .teaching
                .steps
                .iter()
                .filter(|s| matches!(s, TeachStep::Line { .. }))
                .count();
            assert_eq!(lines, line_steps, "{}", t.name);
        }
    }

    /// The end world and the objects' paths when the teaching intent is followed exactly in
    /// `world`: the hand moves in straight pieces between the steps' targets, a grasped object
    /// rides rigidly in it, a released one stays where the intent puts it.
    fn follow_intent(t: &Task, world: &World) -> (World, ObjectPaths) {
        let targets = t.teaching.targets(world).unwrap();
        let mut end = world.clone();
        let mut paths = ObjectPaths::new();
        paths.record(0.0, world);
        let mut held: Option<(&str, Pose)> = None;
        let mut hand = t.teaching.start;
        let mut time = 0.0;
        for (step, target) in t.teaching.steps.iter().zip(&targets) {
            for k in 1..=200 {
                let tcp = hand.lerp_slerp(target, f64::from(k) / 200.0);
                time += 0.005;
                if let Some((object, grasp)) = held {
                    let pose = tcp * grasp.inverse();
                    end.object_mut(object).unwrap().pose = pose;
                    paths.push(object, time, pose);
                }
            }
            match step {
                TeachStep::Grasp { object, tcp } => held = Some((object, *tcp)),
                TeachStep::Release { .. } => held = None,
                _ => {}
            }
            hand = *target;
        }
        (end, paths)
    }

    #[test]
    fn goals_do_not_hold_before_the_task_and_hold_after_the_intent_in_any_layout() {
        for t in all() {
            let before = t.check_goals(&t.world, &ObjectPaths::new());
            assert!(
                before.iter().any(|c| !c.holds),
                "{}: goals already hold",
                t.name
            );
            let mut worlds = vec![t.world.clone()];
            worlds.extend((0..100).map(|seed| crate::randomize(&t, seed).unwrap()));
            for (i, world) in worlds.iter().enumerate() {
                let (end, paths) = follow_intent(&t, world);
                for c in t.check_goals(&end, &paths) {
                    assert!(
                        c.holds,
                        "{} layout {i}: {} fails: {}",
                        t.name, c.goal, c.detail
                    );
                }
            }
        }
    }

    #[test]
    fn the_inspection_scan_line_is_grounded_on_the_scanner_it_passes_over() {
        let t = task("inspection").unwrap().unwrap();
        let truth = t.truth.unwrap();
        let lines: Vec<&str> = truth
            .keyframes
            .iter()
            .filter(|k| k.kind == KeyframeKind::Constraint)
            .map(|k| k.reference.as_str())
            .collect();
        assert_eq!(lines, ["scanner_2", "scanner_2"]);
    }

    #[test]
    fn the_clamp_leaves_the_pipe_a_few_millimetres() {
        let t = task("assembly").unwrap().unwrap();
        let (l, r) = (
            t.world.object("clamp_left").unwrap(),
            t.world.object("clamp_right").unwrap(),
        );
        let gap = (l.pose.translation.x - r.pose.translation.x).abs()
            - l.shape.half_extents().x
            - r.shape.half_extents().x;
        let pipe = match t.world.object("pipe").unwrap().shape {
            crate::Shape::Cylinder { radius, .. } => 2.0 * radius,
            _ => panic!("the pipe is a cylinder"),
        };
        let clearance = 0.5 * (gap - pipe);
        assert!(
            clearance > 0.005 && clearance < 0.007,
            "clearance {clearance}"
        );
    }

    #[test]
    fn resolve_names_unknown_tasks_and_lists_the_builtins() {
        let e = resolve("juggling").unwrap_err().to_string();
        assert!(
            e.contains("juggling") && e.contains("pick_place, inspection, assembly"),
            "{e}"
        );
    }
}
