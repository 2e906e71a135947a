//! Collision benchmark: one full-arm check (self collision, arm and hand against every object)
//! of random configurations in each built-in task scene.
//!
//! Baseline, measured in the same run: the straightforward use of the same libraries, k's
//! forward kinematics (`set_joint_positions` + `update_transforms`) and a parry3d
//! `intersection_test` for every shape pair, without the bounding-box and segment culling.
//! Run with `cargo bench -p akl-planner --bench collision`.

use akl_planner::collision::{Checker, RobotCollision, Scene};
use akl_planner::contact_rules::Allowances;
use akl_planner::internals::{intersects, object_shape, robot_shape};
use akl_planner::Robot;
use akl_scene::builtin;
use akl_tsr::Pose;
use criterion::{black_box, Criterion};
use parry3d_f64::shape::SharedShape;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::time::Duration;

/// The straightforward checker: k forward kinematics, every pair through parry.
struct Naive<'a> {
    robot: &'a Robot,
    shapes: Vec<(String, SharedShape, Pose)>,
    self_shapes: Vec<SharedShape>,
    obstacles: Vec<(SharedShape, Pose)>,
    pairs: Vec<(usize, usize)>,
    mount: Vec<String>,
}

impl<'a> Naive<'a> {
    fn new(robot: &'a Robot, world: &akl_scene::World) -> Naive<'a> {
        let c = &robot.config().collision;
        let mut shapes = Vec::new();
        let mut self_shapes = Vec::new();
        for (i, link) in robot.links().iter().enumerate() {
            let margin = if robot.hand_links().contains(&i) {
                c.hand_margin
            } else {
                c.arm_margin
            };
            for s in &link.shapes {
                let (shape, fix) = robot_shape(&s.geometry, margin);
                shapes.push((link.name.clone(), shape, s.origin * fix));
                self_shapes.push(robot_shape(&s.geometry, 0.5 * c.self_margin).0);
            }
        }
        let obstacles = world
            .objects
            .iter()
            .map(|o| {
                let (shape, fix) = object_shape(&o.shape, 0.0);
                (shape, o.pose * fix)
            })
            .collect();
        let allowed = |a: &str, b: &str| {
            a == b
                || c.allowed_pairs
                    .iter()
                    .any(|[x, y]| (x == a && y == b) || (x == b && y == a))
        };
        let mut pairs = Vec::new();
        for i in 0..shapes.len() {
            for j in i + 1..shapes.len() {
                if !allowed(&shapes[i].0, &shapes[j].0) {
                    pairs.push((i, j));
                }
            }
        }
        Naive {
            robot,
            shapes,
            self_shapes,
            obstacles,
            pairs,
            mount: c.mount_links.clone(),
        }
    }

    fn free(&self, q: &[f64], width: f64) -> bool {
        let chain = self.robot.chain();
        let positions: Vec<f64> = chain
            .iter_joints()
            .filter(|j| j.is_movable())
            .map(
                |j| match self.robot.joint_names().iter().position(|n| *n == j.name) {
                    Some(i) => q[i],
                    None => width / 2.0,
                },
            )
            .collect();
        chain.set_joint_positions_clamped(&positions);
        chain.update_transforms();
        let poses: Vec<Pose> = self
            .shapes
            .iter()
            .map(|(link, _, local)| {
                chain
                    .find_link(link)
                    .and_then(|n| n.world_transform())
                    .unwrap_or_else(Pose::identity)
                    * local
            })
            .collect();
        for &(i, j) in &self.pairs {
            if intersects(
                &self.self_shapes[i],
                &poses[i],
                &self.self_shapes[j],
                &poses[j],
            ) {
                return false;
            }
        }
        for (k, (link, shape, _)) in self.shapes.iter().enumerate() {
            for (m, (o, pose)) in self.obstacles.iter().enumerate() {
                if m == 0 && self.mount.contains(link) {
                    continue;
                }
                if intersects(shape, &poses[k], o, pose) {
                    return false;
                }
            }
        }
        true
    }
}

fn main() {
    let robot = Robot::panda().expect("the built-in Panda loads");
    let model = RobotCollision::new(&robot);
    let mut c = Criterion::default()
        .sample_size(30)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .configure_from_args();
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    let configurations: Vec<Vec<f64>> = (0..1000)
        .map(|_| {
            robot
                .joint_limits()
                .iter()
                .map(|[lo, hi]| rng.gen_range(*lo..*hi))
                .collect()
        })
        .collect();
    let allow = Allowances::default();
    for name in builtin::names() {
        let task = builtin::task(name).expect("built in").expect("valid");
        let scene = Scene::new(&task.world, &[]);
        let checker = Checker::new(&robot, &model, &scene);
        let naive = Naive::new(&robot, &task.world);
        let agree = configurations
            .iter()
            .filter(|q| checker.is_free(q, 0.08, None, &allow) == naive.free(q, 0.08))
            .count();
        let free = configurations
            .iter()
            .filter(|q| checker.is_free(q, 0.08, None, &allow))
            .count();
        println!(
            "{name}: {free}/{} random configurations free; the two checkers agree on {agree}",
            configurations.len()
        );
        let mut i = 0;
        c.bench_function(&format!("collision/{name}/akl"), |b| {
            b.iter(|| {
                i = (i + 1) % configurations.len();
                checker.is_free(black_box(&configurations[i]), 0.08, None, &allow)
            })
        });
        let mut j = 0;
        c.bench_function(&format!("collision/{name}/naive_k_parry"), |b| {
            b.iter(|| {
                j = (j + 1) % configurations.len();
                naive.free(black_box(&configurations[j]), 0.08)
            })
        });
    }
    c.final_summary();
}
