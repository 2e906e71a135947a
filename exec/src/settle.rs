//! Scenes that stand still: a task's world, simulated untouched, must stay as it was written.
//!
//! A scene that only the simulation can show to be wrong (a cube 5 cm above its support, a
//! bottle standing half over a shelf's edge) would otherwise load silently and fail later as
//! something else (a grasp that closes on nothing, a collision with an object already falling).
//! So a task's world, and every randomized layout of it, is simulated for
//! [`SETTLE_SECONDS`] with nothing touching it, and any movable object of which some point
//! moves by more than [`SETTLE_TOLERANCE`] is reported: it fell, tipped or slid.

use crate::world::{Physics, SimWorld};
use akl_scene::World;
use akl_tsr::nalgebra::{Point3, Vector3};
use akl_tsr::Pose;
use thiserror::Error;

/// Simulated seconds a scene is left untouched.
pub const SETTLE_SECONDS: f64 = 1.0;

/// How far (metres) any point of a movable object may move while the scene settles.
pub const SETTLE_TOLERANCE: f64 = 1e-3;

/// Turn (radians) beyond which a moving object is said to have tipped rather than slid.
const TIPPED: f64 = 0.02;

/// A movable object that does not stay where the scene puts it.
#[derive(Debug, Clone, PartialEq, Error)]
#[error(
    "{object} does not stay where it is put: left untouched, it {what} within {SETTLE_SECONDS} s"
)]
pub struct Unsettled {
    /// The object.
    pub object: String,
    /// What it did, in words (`fell 4.9 cm`, `tipped 0.31 rad`, `slid 3.2 mm`).
    pub what: String,
    /// How far its furthest point moved (metres).
    pub moved: f64,
}

/// How far the furthest corner of a box of half extents `half` moved from `from` to `to`.
fn corner_motion(half: &Vector3<f64>, from: &Pose, to: &Pose) -> f64 {
    (0..8)
        .map(|i| {
            let sign = |bit: usize| if i & bit == 0 { -1.0 } else { 1.0 };
            let corner = Point3::new(sign(1) * half.x, sign(2) * half.y, sign(4) * half.z);
            (to.transform_point(&corner) - from.transform_point(&corner)).norm()
        })
        .fold(0.0, f64::max)
}

/// Simulates `world` untouched for [`SETTLE_SECONDS`]; the first movable object (in the
/// world's order) that moved by more than [`SETTLE_TOLERANCE`], if any.
pub fn check_settles(world: &World, physics: &Physics) -> Result<(), Unsettled> {
    let mut sim = SimWorld::new(world, physics);
    let movable: Vec<usize> = (0..world.objects.len())
        .filter(|&i| world.objects[i].movable)
        .collect();
    if movable.is_empty() {
        return Ok(());
    }
    let mut worst = vec![0.0f64; world.objects.len()];
    while sim.time() < SETTLE_SECONDS - 0.5 * sim.dt() {
        sim.step();
        for &i in &movable {
            let o = &world.objects[i];
            let moved = corner_motion(&o.shape.half_extents(), &o.pose, &sim.object_pose(i));
            worst[i] = worst[i].max(moved);
        }
    }
    let Some(&i) = movable.iter().find(|&&i| worst[i] > SETTLE_TOLERANCE) else {
        return Ok(());
    };
    let o = &world.objects[i];
    let end = sim.object_pose(i);
    let drop = o.pose.translation.z - end.translation.z;
    let turn = o.pose.rotation.angle_to(&end.rotation);
    let what = if turn > TIPPED {
        format!("tipped {turn:.2} rad")
    } else if drop > 0.5 * worst[i] {
        format!("fell {:.1} cm", drop * 1e2)
    } else {
        let slid = (end.translation.vector - o.pose.translation.vector).norm();
        format!("slid {:.1} mm", slid.max(worst[i]) * 1e3)
    };
    Err(Unsettled {
        object: o.name.clone(),
        what,
        moved: worst[i],
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_scene::builtin;

    #[test]
    fn the_built_in_worlds_stand_still() {
        for name in builtin::names() {
            let task = builtin::task(name).unwrap().unwrap();
            assert_eq!(
                check_settles(&task.world, &Physics::default()),
                Ok(()),
                "{name}"
            );
        }
    }

    #[test]
    fn a_block_in_the_air_falls_and_is_named() {
        let mut world = builtin::task("pick_place").unwrap().unwrap().world;
        let block = world.object_mut("block_a").unwrap();
        block.pose.translation.z += 0.05;
        let e = check_settles(&world, &Physics::default()).unwrap_err();
        assert_eq!(e.object, "block_a");
        assert!(e.what.starts_with("fell "), "{e}");
        assert!(e.to_string().contains("block_a does not stay"), "{e}");
    }

    #[test]
    fn a_block_over_its_shelfs_edge_tips() {
        let mut world = builtin::task("pick_place").unwrap().unwrap().world;
        let shelf = world.object("shelf_1").unwrap().clone();
        let edge = shelf.pose.translation.x + shelf.shape.half_extents().x;
        let block = world.object_mut("block_a").unwrap();
        // Its centre 1 cm beyond the edge.
        block.pose.translation.x = edge + 0.01;
        let e = check_settles(&world, &Physics::default()).unwrap_err();
        assert_eq!(e.object, "block_a");
        assert!(
            e.what.starts_with("tipped ") || e.what.starts_with("fell "),
            "{e}"
        );
    }

    #[test]
    fn every_randomized_layout_is_checked_and_one_that_never_settles_is_an_error() {
        let mut task = builtin::task("pick_place").unwrap().unwrap();
        task.world.object_mut("block_a").unwrap().pose.translation.z += 0.05;
        let e = crate::trial::trial_world(&task, true, 0, &Physics::default()).unwrap_err();
        assert!(e.to_string().contains("block_a does not stay"), "{e}");
    }
}
