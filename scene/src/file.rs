//! Task files: reading one (with its mesh files and ground truth) and checking every rule the
//! JSON shape cannot express, the task file's own layout included.

use crate::error::SceneError;
use crate::intent::TeachStep;
use crate::layout::{check_layout, Infeasible};
use crate::motion::Motion;
use crate::task::{Task, TASK_VERSION};
use crate::world::{Object, World};
use akl_tsr::{FileError, TaskSpec, WORLD_FRAME};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// An obstacle file: objects in a task file's world-object format, on their own.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObstacleFile {
    objects: Vec<Object>,
}

/// Reads an obstacle file, `{"objects": [...]}` with each object as a task file's world
/// gives it, poses in the robot base frame: a world with the robot at its origin. Mesh shapes
/// are found relative to the file; errors name the file and the line or object.
pub fn load_obstacles(path: &Path) -> Result<World, FileError<SceneError>> {
    let wrap = |source| FileError {
        path: path.to_path_buf(),
        source,
    };
    let text = std::fs::read_to_string(path).map_err(|e| wrap(SceneError::Io(e)))?;
    let file: ObstacleFile =
        serde_json::from_str(&text).map_err(|e| wrap(SceneError::from_json(&e, &text)))?;
    let folder = path.parent().unwrap_or(Path::new("."));
    let mut names = std::collections::BTreeSet::new();
    let mut objects = file.objects;
    for (i, o) in objects.iter_mut().enumerate() {
        let at = |problem: String| {
            wrap(SceneError::invalid(
                format!("objects[{i}] ({})", o.name),
                problem,
            ))
        };
        if !names.insert(o.name.clone()) {
            return Err(at("another object has this name".into()));
        }
        o.shape.resolve(folder).map_err(|e| at(e.to_string()))?;
        o.shape.validate().map_err(|e| at(e.to_string()))?;
    }
    Ok(World {
        robot_base: akl_tsr::Pose::identity(),
        objects,
    })
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

    /// Checks the invariants the JSON shape cannot express; errors name the field. The task
    /// file's own layout must keep the layout rules every randomized layout is held to.
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
pub(crate) fn truth_path_for(path: &Path) -> PathBuf {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    path.with_file_name(format!("{stem}.truth.json"))
}
