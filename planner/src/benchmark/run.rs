//! Solving one problem of a problem file with the project's RRT-Connect, as many times as
//! there are seeds, and recording what other planners' runners record.

use super::problems::{Problem, ProblemFile};
use crate::collision::{Checker, Hit, RobotCollision, Scene};
use crate::contact_rules::Allowances;
use crate::rrt::{rrt_connect, RrtOptions, RrtResult};
use crate::space::{path_length, Space};
use crate::Robot;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};
use std::time::Instant;

/// How a problem file is run.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchSettings {
    /// Runs per problem; run s plans with seed s.
    pub seeds: u64,
    /// RRT-Connect's settings.
    pub rrt: RrtOptions,
}

/// What one problem gave: the fields, names and meanings of the peer runner's records, so one
/// analysis reads both (`../shared/peers/run_vamp.py`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProblemRecord {
    /// The problem's id.
    pub id: String,
    /// Its set.
    pub set: String,
    /// Whether the start is free of collisions under the planner's model and margins.
    pub start_valid: bool,
    /// Whether the goal is.
    pub goal_valid: bool,
    /// Whether the start is within the joint limits.
    pub start_in_limits: bool,
    /// Whether the goal is.
    pub goal_in_limits: bool,
    /// Whether the straight joint-space edge from start to goal is free (when both ends are
    /// valid).
    pub straight_edge_free: Option<bool>,
    /// One run per seed (none when start or goal is invalid).
    pub runs: Vec<RunRecord>,
}

/// One planning run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunRecord {
    /// The seed.
    pub seed: u64,
    /// Whether a path was found within the budget.
    pub found: bool,
    /// Samples drawn.
    pub iterations: u64,
    /// Time inside the planner (nanoseconds).
    pub time_ns: u64,
    /// Time including building the collision scene (nanoseconds).
    pub wall_ns: u64,
    /// Waypoints of the path (0 when none was found).
    pub waypoints: usize,
    /// Joint-space length of the path (radians; 0 when none was found).
    pub length: f64,
}

/// A problem's record with what explains it: the first collision found at an invalid end,
/// and the objects the hand was allowed to touch.
#[derive(Debug, Clone, PartialEq)]
pub struct ProblemOutcome {
    /// The record.
    pub record: ProblemRecord,
    /// Why the start is invalid, if it is.
    pub start_hit: Option<Hit>,
    /// Why the goal is invalid, if it is.
    pub goal_hit: Option<Hit>,
    /// Objects the hand touches at the start or goal and may touch throughout (the grasped
    /// object of a problem whose goal is a grasp).
    pub grasped: Vec<String>,
}

/// Runs problem `problem` of `file` with `settings`.
///
/// Problem files do not say which object a goal grasps; where only hand links touch an
/// object at the start or goal, that object is taken to be grasped there and the hand may
/// touch it (not the arm, and nothing else), as the planner allows for a grasp in a task.
pub fn run_problem(
    robot: &Robot,
    model: &RobotCollision,
    file: &ProblemFile,
    problem: &Problem,
    settings: &BenchSettings,
) -> ProblemOutcome {
    // The file was checked when it was loaded, so its problems name its scenes.
    let world = file
        .world(&problem.scene)
        .unwrap_or_else(|| akl_scene::World {
            robot_base: akl_tsr::Pose::identity(),
            objects: Vec::new(),
        });
    let width = robot.open_width();
    let scene = Scene::new(&world, &[]);
    let checker = Checker::new(robot, model, &scene);
    let mut allow = Allowances::default();
    for q in [&problem.start, &problem.goal] {
        for object in grasped(robot, &checker, q, width) {
            if !allow.hand_may_touch.contains(&object) {
                allow.hand_may_touch.push(object);
            }
        }
    }
    let start_hit = checker.check(&problem.start, width, None, &allow);
    let goal_hit = checker.check(&problem.goal, width, None, &allow);
    // The file's configurations have the robot's length and finite values (checked when it
    // was loaded), so the joint check fails only on a limit.
    let in_limits = |q: &[f64]| robot.check_joints(q).is_ok();
    let mut record = ProblemRecord {
        id: problem.id.clone(),
        set: problem.set.clone(),
        start_valid: start_hit.is_none(),
        goal_valid: goal_hit.is_none(),
        start_in_limits: in_limits(&problem.start),
        goal_in_limits: in_limits(&problem.goal),
        straight_edge_free: None,
        runs: Vec::new(),
    };
    let outcome = |record, allow: Allowances| ProblemOutcome {
        record,
        start_hit: start_hit.clone(),
        goal_hit: goal_hit.clone(),
        grasped: allow.hand_may_touch,
    };
    if start_hit.is_some() || goal_hit.is_some() {
        return outcome(record, allow);
    }
    let space = Space {
        checker: &checker,
        width,
        held: None,
        allow: &allow,
    };
    record.straight_edge_free = Some(space.edge_valid(&problem.start, &problem.goal));
    let goals = [problem.goal.clone()];
    for seed in 0..settings.seeds {
        let begun = Instant::now();
        // The scene is built again for every run so that `wall_ns` counts it, as a planner
        // called on a new world would.
        let scene = Scene::new(&world, &[]);
        let checker = Checker::new(robot, model, &scene);
        let space = Space {
            checker: &checker,
            ..space
        };
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let planning = Instant::now();
        let result = rrt_connect(&problem.start, &goals, &space, &settings.rrt, &mut rng);
        let time_ns = nanos(planning);
        let wall_ns = nanos(begun);
        record.runs.push(match result {
            RrtResult::Found {
                path, iterations, ..
            } => RunRecord {
                seed,
                found: true,
                iterations: iterations as u64,
                time_ns,
                wall_ns,
                waypoints: path.len(),
                length: path_length(&path),
            },
            RrtResult::Exhausted { iterations } => RunRecord {
                seed,
                found: false,
                iterations: iterations as u64,
                time_ns,
                wall_ns,
                waypoints: 0,
                length: 0.0,
            },
        });
    }
    outcome(record, allow)
}

/// The objects that hand links, and no other link, touch at `q`.
fn grasped(robot: &Robot, checker: &Checker, q: &[f64], width: f64) -> Vec<String> {
    let is_hand = |link: &str| {
        robot
            .hand_links()
            .iter()
            .any(|&i| robot.links()[i].name == link)
    };
    let report = checker.report(q, width);
    let mut objects: Vec<String> = Vec::new();
    for c in &report.collisions {
        if let Some(object) = &c.object {
            let by_arm = report
                .collisions
                .iter()
                .any(|d| d.object.as_ref() == Some(object) && !is_hand(&d.link));
            if is_hand(&c.link) && !by_arm && !objects.contains(object) {
                objects.push(object.clone());
            }
        }
    }
    objects
}

fn nanos(since: Instant) -> u64 {
    u64::try_from(since.elapsed().as_nanos()).unwrap_or(u64::MAX)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    /// A file of one problem from the ready pose back to it, in a scene of one cube of half
    /// side `half` at `at` (robot base frame).
    fn file(at: [f64; 3], half: f64, ready: &[f64]) -> ProblemFile {
        let q = format!("{ready:?}");
        let text = format!(
            r#"{{"scenes": {{"s": [{{"name": "cube", "kind": "box", "position": {at:?},
                 "half_extents": [{half}, {half}, {half}]}}]}},
                 "problems": [{{"set": "a", "id": "a/1", "scene": "s", "start": {q}, "goal": {q}}}]}}"#
        );
        ProblemFile::parse(&text, Path::new("p.json"), ready.len()).unwrap()
    }

    /// A cube between the open fingers (9 cm wide, so it meets them) is taken as grasped and
    /// the problem stays valid; a cube at the elbow makes it invalid, naming the link.
    #[test]
    fn only_what_the_hand_alone_touches_counts_as_grasped() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let ready = robot.ready().to_vec();
        let settings = BenchSettings {
            seeds: 1,
            rrt: RrtOptions::default(),
        };
        let tcp = robot.tcp_pose(&ready).translation.vector;
        let between = file([tcp.x, tcp.y, tcp.z], 0.045, &ready);
        let o = run_problem(&robot, &model, &between, &between.problems[0], &settings);
        assert_eq!(o.grasped, ["cube"]);
        assert!(o.record.start_valid && o.record.goal_valid, "{o:?}");
        assert!(o.record.runs[0].found);
        let elbow = robot.link_poses(&ready, robot.open_width())[robot
            .links()
            .iter()
            .position(|l| l.name == "fer_link4")
            .unwrap()]
        .translation
        .vector;
        let arm = file([elbow.x, elbow.y, elbow.z], 0.01, &ready);
        let o = run_problem(&robot, &model, &arm, &arm.problems[0], &settings);
        assert!(o.grasped.is_empty());
        assert!(!o.record.start_valid && o.record.runs.is_empty());
        assert!(
            matches!(&o.start_hit, Some(Hit::World(link, object))
                if ["fer_link3", "fer_link4"].contains(&link.as_str()) && object == "cube"),
            "{:?}",
            o.start_hit
        );
    }
}
