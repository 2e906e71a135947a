//! The paths objects took during an execution, as goals that speak of motion read them.

use crate::world::World;
use akl_tsr::Pose;
use std::collections::BTreeMap;

/// One sample of an object's path: its world pose at simulated time `t` (seconds).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathSample {
    /// Simulated time of the sample (seconds).
    pub t: f64,
    /// The object's pose in the world frame at that time.
    pub pose: Pose,
}

/// The sampled paths of objects over one execution: for each object name, its world poses in
/// time order.
///
/// The simulation fills it while it runs (with [`ObjectPaths::push`] per object, or
/// [`ObjectPaths::record`] for a whole world, every step or every few steps) and hands it to
/// [`crate::Task::check_goals`] with the settled end world. Goals interpolate linearly between
/// samples, so the rate only has to resolve the motion, not the objects' sizes: a curve sampled
/// too sparsely looks straighter than it was. Sampling every physics step (1/240 s, under a
/// millimetre of travel) is what the old execution engine does.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ObjectPaths {
    paths: BTreeMap<String, Vec<PathSample>>,
}

impl ObjectPaths {
    /// No paths yet.
    pub fn new() -> ObjectPaths {
        ObjectPaths::default()
    }

    /// Adds a sample of `object`'s path; samples are kept in time order whatever order they
    /// arrive in.
    pub fn push(&mut self, object: &str, t: f64, pose: Pose) {
        let sample = PathSample { t, pose };
        let path = match self.paths.get_mut(object) {
            Some(path) => path,
            None => self.paths.entry(object.to_string()).or_default(),
        };
        let at = path.partition_point(|s| s.t <= t);
        path.insert(at, sample);
    }

    /// Adds a sample at time `t` for every movable object of `world` (furniture does not move
    /// during an execution).
    pub fn record(&mut self, t: f64, world: &World) {
        for o in world.objects.iter().filter(|o| o.movable) {
            self.push(&o.name, t, o.pose);
        }
    }

    /// The samples of `object`'s path in time order; empty when none were recorded.
    pub fn path(&self, object: &str) -> &[PathSample] {
        self.paths.get(object).map_or(&[], Vec::as_slice)
    }

    /// The names of the objects that have a path.
    pub fn objects(&self) -> impl Iterator<Item = &str> {
        self.paths.keys().map(String::as_str)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_tsr::pose::pose_from_xyz;

    #[test]
    fn samples_stay_in_time_order() {
        let mut paths = ObjectPaths::new();
        paths.push("part", 0.2, pose_from_xyz([0.2, 0.0, 0.0]));
        paths.push("part", 0.0, pose_from_xyz([0.0, 0.0, 0.0]));
        paths.push("part", 0.1, pose_from_xyz([0.1, 0.0, 0.0]));
        let ts: Vec<f64> = paths.path("part").iter().map(|s| s.t).collect();
        assert_eq!(ts, [0.0, 0.1, 0.2]);
        assert!(paths.path("pipe").is_empty());
        assert_eq!(paths.objects().collect::<Vec<_>>(), ["part"]);
    }

    #[test]
    fn recording_a_world_samples_only_what_can_move() {
        let task = crate::builtin::task("pick_place").unwrap().unwrap();
        let mut paths = ObjectPaths::new();
        paths.record(0.0, &task.world);
        paths.record(0.01, &task.world);
        assert_eq!(paths.objects().collect::<Vec<_>>(), ["block_a", "block_b"]);
        assert_eq!(paths.path("block_a").len(), 2);
    }
}
