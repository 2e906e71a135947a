//! IK benchmark: success rate and time per call on 10,000 random reachable Panda poses
//! (forward kinematics of uniformly random in-limit configurations, seed = ready pose).
//!
//! Baseline, measured in the same run: k's `JacobianIkSolver` (gain 0.5, 100 iterations per
//! try, tolerance 0.1 mm and 1 mrad) from the ready pose, then from up to 20 random starts.
//! Run with `cargo bench -p akl-planner --bench ik`; `IK_POSES=N` changes the pose count.

use akl_planner::Robot;
use akl_tsr::Pose;
use criterion::{black_box, Criterion};
use k::InverseKinematicsSolver;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::time::{Duration, Instant};

const BASELINE_RESTARTS: usize = 20;

fn random_configuration(robot: &Robot, rng: &mut ChaCha8Rng) -> Vec<f64> {
    robot
        .joint_limits()
        .iter()
        .map(|[lo, hi]| rng.gen_range(*lo..*hi))
        .collect()
}

fn reached(robot: &Robot, q: &[f64], target: &Pose, position: f64, angle: f64) -> bool {
    let got = robot.tcp_pose(q);
    robot.check_joints(q).is_ok()
        && (got.translation.vector - target.translation.vector).norm() <= position
        && got.rotation.angle_to(&target.rotation) <= angle
}

/// k's Jacobian solver on the arm chain up to the TCP, with random restarts.
struct Baseline {
    arm: k::SerialChain<f64>,
    solver: k::JacobianIkSolver<f64>,
    ready: Vec<f64>,
    limits: Vec<[f64; 2]>,
}

impl Baseline {
    fn new(robot: &Robot) -> Baseline {
        let urdf = robot.urdf().clone();
        let chain = k::Chain::<f64>::from(&urdf);
        let tcp = chain
            .find_link(&robot.config().tcp_link)
            .expect("the TCP link is in the chain")
            .clone();
        Baseline {
            arm: k::SerialChain::from_end(&tcp),
            solver: k::JacobianIkSolver::new(1e-4, 1e-3, 0.5, 100),
            ready: robot.ready().to_vec(),
            limits: robot.joint_limits().to_vec(),
        }
    }

    fn solve(&self, target: &Pose, rng: &mut ChaCha8Rng) -> Option<Vec<f64>> {
        for attempt in 0..=BASELINE_RESTARTS {
            let start: Vec<f64> = if attempt == 0 {
                self.ready.clone()
            } else {
                self.limits
                    .iter()
                    .map(|[lo, hi]| rng.gen_range(*lo..*hi))
                    .collect()
            };
            self.arm.set_joint_positions_clamped(&start);
            if self.solver.solve(&self.arm, target).is_ok() {
                return Some(self.arm.joint_positions());
            }
        }
        None
    }
}

struct Stats {
    solved: usize,
    total: usize,
    times: Vec<Duration>,
}

impl Stats {
    fn report(&mut self, name: &str) -> (f64, Duration) {
        self.times.sort();
        let median = self.times[self.times.len() / 2];
        let p99 = self.times[self.times.len() * 99 / 100];
        let mean = self.times.iter().sum::<Duration>() / self.times.len() as u32;
        let rate = 100.0 * self.solved as f64 / self.total as f64;
        println!(
            "{name}: solved {}/{} ({rate:.2} %), median {median:?}, mean {mean:?}, p99 {p99:?}",
            self.solved, self.total
        );
        (rate, median)
    }
}

fn main() {
    let robot = Robot::panda().expect("the built-in Panda loads");
    let count: usize = std::env::var("IK_POSES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(10_000);
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let targets: Vec<Pose> = (0..count)
        .map(|_| robot.tcp_pose(&random_configuration(&robot, &mut rng)))
        .collect();

    let mut ours = Stats {
        solved: 0,
        total: count,
        times: Vec::with_capacity(count),
    };
    for target in &targets {
        let start = Instant::now();
        let result = robot.ik(black_box(target), robot.ready());
        ours.times.push(start.elapsed());
        if result.is_ok_and(|q| reached(&robot, &q, target, 1e-6, 1e-6)) {
            ours.solved += 1;
        }
    }
    let baseline = Baseline::new(&robot);
    let mut theirs = Stats {
        solved: 0,
        total: count,
        times: Vec::with_capacity(count),
    };
    let mut restart_rng = ChaCha8Rng::seed_from_u64(2);
    for target in &targets {
        let start = Instant::now();
        let result = baseline.solve(black_box(target), &mut restart_rng);
        theirs.times.push(start.elapsed());
        if result.is_some_and(|q| reached(&robot, &q, target, 1e-4, 1e-3)) {
            theirs.solved += 1;
        }
    }
    let (_, our_median) = ours.report("analytic (akl)");
    let (_, their_median) = theirs.report("k JacobianIkSolver + restarts (baseline)");
    println!(
        "median speed-up over the baseline: {:.0}x",
        their_median.as_secs_f64() / our_median.as_secs_f64()
    );

    let mut c = Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3))
        .configure_from_args();
    let mut i = 0;
    c.bench_function("ik/analytic", |b| {
        b.iter(|| {
            i = (i + 1) % targets.len();
            robot.ik(black_box(&targets[i]), robot.ready())
        })
    });
    let mut j = 0;
    c.bench_function("ik/k_jacobian_restarts", |b| {
        b.iter(|| {
            j = (j + 1) % targets.len();
            baseline.solve(black_box(&targets[j]), &mut restart_rng)
        })
    });
    c.final_summary();
}
