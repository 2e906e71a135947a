//! Analytic inverse kinematics of the Panda with joint 7 as the redundancy parameter.
//!
//! Once q7 is fixed, the pose of frame 6 follows from the target. Joints 2, 4 and 6 then form
//! a triangle (shoulder O2, elbow O4, wrist O6) whose side |O2 O6| fixes q4; the triangle may
//! turn about the line O2–O6, and the wrist condition z5 ⟂ z6 (joint 5's axis is frame 4's
//! y axis) picks at most two turns. The turn is solved for frame 4's z axis, the triangle's
//! normal, so it stays well defined when the elbow is stretched and the triangle flat. Each
//! turn fixes frame 4, from which q5, q6 (a Y–Z rotation) and q1, q2, q3 (a Z–Y–Z rotation,
//! two branches) follow in closed form: up to eight candidates per q7 (He & Liu 2021 derive
//! the same family). q7 is searched on a grid outward from the seed's q7, with branch and
//! bound on the distance to the seed, then refined; a returned solution is polished by a few
//! Gauss–Newton steps to rounding.
//!
//! Lengths come from the URDF: [`PandaIk::from_kinematics`] checks that the arm has the
//! Panda's modified-DH structure and reads d1, d3, a4, a5, d5 and a7 from the joint origins.

use super::pose_error;
use crate::error::PandaIkError;
use crate::fk::{Drive, Kinematics, Motion};
use akl_tsr::nalgebra::{Matrix3, Matrix6, Rotation3, Vector3};
use akl_tsr::Pose;
use std::f64::consts::{FRAC_PI_2, PI};

/// Number of arm joints the solver handles.
pub(crate) const DOF: usize = 7;

/// Grid step of the q7 search (radians).
pub(crate) const Q7_STEP: f64 = 0.2;

/// Grid step of the second, finer q7 sweep run when the coarse one finds nothing (radians).
pub(crate) const Q7_FINE_STEP: f64 = 0.01;

/// Largest position error (metres) a candidate may have once checked by forward kinematics.
pub(crate) const POSITION_TOLERANCE: f64 = 1e-6;

/// Largest rotation error (radians) a candidate may have once checked by forward kinematics.
pub(crate) const ROTATION_TOLERANCE: f64 = 1e-6;

/// |sin q2| below which the shoulder counts as singular (joints 1 and 3 aligned): q1 is kept
/// at the hint and q2 set to 0, leaving the pose error (at most this times the reach) to the
/// polishing steps, instead of splitting q1 + q3 by a ratio of two vanishing numbers.
const SHOULDER_SINGULAR: f64 = 1e-5;

/// Relative amount by which the shoulder–wrist distance may exceed the elbow's reach and
/// still count as the stretched elbow (rounding of a reachable pose is about 1e-15).
const STRETCH_TOLERANCE: f64 = 1e-12;

/// Most Gauss–Newton steps that polish a closed-form solution.
const POLISH_STEPS: usize = 6;

/// Damping of the polishing steps: directions the arm can barely move in at a singularity
/// (such as q1 - q3 at q2 = 0) are left alone instead of taking an unbounded step.
const POLISH_DAMPING: f64 = 1e-7;

/// Pose error (metres and radians, stacked) below which polishing stops.
const POLISH_TOLERANCE: f64 = 1e-13;

/// The twist angles of the Panda's modified DH parameters, joints 1 to 7.
const ALPHA: [f64; DOF] = [
    0.0, -FRAC_PI_2, FRAC_PI_2, FRAC_PI_2, -FRAC_PI_2, FRAC_PI_2, FRAC_PI_2,
];

/// The analytic Panda solver: the arm's lengths, limits and the TCP offset from frame 7.
#[derive(Debug, Clone)]
pub(crate) struct PandaIk {
    d1: f64,
    d3: f64,
    a4: f64,
    a5: f64,
    d5: f64,
    a7: f64,
    seven_in_tcp: Pose,
    /// The inverse of joint 1's parent frame in the robot's base frame (identity unless
    /// fixed links before the arm move it).
    arm_base_inverse: Pose,
    limits: [[f64; 2]; DOF],
}

/// One joint's modified DH parameters (a, d) recovered from its URDF origin.
fn dh_of(origin: &Pose, alpha: f64) -> Result<(f64, f64), String> {
    let expected = Rotation3::from_axis_angle(&Vector3::x_axis(), alpha);
    let angle = origin.rotation.to_rotation_matrix().angle_to(&expected);
    if angle > 1e-9 {
        return Err(format!(
            "origin rotation is not a turn of {alpha:.4} rad about x"
        ));
    }
    let t = origin.translation.vector;
    let (s, c) = alpha.sin_cos();
    // t = (a, -d sin(alpha), d cos(alpha))
    let d = -t.y * s + t.z * c;
    let residual = (t.y + d * s).abs() + (t.z - d * c).abs();
    if residual > 1e-9 {
        return Err("origin translation does not fit (a, -d sin α, d cos α)".into());
    }
    Ok((t.x, d))
}

impl PandaIk {
    /// Reads the Panda's lengths from compiled kinematics, checking the structure: seven
    /// revolute joints about z directly after one another from the base, with the Panda's
    /// twists and zero offsets where the Panda has them, and only fixed joints to the TCP.
    pub(crate) fn from_kinematics(
        kin: &Kinematics,
        limits: &[[f64; 2]],
    ) -> Result<Self, PandaIkError> {
        if kin.dof() != DOF || limits.len() != DOF {
            return Err(PandaIkError::JointCount(kin.dof()));
        }
        let links = kin.links();
        let tcp = kin.tcp_index();
        let mut path = vec![tcp];
        while let Some(p) = links[*path.last().unwrap_or(&tcp)].parent {
            path.push(p);
        }
        path.reverse();
        // Fixed links before joint 1 (such as the FER's root link `base`, or a mount plate
        // that lifts the arm) are part of the base: targets are moved into joint 1's frame.
        let mut base = links[path[0]].origin;
        while path.len() > 1 && links[path[1]].motion == Motion::Fixed {
            base *= links[path[1]].origin;
            path.remove(0);
        }
        // path: base, joint 1 .. joint 7, then fixed links to the TCP.
        if path.len() < 1 + DOF {
            return Err(PandaIkError::ShortChain);
        }
        let mut ad = [(0.0, 0.0); DOF];
        for (k, &i) in path[1..=DOF].iter().enumerate() {
            let link = &links[i];
            let at = |problem: String| PandaIkError::Joint {
                joint: link.joint.clone(),
                index: k,
                problem,
            };
            match link.motion {
                Motion::Revolute {
                    axis,
                    drive:
                        Drive::Arm {
                            index,
                            scale,
                            offset,
                        },
                } if index == k
                    && scale == 1.0
                    && offset == 0.0
                    && (axis.into_inner() - Vector3::z()).norm() < 1e-12 => {}
                _ => return Err(at("must be arm joint revolving about +z".into())),
            }
            ad[k] = dh_of(&link.origin, ALPHA[k]).map_err(at)?;
        }
        let zero = [
            ("a1", ad[0].0),
            ("a2", ad[1].0),
            ("d2", ad[1].1),
            ("a3", ad[2].0),
            ("d4", ad[3].1),
            ("a6", ad[5].0),
            ("d6", ad[5].1),
            ("d7", ad[6].1),
        ];
        if let Some(&(name, value)) = zero.iter().find(|(_, v)| v.abs() > 1e-9) {
            return Err(PandaIkError::NonZero { name, value });
        }
        let mut tcp_in_7 = Pose::identity();
        for &i in &path[1 + DOF..] {
            if links[i].motion != Motion::Fixed {
                return Err(PandaIkError::MovingTip(links[i].joint.clone()));
            }
            tcp_in_7 *= links[i].origin;
        }
        let mut lim = [[0.0; 2]; DOF];
        lim.copy_from_slice(limits);
        Ok(PandaIk {
            d1: ad[0].1,
            d3: ad[2].1,
            a4: ad[3].0,
            a5: ad[4].0,
            d5: ad[4].1,
            a7: ad[6].0,
            seven_in_tcp: tcp_in_7.inverse(),
            arm_base_inverse: base.inverse(),
            limits: lim,
        })
    }

    /// The pose of frame 7, in the frame of joint 1's parent, that puts the TCP at `tcp`
    /// (given in the robot's base frame).
    pub(crate) fn frame7_for(&self, tcp: &Pose) -> Pose {
        self.arm_base_inverse * tcp * self.seven_in_tcp
    }

    /// Calls `emit` with every in-limit solution that puts frame 7 at `f7` with joint 7 at
    /// `q7`; `q1_hint` resolves the shoulder singularity (q2 = 0), where only q1 + q3 is fixed.
    pub(crate) fn solve_q7(
        &self,
        f7: &Pose,
        q7: f64,
        q1_hint: f64,
        mut emit: impl FnMut([f64; DOF]),
    ) {
        if q7 < self.limits[6][0] || q7 > self.limits[6][1] {
            return;
        }
        let r7: Matrix3<f64> = f7.rotation.to_rotation_matrix().into_inner();
        let o7 = f7.translation.vector;
        let (s7, c7) = q7.sin_cos();
        let x6 = r7 * Vector3::new(c7, -s7, 0.0);
        let y6 = -r7.column(2).into_owned();
        let z6 = r7 * Vector3::new(s7, c7, 0.0);
        let o6 = o7 - self.a7 * x6;
        let o2 = Vector3::new(0.0, 0.0, self.d1);
        let v = o6 - o2;
        let l = v.norm();
        if l < 1e-9 {
            return;
        }
        let l24_sq = self.d3 * self.d3 + self.a4 * self.a4;
        let l46_sq = self.a5 * self.a5 + self.d5 * self.d5;
        let k = 0.5 * (l * l - l24_sq - l46_sq);
        let a = self.a5 * self.a4 + self.d5 * self.d3;
        let b = self.a5 * self.d3 - self.d5 * self.a4;
        let r = a.hypot(b);
        // Rounding can put a pose the stretched (or folded) elbow reaches exactly a hair
        // beyond reach; the verification after polishing judges those.
        if k.abs() > r * (1.0 + STRETCH_TOLERANCE) {
            return;
        }
        let gamma = b.atan2(a);
        let delta = (k / r).clamp(-1.0, 1.0).acos();
        let n = v / l;
        // Distance from O2 to the elbow's foot on the line O2–O6.
        let t = (l24_sq - l46_sq + l * l) / (2.0 * l);
        let helper = if n.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let e1 = n.cross(&helper).normalize();
        let e2 = n.cross(&e1);
        let (p, q) = (e1.dot(&z6), e2.dot(&z6));
        let h = p.hypot(q);
        if h < 1e-12 {
            return;
        }
        let psi = q.atan2(p);
        let n_z6 = n.dot(&z6);
        let (ux, uy) = (self.a5, self.d5);
        for q4 in [gamma + delta, gamma - delta] {
            let Some(q4) = fit(q4, self.limits[3]) else {
                continue;
            };
            let (s4, c4) = q4.sin_cos();
            let (wx, wy) = (
                -(self.d3 * s4 + self.a4 * c4),
                -(self.d3 * c4 - self.a4 * s4),
            );
            // In the triangle's plane, with n and m = z4 × n as axes, O6 - O4 has coordinates
            // (l - t, det / l) (det: the frame-4 cross product of u and w, which a rotation
            // keeps, equals -ρ·l). Its frame-4 coordinates are (ux, uy), so x4 is n turned by
            // θ towards m whatever the elbow's angle φ about n; no length that vanishes at
            // the stretched elbow divides anything.
            let det = ux * wy - uy * wx;
            let theta = (det / l).atan2(l - t) - uy.atan2(ux);
            let (st, ct) = theta.sin_cos();
            // y4 = -sin θ·n + cos θ·m(φ) with m(φ) = sin φ·e1 - cos φ·e2; the wrist needs
            // y4 ⟂ z6: h·sin(φ - ψ) = tan θ·(n·z6).
            if ct.abs() < 1e-12 {
                continue;
            }
            let sine = st * n_z6 / (ct * h);
            if sine.abs() > 1.0 {
                continue;
            }
            let eps = sine.asin();
            for phi in [psi + eps, psi + PI - eps] {
                let z4 = phi.cos() * e1 + phi.sin() * e2;
                let m = z4.cross(&n);
                let x4 = ct * n + st * m;
                let y4 = -st * n + ct * m;
                // R4ᵀ·R6 = Ry(q5)·Rz(q6): q5 from its third column, q6 from its second row.
                let (Some(q5), Some(q6)) = (
                    fit(x4.dot(&z6).atan2(z4.dot(&z6)), self.limits[4]),
                    fit(y4.dot(&x6).atan2(y4.dot(&y6)), self.limits[5]),
                ) else {
                    continue;
                };
                // R3 = R4·Rz(-q4)·Rx(-π/2): columns c·x4 - s·y4, -z4, s·x4 + c·y4.
                let x3 = c4 * x4 - s4 * y4;
                let z3 = s4 * x4 + c4 * y4;
                let r3 = Matrix3::from_columns(&[x3, -z4, z3]);
                self.shoulder(&r3, q1_hint, |q1, q2, q3| {
                    emit([q1, q2, q3, q4, q5, q6, q7])
                });
            }
        }
    }

    /// q1, q2, q3 from R3 = Rz(q1)·Ry(q2)·Rz(q3), both branches, fitted into the limits.
    fn shoulder(&self, r3: &Matrix3<f64>, q1_hint: f64, mut emit: impl FnMut(f64, f64, f64)) {
        let s2 = r3[(0, 2)].hypot(r3[(1, 2)]);
        let c2 = r3[(2, 2)];
        let mut candidates = [[f64::NAN; 3]; 2];
        if s2 < SHOULDER_SINGULAR {
            // q2 = 0: only q1 + q3 is determined; keep q1 at the hint.
            let sum = r3[(1, 0)].atan2(r3[(0, 0)]);
            let q1 = q1_hint.clamp(self.limits[0][0], self.limits[0][1]);
            candidates[0] = [q1, 0.0, sum - q1];
        } else {
            candidates[0] = [
                r3[(1, 2)].atan2(r3[(0, 2)]),
                s2.atan2(c2),
                r3[(2, 1)].atan2(-r3[(2, 0)]),
            ];
            candidates[1] = [
                (-r3[(1, 2)]).atan2(-r3[(0, 2)]),
                (-s2).atan2(c2),
                (-r3[(2, 1)]).atan2(r3[(2, 0)]),
            ];
        }
        for [q1, q2, q3] in candidates {
            if q1.is_nan() {
                continue;
            }
            if let (Some(q1), Some(q2), Some(q3)) = (
                fit(q1, self.limits[0]),
                fit(q2, self.limits[1]),
                fit(q3, self.limits[2]),
            ) {
                emit(q1, q2, q3);
            }
        }
    }
}

/// The angle equivalent to `a` (modulo 2π) inside `[lo, hi]`, if any.
pub(crate) fn fit(a: f64, [lo, hi]: [f64; 2]) -> Option<f64> {
    [a, a - 2.0 * PI, a + 2.0 * PI]
        .into_iter()
        .find(|v| *v >= lo && *v <= hi)
}

/// Euclidean distance between two configurations.
fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

/// Largest single-joint difference between two configurations.
pub(crate) fn max_step(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max)
}

impl PandaIk {
    fn q7_range(&self) -> [f64; 2] {
        self.limits[6]
    }

    /// Whether forward kinematics of `q` puts the TCP at `tcp` within the tolerances.
    fn verified(kin: &Kinematics, q: &[f64], tcp: &Pose) -> bool {
        let got = kin.tcp_pose(q);
        (got.translation.vector - tcp.translation.vector).norm() <= POSITION_TOLERANCE
            && got.rotation.angle_to(&tcp.rotation) <= ROTATION_TOLERANCE
    }

    /// `q` polished to rounding, if forward kinematics then meets `tcp` within the tolerances.
    fn finished(&self, kin: &Kinematics, tcp: &Pose, q: [f64; DOF]) -> Option<[f64; DOF]> {
        let q = self.polished(kin, tcp, q);
        Self::verified(kin, &q, tcp).then_some(q)
    }

    /// `q` moved by damped Gauss–Newton steps on joints 1–6 (joint 7 held) until forward
    /// kinematics meets `tcp` to rounding. The closed form leaves errors where it settles a
    /// singularity: in the shoulder-singular band it sets q2 to 0 (up to [`SHOULDER_SINGULAR`]
    /// times the reach off), and at the stretched elbow q4 comes from an arc cosine near 1.
    /// A step is kept only if it lowers the error and stays within the limits.
    fn polished(&self, kin: &Kinematics, tcp: &Pose, mut q: [f64; DOF]) -> [f64; DOF] {
        let (pose, mut jac) = kin.tcp_jacobian(&q);
        let mut err = pose_error(&pose, tcp);
        for _ in 0..POLISH_STEPS {
            if err.norm() < POLISH_TOLERANCE {
                break;
            }
            let j6: Matrix6<f64> = jac.fixed_columns::<{ DOF - 1 }>(0).into_owned();
            let damped =
                j6 * j6.transpose() + Matrix6::identity() * (POLISH_DAMPING * POLISH_DAMPING);
            let Some(y) = damped.cholesky().map(|c| c.solve(&err)) else {
                break;
            };
            let dq = j6.transpose() * y;
            let mut next = q;
            for (i, v) in next.iter_mut().take(DOF - 1).enumerate() {
                *v += dq[i];
            }
            if next
                .iter()
                .zip(&self.limits)
                .any(|(v, [lo, hi])| v < lo || v > hi)
            {
                break;
            }
            let (next_pose, next_jac) = kin.tcp_jacobian(&next);
            let next_err = pose_error(&next_pose, tcp);
            if next_err.norm() >= err.norm() {
                break;
            }
            (q, jac, err) = (next, next_jac, next_err);
        }
        q
    }

    /// The solution nearest `seed` (Euclidean in joint space) among those on the q7 grid
    /// around the seed's q7, refined by bisection in q7; `None` if the pose is unreachable.
    pub(crate) fn nearest(&self, kin: &Kinematics, tcp: &Pose, seed: &[f64]) -> Option<[f64; DOF]> {
        let f7 = self.frame7_for(tcp);
        let [lo, hi] = self.q7_range();
        let mut best: Option<([f64; DOF], f64)> = None;
        let consider = |q7: f64, best: &mut Option<([f64; DOF], f64)>| {
            let mut improved = false;
            self.solve_q7(&f7, q7, seed[0], |c| {
                let d = distance(&c, seed);
                if best.is_none_or(|(_, bd)| d < bd) {
                    *best = Some((c, d));
                    improved = true;
                }
            });
            improved
        };
        let s7 = seed[6].clamp(lo, hi);
        consider(s7, &mut best);
        let mut k = 1.0;
        loop {
            let offset = k * Q7_STEP;
            if best.is_some_and(|(_, d)| offset >= d) || (s7 + offset > hi && s7 - offset < lo) {
                break;
            }
            for q7 in [s7 + offset, s7 - offset] {
                consider(q7, &mut best);
            }
            k += 1.0;
        }
        if best.is_none() {
            let mut q7 = lo;
            while q7 <= hi {
                consider(q7, &mut best);
                q7 += Q7_FINE_STEP;
            }
        }
        let (mut q, _) = best?;
        let mut h = 0.5 * Q7_STEP;
        for _ in 0..6 {
            let centre = q[6];
            for q7 in [centre - h, centre + h] {
                if consider(q7, &mut best) {
                    q = best.map_or(q, |b| b.0);
                }
            }
            h *= 0.5;
        }
        self.finished(kin, tcp, q)
    }

    /// The nearest solution (see [`PandaIk::nearest`]), then distinct solutions from a sweep
    /// over the whole q7 range, nearest `seed` first; two solutions are distinct when some
    /// joint differs by more than `spacing` radians.
    pub(crate) fn solutions(
        &self,
        kin: &Kinematics,
        tcp: &Pose,
        seed: &[f64],
        max: usize,
        spacing: f64,
    ) -> Vec<[f64; DOF]> {
        let f7 = self.frame7_for(tcp);
        let [lo, hi] = self.q7_range();
        let mut all: Vec<([f64; DOF], f64)> = Vec::new();
        let s7 = seed[6].clamp(lo, hi);
        for step in [1.5 * Q7_STEP, Q7_FINE_STEP] {
            let mut k = 0.0;
            while s7 + k * step <= hi || s7 - k * step >= lo {
                for q7 in [s7 + k * step, s7 - k * step] {
                    self.solve_q7(&f7, q7, seed[0], |c| all.push((c, distance(&c, seed))));
                }
                k += 1.0;
            }
            if !all.is_empty() {
                break;
            }
        }
        all.sort_by(|a, b| a.1.total_cmp(&b.1));
        // The grid can step over narrow q7 windows where the solutions nearest the seed lie;
        // the refined nearest solution goes first.
        if let Some(q) = self.nearest(kin, tcp, seed) {
            all.insert(0, (q, 0.0));
        }
        let mut kept: Vec<[f64; DOF]> = Vec::new();
        for (c, _) in all {
            if kept.len() >= max {
                break;
            }
            if kept.iter().all(|k| max_step(k, &c) > spacing) {
                if let Some(c) = self.finished(kin, tcp, c) {
                    kept.push(c);
                }
            }
        }
        kept
    }

    /// A solution that no joint reaches by moving more than `max_joint_step` from `previous`:
    /// q7 is kept at its previous value if possible, else moved as little as needed.
    pub(crate) fn continuous(
        &self,
        kin: &Kinematics,
        tcp: &Pose,
        previous: &[f64],
        max_joint_step: f64,
    ) -> Option<[f64; DOF]> {
        let f7 = self.frame7_for(tcp);
        let mut best: Option<([f64; DOF], f64)> = None;
        let consider = |q7: f64, best: &mut Option<([f64; DOF], f64)>| {
            self.solve_q7(&f7, q7, previous[0], |c| {
                let d = max_step(&c, previous);
                if d <= max_joint_step && best.is_none_or(|(_, bd)| d < bd) {
                    *best = Some((c, d));
                }
            });
        };
        consider(previous[6], &mut best);
        let step = 0.1 * max_joint_step;
        let mut offset = step;
        while best.is_none() && offset <= max_joint_step {
            consider(previous[6] + offset, &mut best);
            consider(previous[6] - offset, &mut best);
            offset += step;
        }
        let (q, _) = best?;
        self.finished(kin, tcp, q)
            .filter(|q| max_step(q, previous) <= max_joint_step)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::robot::Robot;
    use proptest::prelude::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn arb_q() -> impl Strategy<Value = Vec<f64>> {
        let robot = Robot::panda().unwrap();
        robot
            .joint_limits()
            .iter()
            .map(|[lo, hi]| *lo..*hi)
            .collect::<Vec<_>>()
    }

    /// How far (largest joint difference, radians) a solution may be from the configuration
    /// whose pose it solves and still count as that configuration. Near a singularity the pose
    /// fixes the joints only to about the square root of rounding: within 1e-6 rad of the
    /// stretched elbow, solutions that meet the pose to 1e-15 m lie up to 6e-5 rad apart
    /// (measured over 200,000 poses built at the singularities); other branches lie at least
    /// 0.01 rad away.
    const SAME_SOLUTION: f64 = 1e-4;

    /// The elbow angle at which the shoulder–wrist distance is largest (the stretched elbow).
    fn stretched_elbow() -> f64 {
        let robot = Robot::panda().unwrap();
        let ik = PandaIk::from_kinematics(robot.kinematics(), robot.joint_limits()).unwrap();
        let a = ik.a5 * ik.a4 + ik.d5 * ik.d3;
        let b = ik.a5 * ik.d3 - ik.d5 * ik.a4;
        b.atan2(a)
    }

    /// Poses reached with the elbow stretched, alone and with the shoulder (q2 = 0) and the
    /// wrist (q6 = 0) singular too, each solved seeded with its configuration: the closed form
    /// used to divide by the vanishing elbow-circle radius there and found nothing, or a
    /// solution off by 1e-5 rad (44,343 of 200,000 such poses before).
    #[test]
    fn singular_configurations_are_solved_back_to_themselves() {
        let robot = Robot::panda().unwrap();
        let limits = robot.joint_limits().to_vec();
        let gamma = stretched_elbow();
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for k in 0..4000 {
            let mut q: Vec<f64> = limits
                .iter()
                .map(|[lo, hi]| rng.gen_range(*lo..*hi))
                .collect();
            q[3] = gamma + rng.gen_range(-1e-6..1e-6);
            if k % 2 == 1 {
                q[1] = 0.0;
            }
            if k % 4 >= 2 {
                q[5] = 0.0;
            }
            if k % 8 == 7 {
                q[3] = gamma;
            }
            let target = robot.tcp_pose(&q);
            let sol = robot
                .ik(&target, &q)
                .unwrap_or_else(|e| panic!("{q:?}: {e:?}"));
            assert!(close(&robot, &sol, &target), "{q:?}");
            assert!(max_step(&sol, &q) < SAME_SOLUTION, "{sol:?} vs {q:?}");
        }
    }

    fn close(robot: &Robot, q: &[f64], target: &Pose) -> bool {
        let got = robot.tcp_pose(q);
        (got.translation.vector - target.translation.vector).norm() < 1e-6
            && got.rotation.angle_to(&target.rotation) < 1e-6
    }

    fn within_limits(robot: &Robot, q: &[f64]) -> bool {
        robot.check_joints(q).is_ok()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(500))]

        #[test]
        fn ik_of_fk_reproduces_the_pose(q in arb_q()) {
            let robot = Robot::panda().unwrap();
            let target = robot.tcp_pose(&q);
            let sol = robot.ik(&target, robot.ready()).unwrap();
            prop_assert!(close(&robot, &sol, &target));
            prop_assert!(within_limits(&robot, &sol));
        }

        #[test]
        fn seeded_with_the_answer_ik_returns_it(q in arb_q()) {
            let robot = Robot::panda().unwrap();
            let target = robot.tcp_pose(&q);
            let sol = robot.ik(&target, &q).unwrap();
            prop_assert!(max_step(&sol, &q) < SAME_SOLUTION, "{sol:?} vs {q:?}");
        }

        #[test]
        fn every_listed_solution_reaches_the_pose(q in arb_q()) {
            let robot = Robot::panda().unwrap();
            let target = robot.tcp_pose(&q);
            let sols = robot.ik_solutions(&target, robot.ready(), 8);
            prop_assert!(!sols.is_empty());
            for s in &sols {
                prop_assert!(close(&robot, s, &target) && within_limits(&robot, s));
            }
        }

        #[test]
        fn small_moves_have_continuous_solutions(q in arb_q(), dx in -0.002..0.002f64, dz in -0.002..0.002f64) {
            let robot = Robot::panda().unwrap();
            let mut target = robot.tcp_pose(&q);
            target.translation.vector.x += dx;
            target.translation.vector.z += dz;
            if let Some(s) = robot.ik_continuous(&target, &q, 0.1) {
                prop_assert!(close(&robot, &s, &target));
                prop_assert!(max_step(&s, &q) <= 0.1);
            }
        }
    }

    #[test]
    fn a_pose_out_of_reach_is_unreachable() {
        let robot = Robot::panda().unwrap();
        let far = akl_tsr::pose::pose_from_xyz([1.5, 0.0, 0.5]);
        assert_eq!(
            robot.ik(&far, robot.ready()),
            Err(crate::error::IkError::Unreachable)
        );
        assert!(robot.ik_solutions(&far, robot.ready(), 4).is_empty());
    }

    /// The FER's root link `base` sits before joint 1 on a fixed joint: accepted while that
    /// joint does not move the base, refused (naming it) when it does.
    #[test]
    fn fixed_links_before_joint_1_may_move_the_base() {
        let base_joint = r#"<child link="fer_link0"/>
    <origin rpy="0 0 0" xyz="0 0 0"/>"#;
        assert!(crate::robot::PANDA_URDF.contains(base_joint));
        for moved in [
            r#"rpy="0 0 0" xyz="0 0 0.1""#,
            r#"rpy="0 0 0.7" xyz="0.05 -0.2 0""#,
        ] {
            let urdf = crate::robot::PANDA_URDF.replace(
                base_joint,
                &format!("<child link=\"fer_link0\"/>\n    <origin {moved}/>"),
            );
            let parsed = crate::urdf_load::parse(&urdf).unwrap();
            let chain = crate::urdf_load::chain(&parsed);
            let fingers = [
                "fer_finger_joint1".to_string(),
                "fer_finger_joint2".to_string(),
            ];
            let (kin, arm) = Kinematics::compile(
                &chain,
                "fer_hand_tcp",
                &fingers,
                &crate::fk::UrdfJoints::of(&parsed),
            )
            .unwrap();
            let ik = PandaIk::from_kinematics(&kin, &arm.limits).unwrap();
            let q = [0.3, -0.5, 0.2, -2.0, 0.1, 1.8, 0.6];
            let target = kin.tcp_pose(&q);
            let got = ik.nearest(&kin, &target, &q).expect("solved");
            let pose = kin.tcp_pose(&got);
            assert!((pose.translation.vector - target.translation.vector).norm() < 1e-6);
            assert!(max_step(&got, &q) < 1e-6, "{got:?}");
        }
    }
}
