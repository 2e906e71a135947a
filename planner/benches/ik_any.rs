//! IK benchmark for arms without a closed form: the racing solver (`trac`: damped least
//! squares and Levenberg–Marquardt with restarts) on the UR5e (six joints) and the FER (seven),
//! against k's `JacobianIkSolver` with restarts, both on the same random reachable poses in
//! the same run.
//!
//! The poses are the TCP (UR5e: `tool0`; FER: `fer_hand_tcp`) of uniformly random in-limit
//! configurations, each solved from the middle of the joint limits. The UR5e's description is
//! read from `AKL_SHARED_ROBOTS` (default `../shared/robots` beside the workspace); the FER
//! is the repository's `robots/panda/fer.urdf`. Run with
//! `cargo bench -p akl-planner --bench ik_any`; `IK_POSES=N` changes the pose count
//! (default 2,000).

use akl_planner::internals::{TracIk, UrdfJoints};
use akl_planner::{parse_urdf, urdf_chain, Kinematics};
use akl_tsr::Pose;
use criterion::{black_box, Criterion};
use k::InverseKinematicsSolver;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

const BASELINE_RESTARTS: usize = 20;

/// One arm: its kinematics, limits, and k's serial chain to the same TCP.
struct Arm {
    name: &'static str,
    kin: Kinematics,
    limits: Vec<[f64; 2]>,
    chain: k::SerialChain<f64>,
}

fn arm(name: &'static str, urdf: &Path, tcp: &str, fingers: &[&str]) -> Arm {
    let text = std::fs::read_to_string(urdf).unwrap_or_else(|e| panic!("{}: {e}", urdf.display()));
    let robot = parse_urdf(&text).expect("the URDF parses");
    let chain = urdf_chain(&robot);
    let fingers: Vec<String> = fingers.iter().map(|f| f.to_string()).collect();
    let (kin, joints) = Kinematics::compile(&chain, tcp, &fingers, &UrdfJoints::of(&robot))
        .expect("the arm compiles");
    let k_chain = k::Chain::<f64>::from(&robot);
    let end = k_chain.find_link(tcp).expect("the TCP is a link").clone();
    Arm {
        name,
        kin,
        limits: joints.limits,
        chain: k::SerialChain::from_end(&end),
    }
}

fn random(limits: &[[f64; 2]], rng: &mut ChaCha8Rng) -> Vec<f64> {
    limits
        .iter()
        .map(|[lo, hi]| rng.gen_range(*lo..*hi))
        .collect()
}

fn middle(limits: &[[f64; 2]]) -> Vec<f64> {
    limits.iter().map(|[lo, hi]| 0.5 * (lo + hi)).collect()
}

fn reached(arm: &Arm, q: &[f64], target: &Pose, position: f64, angle: f64) -> bool {
    let got = arm.kin.tcp_pose(q);
    q.iter()
        .zip(&arm.limits)
        .all(|(v, [lo, hi])| v >= lo && v <= hi)
        && (got.translation.vector - target.translation.vector).norm() <= position
        && got.rotation.angle_to(&target.rotation) <= angle
}

/// k's Jacobian solver (gain 0.5, 100 iterations per try, 0.1 mm and 1 mrad) from the
/// start, then from up to 20 random starts.
fn baseline(arm: &Arm, target: &Pose, rng: &mut ChaCha8Rng) -> Option<Vec<f64>> {
    let solver = k::JacobianIkSolver::new(1e-4, 1e-3, 0.5, 100);
    for attempt in 0..=BASELINE_RESTARTS {
        let start = if attempt == 0 {
            middle(&arm.limits)
        } else {
            random(&arm.limits, rng)
        };
        arm.chain.set_joint_positions_clamped(&start);
        if solver.solve(&arm.chain, target).is_ok() {
            return Some(arm.chain.joint_positions());
        }
    }
    None
}

fn report(name: &str, solved: usize, times: &mut [Duration]) -> Duration {
    times.sort();
    let median = times[times.len() / 2];
    let p99 = times[times.len() * 99 / 100];
    let mean = times.iter().sum::<Duration>() / times.len() as u32;
    println!(
        "{name}: solved {solved}/{} ({:.2} %), median {median:?}, mean {mean:?}, p99 {p99:?}",
        times.len(),
        100.0 * solved as f64 / times.len() as f64
    );
    median
}

fn main() {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let shared = std::env::var_os("AKL_SHARED_ROBOTS")
        .map(PathBuf::from)
        .unwrap_or_else(|| workspace.join("../shared/robots"));
    let count: usize = std::env::var("IK_POSES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2_000);
    let arms = [
        arm("ur5e", &shared.join("ur5e_2f85.urdf"), "tool0", &[]),
        arm(
            "fer",
            &workspace.join("robots/panda/fer.urdf"),
            "fer_hand_tcp",
            &["fer_finger_joint1"],
        ),
    ];
    let mut c = Criterion::default()
        .sample_size(20)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(3))
        .configure_from_args();
    for arm in &arms {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let targets: Vec<Pose> = (0..count)
            .map(|_| arm.kin.tcp_pose(&random(&arm.limits, &mut rng)))
            .collect();
        let trac = TracIk::new(arm.limits.clone());
        let seed = middle(&arm.limits);
        let (mut ours, mut solved) = (Vec::with_capacity(count), 0);
        for target in &targets {
            let start = Instant::now();
            let q = trac.nearest(&arm.kin, black_box(target), &seed);
            ours.push(start.elapsed());
            solved += usize::from(q.is_some_and(|q| reached(arm, &q, target, 1e-6, 1e-6)));
        }
        let (mut theirs, mut theirs_solved) = (Vec::with_capacity(count), 0);
        let mut restart_rng = ChaCha8Rng::seed_from_u64(2);
        for target in &targets {
            let start = Instant::now();
            let q = baseline(arm, black_box(target), &mut restart_rng);
            theirs.push(start.elapsed());
            theirs_solved += usize::from(q.is_some_and(|q| reached(arm, &q, target, 1e-4, 1e-3)));
        }
        let our_median = report(&format!("{}: trac (akl)", arm.name), solved, &mut ours);
        let their_median = report(
            &format!("{}: k JacobianIkSolver + restarts", arm.name),
            theirs_solved,
            &mut theirs,
        );
        println!(
            "{}: baseline median / trac median = {:.1}",
            arm.name,
            their_median.as_secs_f64() / our_median.as_secs_f64()
        );
        let mut i = 0;
        c.bench_function(&format!("ik_any/{}/trac", arm.name), |b| {
            b.iter(|| {
                i = (i + 1) % targets.len();
                trac.nearest(&arm.kin, black_box(&targets[i]), &seed)
            })
        });
        let mut j = 0;
        c.bench_function(&format!("ik_any/{}/k_jacobian_restarts", arm.name), |b| {
            b.iter(|| {
                j = (j + 1) % targets.len();
                baseline(arm, black_box(&targets[j]), &mut restart_rng)
            })
        });
    }
    c.final_summary();
}
