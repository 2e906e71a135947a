//! Capsules enclosing a triangle mesh: the few capsules a motion planner models a robot link
//! with, fitted so that their union contains every triangle of the link's mesh.
//!
//! A capsule is convex, so a triangle whose three corners lie in one capsule lies wholly in
//! it: every triangle is given to one capsule that holds its corners, and containment is made
//! exact at the end by growing each capsule's radius to its farthest corner (plus 1e-9 m),
//! whatever the search found.
//!
//! The search groups cells of triangles (a voxel grid over their centroids, split by which
//! way the triangles face so that two tubes meeting at a joint keep their triangles apart).
//! A capsule holds a point set when it holds its convex hull, so every cell is summarised by
//! its corners that are extreme along a few dozen directions, and a group by its cells'
//! extremes along more. A group's capsule is fitted by trying axis directions (the principal
//! axes, the coordinate axes, the farthest pair's direction, then a local search around the
//! best); for each, the axis line goes through the centre of the smallest circle holding the
//! points projected across it, and the radius (from that circle's up to a sphere's) is the
//! one giving the least volume, a larger radius shortening the segment.
//!
//! Groupings start, for 2, 3, ... up to the number of capsules asked for, from the best
//! grouping so far with its largest capsule cut in two, and from k-means on the cells'
//! centroids (deterministic k-means++ seeds). Each is refined by moving cells to the nearest
//! capsule by three rules in turn ([`Rule`]) and refitting; groupings with one capsule fewer
//! are tried last. The least total volume seen wins, and its capsules are refitted finely.

use akl_tsr::nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};
use std::collections::HashMap;
use std::f64::consts::PI;
use std::hash::{BuildHasherDefault, Hasher};

/// A capsule: every point within `radius` of the segment from `a` to `b` (`a == b` is a
/// sphere). A planner models a robot link as a few of them because the distance to a capsule
/// is one point-to-segment distance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Capsule {
    /// One end of the segment (metres).
    pub a: Point3<f64>,
    /// The other end of the segment (metres).
    pub b: Point3<f64>,
    /// The distance from the segment to the surface (metres).
    pub radius: f64,
}

impl Capsule {
    /// The volume (m³), `π r² |b − a| + 4/3 π r³`: the free space the capsule takes from the
    /// planner, which the fit keeps small.
    pub fn volume(&self) -> f64 {
        capsule_volume(self.radius, (self.b - self.a).norm())
    }

    /// How far `p` is outside the capsule: its distance to the segment minus the radius, so
    /// negative inside and zero on the surface. A point is contained when this is at most 0.
    pub fn depth_outside(&self, p: &Point3<f64>) -> f64 {
        segment_distance(&self.a.coords, &self.b.coords, &p.coords) - self.radius
    }
}

/// At most `count` capsules whose union contains every triangle of `triangles`, each triangle
/// wholly inside one capsule, with the least total volume the search finds: the collision
/// model of a robot link whose real geometry is the mesh, so that an obstacle touching the
/// link's surface always touches the model while the model takes as little free space as it
/// can.
///
/// The search groups cells of nearby, like-facing triangles and fits each group's capsule
/// over axis directions with the smallest enclosing circle across the axis; its work is
/// bounded (a fixed number of group fits per capsule asked for): a few milliseconds for a
/// link's 25,000-triangle mesh.
///
/// Deterministic (the same input gives the same output). An empty input gives an empty `Vec`;
/// `count` 0 is taken as 1. Fewer than `count` capsules are returned when fewer hold the
/// triangles with less total volume (a ball-like mesh is best held by one). Coordinates must
/// be finite. Containment does not depend on the search: every capsule's radius is at least
/// the distance from its segment to the farthest corner of its triangles plus 1e-9.
pub fn enclosing_capsules(triangles: &[[Point3<f64>; 3]], count: usize) -> Vec<Capsule> {
    if triangles.is_empty() {
        return Vec::new();
    }
    let (cells, points) = cells(triangles);
    let most = count.max(1).min(cells.len());
    let mut search = Search::new(&points, &cells, FIT_BUDGET * most);
    let all: Vec<u32> = (0..cells.len() as u32).collect();
    let whole = search.group(&all, None);
    let mut best = Best {
        total: whole.volume,
        assign: vec![0; cells.len()],
        fits: vec![Some(whole)],
    };
    for k in 2..=most {
        // Starts with k groups: the best grouping so far with its largest capsule cut in two,
        // and k-means. Every k gets the same starts whatever the count asked for, so that
        // asking for more capsules finds no worse than asking for fewer (budget allowing).
        if let Some((assign, groups)) = split(&cells, &best) {
            search.refine(assign, groups, &mut best);
        }
        for seed in 0..KMEANS_STARTS {
            search.refine(kmeans(&cells, k, seed), k, &mut best);
        }
    }
    if most >= 2 {
        search.prune(&mut best);
    }
    search.finish(triangles, &best)
}

/// Cells of triangles the search aims for (a voxel grid's occupied cells).
const CELL_TARGET: usize = 256;
/// At most how many times the cells of the grid the cells split by facing may be.
const FACED_CELLS: usize = 3;
/// Directions whose extreme corners summarise a cell.
const CELL_DIRECTIONS: usize = 32;
/// Directions whose extreme points summarise a group of cells for the capsule fit.
const GROUP_DIRECTIONS: usize = 96;
/// k-means starts (seeds) for each number of groups.
const KMEANS_STARTS: u64 = 3;
/// How many groups the search may fit per capsule asked for.
const FIT_BUDGET: usize = 40;
/// Rounds of reassigning cells and refitting per start.
const ROUNDS: usize = 6;
/// The rules cells are reassigned by, in turn.
const RULES: [Rule; 3] = [Rule::Segment, Rule::Depth, Rule::Line];
/// What [`Rule::Line`] counts a cell's distance beyond a segment's end as, against its
/// distance beyond the capsule's typical reach from the axis.
const LENGTHEN: f64 = 0.25;
/// The smallest axis step (radians) of the direction search during the rounds.
const COARSE_STEP: f64 = 0.035;
/// The smallest axis step (radians) of the direction search of the final capsules.
const FINE_STEP: f64 = 0.002;
/// Directions tried around the best axis at each step of the local search.
const RING: usize = 6;
/// The margin (metres) every final radius has beyond its farthest corner.
const MARGIN: f64 = 1e-9;

fn capsule_volume(r: f64, length: f64) -> f64 {
    PI * r * r * (length + 4.0 / 3.0 * r)
}

/// The distance from `p` to the segment from `a` to `b`.
fn segment_distance(a: &Vector3<f64>, b: &Vector3<f64>, p: &Vector3<f64>) -> f64 {
    let ab = b - a;
    let ap = p - a;
    let l2 = ab.norm_squared();
    let s = if l2 > 0.0 {
        (ap.dot(&ab) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (ap - ab * s).norm()
}

/// A small fixed-seed generator (splitmix64): the searches' randomness, the same on every run.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    fn unit(&mut self) -> f64 {
        (self.next() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform in 0..n (n > 0).
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

/// A fast hasher for the integer keys of the cell map and of the fit cache (multiply and
/// rotate).
#[derive(Default)]
struct MixHasher(u64);

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

type Mix = BuildHasherDefault<MixHasher>;

/// Directions spread evenly over the sphere (a Fibonacci lattice), as coordinate arrays so
/// that the extreme-point loop vectorizes.
struct Directions {
    x: Vec<f64>,
    y: Vec<f64>,
    z: Vec<f64>,
}

impl Directions {
    fn fibonacci(n: usize) -> Directions {
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
    fn support(
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
fn distinct(ids: &[u32], out: &mut Vec<u32>) {
    out.clear();
    out.extend_from_slice(ids);
    out.sort_unstable();
    out.dedup();
}

/// A cell of triangles: the unit the search groups.
struct Cell {
    /// Its triangles.
    triangles: Vec<u32>,
    /// Its corners extreme along [`CELL_DIRECTIONS`] directions (all of them when few).
    kernel: Vec<u32>,
    /// For each of the [`GROUP_DIRECTIONS`] directions, the largest projection of its kernel
    /// on it and the point that has it: a group's extremes are its cells' best.
    top_value: Vec<f64>,
    /// The points of `top_value`.
    top_arg: Vec<u32>,
    /// The area-weighted mean of its triangles' centroids.
    centroid: Vector3<f64>,
    /// Its weight in k-means: its area (plus a little per triangle, so that degenerate
    /// triangles count).
    weight: f64,
}

/// The triangles in cells of a voxel grid over their centroids, about [`CELL_TARGET`] of them,
/// numbered in the order of their first triangle, and the cells' kernel points (the cells
/// index them).
fn cells(triangles: &[[Point3<f64>; 3]]) -> (Vec<Cell>, Vec<Vector3<f64>>) {
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
fn split(cells: &[Cell], best: &Best) -> Option<(Vec<u32>, usize)> {
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
fn kmeans(cells: &[Cell], k: usize, seed: u64) -> Vec<u32> {
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

/// A capsule fitted to a group, with its volume and axis direction.
#[derive(Clone, Copy)]
struct Fit {
    capsule: Capsule,
    volume: f64,
    axis: Vector3<f64>,
}

impl Fit {
    /// The fit with the radius grown to hold `ids` of `points`.
    fn holding(mut self, points: &[Vector3<f64>], ids: &[u32]) -> Fit {
        let (a, b) = (self.capsule.a.coords, self.capsule.b.coords);
        let far = ids
            .iter()
            .map(|&i| segment_distance(&a, &b, &points[i as usize]))
            .fold(0.0, f64::max);
        if far > self.capsule.radius {
            self.capsule.radius = far;
            self.volume = self.capsule.volume();
        }
        self
    }
}

/// A capsule's segment as its start, unit direction (the fit's axis for a sphere) and length.
fn line_of(f: &Fit) -> (Vector3<f64>, Vector3<f64>, f64) {
    let c = &f.capsule;
    let length = (c.b - c.a).norm();
    let u = if length > 0.0 {
        (c.b - c.a) / length
    } else {
        f.axis
    };
    (c.a.coords, u, length)
}

/// How a cell picks its capsule when the groups are refined.
#[derive(Clone, Copy)]
enum Rule {
    /// The capsule whose segment is nearest to the cell's farthest kernel point (k-segments):
    /// lets a capsule grow a little to take cells that make another one much larger.
    Segment,
    /// The capsule that holds the cell deepest (least distance beyond its radius): lets a
    /// capsule shed cells another one holds anyway.
    Depth,
    /// The capsule whose axis line the cell is nearest to beyond the capsule's typical
    /// (median) reach, plus [`LENGTHEN`] times how far the cell lies beyond the segment's
    /// ends: gives a tube's cells back to the tube when a neighbour grew fat taking them (at
    /// a joint), since a capsule lengthens cheaply but widens dearly.
    Line,
}

/// The best grouping found: each cell's group and each group's fit (`None` when empty).
struct Best {
    total: f64,
    assign: Vec<u32>,
    fits: Vec<Option<Fit>>,
}

/// Work buffers of the capsule fit, reused so that the inner loops do not allocate.
#[derive(Default)]
struct Work {
    xy: Vec<[f64; 2]>,
    t: Vec<f64>,
    d2: Vec<f64>,
}

/// Two unit vectors completing unit `u` to an orthonormal basis.
fn across(u: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let other = if u.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = (other - u * other.dot(u)).normalize();
    (e1, u.cross(&e1))
}

/// The smallest circle holding `xy` (not empty), as centre and squared radius: the iterative
/// form of Welzl's algorithm, expected linear time when the points come in random order.
fn min_circle(xy: &[[f64; 2]]) -> ([f64; 2], f64) {
    let d2 = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).powi(2) + (p[1] - q[1]).powi(2);
    let outside = |p: [f64; 2], c: [f64; 2], r2: f64| d2(p, c) > r2 * (1.0 + 1e-12);
    let mut c = xy[0];
    let mut r2 = 0.0;
    for i in 1..xy.len() {
        if !outside(xy[i], c, r2) {
            continue;
        }
        c = xy[i];
        r2 = 0.0;
        for j in 0..i {
            if !outside(xy[j], c, r2) {
                continue;
            }
            c = [0.5 * (xy[i][0] + xy[j][0]), 0.5 * (xy[i][1] + xy[j][1])];
            r2 = d2(c, xy[i]);
            for k in 0..j {
                if outside(xy[k], c, r2) {
                    (c, r2) = circle_through(xy[i], xy[j], xy[k]);
                }
            }
        }
    }
    (c, r2)
}

/// The circle through three points, or when they are (nearly) on a line the circle on the
/// farthest two as diameter.
fn circle_through(p: [f64; 2], q: [f64; 2], r: [f64; 2]) -> ([f64; 2], f64) {
    let (ax, ay) = (q[0] - p[0], q[1] - p[1]);
    let (bx, by) = (r[0] - p[0], r[1] - p[1]);
    let (a2, b2) = (ax * ax + ay * ay, bx * bx + by * by);
    let det = 2.0 * (ax * by - ay * bx);
    if det.abs() > 1e-12 * (a2 * b2).sqrt() && det != 0.0 {
        let ux = (by * a2 - ay * b2) / det;
        let uy = (ax * b2 - bx * a2) / det;
        return ([p[0] + ux, p[1] + uy], ux * ux + uy * uy);
    }
    let pairs = [(p, q), (p, r), (q, r)];
    let (s, t) = pairs
        .into_iter()
        .max_by(|x, y| {
            let dx = (x.0[0] - x.1[0]).powi(2) + (x.0[1] - x.1[1]).powi(2);
            let dy = (y.0[0] - y.1[0]).powi(2) + (y.0[1] - y.1[1]).powi(2);
            dx.total_cmp(&dy)
        })
        .unwrap_or((p, q));
    let c = [0.5 * (s[0] + t[0]), 0.5 * (s[1] + t[1])];
    (c, (c[0] - s[0]).powi(2) + (c[1] - s[1]).powi(2))
}

/// The segment and radius of a capsule about a fixed axis line.
#[derive(Clone, Copy)]
struct Axial {
    volume: f64,
    s0: f64,
    s1: f64,
    radius: f64,
}

/// The least-volume capsule of radius `r` about the axis line, for points at axial
/// coordinates `t` and squared distances `d2` from the line (all within `r`): the segment
/// must reach within `sqrt(r² - d²)` of every point along the axis. When no segment is
/// needed, the sphere about the middle with the radius of its farthest point.
fn axial(t: &[f64], d2: &[f64], r: f64) -> Axial {
    let r2 = r * r;
    let (mut s0, mut s1) = (f64::INFINITY, f64::NEG_INFINITY);
    for (&t, &d2) in t.iter().zip(d2) {
        let h = (r2 - d2).max(0.0).sqrt();
        s0 = s0.min(t + h);
        s1 = s1.max(t - h);
    }
    if s0 <= s1 {
        return Axial {
            volume: capsule_volume(r, s1 - s0),
            s0,
            s1,
            radius: r,
        };
    }
    let mid = 0.5 * (s0 + s1);
    let far2 = t
        .iter()
        .zip(d2)
        .map(|(&t, &d2)| d2 + (t - mid) * (t - mid))
        .fold(0.0, f64::max);
    let radius = far2.sqrt().min(r);
    Axial {
        volume: capsule_volume(radius, 0.0),
        s0: mid,
        s1: mid,
        radius,
    }
}

/// The least-volume capsule with axis direction `u` (unit) holding `points` (not empty, in
/// random order): the axis line through the centre of the smallest circle holding the points
/// projected across `u`, and the radius from that circle's up to the sphere's that gives the
/// least volume (a larger radius shortens the segment).
fn fit_along(points: &[Vector3<f64>], u: &Vector3<f64>, w: &mut Work) -> Fit {
    let (e1, e2) = across(u);
    w.xy.clear();
    w.t.clear();
    for p in points {
        w.xy.push([p.dot(&e1), p.dot(&e2)]);
        w.t.push(p.dot(u));
    }
    let (c, _) = min_circle(&w.xy);
    w.d2.clear();
    w.d2.extend(
        w.xy.iter()
            .map(|q| (q[0] - c[0]).powi(2) + (q[1] - c[1]).powi(2)),
    );
    let (t, d2) = (&w.t, &w.d2);
    let r0 = d2.iter().copied().fold(0.0, f64::max).sqrt();
    let tlo = t.iter().copied().fold(f64::INFINITY, f64::min);
    let thi = t.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let r_hi = r0.hypot(0.5 * (thi - tlo));
    const GRID: usize = 8;
    const GOLDEN: usize = 5;
    let radius_at = |k: f64| r0 + (r_hi - r0) * (k / GRID as f64).powi(2);
    let mut best = axial(t, d2, r0);
    let mut best_k = 0;
    for k in 1..=GRID {
        let a = axial(t, d2, radius_at(k as f64));
        if a.volume < best.volume {
            best = a;
            best_k = k;
        }
    }
    // Golden-section search between the best grid radius's neighbours.
    let (mut lo, mut hi) = (
        radius_at(best_k.saturating_sub(1) as f64),
        radius_at((best_k + 1).min(GRID) as f64),
    );
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let mut x1 = hi - g * (hi - lo);
    let mut x2 = lo + g * (hi - lo);
    let mut f1 = axial(t, d2, x1);
    let mut f2 = axial(t, d2, x2);
    for _ in 0..GOLDEN {
        for f in [f1, f2] {
            if f.volume < best.volume {
                best = f;
            }
        }
        if f1.volume < f2.volume {
            hi = x2;
            (x2, f2) = (x1, f1);
            x1 = hi - g * (hi - lo);
            f1 = axial(t, d2, x1);
        } else {
            lo = x1;
            (x1, f1) = (x2, f2);
            x2 = lo + g * (hi - lo);
            f2 = axial(t, d2, x2);
        }
    }
    for f in [f1, f2] {
        if f.volume < best.volume {
            best = f;
        }
    }
    let base = e1 * c[0] + e2 * c[1];
    let capsule = Capsule {
        a: Point3::from(base + u * best.s0),
        b: Point3::from(base + u * best.s1),
        radius: best.radius,
    };
    Fit {
        capsule,
        volume: capsule.volume(),
        axis: *u,
    }
}

/// The least-volume capsule the direction search finds for `points` (not empty, in random
/// order): the principal axis and the farthest pair's direction, and either the `hint` (a
/// group's last axis, near the best when the group changed little) or the other principal
/// axes and the coordinate axes; then a local search around the best down to steps of
/// `min_step` radians.
fn fit_search(
    points: &[Vector3<f64>],
    hint: Option<Vector3<f64>>,
    min_step: f64,
    w: &mut Work,
) -> Fit {
    let n = points.len() as f64;
    let mean = points.iter().sum::<Vector3<f64>>() / n;
    let mut covariance = Matrix3::zeros();
    for p in points {
        let d = p - mean;
        covariance += d * d.transpose();
    }
    let eigen = SymmetricEigen::new(covariance / n);
    let far = |from: &Vector3<f64>| {
        *points
            .iter()
            .max_by(|p, q| {
                (*p - from)
                    .norm_squared()
                    .total_cmp(&(*q - from).norm_squared())
            })
            .unwrap_or(from)
    };
    let first = far(&mean);
    let second = far(&first);
    // nalgebra leaves the eigenvalues unordered: largest (the principal axis) first.
    let mut axes: Vec<(f64, Vector3<f64>)> = eigen
        .eigenvalues
        .iter()
        .zip(eigen.eigenvectors.column_iter())
        .map(|(&l, v)| (l, v.into_owned()))
        .collect();
    axes.sort_by(|a, b| b.0.total_cmp(&a.0));
    let mut candidates = vec![axes[0].1, second - first];
    match hint {
        Some(h) => candidates.push(h),
        None => candidates.extend([
            axes[1].1,
            axes[2].1,
            Vector3::x(),
            Vector3::y(),
            Vector3::z(),
        ]),
    }
    let mut best: Option<Fit> = None;
    for u in candidates {
        let norm = u.norm();
        if !(norm > 0.0 && norm.is_finite()) {
            continue;
        }
        let fit = fit_along(points, &(u / norm), w);
        if best.is_none_or(|b| fit.volume < b.volume) {
            best = Some(fit);
        }
    }
    let mut best = best.unwrap_or_else(|| fit_along(points, &Vector3::z(), w));
    let mut step = if hint.is_some() { 0.1 } else { 0.25 };
    let mut turn = 0.0;
    let mut evaluations = 0;
    while step >= min_step && evaluations < 150 {
        let (e1, e2) = across(&best.axis);
        let mut improved = false;
        for j in 0..RING {
            let phi = turn + j as f64 * 2.0 * PI / RING as f64;
            let u = (best.axis * step.cos() + (e1 * phi.cos() + e2 * phi.sin()) * step.sin())
                .normalize();
            let fit = fit_along(points, &u, w);
            evaluations += 1;
            if fit.volume < best.volume * (1.0 - 1e-9) {
                best = fit;
                improved = true;
            }
        }
        turn += PI / RING as f64;
        if !improved {
            step *= 0.5;
        }
    }
    best
}

/// The search over groupings of cells, with its work space and a cache of group fits.
struct Search<'a> {
    points: &'a [Vector3<f64>],
    cells: &'a [Cell],
    cache: HashMap<Vec<u32>, Fit, Mix>,
    /// How many more groups may be fitted: bounds the search's time whatever the mesh.
    budget: usize,
    work: Work,
    union: Vec<u32>,
    kernel: Vec<u32>,
    value: Vec<f64>,
    arg: Vec<u32>,
    shuffled: Vec<Vector3<f64>>,
}

impl<'a> Search<'a> {
    fn new(points: &'a [Vector3<f64>], cells: &'a [Cell], budget: usize) -> Search<'a> {
        Search {
            points,
            cells,
            cache: HashMap::default(),
            budget,
            work: Work::default(),
            union: Vec::new(),
            kernel: Vec::new(),
            value: Vec::new(),
            arg: Vec::new(),
            shuffled: Vec::new(),
        }
    }

    /// Into `self.union`: the kernel points of the cells `members`; into `self.shuffled`, in
    /// a fixed random order: `self.union` itself when `all`, else its extremes along the
    /// group directions.
    fn gather(&mut self, members: &[u32], all: bool) {
        self.union.clear();
        for &m in members {
            self.union.extend_from_slice(&self.cells[m as usize].kernel);
        }
        self.union.sort_unstable();
        self.union.dedup();
        if all || self.union.len() <= GROUP_DIRECTIONS / 2 {
            self.kernel.clone_from(&self.union);
        } else {
            self.value.clear();
            self.value.resize(GROUP_DIRECTIONS, f64::NEG_INFINITY);
            self.arg.clear();
            self.arg.resize(GROUP_DIRECTIONS, 0);
            for &m in members {
                let cell = &self.cells[m as usize];
                for (((v, a), cv), ca) in self
                    .value
                    .iter_mut()
                    .zip(&mut self.arg)
                    .zip(&cell.top_value)
                    .zip(&cell.top_arg)
                {
                    if cv > v {
                        *v = *cv;
                        *a = *ca;
                    }
                }
            }
            distinct(&self.arg, &mut self.kernel);
        }
        self.shuffled.clear();
        self.shuffled
            .extend(self.kernel.iter().map(|&i| self.points[i as usize]));
        let mut rng = SplitMix(self.shuffled.len() as u64);
        for i in (1..self.shuffled.len()).rev() {
            self.shuffled.swap(i, rng.below(i + 1));
        }
    }

    /// The capsule of the cells `members` (not empty), holding their kernel points.
    fn group(&mut self, members: &[u32], hint: Option<Vector3<f64>>) -> Fit {
        if let Some(fit) = self.cache.get(members) {
            return *fit;
        }
        self.gather(members, false);
        self.budget = self.budget.saturating_sub(1);
        let fit = fit_search(&self.shuffled, hint, COARSE_STEP, &mut self.work)
            .holding(self.points, &self.union);
        self.cache.insert(members.to_vec(), fit);
        fit
    }

    /// The fits of the groups of `assign` (cell → group below `k`; `None` for an empty
    /// group) and their total volume. `axes` holds each group's last axis, the first direction
    /// its fit tries, and is updated.
    fn fit_all(
        &mut self,
        assign: &[u32],
        k: usize,
        axes: &mut [Option<Vector3<f64>>],
    ) -> (Vec<Option<Fit>>, f64) {
        let mut members: Vec<Vec<u32>> = vec![Vec::new(); k];
        for (c, &g) in assign.iter().enumerate() {
            members[g as usize].push(c as u32);
        }
        let mut total = 0.0;
        let fits = members
            .iter()
            .zip(axes.iter_mut())
            .map(|(m, axis)| {
                let fit = (!m.is_empty()).then(|| self.group(m, *axis));
                total += fit.map_or(0.0, |f| f.volume);
                *axis = fit.map(|f| f.axis).or(*axis);
                fit
            })
            .collect();
        (fits, total)
    }

    /// Moves every cell of `assign` to the capsule of `fits` that is nearest by `rule`, and
    /// tells whether any cell moved. Group `skip` gets no cells.
    fn reassign(
        &self,
        assign: &mut [u32],
        fits: &[Option<Fit>],
        rule: Rule,
        skip: Option<usize>,
    ) -> bool {
        let typical = match rule {
            Rule::Line => self.typical_reach(assign, fits),
            _ => Vec::new(),
        };
        let mut changed = false;
        for (cell, a) in self.cells.iter().zip(assign) {
            let cost_of = |g: usize, f: &Fit| match rule {
                Rule::Line => {
                    let (line, u, length) = line_of(f);
                    cell.kernel
                        .iter()
                        .map(|&i| {
                            let d = self.points[i as usize] - line;
                            let t = d.dot(&u);
                            let over = (-t).max(t - length).max(0.0);
                            ((d - u * t).norm() - typical[g]).max(0.0) + LENGTHEN * over
                        })
                        .fold(0.0, f64::max)
                }
                _ => {
                    let (s0, s1) = (f.capsule.a.coords, f.capsule.b.coords);
                    let far = cell
                        .kernel
                        .iter()
                        .map(|&i| segment_distance(&s0, &s1, &self.points[i as usize]))
                        .fold(0.0, f64::max);
                    match rule {
                        Rule::Depth => far - f.capsule.radius,
                        _ => far,
                    }
                }
            };
            let own = *a as usize;
            let mut choice = (
                own,
                match (&fits[own], skip == Some(own)) {
                    (Some(f), false) => cost_of(own, f),
                    _ => f64::INFINITY,
                },
            );
            for (g, f) in fits.iter().enumerate() {
                if let (Some(f), false) = (f, skip == Some(g)) {
                    let c = cost_of(g, f);
                    if c < choice.1 {
                        choice = (g, c);
                    }
                }
            }
            changed |= choice.0 != own;
            *a = choice.0 as u32;
        }
        changed
    }

    /// For each group of `assign`, the median over its cells of their reach from its capsule's
    /// axis line (0 for an empty group).
    fn typical_reach(&self, assign: &[u32], fits: &[Option<Fit>]) -> Vec<f64> {
        let mut reach: Vec<Vec<f64>> = vec![Vec::new(); fits.len()];
        for (cell, &a) in self.cells.iter().zip(assign) {
            let Some(f) = &fits[a as usize] else { continue };
            let (line, u, _) = line_of(f);
            reach[a as usize].push(
                cell.kernel
                    .iter()
                    .map(|&i| {
                        let d = self.points[i as usize] - line;
                        (d - u * d.dot(&u)).norm()
                    })
                    .fold(0.0, f64::max),
            );
        }
        reach
            .into_iter()
            .map(|mut r| {
                r.sort_unstable_by(f64::total_cmp);
                r.get(r.len() / 2).copied().unwrap_or(0.0)
            })
            .collect()
    }

    /// Improves the grouping `assign` (cell → group below `k`): fits every group, moves the
    /// cells to the capsule nearest by each [`Rule`] in turn, refits, and repeats until no
    /// rule moves a cell (or the rounds or the budget run out), recording in `best` any
    /// grouping with less total volume.
    fn refine(&mut self, mut assign: Vec<u32>, k: usize, best: &mut Best) {
        if self.budget == 0 {
            return;
        }
        let mut axes: Vec<Option<Vector3<f64>>> = vec![None; k];
        let (mut fits, mut total) = self.fit_all(&assign, k, &mut axes);
        let mut idle = 0;
        for round in 0..ROUNDS {
            if total < best.total {
                *best = Best {
                    total,
                    assign: assign.clone(),
                    fits: fits.clone(),
                };
            }
            if self.budget == 0 {
                return;
            }
            let rule = RULES[round % RULES.len()];
            if self.reassign(&mut assign, &fits, rule, None) {
                idle = 0;
                (fits, total) = self.fit_all(&assign, k, &mut axes);
            } else {
                idle += 1;
                if idle == RULES.len() {
                    break;
                }
            }
        }
        if total < best.total {
            *best = Best {
                total,
                assign,
                fits,
            };
        }
    }

    /// Tries the best grouping with one capsule fewer (each group's cells given to the
    /// others), refines the best such, and repeats while that lowers the total volume: fewer
    /// capsules than asked for can hold the mesh in less volume.
    fn prune(&mut self, best: &mut Best) {
        loop {
            let groups: Vec<usize> = (0..best.fits.len())
                .filter(|&g| best.fits[g].is_some())
                .collect();
            if groups.len() < 2 || self.budget == 0 {
                return;
            }
            let mut trial_best: Option<(f64, Vec<u32>)> = None;
            for &g in &groups {
                let mut assign = best.assign.clone();
                self.reassign(&mut assign, &best.fits, Rule::Segment, Some(g));
                // Relabel the groups left as 0.. in order.
                let relabel: Vec<u32> = groups.iter().filter(|&&h| h != g).enumerate().fold(
                    vec![0; best.fits.len()],
                    |mut r, (i, &h)| {
                        r[h] = i as u32;
                        r
                    },
                );
                for a in &mut assign {
                    *a = relabel[*a as usize];
                }
                let mut axes = vec![None; groups.len() - 1];
                let (_, total) = self.fit_all(&assign, groups.len() - 1, &mut axes);
                if trial_best.as_ref().is_none_or(|t| total < t.0) {
                    trial_best = Some((total, assign));
                }
            }
            let before = best.total;
            if let Some((_, assign)) = trial_best {
                self.refine(assign, groups.len() - 1, best);
            }
            if best.total >= before {
                return;
            }
        }
    }

    /// The capsules of the best grouping: each refitted finely; every triangle given to its
    /// cell's capsule or, when it sticks out of that one, to one that holds it; a capsule that
    /// some corners stick out of refitted with them; and every radius grown to the farthest
    /// corner given to it plus [`MARGIN`].
    fn finish(&mut self, triangles: &[[Point3<f64>; 3]], best: &Best) -> Vec<Capsule> {
        let mut groups = Vec::with_capacity(best.fits.len());
        for (g, fit) in best.fits.iter().enumerate() {
            let Some(coarse) = fit else { continue };
            let members: Vec<u32> = (0..self.cells.len() as u32)
                .filter(|&c| best.assign[c as usize] == g as u32)
                .collect();
            self.gather(&members, false);
            let fine = fit_search(&self.shuffled, Some(coarse.axis), FINE_STEP, &mut self.work)
                .holding(self.points, &self.union);
            self.gather(&members, true);
            let full = fit_along(&self.shuffled, &fine.axis, &mut self.work)
                .holding(self.points, &self.union);
            let chosen =
                [fine, full]
                    .into_iter()
                    .fold(*coarse, |b, f| if f.volume < b.volume { f } else { b });
            groups.push((members, chosen));
        }
        let mut owner_of_cell = vec![0; self.cells.len()];
        for (i, (members, _)) in groups.iter().enumerate() {
            for &c in members {
                owner_of_cell[c as usize] = i;
            }
        }
        // Each capsule's triangles, the farthest of their corners, and the corners outside it.
        let mut owned: Vec<Vec<u32>> = vec![Vec::new(); groups.len()];
        let mut reach = vec![f64::NEG_INFINITY; groups.len()];
        let mut outside: Vec<Vec<Vector3<f64>>> = vec![Vec::new(); groups.len()];
        for (cell, &own) in self.cells.iter().zip(&owner_of_cell) {
            for &t in &cell.triangles {
                let corners = triangles[t as usize].map(|p| p.coords);
                let far = |c: &Capsule| {
                    corners
                        .iter()
                        .map(|p| segment_distance(&c.a.coords, &c.b.coords, p))
                        .fold(0.0, f64::max)
                };
                let capsule = |i: usize| &groups[i].1.capsule;
                let mut owner = (own, far(capsule(own)));
                if owner.1 > capsule(own).radius {
                    for i in 0..groups.len() {
                        let d = far(capsule(i));
                        if d <= capsule(i).radius
                            && d - capsule(i).radius < owner.1 - capsule(owner.0).radius
                        {
                            owner = (i, d);
                        }
                    }
                }
                let (i, d) = owner;
                owned[i].push(t);
                reach[i] = reach[i].max(d);
                if d > capsule(i).radius {
                    let c = capsule(i);
                    outside[i].extend(
                        corners
                            .iter()
                            .filter(|p| segment_distance(&c.a.coords, &c.b.coords, p) > c.radius),
                    );
                }
            }
        }
        let mut capsules = Vec::with_capacity(groups.len());
        for (((members, fit), triangles_of), (reach, outside)) in groups
            .iter()
            .zip(&owned)
            .zip(reach.into_iter().zip(&outside))
        {
            if triangles_of.is_empty() {
                continue;
            }
            let grown = |c: Capsule, reach: f64| Capsule {
                radius: c.radius.max(reach + MARGIN),
                ..c
            };
            let mut capsule = grown(fit.capsule, reach);
            if !outside.is_empty() {
                // The kernels missed these corners: fit again with them.
                self.gather(members, true);
                self.shuffled.extend_from_slice(outside);
                let refit = fit_along(&self.shuffled, &fit.axis, &mut self.work).capsule;
                let far = triangles_of
                    .iter()
                    .flat_map(|&t| &triangles[t as usize])
                    .map(|p| segment_distance(&refit.a.coords, &refit.b.coords, &p.coords))
                    .fold(0.0, f64::max);
                let refit = grown(refit, far);
                if refit.volume() < capsule.volume() {
                    capsule = refit;
                }
            }
            capsules.push(capsule);
        }
        capsules
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_tsr::nalgebra::{Rotation3, Translation3};
    use proptest::prelude::*;

    type Triangle = [Point3<f64>; 3];

    /// Fails unless every triangle has a capsule holding its three corners.
    fn assert_encloses(triangles: &[Triangle], capsules: &[Capsule]) {
        for (i, t) in triangles.iter().enumerate() {
            assert!(
                capsules
                    .iter()
                    .any(|c| t.iter().all(|p| c.depth_outside(p) <= 0.0)),
                "triangle {i} {t:?} lies in no capsule of {capsules:?}"
            );
        }
    }

    fn total_volume(capsules: &[Capsule]) -> f64 {
        capsules.iter().map(Capsule::volume).sum()
    }

    /// The surface of the box from `lo` to `hi`: 12 triangles.
    fn cuboid(lo: [f64; 3], hi: [f64; 3]) -> Vec<Triangle> {
        let corner = |i: usize| {
            Point3::new(
                if i & 1 == 0 { lo[0] } else { hi[0] },
                if i & 2 == 0 { lo[1] } else { hi[1] },
                if i & 4 == 0 { lo[2] } else { hi[2] },
            )
        };
        let faces = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        faces
            .iter()
            .flat_map(|f| {
                let [a, b, c, d] = f.map(corner);
                [[a, b, c], [a, c, d]]
            })
            .collect()
    }

    /// The closed surface of a cylinder along z about the origin (side and both caps), with
    /// `around` vertices on each circle and `along` rings of side triangles.
    fn cylinder(radius: f64, length: f64, around: usize, along: usize) -> Vec<Triangle> {
        let rim = |i: usize, z: f64| {
            let angle = 2.0 * PI * (i % around) as f64 / around as f64;
            Point3::new(radius * angle.cos(), radius * angle.sin(), z)
        };
        let z = |j: usize| length * (j as f64 / along as f64 - 0.5);
        let mut triangles = Vec::new();
        for j in 0..along {
            for i in 0..around {
                let (p, q) = (rim(i, z(j)), rim(i + 1, z(j)));
                let (r, s) = (rim(i + 1, z(j + 1)), rim(i, z(j + 1)));
                triangles.push([p, q, r]);
                triangles.push([p, r, s]);
            }
        }
        for (end, top) in [(-0.5 * length, false), (0.5 * length, true)] {
            let centre = Point3::new(0.0, 0.0, end);
            for i in 0..around {
                let (p, q) = (rim(i, end), rim(i + 1, end));
                triangles.push(if top { [centre, p, q] } else { [centre, q, p] });
            }
        }
        triangles
    }

    /// Two bars of 0.3 x 0.04 x 0.04 m at right angles, meeting at a corner.
    fn l_shape() -> Vec<Triangle> {
        let mut triangles = cuboid([0.0; 3], [0.3, 0.04, 0.04]);
        triangles.extend(cuboid([0.0; 3], [0.04, 0.3, 0.04]));
        triangles
    }

    /// A soup of triangles: each of `corners` is a triangle's cluster (an index into
    /// `clusters`, each a centre and a size), its shape (0 and 1 plain, 2 all three corners
    /// equal, 3 on a line) and its corners' offsets from the centre in cluster sizes.
    fn soup(
        clusters: &[([f64; 3], f64)],
        corners: &[(prop::sample::Index, u8, [f64; 9])],
    ) -> Vec<Triangle> {
        corners
            .iter()
            .map(|(cluster, shape, offsets)| {
                let (centre, size) = clusters[cluster.index(clusters.len())];
                let corner = |k: usize| {
                    Point3::new(
                        centre[0] + size * offsets[3 * k],
                        centre[1] + size * offsets[3 * k + 1],
                        centre[2] + size * offsets[3 * k + 2],
                    )
                };
                let (a, b) = (corner(0), corner(1));
                match shape {
                    2 => [a, a, a],
                    3 => [a, b, a + (b - a) * 0.25],
                    _ => [a, b, corner(2)],
                }
            })
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// Whatever the triangles, each lies in a returned capsule, and the capsules are at
        /// most as many as asked for, with finite ends and radii at least 0.
        #[test]
        fn every_triangle_lies_in_one_capsule(
            clusters in prop::collection::vec(
                (prop::array::uniform3(-1.0f64..1.0), 0.001f64..0.3),
                1..4,
            ),
            corners in prop::collection::vec(
                (any::<prop::sample::Index>(), 0u8..4, prop::array::uniform9(-1.0f64..1.0)),
                1..40,
            ),
            count in 1usize..=4,
        ) {
            let triangles = soup(&clusters, &corners);
            let capsules = enclosing_capsules(&triangles, count);
            prop_assert!(!capsules.is_empty() && capsules.len() <= count);
            for c in &capsules {
                prop_assert!(c.radius.is_finite() && c.radius >= 0.0, "{c:?}");
                prop_assert!(c.a.coords.iter().chain(c.b.coords.iter()).all(|x| x.is_finite()));
            }
            assert_encloses(&triangles, &capsules);
        }
    }

    /// `n` triangles in a few clusters of assorted sizes, drawn with the generator seeded by
    /// `seed`: enough triangles per cell that the cells' extreme corners leave some out.
    fn big_soup(seed: u64, n: usize) -> Vec<Triangle> {
        let mut rng = SplitMix(seed);
        let mut uniform = |lo: f64, hi: f64| lo + (hi - lo) * rng.unit();
        let clusters: Vec<([f64; 3], f64, f64)> = (0..4)
            .map(|_| {
                let centre = [uniform(-0.5, 0.5), uniform(-0.5, 0.5), uniform(-0.5, 0.5)];
                (centre, uniform(0.01, 0.3), uniform(0.001, 0.05))
            })
            .collect();
        (0..n)
            .map(|i| {
                let (centre, spread, size) = clusters[i % clusters.len()];
                let middle = Vector3::new(
                    centre[0] + spread * uniform(-1.0, 1.0),
                    centre[1] + spread * uniform(-1.0, 1.0),
                    centre[2] + spread * uniform(-1.0, 1.0),
                );
                [0; 3].map(|_| {
                    Point3::from(
                        middle
                            + Vector3::new(
                                uniform(-size, size),
                                uniform(-size, size),
                                uniform(-size, size),
                            ),
                    )
                })
            })
            .collect()
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(16))]

        /// The same for soups of hundreds of triangles, where containment rests on the final
        /// growth of the radii rather than on the fit.
        #[test]
        fn every_triangle_of_a_big_soup_lies_in_one_capsule(
            seed in any::<u64>(),
            n in 100usize..800,
            count in 1usize..=4,
        ) {
            let triangles = big_soup(seed, n);
            let capsules = enclosing_capsules(&triangles, count);
            prop_assert!(!capsules.is_empty() && capsules.len() <= count);
            assert_encloses(&triangles, &capsules);
        }
    }

    /// A closed tube of radius 0.05 m and length 0.2 m, turned and moved off the axes, is
    /// held by one capsule of its radius, within 1.6 times its volume (a capsule of the
    /// tube's radius and length is 4/3 of it).
    #[test]
    fn a_cylinder_gets_a_capsule_of_its_radius() {
        let place =
            Translation3::new(0.3, -0.2, 0.7) * Rotation3::from_euler_angles(0.4, -1.1, 0.3);
        let triangles: Vec<Triangle> = cylinder(0.05, 0.2, 32, 4)
            .into_iter()
            .map(|t| t.map(|p| place * p))
            .collect();
        let capsules = enclosing_capsules(&triangles, 1);
        assert_eq!(capsules.len(), 1);
        assert_encloses(&triangles, &capsules);
        let cylinder_volume = PI * 0.05f64.powi(2) * 0.2;
        let c = capsules[0];
        assert!((c.radius - 0.05).abs() <= 0.002, "{c:?}");
        assert!(
            c.volume() <= 1.6 * cylinder_volume,
            "{c:?}: {}",
            c.volume() / cylinder_volume
        );
    }

    /// Two capsules for an L of two bars take at most half the volume of one.
    #[test]
    fn an_l_shape_splits_into_its_bars() {
        let triangles = l_shape();
        let one = enclosing_capsules(&triangles, 1);
        let two = enclosing_capsules(&triangles, 2);
        assert_encloses(&triangles, &one);
        assert_encloses(&triangles, &two);
        assert_eq!(two.len(), 2);
        assert!(
            total_volume(&two) <= 0.5 * total_volume(&one),
            "{} against {}",
            total_volume(&two),
            total_volume(&one)
        );
    }

    /// Where two tubes meet at an angle, two capsules hold them about as tightly as one
    /// capsule for each tube alone: the joint's triangles go to the tube they belong to.
    #[test]
    fn tubes_at_a_joint_each_get_their_own_capsule() {
        let first = cylinder(0.03, 0.3, 16, 4);
        let bend = Translation3::new(0.0, 0.0, 0.15)
            * Rotation3::from_axis_angle(&Vector3::x_axis(), 1.0)
            * Translation3::new(0.0, 0.0, 0.125);
        let second: Vec<Triangle> = cylinder(0.03, 0.25, 16, 4)
            .into_iter()
            .map(|t| t.map(|p| bend * p))
            .collect();
        let alone = total_volume(&enclosing_capsules(&first, 1))
            + total_volume(&enclosing_capsules(&second, 1));
        let triangles: Vec<Triangle> = first.iter().chain(&second).copied().collect();
        let capsules = enclosing_capsules(&triangles, 2);
        assert_encloses(&triangles, &capsules);
        assert!(
            total_volume(&capsules) <= 1.05 * alone,
            "{} against {alone} for the tubes alone",
            total_volume(&capsules)
        );
    }

    /// The same input gives the same capsules.
    #[test]
    fn same_input_same_output() {
        let mut triangles = l_shape();
        triangles.extend(cylinder(0.02, 0.1, 12, 2));
        for count in 1..=4 {
            assert_eq!(
                enclosing_capsules(&triangles, count),
                enclosing_capsules(&triangles, count)
            );
        }
    }

    #[test]
    fn no_triangles_no_capsules() {
        assert!(enclosing_capsules(&[], 3).is_empty());
    }

    /// A triangle shrunk to a point gets one capsule of about no size holding it.
    #[test]
    fn a_point_gets_a_point_capsule() {
        let p = Point3::new(0.1, -0.2, 0.3);
        let capsules = enclosing_capsules(&[[p, p, p]], 2);
        assert_eq!(capsules.len(), 1);
        assert!(capsules[0].depth_outside(&p) <= 0.0);
        assert!(capsules[0].radius <= 1e-6 && capsules[0].volume() < 1e-15);
    }

    #[test]
    fn volume_and_depth_of_a_capsule() {
        let c = Capsule {
            a: Point3::new(0.0, 0.0, 0.0),
            b: Point3::new(0.0, 0.0, 2.0),
            radius: 0.5,
        };
        let expected = PI * 0.25 * 2.0 + 4.0 / 3.0 * PI * 0.125;
        assert!((c.volume() - expected).abs() < 1e-12);
        assert!((c.depth_outside(&Point3::new(0.0, 0.0, 1.0)) + 0.5).abs() < 1e-12);
        assert!((c.depth_outside(&Point3::new(2.0, 0.0, 1.0)) - 1.5).abs() < 1e-12);
        assert!((c.depth_outside(&Point3::new(0.0, 0.0, -1.0)) - 0.5).abs() < 1e-12);
    }

    proptest! {
        /// The circle holds every point and is no larger than the smallest circle through two
        /// or three of them that holds them all.
        #[test]
        fn the_smallest_circle_is_the_smallest(
            points in prop::collection::vec(prop::array::uniform2(-1.0f64..1.0), 1..10),
        ) {
            let (centre, r2) = min_circle(&points);
            let d2 = |p: [f64; 2], c: [f64; 2]| (p[0] - c[0]).powi(2) + (p[1] - c[1]).powi(2);
            for p in &points {
                prop_assert!(d2(*p, centre) <= r2 * (1.0 + 1e-9) + 1e-15);
            }
            let holds = |(c, r2): ([f64; 2], f64)| {
                points.iter().all(|p| d2(*p, c) <= r2 * (1.0 + 1e-9) + 1e-15)
            };
            let mut smallest = f64::INFINITY;
            for (i, &p) in points.iter().enumerate() {
                for (j, &q) in points.iter().enumerate().skip(i) {
                    let mid = [0.5 * (p[0] + q[0]), 0.5 * (p[1] + q[1])];
                    if holds((mid, d2(p, mid))) {
                        smallest = smallest.min(d2(p, mid));
                    }
                    for &r in &points[j..] {
                        let circle = circle_through(p, q, r);
                        if holds(circle) {
                            smallest = smallest.min(circle.1);
                        }
                    }
                }
            }
            prop_assert!(r2 <= smallest * (1.0 + 1e-9) + 1e-15, "{r2} against {smallest}");
        }
    }
}
