//! Cells of like-facing triangles and the first groupings of them: cutting the largest
//! capsule's cells in two, and k-means on the cells' centroids.

use super::fit::*;
use super::*;
use akl_tsr::nalgebra::{Point3, Vector3};
use std::collections::HashMap;
use std::f64::consts::PI;
use std::hash::{BuildHasherDefault, Hasher};

/// A small fixed-seed generator (splitmix64): the searches' randomness, the same on every run.
pub(super) struct SplitMix(pub(super) u64);

impl SplitMix {
    pub(super) fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub(super) fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in 0..n (n > 0).
    pub(super) fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// A fast hasher for the integer keys of the cell map and of the fit cache (multiply and
/// rotate).
#[derive(Default)]
pub(super) struct MixHasher(u64);

impl Hasher for MixHasher {
    fn finish(&self) -> u64 {
        let z = (self.0 ^ (self.0 >> 29)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z ^ (z >> 32)
    }

    fn write(&mut self, bytes: &[u8]) {
        let mut chunks = bytes.chunks_exact(8);
        for chunk in &mut chunks {
            let mut word = [0; 8];
            word.copy_from_slice(chunk);
            self.write_u64(u64::from_le_bytes(word));
        }
        for &b in chunks.remainder() {
            self.write_u64(u64::from(b));
        }
    }

    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(23) ^ v).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }

    fn write_i64(&mut self, v: i64) {
        self.write_u64(v as u64);
    }
}

pub(super) type Mix = BuildHasherDefault<MixHasher>;

/// Directions spread evenly over the sphere (a Fibonacci lattice), as coordinate arrays so
/// that the extreme-point loop vectorizes.
pub(super) struct Directions {
    pub(super) x: Vec<f64>,
    pub(super) y: Vec<f64>,
    pub(super) z: Vec<f64>,
}

impl Directions {
    pub(super) fn fibonacci(n: usize) -> Directions {
        let turn = PI * (3.0 - 5f64.sqrt());
        let mut d = Directions {
            x: Vec::with_capacity(n),
            y: Vec::with_capacity(n),
            z: Vec::with_capacity(n),
        };
        for i in 0..n {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let rho = (1.0 - z * z).max(0.0).sqrt();
            let phi = turn * i as f64;
            d.x.push(rho * phi.cos());
            d.y.push(rho * phi.sin());
            d.z.push(z);
        }
        d
    }

    /// Into `value` and `arg`, for every direction: the largest projection of the points
    /// `ids` (not empty) on it, and the point that has it (its index as `f64`, exact, so that
    /// the loop vectorizes).
    pub(super) fn support(
        &self,
        points: &[Vector3<f64>],
        ids: &[u32],
        value: &mut Vec<f64>,
        arg: &mut Vec<f64>,
    ) {
        value.clear();
        value.resize(self.x.len(), f64::NEG_INFINITY);
        arg.clear();
        arg.resize(self.x.len(), f64::from(ids[0]));
        for &id in ids {
            let p = points[id as usize];
            let id = f64::from(id);
            for ((((dx, dy), dz), v), a) in self
                .x
                .iter()
                .zip(&self.y)
                .zip(&self.z)
                .zip(value.iter_mut())
                .zip(arg.iter_mut())
            {
                let s = p.x * dx + p.y * dy + p.z * dz;
                let more = s > *v;
                *v = if more { s } else { *v };
                *a = if more { id } else { *a };
            }
        }
    }
}

/// `ids` sorted and without repeats, into `out`.
pub(super) fn distinct(ids: &[u32], out: &mut Vec<u32>) {
    out.clear();
    out.extend_from_slice(ids);
    out.sort_unstable();
    out.dedup();
}

/// A cell of triangles: the unit the search groups.
pub(super) struct Cell {
    /// Its triangles.
    pub(super) triangles: Vec<u32>,
    /// Its corners extreme along [`CELL_DIRECTIONS`] directions (all of them when few).
    pub(super) kernel: Vec<u32>,
    /// For each of the [`GROUP_DIRECTIONS`] directions, the largest projection of its kernel
    /// on it and the point that has it: a group's extremes are its cells' best.
    pub(super) top_value: Vec<f64>,
    /// The points of `top_value`.
    pub(super) top_arg: Vec<u32>,
    /// The area-weighted mean of its triangles' centroids.
    pub(super) centroid: Vector3<f64>,
    /// Its weight in k-means: its area (plus a little per triangle, so that degenerate
    /// triangles count).
    pub(super) weight: f64,
}

/// The triangles in cells of a voxel grid over their centroids, about [`CELL_TARGET`] of them,
/// numbered in the order of their first triangle, and the cells' kernel points (the cells
/// index them).
pub(super) fn cells(triangles: &[[Point3<f64>; 3]]) -> (Vec<Cell>, Vec<Vector3<f64>>) {
    let n = triangles.len();
    let mut centroids = Vec::with_capacity(n);
    let mut areas = Vec::with_capacity(n);
    let mut facing = Vec::with_capacity(n);
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for t in triangles {
        let [a, b, c] = t.map(|p| p.coords);
        let centroid = (a + b + c) / 3.0;
        lo = lo.inf(&centroid);
        hi = hi.sup(&centroid);
        centroids.push(centroid);
        let normal = (b - a).cross(&(c - a));
        let area = 0.5 * normal.norm();
        areas.push(area);
        // The nearest of 26 directions (each coordinate -1, 0 or 1) to the normal.
        let bin = |x: f64| {
            let x = x / (2.0 * area);
            i64::from(x > 0.38) - i64::from(x < -0.38)
        };
        facing.push(if area > 0.0 {
            bin(normal.x) + 3 * bin(normal.y) + 9 * bin(normal.z)
        } else {
            0
        });
    }
    let area: f64 = areas.iter().sum();
    let extent = (hi - lo).max();
    // A surface of area A fills about A / h² cells of side h.
    let mut side = if area > 0.0 {
        (1.5 * area / CELL_TARGET as f64).sqrt()
    } else {
        extent / (CELL_TARGET as f64).cbrt()
    }
    .max(extent * 1e-3);
    let mut of = vec![0u32; n];
    // Numbers the cells of side `side` (split by facing when `faced`) into `of`, and counts
    // them.
    let mut number = |side: f64, faced: bool| {
        let mut index: HashMap<(i64, i64, i64, i64), u32, Mix> =
            HashMap::with_capacity_and_hasher(4 * CELL_TARGET, Mix::default());
        for ((o, c), &f) in of.iter_mut().zip(&centroids).zip(&facing) {
            let f = if faced { f } else { 0 };
            let key = if side > 0.0 {
                let q = (c - lo) / side;
                (q.x as i64, q.y as i64, q.z as i64, f)
            } else {
                (0, 0, 0, f)
            };
            let next = index.len() as u32;
            *o = *index.entry(key).or_insert(next);
        }
        index.len()
    };
    let mut count;
    let mut tries = 0;
    loop {
        count = number(side, false);
        tries += 1;
        let few = count < CELL_TARGET / 2 && count < n;
        if !(few || count > 2 * CELL_TARGET) || tries == 8 {
            break;
        }
        // A surface fills about 1 / side² cells.
        side *= (count as f64 / CELL_TARGET as f64).sqrt().clamp(0.5, 2.0);
    }
    // Triangles facing apart go in different cells: where two tubes meet at a joint, each
    // tube's triangles then stay with its own capsule. A soup of randomly facing triangles
    // would make far too many cells, so it keeps the plain grid.
    let faced = number(side, true);
    count = if faced <= FACED_CELLS * count {
        faced
    } else {
        number(side, false)
    };
    let per_triangle = if area > 0.0 {
        0.05 * area / n as f64
    } else {
        1.0
    };
    let mut cells: Vec<Cell> = (0..count)
        .map(|_| Cell {
            triangles: Vec::new(),
            kernel: Vec::new(),
            top_value: Vec::new(),
            top_arg: Vec::new(),
            centroid: Vector3::zeros(),
            weight: 0.0,
        })
        .collect();
    for (t, &c) in of.iter().enumerate() {
        let cell = &mut cells[c as usize];
        let w = areas[t] + per_triangle;
        cell.triangles.push(t as u32);
        cell.centroid += centroids[t] * w;
        cell.weight += w;
    }
    let directions = Directions::fibonacci(CELL_DIRECTIONS);
    let group_directions = Directions::fibonacci(GROUP_DIRECTIONS);
    let (mut corners, mut ids, mut value, mut arg) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let mut chosen: Vec<Vector3<f64>> = Vec::new();
    let mut points = Vec::new();
    for cell in &mut cells {
        cell.centroid /= cell.weight;
        corners.clear();
        corners.extend(
            cell.triangles
                .iter()
                .flat_map(|&t| triangles[t as usize].map(|p| p.coords)),
        );
        chosen.clear();
        // A few corners are kept all.
        if corners.len() <= 8 {
            chosen.extend_from_slice(&corners);
        } else {
            ids.clear();
            ids.extend(0..corners.len() as u32);
            directions.support(&corners, &ids, &mut value, &mut arg);
            chosen.extend(arg.iter().map(|&i| corners[i as usize]));
        }
        // Corners shared by triangles come once.
        chosen.sort_unstable_by(|p, q| {
            (p.x.total_cmp(&q.x))
                .then(p.y.total_cmp(&q.y))
                .then(p.z.total_cmp(&q.z))
        });
        chosen.dedup();
        cell.kernel
            .extend(points.len() as u32..(points.len() + chosen.len()) as u32);
        points.extend_from_slice(&chosen);
        group_directions.support(&points, &cell.kernel, &mut cell.top_value, &mut arg);
        cell.top_arg.extend(arg.iter().map(|&i| i as u32));
    }
    (cells, points)
}

/// The grouping `best` with its largest capsule's cells cut in two across its axis (at the
/// middle of their centroids' span), the groups numbered from 0 in order, and their number;
/// `None` when no group has cells apart along its axis.
pub(super) fn split(cells: &[Cell], best: &Best) -> Option<(Vec<u32>, usize)> {
    let mut order: Vec<usize> = (0..best.fits.len())
        .filter(|&g| best.fits[g].is_some())
        .collect();
    let groups = order.len();
    order.sort_by(|&g, &h| {
        let volume = |g: usize| best.fits[g].map_or(0.0, |f| f.volume);
        volume(h).total_cmp(&volume(g))
    });
    for g in order {
        let axis = best.fits[g].map(|f| f.axis)?;
        let t = |c: &Cell| c.centroid.dot(&axis);
        let (lo, hi) = cells
            .iter()
            .zip(&best.assign)
            .filter(|(_, &a)| a as usize == g)
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (c, _)| {
                (lo.min(t(c)), hi.max(t(c)))
            });
        if hi <= lo {
            continue;
        }
        let middle = 0.5 * (lo + hi);
        // Groups left keep their order, the cut's far half comes last.
        let mut relabel = vec![0; best.fits.len()];
        let mut next = 0;
        for (h, f) in best.fits.iter().enumerate() {
            if f.is_some() {
                relabel[h] = next;
                next += 1;
            }
        }
        let assign = cells
            .iter()
            .zip(&best.assign)
            .map(|(c, &a)| {
                if a as usize == g && t(c) > middle {
                    next
                } else {
                    relabel[a as usize]
                }
            })
            .collect();
        return Some((assign, groups + 1));
    }
    None
}

/// The cells in at most `k` groups by Lloyd's k-means on their weighted centroids, seeded by
/// k-means++ with the generator seeded by `seed`.
pub(super) fn kmeans(cells: &[Cell], k: usize, seed: u64) -> Vec<u32> {
    const LLOYD: usize = 30;
    let mut rng = SplitMix(0x5EED_0000 + seed);
    let pick = |rng: &mut SplitMix, weight: &dyn Fn(usize) -> f64, total: f64| {
        let mut x = rng.unit() * total;
        let mut last = 0;
        for i in 0..cells.len() {
            let w = weight(i);
            if w > 0.0 {
                last = i;
                if x < w {
                    return i;
                }
                x -= w;
            }
        }
        last
    };
    let total: f64 = cells.iter().map(|c| c.weight).sum();
    let first = pick(&mut rng, &|i| cells[i].weight, total);
    let mut centres = vec![cells[first].centroid];
    let mut d2: Vec<f64> = cells
        .iter()
        .map(|c| (c.centroid - centres[0]).norm_squared())
        .collect();
    while centres.len() < k {
        let total: f64 = cells.iter().zip(&d2).map(|(c, d)| c.weight * d).sum();
        if total <= 0.0 {
            break;
        }
        let next = pick(&mut rng, &|i| cells[i].weight * d2[i], total);
        let centre = cells[next].centroid;
        for (d, c) in d2.iter_mut().zip(cells) {
            *d = d.min((c.centroid - centre).norm_squared());
        }
        centres.push(centre);
    }
    let mut assign = vec![u32::MAX; cells.len()];
    for _ in 0..LLOYD {
        let mut changed = false;
        for (a, c) in assign.iter_mut().zip(cells) {
            let nearest = centres
                .iter()
                .map(|m| (c.centroid - m).norm_squared())
                .enumerate()
                .fold(
                    (0, f64::INFINITY),
                    |b, (i, d)| if d < b.1 { (i, d) } else { b },
                )
                .0 as u32;
            changed |= *a != nearest;
            *a = nearest;
        }
        if !changed {
            break;
        }
        let mut sums = vec![(Vector3::zeros(), 0.0); centres.len()];
        for (&a, c) in assign.iter().zip(cells) {
            sums[a as usize].0 += c.centroid * c.weight;
            sums[a as usize].1 += c.weight;
        }
        for (m, (s, w)) in centres.iter_mut().zip(sums) {
            if w > 0.0 {
                *m = s / w;
            }
        }
    }
    assign
}
