//! `akl robot check` through the binary: the collision model holds every point of the real
//! Panda's meshes, is not much bigger than them, and reports what it finds as documented.

use akl_planner::internals::point_triangle_distance;
use akl_planner::{MeshRole, Robot};
use akl_tsr::nalgebra::Point3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::{json, Value};
use std::path::Path;

mod common;
use common::*;

const READY: &str =
    "0,-0.7853981633974483,0,-2.356194490192345,0,1.5707963267948966,0.7853981633974483";

/// 1 mm cubes at `points` (robot base frame) as an obstacle file.
fn cubes(path: &Path, points: &[Point3<f64>]) {
    let objects: Vec<Value> = points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            json!({"name": format!("p{i}"), "shape": {"type": "box", "size": [0.001, 0.001, 0.001]},
                   "pose": {"p": [p.x, p.y, p.z], "q": [0.0, 0.0, 0.0, 1.0]},
                   "movable": false, "mass": 0.0, "friction": 0.5})
        })
        .collect();
    std::fs::write(path, json!({ "objects": objects }).to_string()).unwrap();
}

/// `akl robot check --json` of `joints` against the obstacle file, on the geometry alone.
fn check_geometry(joints: &str, obstacles: &Path) -> std::process::Output {
    akl(&[
        "robot",
        "check",
        "--joints",
        joints,
        "--obstacles",
        obstacles.to_str().unwrap(),
        "--margin",
        "0",
        "--json",
    ])
}

fn joints_arg(q: &[f64]) -> String {
    q.iter()
        .map(|v| v.to_string())
        .collect::<Vec<_>>()
        .join(",")
}

/// The objects `robot check --json` reports in collision.
fn colliding_objects(v: &Value) -> std::collections::BTreeSet<String> {
    v["collisions"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|c| c["object"].as_str().map(str::to_string))
        .collect()
}

/// Points on every collision and visual mesh of the vendor's Panda, at 100 random
/// configurations with the fingers open, each as a 1 mm cube: every one is reported.
#[test]
fn every_point_of_every_mesh_is_inside_the_model() {
    let robot = Robot::panda().unwrap();
    let dir = scratch("robot-check-meshes");
    let mut rng = ChaCha8Rng::seed_from_u64(22);
    let width = robot.open_width();
    let configurations: Vec<Vec<f64>> = (0..100)
        .map(|_| {
            robot
                .joint_limits()
                .iter()
                .map(|[lo, hi]| rng.gen_range(*lo..*hi))
                .collect()
        })
        .collect();
    let (collision, visual) = robot
        .meshes()
        .iter()
        .fold((0, 0), |(c, v), m| match m.role {
            MeshRole::Collision => (c + 1, v),
            MeshRole::Visual => (c, v + 1),
        });
    assert_eq!(
        (collision, visual),
        (9, 11),
        "links 0-7 and the hand; also both fingers"
    );
    let runs: Vec<(Vec<f64>, Vec<Point3<f64>>)> = configurations
        .into_iter()
        .map(|q| {
            let poses = robot.link_poses(&q, width);
            // Four points on each mesh: a random triangle, a random point on it.
            let points = robot
                .meshes()
                .iter()
                .flat_map(|m| {
                    let corners: Vec<[Point3<f64>; 3]> = m.mesh.corners().collect();
                    (0..4)
                        .map(|_| {
                            let [a, b, c] = corners[rng.gen_range(0..corners.len())];
                            let (mut u, mut v) = (rng.gen::<f64>(), rng.gen::<f64>());
                            if u + v > 1.0 {
                                (u, v) = (1.0 - u, 1.0 - v);
                            }
                            poses[m.link] * (a + u * (b - a) + v * (c - a))
                        })
                        .collect::<Vec<_>>()
                })
                .collect();
            (q, points)
        })
        .collect();
    // Two processes at a time.
    std::thread::scope(|s| {
        for half in runs.chunks(runs.len().div_ceil(2)) {
            let dir = &dir;
            s.spawn(move || {
                for (k, (q, points)) in half.iter().enumerate() {
                    let file = dir.join(format!("cubes-{}-{k}.json", q[0]));
                    cubes(&file, points);
                    let o = check_geometry(&joints_arg(q), &file);
                    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
                    let hit = colliding_objects(&json(&o));
                    let missed: Vec<usize> = (0..points.len())
                        .filter(|i| !hit.contains(&format!("p{i}")))
                        .collect();
                    assert!(
                        missed.is_empty(),
                        "q {q:?}: points {missed:?} of {} not reported",
                        points.len()
                    );
                }
            });
        }
    });
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Cubes 2 cm outside the outline of the hand and of the forearm (link5), at the middle of
/// each side of their meshes' bounding boxes and at its corners, are not reported.
#[test]
fn the_model_is_tight_around_the_hand_and_the_forearm() {
    let robot = Robot::panda().unwrap();
    let q: Vec<f64> = READY.split(',').map(|v| v.parse().unwrap()).collect();
    let poses = robot.link_poses(&q, robot.open_width());
    let dir = scratch("robot-check-tight");
    for name in ["fer_hand", "fer_link5"] {
        let link = robot.links().iter().position(|l| l.name == name).unwrap();
        let (lo, hi) = robot
            .meshes()
            .iter()
            .filter(|m| m.link == link)
            .flat_map(|m| &m.mesh.vertices)
            .fold(([f64::MAX; 3], [f64::MIN; 3]), |(mut lo, mut hi), v| {
                for k in 0..3 {
                    lo[k] = lo[k].min(v[k]);
                    hi[k] = hi[k].max(v[k]);
                }
                (lo, hi)
            });
        let mut points = Vec::new();
        for sx in [-1, 0, 1] {
            for sy in [-1, 0, 1] {
                for sz in [-1, 0, 1] {
                    if (sx, sy, sz) == (0, 0, 0) {
                        continue;
                    }
                    let at = |s: i32, k: usize| match s {
                        -1 => lo[k] - 0.02,
                        1 => hi[k] + 0.02,
                        _ => 0.5 * (lo[k] + hi[k]),
                    };
                    points.push(poses[link] * Point3::new(at(sx, 0), at(sy, 1), at(sz, 2)));
                }
            }
        }
        // Only the cube's own link may be near it: drop cubes that come within 3 cm of
        // another link's meshes (the hand sits on link7, link5 beside link4 and link6).
        let near_other = |p: &Point3<f64>| {
            robot.meshes().iter().filter(|m| m.link != link).any(|m| {
                let local = poses[m.link].inverse() * p;
                m.mesh
                    .corners()
                    .any(|t| point_triangle_distance(&local, &t) < 0.03)
            })
        };
        let points: Vec<Point3<f64>> = points.into_iter().filter(|p| !near_other(p)).collect();
        assert!(points.len() >= 12, "{name}: {} cubes left", points.len());
        let file = dir.join(format!("{name}.json"));
        cubes(&file, &points);
        let o = check_geometry(READY, &file);
        assert_eq!(o.status.code(), Some(0), "{name}: {}", stdout(&o));
        let v = json(&o);
        assert_eq!(v["free"], true);
        // Each cube's clearance is reported, none closer than 1 cm.
        for c in v["clearances"].as_array().unwrap() {
            assert!(c["distance"].as_f64().unwrap() > 0.01, "{name}: {c}");
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn check_reports_collisions_with_a_task_and_exits_by_verdict() {
    // The ready pose is free in the pick-and-place scene.
    let o = akl(&[
        "robot",
        "check",
        "--joints",
        READY,
        "--task",
        "pick_place",
        "--json",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v = json(&o);
    assert_eq!(v["free"], true);
    assert!(v["collisions"].as_array().unwrap().is_empty());
    let table = v["clearances"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["object"] == "table")
        .unwrap();
    assert!(table["distance"].as_f64().unwrap() > 0.1, "{table}");
    // Reaching down into the table: a finger collides with it, exit 1, the pair named.
    let o = akl(&[
        "robot",
        "check",
        "--joints",
        "0,1.7,0,-0.07,0,1.8,0.785",
        "--task",
        "pick_place",
        "--json",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stdout(&o));
    let v = json(&o);
    assert_eq!(v["free"], false);
    let pairs: Vec<(String, String)> = v["collisions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            (
                c["link"].as_str().unwrap().to_string(),
                c["object"].as_str().unwrap_or("").to_string(),
            )
        })
        .collect();
    assert!(pairs.iter().any(|(_, o)| o == "table"), "{pairs:?}");
    // The text form says the same.
    let o = akl(&[
        "robot",
        "check",
        "--joints",
        "0,1.7,0,-0.07,0,1.8,0.785",
        "--task",
        "pick_place",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stdout(&o).contains("in collision") && stdout(&o).contains("with table"),
        "{}",
        stdout(&o)
    );
    assert!(stderr(&o).is_empty(), "{}", stderr(&o));
}

#[test]
fn a_self_collision_names_both_links() {
    let robot = Robot::panda().unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    // Find a configuration in self collision by sampling; the planner's own check agrees.
    let model = akl_planner::collision::RobotCollision::new(&robot);
    let world = akl_scene::World {
        robot_base: akl_tsr::Pose::identity(),
        objects: Vec::new(),
    };
    let scene = akl_planner::collision::Scene::new(&world, &[]);
    let checker = akl_planner::collision::Checker::new(&robot, &model, &scene);
    let q = loop {
        let q: Vec<f64> = robot
            .joint_limits()
            .iter()
            .map(|[lo, hi]| rng.gen_range(*lo..*hi))
            .collect();
        if let Some(akl_planner::collision::Hit::SelfCollision(..)) = checker.check(
            &q,
            robot.open_width(),
            None,
            &akl_planner::contact_rules::Allowances::default(),
        ) {
            break q;
        }
    };
    let o = akl(&["robot", "check", "--joints", &joints_arg(&q), "--json"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let v = json(&o);
    let c = &v["collisions"][0];
    assert!(c["link"].is_string() && c["other_link"].is_string(), "{v}");
}

#[test]
fn bad_input_is_named_with_exit_2() {
    let dir = scratch("robot-check-bad");
    let broken = dir.join("broken.json");
    std::fs::write(&broken, "{\"objects\": [\n  {\"name\": \"a\"}\n]}").unwrap();
    let cube = |name: &str, size: f64| {
        json!({"name": name, "shape": {"type": "box", "size": [size, size, size]},
               "pose": {"p": [0.5, 0.0, 0.5], "q": [0.0, 0.0, 0.0, 1.0]},
               "movable": false, "mass": 0.0, "friction": 0.5})
    };
    let twice = dir.join("twice.json");
    std::fs::write(
        &twice,
        json!({"objects": [cube("a", 0.1), cube("a", 0.1)]}).to_string(),
    )
    .unwrap();
    let flat = dir.join("flat.json");
    std::fs::write(&flat, json!({"objects": [cube("a", 0.0)]}).to_string()).unwrap();
    for (args, expected) in [
        (vec!["--joints", "0,0,0"], "expected 7 joint values"),
        (vec!["--joints", READY, "--margin", "-1"], "--margin"),
        (vec!["--joints", READY, "--gripper", "0.5"], "--gripper"),
        (
            vec!["--joints", READY, "--obstacles", "no/such.json"],
            "no/such.json",
        ),
        (
            vec!["--joints", READY, "--obstacles", broken.to_str().unwrap()],
            "line",
        ),
        (
            vec!["--joints", READY, "--task", "no_such_task"],
            "no_such_task",
        ),
        (
            vec!["--joints", READY, "--obstacles", twice.to_str().unwrap()],
            "another object has this name",
        ),
        (
            vec!["--joints", READY, "--obstacles", flat.to_str().unwrap()],
            "objects[0] (a)",
        ),
    ] {
        let mut all = vec!["robot", "check"];
        all.extend(args.iter().copied());
        let o = akl(&all);
        assert_refused(&o, &[expected]);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
