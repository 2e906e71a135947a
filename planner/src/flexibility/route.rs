//! The task's step budget: a trace may take a fixed multiple of the steps of the shortest
//! lattice walk along the task's teaching route (from the start through every teaching step's
//! target in order, and back). The route belongs to the task, not to a spec, so every spec of a
//! task is counted within the same budget.

use super::lattice::Lattice;
use super::FlexibilityError;
use akl_scene::Task;

/// Steps of the shortest walk from `start` through the cells of the task's teaching targets
/// in order and back to `start`.
pub(super) fn route_steps(
    lattice: &Lattice,
    task: &Task,
    start: u32,
) -> Result<usize, FlexibilityError> {
    let targets = task
        .teaching
        .targets(&task.world)
        .map_err(|e| FlexibilityError::Workspace(e.to_string()))?;
    let mut stops = vec![start];
    for (i, pose) in targets.iter().enumerate() {
        let cell = lattice.cell_at(&pose.translation.vector).ok_or_else(|| {
            FlexibilityError::Workspace(format!(
                "teaching.steps[{i}]: its target is outside the workspace lattice or inside furniture"
            ))
        })?;
        stops.push(cell);
    }
    stops.push(start);
    let mut steps = 0usize;
    for (i, w) in stops.windows(2).enumerate() {
        let d = lattice.distances(&[(w[0], 0)])[w[1] as usize];
        if d == u32::MAX {
            let to = if i < targets.len() {
                format!("the target of teaching.steps[{i}]")
            } else {
                "the start".to_string()
            };
            return Err(FlexibilityError::Workspace(format!(
                "no lattice walk reaches {to} from the stop before it"
            )));
        }
        steps += d as usize;
    }
    Ok(steps)
}
