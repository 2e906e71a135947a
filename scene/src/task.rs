//! Task files: `tasks/<name>.json` (versioned `akl_task: 1`) with an optional ground-truth
//! spec beside them in `tasks/<name>.truth.json`.

use crate::error::SceneError;
use crate::goal::{Goal, GoalCheck};
use crate::intent::{TeachStep, Teaching};
use crate::layout::{check_layout, Infeasible, Reach};
use crate::motion::{FixedRelation, Motion};
use crate::paths::ObjectPaths;
use crate::range::{Groups, Ranges};
use crate::world::World;
use akl_tsr::{FileError, TaskSpec, WORLD_FRAME};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

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

#[derive(Deserialize)]
struct VersionProbe {
    akl_task: Option<serde_json::Value>,
}

impl Task {
    /// Parses and validates a task from JSON text (without its ground truth). Mesh shapes
    /// need the task's file to find theirs: see [`Task::load`].
    pub fn from_json(text: &str) -> Result<Self, SceneError> {
        let task = Self::parse(text)?;
        task.validate()?;
        Ok(task)
    }

    /// Parses a task from JSON text, checking its version, without validating it.
    fn parse(text: &str) -> Result<Self, SceneError> {
        let probe: VersionProbe =
            serde_json::from_str(text).map_err(|e| SceneError::from_json(&e, text))?;
        match probe.akl_task {
            Some(v) if v.as_u64() == Some(u64::from(TASK_VERSION)) => {}
            other => {
                return Err(SceneError::UnsupportedVersion {
                    found: other.map_or("missing (no `akl_task` field)".into(), |v| v.to_string()),
                    expected: TASK_VERSION,
                })
            }
        }
        serde_json::from_str(text).map_err(|e| SceneError::from_json(&e, text))
    }

    /// Loads a task file, the mesh files its shapes name (relative to the task file's folder)
    /// and, if present, the ground truth beside it; errors name the file.
    pub fn load(path: &Path) -> Result<Self, FileError<SceneError>> {
        let wrap = |source| FileError {
            path: path.to_path_buf(),
            source,
        };
        let text = std::fs::read_to_string(path).map_err(|e| wrap(SceneError::Io(e)))?;
        let mut task = Self::parse(&text).map_err(wrap)?;
        let folder = path.parent().unwrap_or(Path::new("."));
        for (i, o) in task.world.objects.iter_mut().enumerate() {
            o.shape.resolve(folder).map_err(|e| {
                wrap(SceneError::invalid(
                    format!("world.objects[{i}] ({}).shape", o.name),
                    e.to_string(),
                ))
            })?;
        }
        task.validate().map_err(wrap)?;
        let truth_path = truth_path_for(path);
        if truth_path.exists() {
            let truth = TaskSpec::load(&truth_path).map_err(|e| wrap(SceneError::Truth(e)))?;
            task.set_truth(truth, &truth_path).map_err(wrap)?;
        }
        Ok(task)
    }

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

    /// Checks the invariants the JSON shape cannot express; errors name the field. The task
    /// file's own layout must be one the task can be done in (see [`check_layout`]).
    pub fn validate(&self) -> Result<(), SceneError> {
        if self.name.trim().is_empty() {
            return Err(SceneError::invalid("name", "is empty"));
        }
        self.world
            .validate()
            .map_err(|(location, problem)| SceneError::Invalid { location, problem })?;
        self.validate_groups()?;
        self.validate_ranges()?;
        if !self.min_gap.is_finite() || self.min_gap < 0.0 {
            return Err(SceneError::invalid(
                "min_gap",
                format!("must be finite and >= 0, got {}", self.min_gap),
            ));
        }
        self.reach
            .validate()
            .map_err(|(field, problem)| SceneError::invalid(format!("reach.{field}"), problem))?;
        for (i, goal) in self.goals.iter().enumerate() {
            goal.validate(&self.world).map_err(|(field, problem)| {
                let at = format!("goals[{i}] ({})", goal.kind());
                let location = if field.is_empty() {
                    at
                } else {
                    format!("{at}.{field}")
                };
                SceneError::Invalid { location, problem }
            })?;
        }
        self.validate_teaching()?;
        Motion::of(self)?;
        check_layout(self, &self.world).map_err(|why| {
            let location = match &why {
                Infeasible::TooClose { .. } => "min_gap".to_string(),
                Infeasible::OutOfReach { step, .. } | Infeasible::TooNearBase { step, .. } => {
                    format!("teaching.steps[{step}]")
                }
                _ => "world".to_string(),
            };
            SceneError::invalid(location, format!("in the task file's own layout, {why}"))
        })
    }

    fn validate_groups(&self) -> Result<(), SceneError> {
        let mut group_of: BTreeMap<&str, &str> = BTreeMap::new();
        for (name, members) in &self.groups {
            let at = format!("groups.{name}");
            if name.trim().is_empty() || name == WORLD_FRAME || self.world.object(name).is_some() {
                return Err(SceneError::invalid(
                    at,
                    "a group's name must be non-empty and differ from `world` and every object's",
                ));
            }
            if members.len() < 2 {
                return Err(SceneError::invalid(
                    at,
                    "a group needs at least two objects",
                ));
            }
            for (i, member) in members.iter().enumerate() {
                let at = format!("groups.{name}[{i}]");
                match self.world.object(member) {
                    None => {
                        return Err(SceneError::invalid(at, format!("no object `{member}`")))
                    }
                    Some(o) if o.movable => {
                        return Err(SceneError::invalid(
                            at,
                            format!(
                                "`{member}` is movable; only furniture forms rigid groups (a movable object rides on its support)"
                            ),
                        ))
                    }
                    Some(_) => {}
                }
                if let Some(other) = group_of.insert(member, name) {
                    return Err(SceneError::invalid(
                        at,
                        format!("`{member}` is already in group `{other}`"),
                    ));
                }
            }
        }
        Ok(())
    }

    fn validate_ranges(&self) -> Result<(), SceneError> {
        for (name, range) in &self.randomize {
            let at = format!("randomize.{name}");
            let grouped = self
                .groups
                .iter()
                .find(|(_, members)| members.contains(name));
            if let Some((group, _)) = grouped {
                return Err(SceneError::invalid(
                    at,
                    format!("`{name}` moves with group `{group}`; give the range to the group"),
                ));
            }
            if !self.groups.contains_key(name) && self.world.object(name).is_none() {
                return Err(SceneError::invalid(at, "no such object or group"));
            }
            range.validate().map_err(|(field, problem)| {
                SceneError::invalid(format!("{at}.{field}"), problem)
            })?;
        }
        Ok(())
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

    /// How randomization moves this task's objects: movers, carriers and ranges.
    pub fn motion(&self) -> Result<Motion, SceneError> {
        Motion::of(self)
    }

    /// The sets of objects that every randomized layout keeps in one fixed relation: the
    /// members of a rigid group, what stands without a range of its own on something that
    /// moves (with it), and everything not moved at all (with `world`). A keyframe grounded on
    /// one member of a set lands where it would grounded on another, so re-grounding between
    /// them is an equivalent grounding, not an error randomization can reveal. Relations that
    /// only the execution creates (an object placed relative to another) are not included:
    /// they depend on the spec. Only sets of two or more names are listed.
    pub fn fixed_relations(&self) -> Result<Vec<FixedRelation>, SceneError> {
        Ok(Motion::of(self)?.fixed_relations(&self.world))
    }

    /// Whether every randomized layout keeps `a` and `b` (object names or `world`) in one
    /// fixed relation (see [`Task::fixed_relations`]).
    pub fn held_together(&self, a: &str, b: &str) -> Result<bool, SceneError> {
        Ok(a == b
            || self
                .fixed_relations()?
                .iter()
                .any(|r| r.members.iter().any(|m| m == a) && r.members.iter().any(|m| m == b)))
    }

    fn validate_teaching(&self) -> Result<(), SceneError> {
        let mut holding: Option<&str> = None;
        for (i, step) in self.teaching.steps.iter().enumerate() {
            let at = format!("teaching.steps[{i}]");
            for name in step.objects() {
                if name != WORLD_FRAME && self.world.object(name).is_none() {
                    return Err(SceneError::invalid(at, format!("unknown object `{name}`")));
                }
            }
            match step {
                TeachStep::Grasp { object, .. } => {
                    if let Some(held) = holding {
                        return Err(SceneError::invalid(
                            at,
                            format!("grasps {object} while still holding {held}"),
                        ));
                    }
                    if !self.world.object(object).is_some_and(|o| o.movable) {
                        return Err(SceneError::invalid(at, format!("{object} is not movable")));
                    }
                    holding = Some(object);
                }
                TeachStep::Release { .. } => {
                    if holding.take().is_none() {
                        return Err(SceneError::invalid(at, "releases while holding nothing"));
                    }
                }
                TeachStep::Move { .. } | TeachStep::Line { .. } => {}
            }
        }
        Ok(())
    }
}

/// Where the ground truth of the task file at `path` lives: `<stem>.truth.json` beside it.
pub fn truth_path_for(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!("{stem}.truth.json"))
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
