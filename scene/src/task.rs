//! Task files: `tasks/<name>.json` (versioned `akl_task: 1`) with an optional ground-truth
//! spec beside them in `tasks/<name>.truth.json`.

use crate::error::SceneError;
use crate::goal::{Goal, GoalCheck};
use crate::intent::Teaching;
use crate::paths::ObjectPaths;
use crate::range::{Groups, Ranges};
use crate::reach::Reach;
use crate::world::World;
use akl_tsr::{FileError, TaskSpec};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// The `akl_task` version this build reads and writes.
pub const TASK_VERSION: u32 = 1;

/// A task: a world, what may move, what must hold at the end, how it is demonstrated, and
/// (when known) its ground-truth least restrictive spec.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Task {
    /// Format version; always [`TASK_VERSION`].
    pub akl_task: u32,
    /// Short name, e.g. `inspection`.
    pub name: String,
    /// What the task is, as told to a teacher.
    pub description: String,
    /// The scene as laid out in the file.
    pub world: World,
    /// Rigid groups of furniture that randomization moves as one body, by group name.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub groups: Groups,
    /// How far each listed object or group may be moved by randomization.
    #[serde(default)]
    pub randomize: Ranges,
    /// Clearance (metres) the hand needs between movable objects: randomized layouts keep
    /// every two movable objects at least this far apart.
    #[serde(default)]
    pub min_gap: f64,
    /// Where the robot can work; every layout keeps the teaching's targets within it.
    #[serde(default)]
    pub reach: Reach,
    /// What must hold once the task has been executed.
    pub goals: Vec<Goal>,
    /// How a simulated teacher demonstrates the task.
    pub teaching: Teaching,
    /// The ground-truth least restrictive spec, from `<name>.truth.json` when present.
    #[serde(skip)]
    pub truth: Option<TaskSpec>,
}

impl Task {
    /// Attaches a ground-truth spec after checking that it is for this task and grounded on
    /// objects the world has.
    pub fn set_truth(&mut self, truth: TaskSpec, path: &Path) -> Result<(), SceneError> {
        let in_truth = |source| {
            SceneError::Truth(FileError {
                path: path.to_path_buf(),
                source,
            })
        };
        truth
            .check_references(self.world.names())
            .map_err(in_truth)?;
        if truth.task != self.name {
            return Err(in_truth(akl_tsr::SpecError::Invalid {
                location: "task".into(),
                problem: format!("is `{}`, expected `{}`", truth.task, self.name),
            }));
        }
        self.truth = Some(truth);
        Ok(())
    }

    /// The task as pretty JSON (without its ground truth, which lives in its own file).
    pub fn to_json(&self) -> String {
        akl_tsr::io::to_readable_json(self).expect("a task always serializes")
    }

    /// Checks every goal at the end of an execution: `end` is the settled world, `paths` the
    /// sampled paths of the objects (see [`ObjectPaths`]); the task file's world says which
    /// way up objects stand.
    pub fn check_goals(&self, end: &World, paths: &ObjectPaths) -> Vec<GoalCheck> {
        self.goals
            .iter()
            .map(|g| g.check(end, paths, &self.world))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::{json, Value};

    /// A built-in task file as JSON, to edit.
    fn file(name: &str) -> Value {
        let text = match name {
            "pick_place" => include_str!("../../tasks/pick_place.json"),
            "inspection" => include_str!("../../tasks/inspection.json"),
            _ => include_str!("../../tasks/assembly.json"),
        };
        serde_json::from_str(text).unwrap()
    }

    /// The location and problem the edited task is rejected for.
    fn rejected(v: &Value) -> (String, String) {
        match Task::from_json(&v.to_string()) {
            Err(SceneError::Invalid { location, problem }) => (location, problem),
            other => panic!("expected an invalid value, got {other:?}"),
        }
    }

    #[test]
    fn the_built_in_files_round_trip() {
        for name in ["pick_place", "inspection", "assembly"] {
            let task = Task::from_json(&file(name).to_string()).unwrap();
            assert_eq!(Task::from_json(&task.to_json()).unwrap(), task, "{name}");
        }
    }

    #[test]
    fn bad_groups_are_named_by_field() {
        let mut v = file("inspection");
        v["groups"]["scanners"][1] = json!("scanner_9");
        let (at, why) = rejected(&v);
        assert_eq!(at, "groups.scanners[1]");
        assert!(why.contains("scanner_9"), "{why}");

        let mut v = file("inspection");
        v["groups"]["scanners"][2] = json!("part");
        let (at, why) = rejected(&v);
        assert_eq!(at, "groups.scanners[2]");
        assert!(why.contains("movable"), "{why}");

        let mut v = file("inspection");
        v["groups"]["row"] = json!(["scanner_3", "shelf_2"]);
        let (at, why) = rejected(&v);
        assert_eq!(at, "groups.scanners[2]");
        assert!(why.contains("already in group `row`"), "{why}");

        let mut v = file("inspection");
        v["groups"]["shelf_1"] = json!(["table", "shelf_2"]);
        assert_eq!(rejected(&v).0, "groups.shelf_1");

        let mut v = file("inspection");
        v["groups"]["scanners"] = json!(["scanner_1"]);
        assert!(rejected(&v).1.contains("at least two"));
    }

    #[test]
    fn bad_ranges_are_named_by_field() {
        let mut v = file("inspection");
        v["randomize"]["scanner_1"] = json!({"x": [-0.01, 0.01]});
        let (at, why) = rejected(&v);
        assert_eq!(at, "randomize.scanner_1");
        assert!(why.contains("group `scanners`"), "{why}");

        let mut v = file("inspection");
        v["randomize"]["lamp"] = json!({"x": [-0.01, 0.01]});
        assert_eq!(rejected(&v).0, "randomize.lamp");

        let mut v = file("inspection");
        v["randomize"]["shelf_2"]["yaw"] = json!([0.1, -0.1]);
        assert_eq!(rejected(&v).0, "randomize.shelf_2.yaw");
    }

    #[test]
    fn bad_layout_rules_are_named_by_field() {
        let mut v = file("pick_place");
        v["min_gap"] = json!(-0.01);
        assert_eq!(rejected(&v).0, "min_gap");

        // The blocks stand 6 cm apart in the file: a 10 cm clearance rules out its own layout.
        let mut v = file("pick_place");
        v["min_gap"] = json!(0.1);
        let (at, why) = rejected(&v);
        assert_eq!(at, "min_gap");
        assert!(
            why.contains("own layout") && why.contains("block_a"),
            "{why}"
        );

        let mut v = file("pick_place");
        v["reach"] = json!({"shoulder": [0, 0, 0.333], "max": 0.0, "min_radial": 0.25});
        assert_eq!(rejected(&v).0, "reach.max");

        let mut v = file("pick_place");
        v["reach"] = json!({"shoulder": [0, 0, 0.333], "max": 0.5, "min_radial": 0.25});
        let (at, why) = rejected(&v);
        assert!(at.starts_with("teaching.steps["), "{at}");
        assert!(why.contains("beyond reach"), "{why}");
    }

    #[test]
    fn bad_goals_are_named_by_field() {
        let mut v = file("inspection");
        v["goals"][0]["scan"]["height"] = json!([0.08, 0.02]);
        assert_eq!(rejected(&v).0, "goals[0] (scan).height");

        let mut v = file("inspection");
        v["goals"][0]["scan"]["scanners"][1] = json!("scanner_7");
        let (at, why) = rejected(&v);
        assert_eq!(at, "goals[0] (scan)");
        assert!(why.contains("scanner_7"), "{why}");

        let mut v = file("assembly");
        v["goals"][1]["inside"]["max_offset"] = json!(0.0);
        assert_eq!(rejected(&v).0, "goals[1] (inside).max_offset");

        let mut v = file("assembly");
        v["goals"][1]["inside"]["axis"] = json!([[0, 0, 0], [0, 0, 0]]);
        assert_eq!(rejected(&v).0, "goals[1] (inside).axis");

        let mut v = file("pick_place");
        v["goals"][2]["apart"]["objects"] = json!(["block_a", "block_a"]);
        assert_eq!(rejected(&v).0, "goals[2] (apart).objects");

        let mut v = file("pick_place");
        v["goals"][0]["on"]["max_tilt"] = json!(-1.0);
        assert_eq!(rejected(&v).0, "goals[0] (on).max_tilt");
    }

    #[test]
    fn unknown_goal_fields_are_json_errors_with_their_line() {
        let mut v = file("inspection");
        v["goals"][0]["scan"]["speed"] = json!(1.0);
        match Task::from_json(&v.to_string()) {
            Err(SceneError::Json { message, .. }) => {
                assert!(message.contains("speed"), "{message}")
            }
            other => panic!("{other:?}"),
        }
    }
}
