//! Where a spec lets a trace go, on the lattice: each keyframe's region (the cells its TSR
//! reaches) and each `move_in_line` segment's cells (those of the straight lines between its
//! two keyframes' regions).

use super::lattice::{Lattice, NONE};
use akl_tsr::nalgebra::Vector3;
use akl_tsr::rpy::rotation_from_rpy;
use akl_tsr::Tsr;
use std::collections::BTreeSet;

/// Largest number of samples per rotation axis when testing a region's cells.
const MAX_ANGLE_SAMPLES: usize = 25;

/// The cells of `tsr` (world frame): every cell that holds the TCP position of one of its
/// poses (the nominal one's cell always among them).
///
/// The positions of a TSR are `p0 + R0·(t + R(rpy)·e)` for `t` and `rpy` within the bounds,
/// where `p0, R0` is the frame w and `e` the offset `tw_e`: the position box moved by the
/// offset turned through the rotation bounds. Rotations are sampled on a grid fine enough that
/// the offset moves at most an eighth of a cell between neighbouring samples (at most
/// [`MAX_ANGLE_SAMPLES`] per axis); a cell counts when, along each axis of frame w, its extent
/// comes within the grid's error of the box moved by some sample. The region may so exceed the
/// exact one (by that error, and for a frame w turned against the lattice by the corners of
/// the turned cell) but never falls short of it.
pub(super) fn keyframe_cells(lattice: &Lattice, tsr: &Tsr) -> Vec<u32> {
    let mut cells = BTreeSet::new();
    if let Some(c) = lattice.cell_at(&tsr.nominal().translation.vector) {
        cells.insert(c);
    }
    let e = tsr.tw_e.translation.vector;
    let lever = e.norm();
    let target_step = lattice.resolution() / 8.0;
    let mut axes: [Vec<f64>; 3] = Default::default();
    let mut error = 0.0;
    for (a, axis) in axes.iter_mut().enumerate() {
        let [lo, hi] = tsr.bw.0[3 + a];
        let span = hi - lo;
        let steps = ((span * lever / target_step).ceil() as usize).clamp(1, MAX_ANGLE_SAMPLES - 1);
        let step = span / steps as f64;
        error += 0.5 * step * lever;
        *axis = (0..=steps).map(|k| lo + step * k as f64).collect();
    }
    let mut offsets = Vec::with_capacity(axes[0].len() * axes[1].len() * axes[2].len());
    for &roll in &axes[0] {
        for &pitch in &axes[1] {
            for &yaw in &axes[2] {
                offsets.push(rotation_from_rpy([roll, pitch, yaw]) * e);
            }
        }
    }
    let p0 = tsr.t0_w.translation.vector;
    let r0 = tsr.t0_w.rotation;
    let bounds = &tsr.bw.0;
    // A cell's extent along each axis of frame w: half a cell along each world axis, turned.
    let m = r0.to_rotation_matrix();
    let extent = Vector3::from_fn(|i, _| {
        0.5 * lattice.resolution() * (0..3).map(|j| m[(j, i)].abs()).sum::<f64>()
    });
    let inside = |u: &Vector3<f64>| {
        offsets.iter().any(|v| {
            (0..3).all(|i| {
                let d = u[i] - v[i];
                let slack = error + extent[i];
                d >= bounds[i][0] - slack && d <= bounds[i][1] + slack
            })
        })
    };
    // Grid points around the region: the position box grown by the offset, in world axes.
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for corner in 0..8 {
        let local = Vector3::from_fn(|i, _| {
            let [l, h] = bounds[i];
            if corner >> i & 1 == 0 {
                l - lever - error
            } else {
                h + lever + error
            }
        });
        let w = p0 + r0 * local;
        lo = lo.inf(&w);
        hi = hi.sup(&w);
    }
    let (glo, ghi) = (lattice.grid_of(&lo), lattice.grid_of(&hi));
    for x in glo[0]..=ghi[0] {
        for y in glo[1]..=ghi[1] {
            for z in glo[2]..=ghi[2] {
                let id = lattice.id_at([x, y, z]);
                if id == NONE {
                    continue;
                }
                let u = r0.inverse() * (lattice.centre(id) - p0);
                if inside(&u) {
                    cells.insert(id);
                }
            }
        }
    }
    cells.into_iter().collect()
}

/// The grid points a straight line from grid point `a` to grid point `b` passes through, in
/// order, each a face neighbour of the one before (a 3-D voxel traversal; where the line
/// crosses an edge or corner exactly, x steps before y before z).
pub(super) fn traversal(a: [i64; 3], b: [i64; 3]) -> Vec<[i64; 3]> {
    let d = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
    let steps = d.iter().map(|v| v.unsigned_abs() as usize).sum::<usize>();
    let mut out = Vec::with_capacity(steps + 1);
    let mut g = a;
    out.push(g);
    // Crossing k along axis i (k = 1..|d_i|) happens at line parameter (k - 1/2) / |d_i|.
    let mut crossed = [0i64; 3];
    for _ in 0..steps {
        let mut best = None;
        for i in 0..3 {
            let n = d[i].abs();
            if crossed[i] == n {
                continue;
            }
            // Compare (crossed+1/2)/n across axes without division: (2c+1)/(2n).
            let key = (2 * crossed[i] + 1, 2 * n);
            best = match best {
                None => Some((i, key)),
                Some((j, kj)) => {
                    let (p, q) = key;
                    let (pj, qj) = kj;
                    if (p as i128) * (qj as i128) < (pj as i128) * (q as i128) {
                        Some((i, key))
                    } else {
                        Some((j, kj))
                    }
                }
            };
        }
        let Some((i, _)) = best else { break };
        crossed[i] += 1;
        g[i] += d[i].signum();
        out.push(g);
    }
    out
}

/// The cells of a `move_in_line` segment from region `from` to region `to`: every cell the
/// straight line between a cell of one and a cell of the other passes through. A line that
/// crosses a point that is not a cell (furniture, out of reach) contributes nothing: no trace
/// can follow it.
pub(super) fn line_cells(lattice: &Lattice, from: &[u32], to: &[u32]) -> Vec<u32> {
    let mut cells = BTreeSet::new();
    for &a in from {
        for &b in to {
            let path: Vec<u32> = traversal(lattice.coords(a), lattice.coords(b))
                .into_iter()
                .map(|g| lattice.id_at(g))
                .collect();
            if path.iter().all(|&c| c != NONE) {
                cells.extend(path);
            }
        }
    }
    cells.into_iter().collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_scene::World;
    use akl_tsr::pose::{pose_from_xyz, pose_from_xyz_rpy};
    use akl_tsr::Bounds;
    use akl_tsr::Pose;
    use proptest::prelude::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    fn open_lattice(resolution: f64) -> Lattice {
        let world = World {
            robot_base: Pose::identity(),
            objects: Vec::new(),
        };
        Lattice::new(
            &world,
            &Pose::identity(),
            1.0,
            &Vector3::new(0.3, 0.0, 0.5),
            resolution,
        )
    }

    #[test]
    fn a_tight_tsr_inside_a_cell_is_that_cell() {
        let lattice = open_lattice(0.05);
        let tsr = Tsr::new(
            pose_from_xyz([0.41, 0.11, 0.29]),
            pose_from_xyz_rpy([0.0, 0.0, 0.02], [std::f64::consts::PI, 0.0, 0.0]),
            Bounds::symmetric(0.005, 0.05),
        );
        let cells = keyframe_cells(&lattice, &tsr);
        assert_eq!(
            cells,
            vec![lattice.cell_at(&Vector3::new(0.41, 0.11, 0.31)).unwrap()]
        );
    }

    #[test]
    fn a_long_offset_turns_the_region_across_cells() {
        let lattice = open_lattice(0.02);
        // 0.5 m of offset turned by ±0.1 rad of yaw sweeps ±5 cm sideways.
        let mut bw = Bounds::point();
        bw.0[5] = [-0.1, 0.1];
        let tsr = Tsr::new(
            pose_from_xyz([0.2, 0.0, 0.4]),
            pose_from_xyz([0.5, 0.0, 0.0]),
            bw,
        );
        let cells = keyframe_cells(&lattice, &tsr);
        let ys: BTreeSet<i64> = cells.iter().map(|&c| lattice.coords(c)[1]).collect();
        assert!(ys.len() >= 5, "{ys:?}");
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(32))]

        /// Every pose drawn from a TSR has its position in a cell of the region, and widening
        /// the bounds never drops a cell.
        #[test]
        fn regions_cover_their_poses_and_grow_with_their_bounds(
            x in 0.2..0.6f64, y in -0.3..0.3f64, half in 0.0..0.08f64, turn in 0.0..0.6f64,
            lever in 0.0..0.3f64, seed in any::<u64>()
        ) {
            let lattice = open_lattice(0.04);
            let tsr = Tsr::new(
                pose_from_xyz_rpy([x, y, 0.4], [0.0, 0.0, 0.3]),
                pose_from_xyz([lever, 0.0, 0.05]),
                Bounds::symmetric(half, turn),
            );
            let cells: BTreeSet<u32> = keyframe_cells(&lattice, &tsr).into_iter().collect();
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            for _ in 0..20 {
                let p = tsr.sample(&mut rng).translation.vector;
                if let Some(c) = lattice.cell_at(&p) {
                    prop_assert!(cells.contains(&c), "{p:?} not in the region");
                }
            }
            let wider = Tsr::new(tsr.t0_w, tsr.tw_e, Bounds::symmetric(half + 0.03, turn));
            let grown: BTreeSet<u32> = keyframe_cells(&lattice, &wider).into_iter().collect();
            prop_assert!(cells.is_subset(&grown));
        }

        /// A traversal joins its ends by face steps, as many as the grid distance, and stays
        /// within a cell's half-diagonal of the straight line.
        #[test]
        fn traversals_are_shortest_face_paths_along_the_line(
            a in prop::array::uniform3(-6i64..6), b in prop::array::uniform3(-6i64..6)
        ) {
            let path = traversal(a, b);
            prop_assert_eq!(path[0], a);
            prop_assert_eq!(path[path.len() - 1], b);
            let manhattan: i64 = (0..3).map(|i| (b[i] - a[i]).abs()).sum();
            prop_assert_eq!(path.len() as i64, manhattan + 1);
            let (pa, pb) = (Vector3::new(a[0] as f64, a[1] as f64, a[2] as f64), Vector3::new(b[0] as f64, b[1] as f64, b[2] as f64));
            for w in path.windows(2) {
                let step: i64 = (0..3).map(|i| (w[1][i] - w[0][i]).abs()).sum();
                prop_assert_eq!(step, 1);
            }
            for g in &path {
                let p = Vector3::new(g[0] as f64, g[1] as f64, g[2] as f64);
                let d = crate::line::distance_to_segment(&p, &pa, &pb);
                prop_assert!(d <= 0.5 * 3f64.sqrt() + 1e-9, "{g:?} is {d} from the line");
            }
        }
    }
}
