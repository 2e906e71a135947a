//! The search over groupings of cells: refining a grouping by reassigning cells, pruning
//! capsules, and the final fine fits that make containment exact.

use super::cells::*;
use super::fit::*;
use super::*;
use akl_tsr::nalgebra::{Point3, Vector3};
use std::collections::HashMap;

/// The search over groupings of cells, with its work space and a cache of group fits.
pub(super) struct Search<'a> {
    pub(super) points: &'a [Vector3<f64>],
    pub(super) cells: &'a [Cell],
    pub(super) cache: HashMap<Vec<u32>, Fit, Mix>,
    /// How many more groups may be fitted: bounds the search's time whatever the mesh.
    pub(super) budget: usize,
    pub(super) work: Work,
    pub(super) union: Vec<u32>,
    pub(super) kernel: Vec<u32>,
    pub(super) value: Vec<f64>,
    pub(super) arg: Vec<u32>,
    pub(super) shuffled: Vec<Vector3<f64>>,
}

impl<'a> Search<'a> {
    pub(super) fn new(points: &'a [Vector3<f64>], cells: &'a [Cell], budget: usize) -> Search<'a> {
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
    pub(super) fn gather(&mut self, members: &[u32], all: bool) {
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
    pub(super) fn group(&mut self, members: &[u32], hint: Option<Vector3<f64>>) -> Fit {
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
    pub(super) fn fit_all(
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
    pub(super) fn reassign(
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
    pub(super) fn typical_reach(&self, assign: &[u32], fits: &[Option<Fit>]) -> Vec<f64> {
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
    pub(super) fn refine(&mut self, mut assign: Vec<u32>, k: usize, best: &mut Best) {
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
    pub(super) fn prune(&mut self, best: &mut Best) {
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
    pub(super) fn finish(&mut self, triangles: &[[Point3<f64>; 3]], best: &Best) -> Vec<Capsule> {
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
