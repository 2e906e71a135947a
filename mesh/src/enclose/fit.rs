//! Fitting one capsule to a group of points: axis directions searched, the smallest circle
//! across each, the radius that gives the least volume.

use super::*;
use akl_tsr::nalgebra::{Matrix3, Point3, SymmetricEigen, Vector3};
use std::f64::consts::PI;

/// A capsule fitted to a group, with its volume and axis direction.
#[derive(Clone, Copy)]
pub(super) struct Fit {
    pub(super) capsule: Capsule,
    pub(super) volume: f64,
    pub(super) axis: Vector3<f64>,
}

impl Fit {
    /// The fit with the radius grown to hold `ids` of `points`.
    pub(super) fn holding(mut self, points: &[Vector3<f64>], ids: &[u32]) -> Fit {
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
pub(super) fn line_of(f: &Fit) -> (Vector3<f64>, Vector3<f64>, f64) {
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
pub(super) enum Rule {
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
pub(super) struct Best {
    pub(super) total: f64,
    pub(super) assign: Vec<u32>,
    pub(super) fits: Vec<Option<Fit>>,
}

/// Work buffers of the capsule fit, reused so that the inner loops do not allocate.
#[derive(Default)]
pub(super) struct Work {
    pub(super) xy: Vec<[f64; 2]>,
    pub(super) t: Vec<f64>,
    pub(super) d2: Vec<f64>,
}

/// Two unit vectors completing unit `u` to an orthonormal basis.
pub(super) fn across(u: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
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
pub(super) fn min_circle(xy: &[[f64; 2]]) -> ([f64; 2], f64) {
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
pub(super) fn circle_through(p: [f64; 2], q: [f64; 2], r: [f64; 2]) -> ([f64; 2], f64) {
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
pub(super) struct Axial {
    pub(super) volume: f64,
    pub(super) s0: f64,
    pub(super) s1: f64,
    pub(super) radius: f64,
}

/// The least-volume capsule of radius `r` about the axis line, for points at axial
/// coordinates `t` and squared distances `d2` from the line (all within `r`): the segment
/// must reach within `sqrt(r² - d²)` of every point along the axis. When no segment is
/// needed, the sphere about the middle with the radius of its farthest point.
pub(super) fn axial(t: &[f64], d2: &[f64], r: f64) -> Axial {
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
pub(super) fn fit_along(points: &[Vector3<f64>], u: &Vector3<f64>, w: &mut Work) -> Fit {
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
pub(super) fn fit_search(
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
