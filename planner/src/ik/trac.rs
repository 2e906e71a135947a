//! Numerical inverse kinematics for any arm, in the manner of TRAC-IK (Beeson and Ames,
//! 2015): two solvers race, each restarting from random configurations when it stalls, and the
//! first to reach the target wins.
//!
//! - **Damped least squares**: the step `Jᵀ(JJᵀ + λ²I)⁻¹e`, capped in size and clipped at the
//!   joint limits (robust far from the target and near singularities).
//! - **Levenberg–Marquardt** (a Newton method with a trust region): the step solves
//!   `(JᵀJ + μ·diag(JᵀJ) + μεI) Δq = Jᵀe`; it is taken only when it lowers the error, and μ
//!   shrinks after a success and grows after a failure (fast, quadratic convergence near
//!   the target, and it slides along joint limits where the pseudo-inverse keeps pushing).
//!
//! The race is deterministic: the two take turns one iteration at a time, each drawing its
//! restarts from its own seeded generator, so the answer never depends on timing.

use super::dls::DlsIk;
use super::pose_error;
use crate::fk::Kinematics;
use akl_tsr::nalgebra::{DMatrix, DVector, Matrix6, Vector6};
use akl_tsr::Pose;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

/// Settings of the racing solver.
#[derive(Debug, Clone)]
pub struct TracIk {
    /// The damped least-squares solver (also used alone to follow paths).
    pub(crate) dls: DlsIk,
    /// Iterations of one solver from one start before it restarts.
    pub(crate) iterations_per_start: usize,
    /// Iterations of each solver in all, over its restarts, before giving up.
    pub(crate) iterations: usize,
}

/// One racer: where it is, its start count and its generator.
struct Racer {
    q: Vec<f64>,
    error: f64,
    steps: usize,
    mu: f64,
    rng: ChaCha8Rng,
}

/// Which way a racer steps.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Method {
    Dls,
    Lm,
}

impl TracIk {
    /// The racing solver over the joint limits `limits`, with the defaults the planner uses.
    pub fn new(limits: Vec<[f64; 2]>) -> Self {
        TracIk {
            dls: DlsIk::new(limits),
            iterations_per_start: 60,
            iterations: 6_000,
        }
    }

    fn limits(&self) -> &[[f64; 2]] {
        &self.dls.limits
    }

    fn clamp(&self, q: &mut [f64]) {
        for (v, [lo, hi]) in q.iter_mut().zip(self.limits()) {
            *v = v.clamp(*lo, *hi);
        }
    }

    fn reached(&self, e: &Vector6<f64>) -> bool {
        e.fixed_rows::<3>(0).norm() <= self.dls.position_tolerance
            && e.fixed_rows::<3>(3).norm() <= self.dls.rotation_tolerance
    }

    /// One iteration of `racer` by `method`; `true` once it is at the target.
    fn step(&self, kin: &Kinematics, target: &Pose, r: &mut Racer, method: Method) -> bool {
        if r.steps >= self.iterations_per_start {
            r.q = self.dls.random(&mut r.rng);
            r.steps = 0;
            r.mu = 1e-3;
        }
        r.steps += 1;
        let (pose, jac) = kin.tcp_jacobian(&r.q);
        let e = pose_error(&pose, target);
        if self.reached(&e) {
            return true;
        }
        r.error = e.norm();
        let n = r.q.len();
        let dq: DVector<f64> = match method {
            Method::Dls => {
                let lambda_sq = self.dls.damping * self.dls.damping;
                let jjt: Matrix6<f64> = &jac * jac.transpose() + Matrix6::identity() * lambda_sq;
                let Some(y) = jjt.cholesky().map(|c| c.solve(&e)) else {
                    r.steps = self.iterations_per_start;
                    return false;
                };
                let dq = jac.transpose() * y;
                let largest = dq.amax();
                let cap = self.dls.max_iteration_step;
                DVector::from_iterator(n, dq.iter().copied())
                    * if largest > cap { cap / largest } else { 1.0 }
            }
            Method::Lm => {
                let jtj: DMatrix<f64> =
                    DMatrix::from_iterator(n, n, (jac.transpose() * &jac).iter().copied());
                let g: DVector<f64> =
                    DVector::from_iterator(n, (jac.transpose() * e).iter().copied());
                let mut a = jtj.clone();
                for i in 0..n {
                    a[(i, i)] += r.mu * (jtj[(i, i)] + 1e-6);
                }
                let Some(dq) = a.cholesky().map(|c| c.solve(&g)) else {
                    r.steps = self.iterations_per_start;
                    return false;
                };
                let mut trial = r.q.clone();
                for (v, d) in trial.iter_mut().zip(dq.iter()) {
                    *v += d;
                }
                self.clamp(&mut trial);
                let better = pose_error(&kin.tcp_pose(&trial), target).norm() < r.error;
                if better {
                    r.mu = (r.mu * 0.3).max(1e-12);
                    r.q = trial;
                } else {
                    r.mu = (r.mu * 4.0).min(1e6);
                }
                return false;
            }
        };
        for (v, d) in r.q.iter_mut().zip(dq.iter()) {
            *v += d;
        }
        self.clamp(&mut r.q);
        false
    }

    /// Races the two solvers from `start` (then from random starts, the generators seeded
    /// with `seed`); the configuration of the first to reach `target`.
    pub(crate) fn race(
        &self,
        kin: &Kinematics,
        target: &Pose,
        start: &[f64],
        seed: u64,
    ) -> Option<Vec<f64>> {
        let mut q = start.to_vec();
        self.clamp(&mut q);
        let racer = |salt: u64| Racer {
            q: q.clone(),
            error: f64::INFINITY,
            steps: 0,
            mu: 1e-3,
            rng: ChaCha8Rng::seed_from_u64(seed ^ salt),
        };
        let mut dls = racer(0x0d15);
        let mut lm = racer(0x0e3a);
        for _ in 0..self.iterations {
            if self.step(kin, target, &mut lm, Method::Lm) {
                return Some(lm.q);
            }
            if self.step(kin, target, &mut dls, Method::Dls) {
                return Some(dls.q);
            }
        }
        None
    }

    /// A solution from the seed, else from random starts.
    pub fn nearest(&self, kin: &Kinematics, tcp: &Pose, seed: &[f64]) -> Option<Vec<f64>> {
        self.race(kin, tcp, seed, 0x5eed)
    }

    /// Up to `max` distinct solutions (some joint differs by more than `spacing`), raced
    /// from the seed and then from random starts, nearest the seed first.
    pub(crate) fn solutions(
        &self,
        kin: &Kinematics,
        tcp: &Pose,
        seed: &[f64],
        max: usize,
        spacing: f64,
    ) -> Vec<Vec<f64>> {
        // Each attempt is one start for each racer: a few restarts at most.
        let one = TracIk {
            iterations: self.iterations_per_start * 2,
            ..self.clone()
        };
        self.dls
            .distinct_solutions(seed, max, spacing, |start, attempt| {
                one.race(kin, tcp, start, attempt as u64)
            })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::Robot;
    use proptest::prelude::*;

    fn solver(robot: &Robot) -> TracIk {
        TracIk::new(robot.joint_limits().to_vec())
    }

    fn in_limits(robot: &Robot, unit: &[f64]) -> Vec<f64> {
        unit.iter()
            .zip(robot.joint_limits())
            .map(|(u, [lo, hi])| lo + u * (hi - lo))
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// A configuration's TCP pose, solved from the ready pose, is reached within the
        /// tolerances and the joint limits (the Panda: seven joints, and the six-joint arm
        /// with continuous joints). Configurations keep 0.1 % of each range from the limits:
        /// a pose reached only with three joints exactly at their limits (shrunk to by
        /// proptest: the Panda's joints 1, 4 and 5 at their lower limits) is found, but
        /// after tens of thousands of iterations, and such poses have probability zero.
        #[test]
        fn a_reachable_pose_is_solved(unit in proptest::collection::vec(0.001f64..0.999, 7)) {
            let panda = Robot::panda().unwrap();
            let arm6 = crate::robot::quirks::arm6();
            for robot in [&panda, &arm6] {
                let q = in_limits(robot, &unit[..robot.dof()]);
                let target = robot.tcp_pose(&q);
                let ik = solver(robot);
                let got = ik.nearest(robot.kinematics(), &target, robot.ready());
                let got = got.expect("a reachable pose is solved");
                let pose = robot.tcp_pose(&got);
                prop_assert!((pose.translation.vector - target.translation.vector).norm() <= 1e-6);
                prop_assert!(pose.rotation.angle_to(&target.rotation) <= 1e-6);
                prop_assert!(robot.check_joints(&got).is_ok());
            }
        }
    }

    #[test]
    fn an_unreachable_pose_is_reported() {
        let robot = Robot::panda().unwrap();
        let far = akl_tsr::pose::pose_from_xyz([1.5, 0.0, 0.5]);
        assert!(solver(&robot)
            .nearest(robot.kinematics(), &far, robot.ready())
            .is_none());
    }

    #[test]
    fn distinct_solutions_are_found_nearest_the_seed_first() {
        let robot = Robot::panda().unwrap();
        let target = robot.tcp_pose(robot.ready());
        let found = solver(&robot).solutions(robot.kinematics(), &target, robot.ready(), 4, 0.1);
        assert!(found.len() >= 2, "{found:?}");
        assert!(super::super::analytic::max_step(&found[0], robot.ready()) < 1e-6);
    }
}
