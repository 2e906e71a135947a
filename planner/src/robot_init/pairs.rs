//! Link pairs that need no collision check, measured as the MoveIt setup assistant does:
//! links next to each other in the chain, and pairs whose collision models never (or always)
//! meet over random configurations within the joint limits, with random gripper openings.

use crate::parry_convert::{intersects, robot_shape};
use crate::robot::Robot;
use akl_tsr::Pose;
use parry3d_f64::shape::SharedShape;
use rand::{Rng, SeedableRng};
use serde::Serialize;

/// The link pairs found not to need checking, each as link indices (lower first).
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub(super) struct PairGuess {
    /// Links next to each other in the chain (nearest ancestors with collision geometry),
    /// and the two fingers.
    pub adjacent: Vec<(usize, usize)>,
    /// Pairs whose models met in none of the samples.
    pub never: Vec<(usize, usize)>,
    /// Pairs whose models met in every sample.
    pub always: Vec<(usize, usize)>,
    /// Pairs left to check.
    pub checked: Vec<(usize, usize)>,
    /// Random configurations drawn.
    pub samples: usize,
}

impl PairGuess {
    /// Every pair not to check, sorted.
    pub(crate) fn allowed(&self) -> Vec<(usize, usize)> {
        let mut all: Vec<(usize, usize)> = [&self.adjacent, &self.never, &self.always]
            .into_iter()
            .flatten()
            .copied()
            .collect();
        all.sort_unstable();
        all.dedup();
        all
    }
}

/// Each link's collision shapes as parry shapes and their poses in the link frame.
pub(super) fn link_shapes(robot: &Robot) -> Vec<Vec<(SharedShape, Pose)>> {
    robot
        .links()
        .iter()
        .map(|link| {
            link.shapes
                .iter()
                .map(|s| {
                    let (shape, local) = robot_shape(&s.geometry, 0.0);
                    (shape, s.origin * local)
                })
                .collect()
        })
        .collect()
}

/// Whether links `a` and `b` meet at the link poses `poses`.
pub(super) fn meet(
    shapes: &[Vec<(SharedShape, Pose)>],
    poses: &[Pose],
    a: usize,
    b: usize,
) -> bool {
    shapes[a].iter().any(|(sa, la)| {
        let pa = poses[a] * la;
        shapes[b]
            .iter()
            .any(|(sb, lb)| intersects(sa, &pa, sb, &(poses[b] * lb)))
    })
}

/// Measures which link pairs of `robot` need checking over `samples` random configurations
/// (seeded: the same every time); `fingers` are the finger links, never checked against each
/// other.
pub(super) fn measure(robot: &Robot, fingers: &[usize], samples: usize, seed: u64) -> PairGuess {
    let links = robot.links();
    let shapes = link_shapes(robot);
    let shaped: Vec<usize> = (0..links.len())
        .filter(|&i| !shapes[i].is_empty())
        .collect();
    let shaped_parent = |mut i: usize| loop {
        match links[i].parent {
            Some(p) if !shapes[p].is_empty() => return Some(p),
            Some(p) => i = p,
            None => return None,
        }
    };
    let mut guess = PairGuess {
        samples,
        ..PairGuess::default()
    };
    let mut open = Vec::new();
    for (k, &a) in shaped.iter().enumerate() {
        for &b in &shaped[k + 1..] {
            let next = shaped_parent(a) == Some(b) || shaped_parent(b) == Some(a);
            if next || (fingers.contains(&a) && fingers.contains(&b)) {
                guess.adjacent.push((a, b));
            } else {
                open.push((a, b));
            }
        }
    }
    let mut hits = vec![0usize; open.len()];
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    for _ in 0..samples {
        let q: Vec<f64> = robot
            .joint_limits()
            .iter()
            .map(|[lo, hi]| rng.gen_range(*lo..=*hi))
            .collect();
        let poses = robot.link_poses(&q, rng.gen_range(0.0..=robot.open_width()));
        for (n, &(a, b)) in open.iter().enumerate() {
            if meet(&shapes, &poses, a, b) {
                hits[n] += 1;
            }
        }
    }
    for (pair, n) in open.into_iter().zip(hits) {
        match n {
            0 => guess.never.push(pair),
            n if n == samples => guess.always.push(pair),
            _ => guess.checked.push(pair),
        }
    }
    guess
}

#[cfg(test)]
mod tests {
    use super::*;

    /// On the Panda, every pair its `robot.toml` checks is measured as needing a check.
    #[test]
    fn the_pandas_checked_pairs_are_found_to_need_checking() {
        let robot = Robot::panda().unwrap();
        let fingers: Vec<usize> = robot
            .finger_joints()
            .iter()
            .filter_map(|j| robot.links().iter().position(|l| l.joint == *j))
            .collect();
        let guess = measure(&robot, &fingers, 400, 7);
        let allowed = guess.allowed();
        let name = |i: usize| robot.links()[i].name.as_str();
        for (a, b) in &guess.checked {
            assert!(!allowed.contains(&(*a, *b)));
        }
        // Adjacent links and the fingers are never checked; link 0 and link 7 meet somewhere.
        let index = |n: &str| robot.links().iter().position(|l| l.name == n).unwrap();
        assert!(allowed.contains(&(index("fer_link0"), index("fer_link1"))));
        assert!(allowed.contains(&(index("fer_leftfinger"), index("fer_rightfinger"))));
        assert!(
            guess
                .checked
                .contains(&(index("fer_link0"), index("fer_link7"))),
            "{:?}",
            guess
                .checked
                .iter()
                .map(|&(a, b)| (name(a), name(b)))
                .collect::<Vec<_>>()
        );
    }
}
