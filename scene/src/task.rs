//! Task files: `tasks/<name>.json` (versioned `akl_task: 1`) with an optional ground-truth
//! spec beside them in `tasks/<name>.truth.json`.

use crate::error::SceneError;
use crate::goal::Goal;
use crate::intent::{TeachStep, Teaching};
use crate::randomize::Ranges;
use crate::world::World;
use akl_tsr::{FileError, TaskSpec, WORLD_FRAME};
use serde::{Deserialize, Serialize};
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
    /// How far each listed object may be moved by randomization.
    #[serde(default)]
    pub randomize: Ranges,
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
    /// Parses and validates a task from JSON text (without its ground truth).
    pub fn from_json(text: &str) -> Result<Self, SceneError> {
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
        let task: Task = serde_json::from_str(text).map_err(|e| SceneError::from_json(&e, text))?;
        task.validate()?;
        Ok(task)
    }

    /// Loads a task file and, if present, the ground truth beside it; errors name the file.
    pub fn load(path: &Path) -> Result<Self, FileError<SceneError>> {
        let wrap = |source| FileError {
            path: path.to_path_buf(),
            source,
        };
        let text = std::fs::read_to_string(path).map_err(|e| wrap(SceneError::Io(e)))?;
        let mut task = Self::from_json(&text).map_err(wrap)?;
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

    /// Checks the invariants the JSON shape cannot express; errors name the field.
    pub fn validate(&self) -> Result<(), SceneError> {
        if self.name.trim().is_empty() {
            return Err(SceneError::invalid("name", "is empty"));
        }
        self.world
            .validate()
            .map_err(|(location, problem)| SceneError::Invalid { location, problem })?;
        let known = |name: &str| name == WORLD_FRAME || self.world.object(name).is_some();
        for (name, range) in &self.randomize {
            let at = format!("randomize.{name}");
            match self.world.object(name) {
                None => return Err(SceneError::invalid(at, "no such object")),
                Some(o) if !o.movable => {
                    return Err(SceneError::invalid(
                        at,
                        "only movable objects are randomized",
                    ))
                }
                Some(_) => range.validate().map_err(|p| SceneError::invalid(at, p))?,
            }
        }
        for (i, goal) in self.goals.iter().enumerate() {
            if let Some(name) = goal.objects().into_iter().find(|n| !known(n)) {
                return Err(SceneError::invalid(
                    format!("goals[{i}]"),
                    format!("unknown object `{name}`"),
                ));
            }
        }
        self.validate_teaching()
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
