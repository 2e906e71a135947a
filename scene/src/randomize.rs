//! Moving a task's objects to random places within their ranges.

use crate::error::SceneError;
use crate::task::Task;
use crate::world::World;
use akl_tsr::nalgebra::{Translation3, UnitQuaternion, Vector3};
use rand::Rng;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// How far an object may be moved from its place in the task file: offsets along world x and
/// y (metres) and a turn about the world vertical through its centre (radians).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Range {
    /// Offset along world x, `[min, max]`.
    #[serde(default)]
    pub x: [f64; 2],
    /// Offset along world y, `[min, max]`.
    #[serde(default)]
    pub y: [f64; 2],
    /// Turn about world z, `[min, max]`.
    #[serde(default)]
    pub yaw: [f64; 2],
}

/// Randomization ranges by object name.
pub type Ranges = BTreeMap<String, Range>;

/// Placements tried per object before giving up.
pub const MAX_ATTEMPTS: usize = 10_000;

impl Range {
    /// Checks each interval is finite and ordered.
    pub fn validate(&self) -> Result<(), String> {
        for (name, [lo, hi]) in [("x", self.x), ("y", self.y), ("yaw", self.yaw)] {
            if !lo.is_finite() || !hi.is_finite() || lo > hi {
                return Err(format!(
                    "{name} range [{lo}, {hi}] must be finite with min <= max"
                ));
            }
        }
        Ok(())
    }
}

/// The task's world with every object that has a range moved to a random place within it.
///
/// Deterministic per seed (ChaCha8, objects in name order). A placement is kept only if the
/// object overlaps nothing and still rests on the support it stood on in the task file.
pub fn randomize(task: &Task, seed: u64) -> Result<World, SceneError> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut world = task.world.clone();
    for (name, range) in &task.randomize {
        let nominal = task
            .world
            .object(name)
            .ok_or_else(|| SceneError::invalid(format!("randomize.{name}"), "no such object"))?
            .pose;
        let support = task.world.support_of(name).map(|s| s.name.clone());
        let mut placed = false;
        for _ in 0..MAX_ATTEMPTS {
            let dx = sample(&mut rng, range.x);
            let dy = sample(&mut rng, range.y);
            let yaw = sample(&mut rng, range.yaw);
            let mut pose = nominal;
            pose.translation =
                Translation3::from(nominal.translation.vector + Vector3::new(dx, dy, 0.0));
            pose.rotation =
                UnitQuaternion::from_axis_angle(&Vector3::z_axis(), yaw) * nominal.rotation;
            if let Some(o) = world.object_mut(name) {
                o.pose = pose;
            }
            let rests = match &support {
                Some(s) => world.support_of(name).map(|o| &o.name) == Some(s),
                None => true,
            };
            if rests && world.overlaps_any(name).is_none() {
                placed = true;
                break;
            }
        }
        if !placed {
            return Err(SceneError::Randomize {
                object: name.clone(),
                attempts: MAX_ATTEMPTS,
            });
        }
    }
    Ok(world)
}

fn sample(rng: &mut ChaCha8Rng, [lo, hi]: [f64; 2]) -> f64 {
    if hi > lo {
        rng.gen_range(lo..=hi)
    } else {
        lo
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtin;

    #[test]
    fn the_same_seed_gives_the_same_world() {
        let t = builtin::task("pick_place").unwrap().unwrap();
        assert_eq!(randomize(&t, 7).unwrap(), randomize(&t, 7).unwrap());
        assert_ne!(randomize(&t, 7).unwrap(), randomize(&t, 8).unwrap());
    }

    #[test]
    fn objects_stay_in_range_on_their_support_and_apart() {
        for name in builtin::names() {
            let t = builtin::task(name).unwrap().unwrap();
            for seed in 0..200 {
                let w = randomize(&t, seed).unwrap();
                assert!(
                    w.overlapping_pairs().is_empty(),
                    "{name} seed {seed}: {:?}",
                    w.overlapping_pairs()
                );
                for (obj, range) in &t.randomize {
                    let before = t.world.object(obj).unwrap();
                    let after = w.object(obj).unwrap();
                    let d = after.pose.translation.vector - before.pose.translation.vector;
                    assert!(d.x >= range.x[0] - 1e-12 && d.x <= range.x[1] + 1e-12);
                    assert!(d.y >= range.y[0] - 1e-12 && d.y <= range.y[1] + 1e-12);
                    assert!(d.z.abs() < 1e-12);
                    let yaw = before
                        .pose
                        .rotation
                        .rotation_to(&after.pose.rotation)
                        .angle();
                    assert!(yaw <= range.yaw[1].abs().max(range.yaw[0].abs()) + 1e-9);
                    assert_eq!(
                        w.support_of(obj).map(|s| &s.name),
                        t.world.support_of(obj).map(|s| &s.name),
                        "{name} seed {seed}: {obj} left its support"
                    );
                }
                for fixed in t
                    .world
                    .objects
                    .iter()
                    .filter(|o| !t.randomize.contains_key(&o.name))
                {
                    assert_eq!(w.object(&fixed.name).unwrap().pose, fixed.pose);
                }
            }
        }
    }

    #[test]
    fn impossible_ranges_fail_with_the_object_named() {
        let mut t = builtin::task("pick_place").unwrap().unwrap();
        // Force block_a onto block_b's spot and forbid any other place.
        let b = t.world.object("block_b").unwrap().pose.translation.vector;
        let a = t.world.object("block_a").unwrap().pose.translation.vector;
        let r = t.randomize.get_mut("block_a").unwrap();
        r.x = [b.x - a.x; 2];
        r.y = [b.y - a.y; 2];
        let e = randomize(&t, 1).unwrap_err().to_string();
        assert!(e.contains("block_a"), "{e}");
    }
}
