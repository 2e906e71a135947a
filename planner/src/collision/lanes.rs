//! The motion bounds of every chain of a model, four chains side by side.
//!
//! An edge proof bounds, at each of its checks, how far every collision element moves over the
//! stretch being proved ([`super::Checker::sweep_bounds`]): for each element's chain of joints,
//! from every joint on, the smaller of two bounds kept as a [`Motion`]. The work is the same
//! for every chain, joint by joint, so chains are taken in groups of four and computed in the
//! lanes of `f64x4` vectors. Shorter chains of a group are padded with joints that do not move
//! (a turn of zero), which leaves every bound exactly as a chain computed alone would give it:
//! each operation is the one a chain alone performs, in the same order, and a padding joint
//! adds exact zeros. A proof check spends about a quarter of its instructions here.
//!
//! The two bounds, from the last joint of a chain to the first (joint j turning by Δⱼ about
//! the world axis aⱼ through oⱼ, the element's centre at p, its points within `extent` of it):
//!
//! - **reached**: the bound beyond j grown by what j adds: r·|Δⱼ| to the first order, r being
//!   the element's furthest distance from the axis, and |Δⱼ| times the bound beyond for what
//!   the joints beyond move the point further from the axis (see [`Motion`]).
//! - **carried**: the element's velocity at the check through joints j and beyond, the
//!   joints' motions added as vectors so that turns that carry it opposite ways cancel (the
//!   centre's velocity Σ Δⱼ·aⱼ × (p − oⱼ) plus the turning rate Σ Δⱼ·aⱼ times the extent),
//!   plus how far that velocity can stray over the stretch. Joint j's velocity vector is
//!   turned by the rotation of every joint up to j (by at most their turns T times its length,
//!   the reach r plus what the joints beyond move the point, D(s)), and the joints beyond move
//!   p (by D(s)); integrated over the share f, with D(s) ≤ L·s + Q·s² from the bound beyond j,
//!   joint j's stray is at most f²·|Δⱼ|·(T·(r/2 + L/3 + Q/4) + L/2 + Q/3), and a slide's
//!   f²·|Δⱼ|·T/2.

use super::model::Mover;
use super::sweep::{Carried, Motion, Sweep};
use akl_tsr::nalgebra::Vector3;
use akl_tsr::Pose;
use smallvec::SmallVec;
use wide::f64x4;

/// Chains computed side by side.
const LANES: usize = 4;

/// Levels of one group whose turns are kept on the stack.
const INLINE_LEVELS: usize = 16;

/// A lane with no chain.
const EMPTY: usize = usize::MAX;

/// One lane's joint at one level of a group: the arm joint that drives it and by how much,
/// the link it moves and whether it turns (a padding joint neither turns nor slides).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct LaneJoint {
    index: usize,
    scale: f64,
    link: usize,
    turns: bool,
    slides: bool,
}

/// Four chains, level by level: `levels[m]` holds the m-th joint (from the base) of each
/// lane's chain, padding past its end.
#[derive(Debug, Clone, PartialEq)]
struct Group {
    chains: [usize; LANES],
    lengths: [usize; LANES],
    levels: Vec<Level>,
}

/// One level of a group.
#[derive(Debug, Clone, PartialEq)]
struct Level {
    joints: [LaneJoint; LANES],
    /// The joint of every lane whose chain reaches this level, when they all have the same
    /// one (chains of one serial arm share their first joints): its axis and turn are then
    /// read once for the four lanes.
    shared: Option<LaneJoint>,
    /// 1 for the lanes whose chain reaches this level, 0 for padding.
    active: [f64; LANES],
}

/// Where one chain's element is at a check: its centre and how far its points reach from it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Element {
    /// The centre, in the world.
    pub(super) centre: Vector3<f64>,
    /// The furthest any of its points lies from the centre.
    pub(super) extent: f64,
}

/// The chains of a model in groups of four, longest first (so that chains of one length
/// share a group and little is padded).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct ChainLanes {
    groups: Vec<Group>,
}

impl ChainLanes {
    /// The lanes of `chains` (each base first, as [`super::model::chain_to`] gives them).
    #[cfg(test)]
    pub(super) fn new(chains: &[Vec<Mover>]) -> ChainLanes {
        Self::of(chains, &vec![true; chains.len()])
    }

    /// The lanes of the chains `k` of `chains` for which `bounded[k]` holds (the others share
    /// another chain's bounds).
    pub(super) fn of(chains: &[Vec<Mover>], bounded: &[bool]) -> ChainLanes {
        let mut order: Vec<usize> = (0..chains.len()).filter(|&k| bounded[k]).collect();
        order.sort_by_key(|&k| std::cmp::Reverse(chains[k].len()));
        let groups = order
            .chunks(LANES)
            .map(|members| {
                let mut group = Group {
                    chains: [EMPTY; LANES],
                    lengths: [0; LANES],
                    levels: Vec::new(),
                };
                for (lane, &k) in members.iter().enumerate() {
                    group.chains[lane] = k;
                    group.lengths[lane] = chains[k].len();
                }
                for level in 0..chains[members[0]].len() {
                    let mut joints = [LaneJoint::default(); LANES];
                    let mut active = [0.0; LANES];
                    for (lane, &k) in members.iter().enumerate() {
                        if let Some(mover) = chains[k].get(level) {
                            joints[lane] = LaneJoint {
                                index: mover.index,
                                scale: mover.scale,
                                link: mover.link,
                                turns: mover.axis.is_some(),
                                slides: mover.axis.is_none(),
                            };
                            active[lane] = 1.0;
                        }
                    }
                    let first = joints[0];
                    let shared = (0..LANES)
                        .all(|lane| active[lane] == 0.0 || joints[lane] == first)
                        .then_some(first);
                    group.levels.push(Level {
                        joints,
                        shared,
                        active,
                    });
                }
                group
            })
            .collect();
        ChainLanes { groups }
    }

    /// Writes the motion bounds of every chain for the joint motion `sweep.step` into
    /// `sweep.bounds`: `bounds[offsets[k] + m]` for chain k from its m-th joint on (0 past
    /// its last), and its element's first-order motion through the whole chain into
    /// `sweep.carried[offsets[k]]`. `element(k)` places chain k's element; `axes[link]` is
    /// the world axis of each link's joint, and the link's pose in `poses` puts its origin on
    /// that axis.
    pub(super) fn bound(
        &self,
        sweep: &mut Sweep,
        axes: &[Vector3<f64>],
        poses: &[Pose],
        element: impl Fn(usize) -> Element,
        offsets: &[usize],
    ) {
        let Sweep {
            step,
            bounds,
            carried,
        } = sweep;
        for group in &self.groups {
            bound_group(group, step, axes, poses, &element, offsets, bounds, carried);
        }
    }
}

/// A vector of four lanes, each from `f` of the lane.
#[inline(always)]
fn lanes(f: impl Fn(usize) -> f64) -> f64x4 {
    f64x4::new([f(0), f(1), f(2), f(3)])
}

/// The length of the vector with lanes `x`, `y`, `z`, its squares summed as nalgebra sums
/// them.
#[inline(always)]
fn norm(x: f64x4, y: f64x4, z: f64x4) -> f64x4 {
    (x * x + y * y + z * z).sqrt()
}

/// Each lane's signed turn and the length of its slide at `level` for the joint motion
/// `step` (0 for padding and for the other kind of joint).
#[inline(always)]
fn motions(level: &Level, step: &[f64]) -> (f64x4, f64x4) {
    if let Some(j) = level.shared {
        let moved = f64x4::splat(j.scale * step[j.index]);
        let active = f64x4::new(level.active);
        return if j.turns {
            (moved * active, f64x4::ZERO)
        } else {
            (f64x4::ZERO, moved.abs() * active)
        };
    }
    let moved = |l: usize, wanted: bool| {
        let j = level.joints[l];
        if wanted {
            j.scale * step[j.index]
        } else {
            0.0
        }
    };
    (
        lanes(|l| moved(l, level.joints[l].turns)),
        lanes(|l| moved(l, level.joints[l].slides)).abs(),
    )
}

/// Each lane's joint axis (0 where it does not turn) and a point on it at `level`.
#[inline(always)]
fn joint_frames(level: &Level, axes: &[Vector3<f64>], poses: &[Pose]) -> [f64x4; 6] {
    if let Some(j) = level.shared {
        let axis = if j.turns {
            axes[j.link]
        } else {
            Vector3::zeros()
        };
        let origin = poses[j.link].translation.vector;
        let splat = f64x4::splat;
        return [
            splat(axis.x),
            splat(axis.y),
            splat(axis.z),
            splat(origin.x),
            splat(origin.y),
            splat(origin.z),
        ];
    }
    let axis = |i: usize| {
        lanes(|l| {
            let j = level.joints[l];
            if j.turns {
                axes[j.link][i]
            } else {
                0.0
            }
        })
    };
    let origin = |i: usize| lanes(|l| poses[level.joints[l].link].translation.vector[i]);
    [axis(0), axis(1), axis(2), origin(0), origin(1), origin(2)]
}

/// [`ChainLanes::bound`] for one group.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn bound_group(
    group: &Group,
    step: &[f64],
    axes: &[Vector3<f64>],
    poses: &[Pose],
    element: &impl Fn(usize) -> Element,
    offsets: &[usize],
    bounds: &mut [Motion],
    carried: &mut [Carried],
) {
    let zero = f64x4::ZERO;
    let half = f64x4::splat(0.5);
    let quarter = f64x4::splat(0.25);
    let three = f64x4::splat(3.0);
    let placed: [Option<Element>; LANES] =
        std::array::from_fn(|l| (group.chains[l] != EMPTY).then(|| element(group.chains[l])));
    let centre = |i: usize| lanes(|l| placed[l].map_or(0.0, |e| e.centre[i]));
    let (px, py, pz) = (centre(0), centre(1), centre(2));
    let extent = lanes(|l| placed[l].map_or(0.0, |e| e.extent));
    // Each joint's signed turn and slide, and the turns of the chain up to and including it.
    let mut turns: SmallVec<[(f64x4, f64x4); INLINE_LEVELS]> = SmallVec::new();
    let mut rotated: SmallVec<[f64x4; INLINE_LEVELS]> = SmallVec::new();
    let mut total = zero;
    for level in &group.levels {
        let (turn, slide) = motions(level, step);
        total += turn.abs();
        turns.push((turn, slide));
        rotated.push(total);
    }
    // The velocity bound's centre velocity, turning rate, slides and stray; the bound beyond.
    let (mut vx, mut vy, mut vz) = (zero, zero, zero);
    let (mut sx, mut sy, mut sz) = (zero, zero, zero);
    let (mut slid, mut stray) = (zero, zero);
    let (mut linear, mut higher) = (zero, zero);
    for (m, level) in group.levels.iter().enumerate().rev() {
        let (turn, slide) = turns[m];
        let [ax, ay, az, ox, oy, oz] = joint_frames(level, axes, poses);
        let (dx, dy, dz) = (px - ox, py - oy, pz - oz);
        let (lx, ly, lz) = (ay * dz - az * dy, az * dx - ax * dz, ax * dy - ay * dx);
        let reach = norm(lx, ly, lz) + extent;
        let size = turn.abs();
        // The velocity through this joint and those beyond, and its stray.
        vx += turn * lx;
        vy += turn * ly;
        vz += turn * lz;
        sx += turn * ax;
        sy += turn * ay;
        sz += turn * az;
        slid += slide;
        stray = stray
            + size
                * (rotated[m] * (half * reach + linear / three + quarter * higher)
                    + half * linear
                    + higher / three)
            + half * slide * rotated[m];
        let carried_linear = norm(vx, vy, vz) + norm(sx, sy, sz) * extent + slid;
        let carried_higher = stray;
        // The bound beyond grown by this joint's turn or slide.
        let reached_linear = linear + reach * size + slide;
        let reached_higher = higher + size * (linear + higher);
        let carried_wins =
            (carried_linear + carried_higher).simd_lt(reached_linear + reached_higher);
        linear = carried_wins.select(carried_linear, reached_linear);
        higher = carried_wins.select(carried_higher, reached_higher);
        let (linear_lanes, higher_lanes) = (linear.to_array(), higher.to_array());
        for l in 0..LANES {
            if m < group.lengths[l] {
                bounds[offsets[group.chains[l]] + m] = Motion {
                    linear: linear_lanes[l],
                    higher: higher_lanes[l],
                };
            }
        }
    }
    let [vx, vy, vz, sx, sy, sz, extent, slid, stray] =
        [vx, vy, vz, sx, sy, sz, extent, slid, stray].map(|v| v.to_array());
    for l in 0..LANES {
        if group.chains[l] != EMPTY {
            let slot = offsets[group.chains[l]];
            bounds[slot + group.lengths[l]] = Motion::default();
            carried[slot] = Carried {
                velocity: Vector3::new(vx[l], vy[l], vz[l]),
                spin: Vector3::new(sx[l], sy[l], sz[l]),
                extent: extent[l],
                slid: slid[l],
                stray: stray[l],
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The velocity bound of one chain, joint by joint from its last: the statement of what
    /// the lanes compute, written for one chain at a time.
    #[derive(Default)]
    struct Velocity {
        centre: Vector3<f64>,
        spin: Vector3<f64>,
        slid: f64,
        stray: f64,
    }

    impl Velocity {
        fn turn(
            &mut self,
            turn: f64,
            lever: &Vector3<f64>,
            axis: &Vector3<f64>,
            reach: f64,
            rotated: f64,
            beyond: Motion,
        ) {
            self.centre += turn * lever;
            self.spin += turn * axis;
            let (l, q) = (beyond.linear, beyond.higher);
            self.stray +=
                turn.abs() * (rotated * (0.5 * reach + l / 3.0 + 0.25 * q) + 0.5 * l + q / 3.0);
        }

        fn slide(&mut self, distance: f64, rotated: f64) {
            self.slid += distance;
            self.stray += 0.5 * distance * rotated;
        }

        fn motion(&self, extent: f64) -> Motion {
            Motion {
                linear: self.centre.norm() + self.spin.norm() * extent + self.slid,
                higher: self.stray,
            }
        }
    }

    /// [`ChainLanes::bound`] one chain at a time, with [`Motion::turned`] and
    /// [`Motion::slid`] for the first bound.
    fn one_at_a_time(
        chains: &[Vec<Mover>],
        step: &[f64],
        axes: &[Vector3<f64>],
        poses: &[Pose],
        element: impl Fn(usize) -> Element,
        offsets: &[usize],
        bounds: &mut [Motion],
    ) {
        for (k, chain) in chains.iter().enumerate() {
            let Element { centre, extent } = element(k);
            let mut rotated = Vec::new();
            let mut total = 0.0;
            for mover in chain {
                if mover.axis.is_some() {
                    total += (mover.scale * step[mover.index]).abs();
                }
                rotated.push(total);
            }
            let slots = &mut bounds[offsets[k]..offsets[k + 1]];
            let mut velocity = Velocity::default();
            let mut beyond = Motion::default();
            slots[chain.len()] = beyond;
            for (m, mover) in chain.iter().enumerate().rev() {
                let turn = mover.scale * step[mover.index];
                let reached = if mover.axis.is_some() {
                    let axis = axes[mover.link];
                    let lever = axis.cross(&(centre - poses[mover.link].translation.vector));
                    let reach = lever.norm() + extent;
                    velocity.turn(turn, &lever, &axis, reach, rotated[m], beyond);
                    beyond.turned(reach, turn.abs())
                } else {
                    velocity.slide(turn.abs(), rotated[m]);
                    beyond.slid(turn.abs())
                };
                let carried = velocity.motion(extent);
                beyond = if carried.whole() < reached.whole() {
                    carried
                } else {
                    reached
                };
                slots[m] = beyond;
            }
        }
    }

    /// A chain of up to eight joints over links 0..8, driven by arm joints 0..7 (some by the
    /// same one, some scaled or reversed), each turning or, now and then, sliding.
    fn arb_chain() -> impl Strategy<Value = Vec<Mover>> {
        prop::collection::vec((0..7usize, -2.0..2.0f64, 0..10u8), 0..9).prop_map(|joints| {
            joints
                .into_iter()
                .enumerate()
                .map(|(link, (index, scale, kind))| Mover {
                    link,
                    index,
                    scale,
                    axis: (kind != 0).then(|| Vector3::new(0.3, -0.2, 0.9).normalize()),
                })
                .collect()
        })
    }

    fn arb_vector(size: f64) -> impl Strategy<Value = Vector3<f64>> {
        [-size..size, -size..size, -size..size].prop_map(|[x, y, z]| Vector3::new(x, y, z))
    }

    /// Chains as `arb_chain` makes them, and as many prefixes of one more such chain (the
    /// chains of one serial arm share their first joints).
    fn arb_chains() -> impl Strategy<Value = Vec<Vec<Mover>>> {
        (
            prop::collection::vec(arb_chain(), 0..6),
            arb_chain(),
            prop::collection::vec(0..9usize, 0..7),
        )
            .prop_map(|(mut chains, arm, prefixes)| {
                for length in prefixes {
                    chains.push(arm[..length.min(arm.len())].to_vec());
                }
                chains
            })
            .prop_filter("at least one chain", |chains| !chains.is_empty())
    }

    proptest! {
        /// Chains of any lengths (padded in their groups), turning and sliding joints mixed
        /// within a level or shared by every lane of it, get exactly the bounds each chain
        /// computed alone gets, to the last bit: the lanes change how the bounds are computed,
        /// never what they are.
        #[test]
        fn lanes_bound_every_chain_exactly_as_one_chain_at_a_time(
            chains in arb_chains(),
            step in prop::collection::vec(-1.5..1.5f64, 7),
            axes in prop::collection::vec(arb_vector(1.0), 8),
            origins in prop::collection::vec(arb_vector(1.0), 8),
            centres in prop::collection::vec(arb_vector(1.0), 12),
            extents in prop::collection::vec(0.0..0.2f64, 12),
        ) {
            let mut offsets = vec![0];
            for chain in &chains {
                offsets.push(offsets.last().unwrap() + chain.len() + 1);
            }
            let element = |k: usize| Element { centre: centres[k], extent: extents[k] };
            let slots = *offsets.last().unwrap();
            let mut expected = vec![Motion { linear: -1.0, higher: -1.0 }; slots];
            let poses: Vec<Pose> = origins.iter().map(|o| Pose::from_parts((*o).into(), Default::default())).collect();
            one_at_a_time(&chains, &step, &axes, &poses, element, &offsets, &mut expected);
            let mut sweep = Sweep {
                step: step.clone(),
                bounds: vec![Motion { linear: -2.0, higher: -2.0 }; slots],
                carried: vec![Carried::default(); slots],
            };
            ChainLanes::new(&chains).bound(&mut sweep, &axes, &poses, element, &offsets);
            for (slot, (e, f)) in expected.iter().zip(&sweep.bounds).enumerate() {
                prop_assert_eq!(e.linear.to_bits(), f.linear.to_bits(), "slot {}", slot);
                prop_assert_eq!(e.higher.to_bits(), f.higher.to_bits(), "slot {}", slot);
            }
        }
    }
}
