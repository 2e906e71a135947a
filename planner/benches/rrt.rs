//! Free-space planning benchmark: RRT-Connect time per problem on the three task scenes and on
//! table and shelf scenes, and the time to plan each ground-truth spec.
//!
//! Problems: start and goal configurations that are collision-free. In the task scenes, from
//! the ready pose to the pre-grasp and pre-place poses of the ground truths (6 cm back along
//! the tool axis) and between them, plus pairs of random collision-free configurations. In the
//! table scene (four boxes on a table), between tool poses sampled among the boxes; in the
//! shelf scene (two columns of three cells), between poses reaching into the cells. Goals come
//! from inverse kinematics. Every problem is solved with three seeds.
//!
//! Baseline, measured in the same run on the same problems, seeds and checker: a single-tree
//! RRT with 10 % goal bias and the same step size, a connection test to the goal after every
//! extension, and the same iteration budget.
//! The criterion benchmarks (`rrt_connect/<set>`) cycle through each set's problems, so they
//! report the mean over a set; the medians are printed before them.
//! Run with `cargo bench -p akl-planner --bench rrt`.

use akl_planner::collision::{Checker, RobotCollision, Scene};
use akl_planner::contact_rules::Allowances;
use akl_planner::internals::{distance, rrt_connect, RrtResult, Space};
use akl_planner::{plan_task, PlanOptions, Robot, RrtOptions};
use akl_scene::{builtin, Object, Shape, World};
use akl_tsr::pose::{pose_from_xyz, pose_from_xyz_rpy};
use akl_tsr::{Pose, WORLD_FRAME};
use criterion::{black_box, Criterion};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::f64::consts::{FRAC_PI_2, PI};
use std::time::{Duration, Instant};

fn fixed(name: &str, size: [f64; 3], at: [f64; 3]) -> Object {
    Object {
        name: name.into(),
        shape: Shape::Box { size },
        pose: pose_from_xyz(at),
        movable: false,
        mass: 0.0,
        friction: 0.5,
    }
}

fn table_world() -> World {
    World {
        robot_base: Pose::identity(),
        objects: vec![
            fixed("table", [1.2, 1.4, 0.04], [0.35, 0.0, -0.02]),
            fixed("box_a", [0.1, 0.3, 0.25], [0.5, 0.0, 0.125]),
            fixed("box_b", [0.15, 0.1, 0.35], [0.35, -0.35, 0.175]),
            fixed("box_c", [0.12, 0.12, 0.2], [0.3, 0.38, 0.1]),
            fixed("box_d", [0.08, 0.2, 0.4], [0.68, 0.3, 0.2]),
        ],
    }
}

fn shelf_world() -> World {
    let mut objects = vec![
        fixed("table", [1.2, 1.4, 0.04], [0.35, 0.0, -0.02]),
        fixed("back", [0.02, 0.8, 1.0], [0.8, 0.0, 0.5]),
        fixed("left", [0.3, 0.02, 1.0], [0.65, 0.4, 0.5]),
        fixed("right", [0.3, 0.02, 1.0], [0.65, -0.4, 0.5]),
        fixed("middle", [0.3, 0.02, 1.0], [0.65, 0.0, 0.5]),
    ];
    for (i, z) in [0.15, 0.4, 0.65, 0.9].into_iter().enumerate() {
        objects.push(fixed(
            &format!("board_{i}"),
            [0.3, 0.8, 0.02],
            [0.65, 0.0, z],
        ));
    }
    World {
        robot_base: Pose::identity(),
        objects,
    }
}

/// A problem: two collision-free configurations in a world.
struct Problem {
    world: usize,
    start: Vec<f64>,
    goal: Vec<f64>,
}

/// Collision-free configurations reaching `poses`, at most one per pose.
fn configurations(robot: &Robot, checker: &Checker, poses: &[Pose]) -> Vec<Vec<f64>> {
    let allow = Allowances::default();
    poses
        .iter()
        .filter_map(|p| {
            robot
                .ik_solutions(p, robot.ready(), 6)
                .into_iter()
                .find(|q| checker.is_free(q, robot.open_width(), None, &allow))
        })
        .collect()
}

/// Ready to every goal, and goal to goal in a ring.
fn problems_between(world: usize, ready: &[f64], goals: &[Vec<f64>]) -> Vec<Problem> {
    let mut out = Vec::new();
    for (i, g) in goals.iter().enumerate() {
        out.push(Problem {
            world,
            start: ready.to_vec(),
            goal: g.clone(),
        });
        if goals.len() > 1 {
            out.push(Problem {
                world,
                start: g.clone(),
                goal: goals[(i + 1) % goals.len()].clone(),
            });
        }
    }
    out
}

/// Pre-grasp and pre-place poses of a task's ground truth (6 cm back along the tool axis).
fn task_poses(task: &akl_scene::Task) -> Vec<Pose> {
    let Some(truth) = &task.truth else {
        return Vec::new();
    };
    let Ok(grounded) = truth.ground(&task.world.object_poses()) else {
        return Vec::new();
    };
    grounded
        .keyframes
        .iter()
        .filter(|k| k.reference != WORLD_FRAME)
        .map(|k| k.tsr.nominal() * akl_tsr::nalgebra::Translation3::new(0.0, 0.0, -0.06))
        .collect()
}

fn table_poses(rng: &mut ChaCha8Rng) -> Vec<Pose> {
    (0..60)
        .map(|_| {
            let x = rng.gen_range(0.3..0.7);
            let y = rng.gen_range(-0.5..0.5);
            let z = rng.gen_range(0.04..0.22);
            pose_from_xyz_rpy([x, y, z], [PI, 0.0, rng.gen_range(-PI..PI)])
        })
        .collect()
}

fn shelf_poses(rng: &mut ChaCha8Rng) -> Vec<Pose> {
    let mut poses = Vec::new();
    for z in [0.275, 0.525, 0.775] {
        for y in [-0.2, 0.2] {
            for _ in 0..10 {
                let p = [
                    rng.gen_range(0.56..0.64),
                    y + rng.gen_range(-0.06..0.06),
                    z + rng.gen_range(-0.04..0.04),
                ];
                // Tool z along +x, into the cell; a random turn about it.
                let roll = rng.gen_range(-PI..PI);
                poses.push(pose_from_xyz_rpy(p, [roll, FRAC_PI_2, 0.0]));
            }
        }
    }
    poses
}

/// The baseline: single-tree RRT with goal bias and a connection test after each extension.
fn goal_biased_rrt(
    start: &[f64],
    goal: &[f64],
    space: &Space,
    options: &RrtOptions,
    rng: &mut ChaCha8Rng,
) -> bool {
    if space.edge_valid(start, goal) {
        return true;
    }
    let mut nodes: Vec<Vec<f64>> = vec![start.to_vec()];
    let mut sample = vec![0.0; start.len()];
    let sampler = space.sampler();
    for _ in 0..options.max_iterations {
        if rng.gen_bool(0.1) {
            sample.copy_from_slice(goal);
        } else {
            sampler.fill(rng, &mut sample);
        }
        let near = nodes
            .iter()
            .min_by(|a, b| distance(a, &sample).total_cmp(&distance(b, &sample)))
            .cloned()
            .unwrap_or_else(|| start.to_vec());
        let d = distance(&near, &sample);
        let t = if d > options.range {
            options.range / d
        } else {
            1.0
        };
        let new: Vec<f64> = near
            .iter()
            .zip(&sample)
            .map(|(a, b)| a + t * (b - a))
            .collect();
        if !space.edge_valid(&near, &new) {
            continue;
        }
        if distance(&new, goal) <= options.range && space.edge_valid(&new, goal) {
            return true;
        }
        nodes.push(new);
    }
    false
}

/// Random collision-free configurations, paired in order.
fn random_pairs(
    world: usize,
    robot: &Robot,
    checker: &Checker,
    count: usize,
    rng: &mut ChaCha8Rng,
) -> Vec<Problem> {
    let allow = Allowances::default();
    let mut free = Vec::new();
    let mut q = vec![0.0; robot.dof()];
    while free.len() < 2 * count {
        for (v, [lo, hi]) in q.iter_mut().zip(robot.joint_limits()) {
            *v = rng.gen_range(*lo..*hi);
        }
        if checker.is_free(&q, robot.open_width(), None, &allow) {
            free.push(q.clone());
        }
    }
    free.chunks(2)
        .map(|pair| Problem {
            world,
            start: pair[0].clone(),
            goal: pair[1].clone(),
        })
        .collect()
}

/// Seeds each problem is solved with (by both planners).
const SEEDS: u64 = 3;

/// One planner's runs over a set of problems.
#[derive(Default)]
struct Runs {
    /// Time of each run and whether its problem needs a search (no straight edge).
    times: Vec<(Duration, bool)>,
    solved: usize,
}

fn median(mut times: Vec<Duration>) -> Duration {
    times.sort();
    times.get(times.len() / 2).copied().unwrap_or_default()
}

impl Runs {
    /// Prints the summary line and returns the median of all runs and of the runs that
    /// needed a search.
    fn report(&self, label: &str) -> (Duration, Duration) {
        let all: Vec<Duration> = self.times.iter().map(|(t, _)| *t).collect();
        let searched: Vec<Duration> = self
            .times
            .iter()
            .filter(|(_, s)| *s)
            .map(|(t, _)| *t)
            .collect();
        let mean = all.iter().sum::<Duration>() / all.len().max(1) as u32;
        let max = all.iter().max().copied().unwrap_or_default();
        let (m, ms) = (median(all), median(searched));
        println!(
            "  {label:<28} solved {:>3}/{:<3} median {m:>10.2?} (searches {ms:>10.2?}) mean {mean:>10.2?} max {max:>10.2?}",
            self.solved,
            self.times.len()
        );
        (m, ms)
    }
}

fn ratio(baseline: Duration, ours: Duration) -> f64 {
    baseline.as_secs_f64() / ours.as_secs_f64().max(1e-12)
}

/// The planning space of a free move with the hand open and nothing held, as in every
/// problem here.
fn open_hand<'a>(checker: &'a Checker<'a>, allow: &'a Allowances) -> Space<'a> {
    Space {
        checker,
        width: checker.robot().open_width(),
        held: None,
        allow,
    }
}

fn main() {
    let robot = Robot::panda().expect("the built-in Panda loads");
    let model = RobotCollision::new(&robot);
    let mut worlds: Vec<(String, World)> = builtin::names()
        .into_iter()
        .map(|n| {
            let t = builtin::task(n).expect("built in").expect("valid");
            (n.to_string(), t.world)
        })
        .collect();
    worlds.push(("table".into(), table_world()));
    worlds.push(("shelf".into(), shelf_world()));
    let scenes: Vec<Scene> = worlds.iter().map(|(_, w)| Scene::new(w, &[])).collect();
    let mut keyframe_problems = Vec::new();
    let mut random_problems = Vec::new();
    for (i, name) in builtin::names().into_iter().enumerate() {
        let task = builtin::task(name).expect("built in").expect("valid");
        let checker = Checker::new(&robot, &model, &scenes[i]);
        let goals = configurations(&robot, &checker, &task_poses(&task));
        keyframe_problems.extend(problems_between(i, robot.ready(), &goals));
        let mut rng = ChaCha8Rng::seed_from_u64(10 + i as u64);
        random_problems.extend(random_pairs(i, &robot, &checker, 8, &mut rng));
    }
    let mut sets: Vec<(String, Vec<Problem>)> = vec![
        ("task scenes, keyframes".into(), keyframe_problems),
        ("task scenes, random pairs".into(), random_problems),
    ];
    let poses = [
        table_poses(&mut ChaCha8Rng::seed_from_u64(20)),
        shelf_poses(&mut ChaCha8Rng::seed_from_u64(21)),
    ];
    for (i, poses) in [(3, &poses[0]), (4, &poses[1])] {
        let checker = Checker::new(&robot, &model, &scenes[i]);
        let goals = configurations(&robot, &checker, poses);
        sets.push((
            format!("{} scene", worlds[i].0),
            problems_between(i, robot.ready(), &goals),
        ));
    }

    let options = RrtOptions::default();
    let allow = Allowances::default();
    println!(
        "RRT-Connect (akl) against a goal-biased RRT, same checker and budget, {SEEDS} seeds per problem:"
    );
    let mut table_and_shelf: [Vec<Duration>; 2] = Default::default();
    for (label, problems) in &sets {
        let mut ours = Runs::default();
        let mut theirs = Runs::default();
        let mut direct = 0;
        for (k, p) in problems.iter().enumerate() {
            let checker = Checker::new(&robot, &model, &scenes[p.world]);
            let space = open_hand(&checker, &allow);
            let search = !space.edge_valid(&p.start, &p.goal);
            direct += usize::from(!search);
            for seed in 0..SEEDS {
                let mut r = ChaCha8Rng::seed_from_u64(1000 * k as u64 + seed);
                let t = Instant::now();
                let found = rrt_connect(
                    &p.start,
                    std::slice::from_ref(&p.goal),
                    &space,
                    &options,
                    &mut r,
                );
                ours.times.push((t.elapsed(), search));
                if matches!(found, RrtResult::Found { .. }) {
                    ours.solved += 1;
                }
                let mut r = ChaCha8Rng::seed_from_u64(1000 * k as u64 + seed);
                let t = Instant::now();
                if goal_biased_rrt(&p.start, &p.goal, &space, &options, &mut r) {
                    theirs.solved += 1;
                }
                theirs.times.push((t.elapsed(), search));
            }
        }
        println!(
            "{label}: {} problems, {direct} solvable by the straight edge",
            problems.len()
        );
        let (a, a_search) = ours.report("RRT-Connect (akl)");
        let (b, b_search) = theirs.report("goal-biased RRT (baseline)");
        println!(
            "  baseline / akl, medians: {:.1}x (searches {:.1}x)",
            ratio(b, a),
            ratio(b_search, a_search)
        );
        if label.starts_with("table") || label.starts_with("shelf") {
            table_and_shelf[0].extend(ours.times.iter().map(|(t, _)| *t));
            table_and_shelf[1].extend(theirs.times.iter().map(|(t, _)| *t));
        }
    }
    let [ours, theirs] = table_and_shelf;
    let (a, b) = (median(ours), median(theirs));
    println!(
        "table and shelf together: median {a:.2?} (akl), {b:.2?} (baseline), {:.1}x",
        ratio(b, a)
    );

    println!("whole ground-truth specs (plan_task, 5 seeds):");
    for name in builtin::names() {
        let task = builtin::task(name).expect("built in").expect("valid");
        let truth = task.truth.as_ref().expect("truth");
        let mut times = Vec::new();
        let mut planned = 0;
        for seed in 0..5 {
            let t = Instant::now();
            let options = PlanOptions {
                seed,
                ..PlanOptions::default()
            };
            if plan_task(&robot, truth, &task.world, &options).is_ok() {
                planned += 1;
            }
            times.push(t.elapsed());
        }
        println!(
            "  {name:<12} median {:>9.2?}, planned {planned}/5",
            median(times)
        );
    }

    let mut c = Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3))
        .configure_from_args();
    for (label, problems) in &sets {
        let mut k = 0;
        c.bench_function(
            &format!("rrt_connect/{}", label.replace(", ", "_").replace(' ', "_")),
            |b| {
                b.iter(|| {
                    k = (k + 1) % problems.len().max(1);
                    let p = &problems[k];
                    let checker = Checker::new(&robot, &model, &scenes[p.world]);
                    let space = open_hand(&checker, &allow);
                    let mut r = ChaCha8Rng::seed_from_u64(k as u64);
                    black_box(rrt_connect(
                        &p.start,
                        std::slice::from_ref(&p.goal),
                        &space,
                        &options,
                        &mut r,
                    ))
                })
            },
        );
    }
    c.final_summary();
}
