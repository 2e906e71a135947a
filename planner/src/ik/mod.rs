//! Inverse kinematics: the analytic Panda solver, the generic damped least-squares one and the
//! racing one (`trac`),
//! behind one interface that takes TCP poses in the robot base frame.

pub(crate) mod analytic;
mod dls;
mod trac;

use crate::error::IkError;
use crate::fk::Kinematics;
use akl_tsr::nalgebra::Vector6;
use akl_tsr::Pose;
pub(crate) use analytic::PandaIk;
pub(crate) use dls::DlsIk;
pub use trac::TracIk;

/// The pose error `[Δposition, Δrotation]` (base frame) of the TCP at `pose` from `target`,
/// what every numerical step here drives to zero.
fn pose_error(pose: &Pose, target: &Pose) -> Vector6<f64> {
    let dp = target.translation.vector - pose.translation.vector;
    let dr = (target.rotation * pose.rotation.inverse()).scaled_axis();
    Vector6::new(dp.x, dp.y, dp.z, dr.x, dr.y, dr.z)
}

/// The solver a robot uses (chosen in `robot.toml`).
#[derive(Debug, Clone)]
pub(crate) enum IkSolver {
    /// Analytic, for the Panda, with `dls` to follow paths (least-norm steps) and to add the
    /// solution nearest the seed to the analytic ones.
    Panda {
        /// The analytic solver.
        analytic: Box<PandaIk>,
        /// The numerical fallback.
        dls: DlsIk,
    },
    /// Damped least squares with random restarts.
    Dls(DlsIk),
    /// Damped least squares and Levenberg–Marquardt racing, with restarts (any arm).
    Trac(TracIk),
}

impl IkSolver {
    /// The solution nearest `seed`, or [`IkError::Unreachable`].
    pub(crate) fn nearest(
        &self,
        kin: &Kinematics,
        tcp: &Pose,
        seed: &[f64],
    ) -> Result<Vec<f64>, IkError> {
        match self {
            IkSolver::Panda { analytic, .. } => {
                analytic.nearest(kin, tcp, seed).map(|q| q.to_vec())
            }
            IkSolver::Dls(dls) => dls.nearest(kin, tcp, seed),
            IkSolver::Trac(trac) => trac.nearest(kin, tcp, seed),
        }
        .ok_or(IkError::Unreachable)
    }

    /// Up to `max` distinct solutions, nearest `seed` first (empty if unreachable). For the
    /// Panda: the analytic ones and the one damped least squares reaches from the seed.
    pub(crate) fn solutions(
        &self,
        kin: &Kinematics,
        tcp: &Pose,
        seed: &[f64],
        max: usize,
        spacing: f64,
    ) -> Vec<Vec<f64>> {
        match self {
            IkSolver::Panda { analytic, dls } => {
                let mut all: Vec<Vec<f64>> = analytic
                    .solutions(kin, tcp, seed, max, spacing)
                    .into_iter()
                    .map(|q| q.to_vec())
                    .collect();
                // Descent from the seed finds the solution nearest it even where the q7 grid
                // steps over it (near q2 = 0 the split between q1 and q3 turns quickly).
                if let Some(q) = dls.descend(kin, tcp, seed) {
                    if all.iter().all(|s| analytic::max_step(s, &q) > spacing) {
                        all.push(q);
                    }
                }
                let distance = |q: &Vec<f64>| -> f64 {
                    q.iter().zip(seed).map(|(a, b)| (a - b) * (a - b)).sum()
                };
                all.sort_by(|a, b| distance(a).total_cmp(&distance(b)));
                all.truncate(max);
                all
            }
            IkSolver::Dls(dls) => dls.solutions(kin, tcp, seed, max, spacing),
            IkSolver::Trac(trac) => trac.solutions(kin, tcp, seed, max, spacing),
        }
    }

    /// A solution within `max_joint_step` of `previous` on every joint, for following paths.
    pub(crate) fn continuous(
        &self,
        kin: &Kinematics,
        tcp: &Pose,
        previous: &[f64],
        max_joint_step: f64,
    ) -> Option<Vec<f64>> {
        match self {
            // Descent from the previous configuration takes the least-norm step, which splits
            // the motion between redundant joints evenly; with q7 held, the analytic solution
            // can swing q1 and q3 far near q2 = 0. It is the fallback.
            IkSolver::Panda { analytic, dls } => dls
                .continuous(kin, tcp, previous, max_joint_step)
                .or_else(|| {
                    analytic
                        .continuous(kin, tcp, previous, max_joint_step)
                        .map(|q| q.to_vec())
                }),
            IkSolver::Dls(dls) => dls.continuous(kin, tcp, previous, max_joint_step),
            // Following a path wants the least-norm step from the previous configuration.
            IkSolver::Trac(trac) => trac.dls.continuous(kin, tcp, previous, max_joint_step),
        }
    }
}
