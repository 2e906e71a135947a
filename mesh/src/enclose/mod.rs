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

mod cells;
mod fit;
mod search;
#[cfg(test)]
mod tests;

use akl_tsr::nalgebra::{Point3, Vector3};
use cells::{cells, kmeans, split};
use fit::{Best, Rule};
use search::Search;
use std::f64::consts::PI;

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
