//! One simulated run of a plan in the true world: the arm's servos follow the timed plan, the
//! gripper acts when the plan says, contacts are judged every step, and everything the checks
//! need is measured on the simulated bodies ([`Observations`]). After the plan the objects
//! settle for [`ExecOptions::settle`] seconds, longer while one still moves (up to
//! [`ExecOptions::settle_max`]).

mod gripper;
pub(crate) mod observations;

use crate::arm::{PadReading, SimArm};
use crate::contacts::{ContactLog, ContactPoint, ContactRoles, StepContext};
use crate::grasp::read_pads;
use crate::options::{ExecOptions, Setup};
use crate::timeline::{Frame, Timeline};
use crate::world::SimWorld;
use akl_planner::contact_rules::Allowances;
use akl_planner::{Plan, SegmentKind};
use akl_scene::World;
use akl_tsr::pose::position_distance;
use akl_tsr::WORLD_FRAME;
use gripper::Gripper;
pub use observations::{GraspEvent, KeyframeReach, LinePath, Observations, ReleaseEvent};

/// A label for a plan segment, e.g. `free motion to keyframe 2` or `lift after keyframe 0`.
pub(crate) fn segment_label(kind: SegmentKind, keyframe: usize) -> String {
    match kind {
        SegmentKind::Free => format!("free motion to keyframe {keyframe}"),
        SegmentKind::Line => format!("line to keyframe {keyframe}"),
        SegmentKind::Approach => format!("approach to keyframe {keyframe}"),
        SegmentKind::Lift => format!("lift after keyframe {keyframe}"),
        SegmentKind::Retreat => format!("retreat after keyframe {keyframe}"),
        SegmentKind::Gripper => format!("gripper at keyframe {keyframe}"),
    }
}

/// When the plan reaches each keyframe: the end of the last motion segment leading to it.
fn reach_times(plan: &Plan, keyframes: usize) -> Vec<Option<f64>> {
    let mut times = vec![None; keyframes];
    for s in &plan.segments {
        let leads_to = matches!(
            s.kind,
            SegmentKind::Free | SegmentKind::Approach | SegmentKind::Line
        );
        if leads_to && s.keyframe < keyframes {
            times[s.keyframe] = Some(s.end);
        }
    }
    times
}

/// The planned joint velocity at `t` (central difference of the timed plan).
fn planned_velocity(plan: &Plan, t: f64) -> Vec<f64> {
    const H: f64 = 1e-4;
    let (a, b) = ((t - H).max(0.0), (t + H).min(plan.duration));
    if b <= a {
        return vec![0.0; plan.joint_names.len()];
    }
    let (qa, qb) = (plan.sample(a), plan.sample(b));
    qa.iter().zip(&qb).map(|(x, y)| (y - x) / (b - a)).collect()
}

/// Simulates `plan` in `world` (the true placements) and measures the run; records frames
/// into `timeline` when given. `None` when the robot cannot be simulated.
pub fn simulate(
    setup: &Setup,
    world: &World,
    plan: &Plan,
    mut timeline: Option<&mut Timeline>,
) -> Option<Observations> {
    let options: &ExecOptions = setup.options;
    let robot = setup.robot;
    let mut sim = SimWorld::new(world, &options.physics);
    let mut arm = SimArm::new(
        &mut sim,
        robot,
        world.robot_base,
        &plan.sample(0.0),
        plan.gripper_width(0.0),
        &options.drives,
    )?;
    arm.scale_finger_speed(options.plan.speed_scale);
    let mut gripper = Gripper::new(
        plan,
        setup.spec,
        options.grasp,
        options.drives.grasp_force,
        robot.open_width(),
        options.slip_limit,
        robot.links().iter().map(|l| l.name.clone()).collect(),
    );
    let roles = ContactRoles::new(robot, world);
    let labels: Vec<String> = plan
        .segments
        .iter()
        .map(|s| segment_label(s.kind, s.keyframe))
        .collect();
    let settle_label = "settling".to_string();
    let nothing = Allowances::default();
    let mut obs = Observations {
        contacts: ContactLog::default(),
        ..Observations::default()
    };
    let reaches = reach_times(plan, setup.spec.keyframes.len());
    let mut reached = vec![false; reaches.len()];
    let mut lines: Vec<Option<LinePath>> = vec![None; plan.segments.len()];
    let dt = sim.dt();
    let settled_from = plan.duration + options.settle;
    let settle_until = plan.duration + options.settle.max(options.settle_max);
    let path_every = (1.0 / (options.path_rate * dt)).round().max(1.0) as usize;
    let mut square_sum = 0.0;
    let mut tracked = 0usize;
    let mut next_frame = 0.0;
    let mut points: Vec<ContactPoint> = Vec::new();
    if let Some(tl) = timeline.as_deref_mut() {
        tl.plan = Some(plan.clone());
    }
    for step in 0.. {
        let t = sim.time();
        gripper.start_due(t + dt - 1e-9, &mut sim, &mut arm, &mut obs);
        for (k, at) in reaches.iter().enumerate() {
            if let Some(at) = at {
                if !reached[k] && *at <= t + 0.5 * dt {
                    reached[k] = true;
                    obs.reaches.push(reach(setup, &sim, &arm, k, t));
                }
            }
        }
        if step % path_every == 0 {
            for (i, o) in sim.objects.iter().enumerate().filter(|(_, o)| o.movable) {
                obs.paths.push(&o.name, t, sim.object_pose(i));
            }
        }
        if let Some(tl) = timeline.as_deref_mut() {
            if t + 1e-9 >= next_frame {
                tl.frames.push(Frame {
                    t,
                    links: arm.link_poses().to_vec(),
                    objects: (0..sim.objects.len()).map(|i| sim.object_pose(i)).collect(),
                    joints: arm.joint_positions().to_vec(),
                    width: arm.width(),
                    contacts: std::mem::take(&mut points),
                });
                next_frame += 1.0 / tl.rate;
            }
        }
        if t + 0.5 * dt >= settle_until
            || (t + 0.5 * dt >= settled_from && all_resting(&sim, options.rest_speed))
        {
            break;
        }
        let t_next = t + dt;
        let in_plan = t_next <= plan.duration;
        let seg = plan
            .segments
            .partition_point(|s| s.end < t_next)
            .min(plan.segments.len().saturating_sub(1));
        let q = plan.sample(t_next);
        let qd = if in_plan {
            planned_velocity(plan, t_next)
        } else {
            vec![0.0; q.len()]
        };
        let pads = if arm.closing() {
            read_pads(&sim, &arm)
        } else {
            [PadReading::NOTHING; 2]
        };
        arm.advance(&mut sim, robot, (&q, &qd), &pads, dt);
        sim.step();
        gripper.after_step(&mut sim, &mut arm, &mut obs);
        let (allow, during, keyframe) = match plan.segments.get(seg) {
            Some(s) if in_plan => (&s.allowed, &labels[seg], Some(s.keyframe)),
            _ => (&nothing, &settle_label, None),
        };
        let context = StepContext {
            allow,
            held: gripper.held(),
            during,
            keyframe,
            t: t_next,
        };
        let want_points = timeline.is_some();
        obs.contacts.scan(
            &sim,
            &roles,
            &options.contacts,
            &context,
            want_points.then_some(&mut points),
        );
        let tcp = arm.tcp(&sim);
        if in_plan {
            let planned = world.robot_base * robot.tcp_pose(&q);
            let error = position_distance(&tcp, &planned);
            obs.tracking_max = obs.tracking_max.max(error);
            square_sum += error * error;
            tracked += 1;
            if let Some(s) = plan
                .segments
                .get(seg)
                .filter(|s| s.kind == SegmentKind::Line)
            {
                lines[seg]
                    .get_or_insert_with(|| LinePath {
                        keyframe: s.keyframe,
                        start: s.start,
                        end: s.end,
                        points: Vec::new(),
                    })
                    .points
                    .push((t_next, tcp.translation.vector));
            }
        }
    }
    obs.tracking_rms = (square_sum / tracked.max(1) as f64).sqrt();
    obs.lines = lines.into_iter().flatten().collect();
    gripper.finish(&sim, &mut obs);
    obs.settled = Some(sim.snapshot());
    obs.speeds = object_speeds(&sim);
    obs.simulated = sim.time();
    Some(obs)
}

/// Whether every movable object is at rest by the rest check's measure; read every step of
/// the settling, so it allocates nothing.
fn all_resting(sim: &SimWorld, rest_speed: f64) -> bool {
    (0..sim.objects.len())
        .filter(|&i| sim.objects[i].movable)
        .all(|i| {
            let (v, w) = sim.object_speed(i);
            crate::world::resting(v, w, rest_speed)
        })
}

/// Every movable object's (name, linear speed, angular speed), as the rest check reads them.
fn object_speeds(sim: &SimWorld) -> Vec<(String, f64, f64)> {
    (0..sim.objects.len())
        .filter(|&i| sim.objects[i].movable)
        .map(|i| {
            let (v, w) = sim.object_speed(i);
            (sim.objects[i].name.clone(), v, w)
        })
        .collect()
}

/// The simulated TCP and keyframe `k`'s reference object now.
fn reach(setup: &Setup, sim: &SimWorld, arm: &SimArm, k: usize, t: f64) -> KeyframeReach {
    let keyframe = &setup.spec.keyframes[k];
    let name = &keyframe.reference;
    // A keyframe on the world is never re-grounded: its frame is the one the spec stores, as
    // the planner reads it.
    let reference = if name == WORLD_FRAME {
        Some(keyframe.tsr.t0_w)
    } else {
        sim.object_index(name).map(|i| sim.object_pose(i))
    };
    KeyframeReach {
        keyframe: k,
        t,
        tcp: arm.tcp(sim),
        reference,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_planner::{plan_task, Robot};
    use akl_tsr::TaskSpec;

    /// pick_place's ground truth cut to its first keyframe (close on block_a), and its plan in
    /// the nominal world.
    fn grasp_block_a(robot: &Robot, task: &akl_scene::Task) -> (TaskSpec, Plan) {
        let mut spec = task.truth.clone().unwrap();
        spec.keyframes.truncate(1);
        assert_eq!(spec.keyframes[0].reference, "block_a");
        let plan = plan_task(robot, &spec, &task.world, &ExecOptions::default().plan).unwrap();
        (spec, plan)
    }

    /// The gripper closes on the box between its pads: both pads on it, welded, still held at
    /// the end, lifted with the hand, and nothing touched that should not be.
    #[test]
    fn a_simulated_gripper_closes_on_a_box() {
        let robot = Robot::panda().unwrap();
        let task = akl_scene::builtin::task("pick_place").unwrap().unwrap();
        let (spec, plan) = grasp_block_a(&robot, &task);
        let options = ExecOptions::default();
        let setup = Setup {
            robot: &robot,
            task: &task,
            spec: &spec,
            options: &options,
        };
        let obs = simulate(&setup, &task.world, &plan, None).unwrap();
        assert_eq!(obs.grasps.len(), 1);
        let g = &obs.grasps[0];
        let block = Some("block_a".to_string());
        assert_eq!((g.keyframe, &g.intended), (0, &"block_a".to_string()));
        assert_eq!(g.pads, [block.clone(), block]);
        assert!(
            g.welded && g.unsound.is_none() && g.broke_at.is_none(),
            "{g:?}"
        );
        assert!(g.t > 0.0 && g.t < obs.simulated);
        assert_eq!(obs.still_held, ["block_a"]);
        assert_eq!(obs.contacts.collisions(), []);
        // Reached the keyframe once, where the plan says.
        assert_eq!(obs.reaches.len(), 1);
        let planned = task.world.robot_base * robot.tcp_pose(&plan.sample(obs.reaches[0].t));
        assert!(position_distance(&obs.reaches[0].tcp, &planned) < 0.005);
        // Carried: the box ends where the hand holds it, off its mat.
        let before = task.world.object("block_a").unwrap().pose;
        let after = obs
            .settled
            .as_ref()
            .unwrap()
            .object("block_a")
            .unwrap()
            .pose;
        let rise = after.translation.z - before.translation.z;
        assert!(rise > 0.01, "lifted {rise} m");
    }

    /// The same plan with the box 12 cm further out: the fingers close on nothing, nothing is
    /// welded or held.
    #[test]
    fn a_simulated_gripper_closes_on_nothing_where_the_box_is_not() {
        let robot = Robot::panda().unwrap();
        let task = akl_scene::builtin::task("pick_place").unwrap().unwrap();
        let (spec, plan) = grasp_block_a(&robot, &task);
        let mut world = task.world.clone();
        let block = world.object_mut("block_a").unwrap();
        block.pose = akl_tsr::Pose::translation(0.12, 0.0, 0.0) * block.pose;
        let options = ExecOptions::default();
        let setup = Setup {
            robot: &robot,
            task: &task,
            spec: &spec,
            options: &options,
        };
        let obs = simulate(&setup, &world, &plan, None).unwrap();
        assert_eq!(obs.grasps.len(), 1);
        let g = &obs.grasps[0];
        assert_eq!(g.pads, [None, None], "{g:?}");
        assert!(!g.welded && g.measure.is_none());
        assert!(obs.still_held.is_empty());
        let moved = world.object("block_a").unwrap().pose.translation.vector;
        let after = obs
            .settled
            .as_ref()
            .unwrap()
            .object("block_a")
            .unwrap()
            .pose;
        assert!(
            (after.translation.vector - moved).norm() < 0.002,
            "left where it was"
        );
    }

    #[test]
    fn keyframes_are_reached_at_the_end_of_the_motion_leading_to_them() {
        let robot = Robot::panda().unwrap();
        let task = akl_scene::builtin::task("pick_place").unwrap().unwrap();
        let (spec, plan) = grasp_block_a(&robot, &task);
        let times = reach_times(&plan, spec.keyframes.len());
        let last_motion = plan
            .segments
            .iter()
            .filter(|s| s.keyframe == 0)
            .filter(|s| {
                matches!(
                    s.kind,
                    SegmentKind::Free | SegmentKind::Approach | SegmentKind::Line
                )
            })
            .map(|s| s.end)
            .fold(f64::MIN, f64::max);
        assert_eq!(times, [Some(last_motion)]);
        assert!(plan.segments.iter().any(|s| s.kind == SegmentKind::Lift));
        assert_eq!(segment_label(SegmentKind::Lift, 0), "lift after keyframe 0");
        // The planned velocity is the plan's slope: (nearly) zero where it comes to rest.
        let end = planned_velocity(&plan, plan.duration);
        assert!(end.iter().all(|v| v.abs() < 1e-3), "{end:?}");
        let mid = plan.segments[0].start + 0.5 * (plan.segments[0].end - plan.segments[0].start);
        let (a, b) = (plan.sample(mid - 1e-3), plan.sample(mid + 1e-3));
        for (v, (x, y)) in planned_velocity(&plan, mid).iter().zip(a.iter().zip(&b)) {
            assert!((v - (y - x) / 2e-3).abs() < 1e-3, "{v}");
        }
    }
}
