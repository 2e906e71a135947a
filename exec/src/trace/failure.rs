//! A trace of a trial whose planning failed: every keyframe's TSR grounded on the perceived
//! world, and the arm at rejected IK solutions of the keyframe that failed, each labelled with
//! what it collides with.

use akl_foxglove::{Log, LogLevel, SceneUpdate, WriteError};
use akl_planner::collision::{Checker, RobotCollision, Scene};
use akl_planner::contact_rules::Step;
use akl_planner::{PlanError, Robot};
use akl_scene::World;
use akl_tsr::nalgebra::Translation3;

use super::draw::{Primitives, FAIL, GHOST, PASS};
use super::{Outbox, TraceInput, LOG_NAME};

/// IK solutions of a failed keyframe drawn in a planning-failure trace.
const GHOSTS: usize = 6;

/// Puts into `out` the planning failure on `/events`, every keyframe's TSR grounded on the
/// perceived world on `/keyframes`, and for the keyframe that failed, the arm at rejected IK
/// solutions on `/rejected`.
pub(super) fn planning_failure(
    input: &TraceInput,
    failure: &PlanError,
    out: &mut Outbox,
) -> Result<(), WriteError> {
    let seen = input.timeline.perceived.as_ref().unwrap_or(input.world);
    let poses = seen.object_poses();
    let failed = failure.keyframe();
    let said = Log::new(
        0.0,
        LogLevel::Error,
        LOG_NAME,
        format!("planning failed: {failure}"),
    );
    out.push(out.channels.events, 0.0, &said)?;
    let Ok(grounded) = input.spec.ground(&poses) else {
        return Ok(());
    };
    for (k, kf) in grounded.keyframes.iter().enumerate() {
        let mut p = Primitives::default();
        let rgba = if Some(k) == failed { FAIL } else { PASS };
        let nominal = p.tsr_region(&kf.tsr.t0_w, &kf.tsr, rgba);
        p.text(
            &(Translation3::new(0.0, 0.0, 0.04) * nominal),
            &format!("keyframe {k}"),
        );
        let id = format!("keyframe {k}");
        let update = SceneUpdate::new(vec![p.entity(0.0, "world", &id, false)]);
        out.push(out.channels.keyframes, 0.0, &update)?;
    }
    if let Some(kf) = failed.and_then(|k| grounded.keyframes.get(k)) {
        out.push(out.channels.rejected, 0.0, &rejected(input.robot, seen, kf))?;
    }
    Ok(())
}

/// The arm at IK solutions of `kf`'s nominal pose in `world`, each with its first collision.
fn rejected(robot: &Robot, world: &World, kf: &akl_tsr::Keyframe) -> SceneUpdate {
    let model = RobotCollision::new(robot);
    let scene = Scene::new(world, &[]);
    let checker = Checker::new(robot, &model, &scene);
    let grasping = (kf.gripper == akl_tsr::Gripper::Closed).then_some(kf.reference.as_str());
    let allow = Step {
        grasping,
        ..Step::default()
    }
    .allowances();
    let target = world.robot_base.inverse() * kf.tsr.nominal();
    let mut entities = Vec::new();
    for (n, q) in robot
        .ik_solutions(&target, robot.ready(), GHOSTS)
        .iter()
        .enumerate()
    {
        let hit = checker.check(q, robot.open_width(), None, &allow);
        let mut p = Primitives::default();
        let links = robot.link_poses(q, robot.open_width());
        for (link, at) in robot.links().iter().zip(&links) {
            for s in &link.shapes {
                p.geometry(&s.geometry, &(world.robot_base * at * s.origin), GHOST);
            }
        }
        let tcp = world.robot_base * links[robot.tcp_link()];
        let what = hit.map_or_else(|| "free".to_string(), |h| h.to_string());
        p.text(
            &(Translation3::new(0.0, 0.0, 0.08 + 0.03 * n as f64) * tcp),
            &format!("IK {n}: {what}"),
        );
        entities.push(p.entity(0.0, "world", &format!("rejected {n}"), false));
    }
    SceneUpdate::new(entities)
}
