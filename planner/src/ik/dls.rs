//! Generic numerical inverse kinematics: damped least squares with joint limits and random
//! restarts, for arms without an analytic solver.

use super::pose_error;
use crate::fk::Kinematics;
use akl_tsr::nalgebra::Matrix6;
use akl_tsr::Pose;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Settings of the damped least-squares solver.
#[derive(Debug, Clone)]
pub(crate) struct DlsIk {
    /// `[lower, upper]` per arm joint.
    pub limits: Vec<[f64; 2]>,
    /// Damping λ of `Jᵀ(JJᵀ + λ²I)⁻¹`: trades accuracy near singularities for bounded steps.
    pub damping: f64,
    /// Iterations per start.
    pub iterations: usize,
    /// Random starts tried after the seed fails.
    pub restarts: usize,
    /// Largest joint change per iteration (radians or metres).
    pub max_iteration_step: f64,
    /// Position error (metres) below which the target counts as reached.
    pub position_tolerance: f64,
    /// Rotation error (radians) below which the target counts as reached.
    pub rotation_tolerance: f64,
}

impl DlsIk {
    /// A solver with the defaults used by the planner.
    pub(crate) fn new(limits: Vec<[f64; 2]>) -> Self {
        DlsIk {
            limits,
            damping: 0.01,
            iterations: 150,
            restarts: 60,
            max_iteration_step: 0.3,
            position_tolerance: 1e-6,
            rotation_tolerance: 1e-6,
        }
    }

    /// Descends from `start` towards `tcp`; `Some` once within the tolerances.
    pub(crate) fn descend(&self, kin: &Kinematics, tcp: &Pose, start: &[f64]) -> Option<Vec<f64>> {
        let mut q: Vec<f64> = start
            .iter()
            .zip(&self.limits)
            .map(|(v, [lo, hi])| v.clamp(*lo, *hi))
            .collect();
        let lambda_sq = self.damping * self.damping;
        for _ in 0..self.iterations {
            let (pose, jac) = kin.tcp_jacobian(&q);
            let err = pose_error(&pose, tcp);
            if err.fixed_rows::<3>(0).norm() <= self.position_tolerance
                && err.fixed_rows::<3>(3).norm() <= self.rotation_tolerance
            {
                return Some(q);
            }
            let jjt: Matrix6<f64> = &jac * jac.transpose() + Matrix6::identity() * lambda_sq;
            let y = jjt.cholesky()?.solve(&err);
            let dq = jac.transpose() * y;
            let largest = dq.amax();
            let scale = if largest > self.max_iteration_step {
                self.max_iteration_step / largest
            } else {
                1.0
            };
            for (i, v) in q.iter_mut().enumerate() {
                let [lo, hi] = self.limits[i];
                *v = (*v + scale * dq[i]).clamp(lo, hi);
            }
        }
        None
    }

    /// A random configuration within the limits.
    pub(super) fn random(&self, rng: &mut ChaCha8Rng) -> Vec<f64> {
        self.limits
            .iter()
            .map(|[lo, hi]| rng.gen_range(*lo..=*hi))
            .collect()
    }

    /// A solution from the seed, else from random starts (fixed RNG seed: deterministic).
    pub(crate) fn nearest(&self, kin: &Kinematics, tcp: &Pose, seed: &[f64]) -> Option<Vec<f64>> {
        if let Some(q) = self.descend(kin, tcp, seed) {
            return Some(q);
        }
        let mut rng = ChaCha8Rng::seed_from_u64(0x5eed);
        (0..self.restarts).find_map(|_| {
            let start = self.random(&mut rng);
            self.descend(kin, tcp, &start)
        })
    }

    /// Up to `max` distinct solutions (some joint differs by more than `spacing`), from the
    /// seed and from random starts, nearest the seed first.
    pub(crate) fn solutions(
        &self,
        kin: &Kinematics,
        tcp: &Pose,
        seed: &[f64],
        max: usize,
        spacing: f64,
    ) -> Vec<Vec<f64>> {
        self.distinct_solutions(seed, max, spacing, |start, _| self.descend(kin, tcp, start))
    }

    /// Up to `max` solutions that differ in some joint by more than `spacing`, nearest `seed`
    /// first: `solve` is given `seed`, then up to [`DlsIk::restarts`] random starts within the
    /// limits (a fixed RNG seed: deterministic), each with its attempt number.
    pub(super) fn distinct_solutions(
        &self,
        seed: &[f64],
        max: usize,
        spacing: f64,
        mut solve: impl FnMut(&[f64], usize) -> Option<Vec<f64>>,
    ) -> Vec<Vec<f64>> {
        let mut rng = ChaCha8Rng::seed_from_u64(0x5eed);
        let mut found: Vec<Vec<f64>> = Vec::new();
        let mut start = seed.to_vec();
        for attempt in 0..=self.restarts {
            if found.len() >= max {
                break;
            }
            if let Some(q) = solve(&start, attempt) {
                if found
                    .iter()
                    .all(|f| super::analytic::max_step(f, &q) > spacing)
                {
                    found.push(q);
                }
            }
            start = self.random(&mut rng);
        }
        let dist = |q: &Vec<f64>| -> f64 { q.iter().zip(seed).map(|(a, b)| (a - b).powi(2)).sum() };
        found.sort_by(|a, b| dist(a).total_cmp(&dist(b)));
        found
    }

    /// A solution reached from `previous` by descent, if no joint moved more than
    /// `max_joint_step`.
    pub(crate) fn continuous(
        &self,
        kin: &Kinematics,
        tcp: &Pose,
        previous: &[f64],
        max_joint_step: f64,
    ) -> Option<Vec<f64>> {
        self.descend(kin, tcp, previous)
            .filter(|q| super::analytic::max_step(q, previous) <= max_joint_step)
    }
}

#[cfg(test)]
mod tests {
    use crate::robot::{Robot, PANDA_TOML};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn dls_panda() -> Robot {
        Robot::panda_with(&PANDA_TOML.replace("solver = \"panda\"", "solver = \"dls\"")).unwrap()
    }

    #[test]
    fn dls_solves_random_reachable_poses() {
        let robot = dls_panda();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let mut solved = 0;
        let n = 60;
        for _ in 0..n {
            let q: Vec<f64> = robot
                .joint_limits()
                .iter()
                .map(|[lo, hi]| rng.gen_range(*lo..*hi))
                .collect();
            let target = robot.tcp_pose(&q);
            if let Ok(sol) = robot.ik(&target, robot.ready()) {
                let got = robot.tcp_pose(&sol);
                assert!((got.translation.vector - target.translation.vector).norm() < 1e-5);
                assert!(got.rotation.angle_to(&target.rotation) < 1e-5);
                assert!(robot.check_joints(&sol).is_ok());
                solved += 1;
            }
        }
        assert!(solved >= n * 9 / 10, "solved {solved} of {n}");
    }

    #[test]
    fn dls_reports_an_unreachable_pose() {
        let robot = dls_panda();
        let far = akl_tsr::pose::pose_from_xyz([1.5, 0.0, 0.5]);
        assert!(robot.ik(&far, robot.ready()).is_err());
    }
}
