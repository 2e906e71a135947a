//! Path shortcutting: straight joint-space edges between random points of the path replace
//! the stretch between them when collision-free; then waypoints whose neighbours see each
//! other are dropped.

use crate::space::{distance, lerp, Space};
use rand::Rng;

/// Point of `path` at arc length `s` (joint-space), with the index of its segment.
fn point_at(path: &[Vec<f64>], cumulative: &[f64], s: f64) -> (usize, Vec<f64>) {
    let i = cumulative
        .windows(2)
        .position(|w| s <= w[1])
        .unwrap_or(path.len().saturating_sub(2));
    let length = cumulative[i + 1] - cumulative[i];
    let t = if length > 0.0 {
        ((s - cumulative[i]) / length).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (i, lerp(&path[i], &path[i + 1], t))
}

fn cumulative_lengths(path: &[Vec<f64>]) -> Vec<f64> {
    let mut c = Vec::with_capacity(path.len());
    let mut total = 0.0;
    c.push(0.0);
    for w in path.windows(2) {
        total += distance(&w[0], &w[1]);
        c.push(total);
    }
    c
}

/// Shortens `path` with `attempts` random shortcuts, then removes redundant waypoints.
/// The endpoints never change; every new edge is checked in `space`.
pub(crate) fn shortcut<R: Rng + ?Sized>(
    path: Vec<Vec<f64>>,
    space: &Space,
    attempts: usize,
    rng: &mut R,
) -> Vec<Vec<f64>> {
    let mut path = path;
    for _ in 0..attempts {
        if path.len() < 3 {
            break;
        }
        let cumulative = cumulative_lengths(&path);
        let total = cumulative[cumulative.len() - 1];
        if total <= 0.0 {
            break;
        }
        let mut s1 = rng.gen_range(0.0..total);
        let mut s2 = rng.gen_range(0.0..total);
        if s1 > s2 {
            std::mem::swap(&mut s1, &mut s2);
        }
        let (i, a) = point_at(&path, &cumulative, s1);
        let (j, b) = point_at(&path, &cumulative, s2);
        if j <= i {
            continue;
        }
        let old = distance(&a, &path[i + 1])
            + (cumulative[j] - cumulative[i + 1])
            + distance(&path[j], &b);
        if distance(&a, &b) >= old - 1e-9 || !space.edge_valid(&a, &b) {
            continue;
        }
        let mut next = Vec::with_capacity(path.len());
        next.extend(path[..=i].iter().cloned());
        next.push(a);
        next.push(b);
        next.extend(path[j + 1..].iter().cloned());
        next.dedup_by(|x, y| distance(x, y) < 1e-9);
        path = next;
    }
    remove_redundant(path, space)
}

/// Drops every waypoint whose predecessor (in the kept path) sees its successor.
pub(crate) fn remove_redundant(path: Vec<Vec<f64>>, space: &Space) -> Vec<Vec<f64>> {
    if path.len() < 3 {
        return path;
    }
    let mut kept = vec![path[0].clone()];
    let mut i = 1;
    while i < path.len() - 1 {
        let last = kept.last().map_or(&path[0], |v| v);
        if space.edge_valid(last, &path[i + 1]) {
            i += 1;
            continue;
        }
        kept.push(path[i].clone());
        i += 1;
    }
    kept.push(path[path.len() - 1].clone());
    kept
}
