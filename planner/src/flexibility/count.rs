//! Exact count of the lattice traces that satisfy a spec, by dynamic programming.
//!
//! A trace is a walk `c_0 … c_T` over face neighbours (cells may repeat) with `c_0` the start,
//! `c_T` the end and `T` at most the step budget. It satisfies keyframes `1..=n` with regions
//! `R_k` and line cells `L_k` (for the segments that must be straight) when there are times
//! `t_1 ≤ … ≤ t_n` with `c_{t_k} ∈ R_k` and, for every line segment `k`, every cell from
//! `t_{k-1}` to `t_k` in `L_k` (`t_0 = 0`). Adding a keyframe or a line only adds conditions,
//! so it can never increase the count (thesis Lemma 3.2.1).
//!
//! Counting distinct walks (not ways of meeting the keyframes) needs the set of keyframe
//! counts a walk can have met so far: the search runs on pairs (cell, set), the set advancing
//! deterministically with each cell. Sets are bitmasks over `0..=n` (so at most 127
//! keyframes), interned as they appear; a walk's state after each cell depends only on the
//! cell's class (which regions and lines contain it). Walks that can no longer reach the end
//! through their remaining keyframes within the budget (a breadth-first lower bound that
//! ignores lines) are dropped, which changes no count.
//!
//! Counts are exact: a `num_bigint::BigUint` per state. (Fixed-width limbs in one flat array
//! were tried and measured no faster: the time goes to visiting the states, not to adding.)

use super::lattice::{distances, NONE};
use num_bigint::BigUint;
use std::collections::HashMap;

/// The largest number of keyframes a count handles (sets of met keyframes are `u128` masks).
pub(super) const MAX_KEYFRAMES: usize = 127;

/// What a count needs: the lattice's neighbours, the start and end cells, each keyframe's
/// region and each segment's line cells, and the step budget.
#[derive(Debug, Clone, Copy)]
pub(super) struct TraceProblem<'a> {
    /// Six neighbour ids per cell, [`NONE`] where there is none.
    pub neighbors: &'a [u32],
    /// Where every trace starts.
    pub start: u32,
    /// Where every trace ends.
    pub end: u32,
    /// The cells of each keyframe's region, in keyframe order.
    pub regions: &'a [Vec<u32>],
    /// For each keyframe, the cells the segment ending at it must keep to (`None`: free).
    pub lines: &'a [Option<Vec<u32>>],
    /// Most steps a trace may take.
    pub max_steps: usize,
}

impl TraceProblem<'_> {
    fn cells(&self) -> usize {
        self.neighbors.len() / 6
    }

    fn keyframes(&self) -> usize {
        self.regions.len()
    }
}

/// One step's states: per cell a short list of (set, count).
struct Layer {
    /// First entry of each cell, [`NONE`] if none.
    head: Vec<u32>,
    /// Per entry: set id, next entry of the same cell.
    entries: Vec<(u32, u32)>,
    /// Cell of each entry.
    cells: Vec<u32>,
    /// One count per entry.
    counts: Vec<BigUint>,
}

impl Layer {
    fn new(cells: usize) -> Layer {
        Layer {
            head: vec![NONE; cells],
            entries: Vec::new(),
            cells: Vec::new(),
            counts: Vec::new(),
        }
    }

    fn clear(&mut self) {
        for &c in &self.cells {
            self.head[c as usize] = NONE;
        }
        self.entries.clear();
        self.cells.clear();
        self.counts.clear();
    }

    /// The count slot of (cell, set), created at zero if absent.
    fn slot(&mut self, cell: u32, set: u32) -> usize {
        let mut e = self.head[cell as usize];
        while e != NONE {
            let (s, next) = self.entries[e as usize];
            if s == set {
                return e as usize;
            }
            e = next;
        }
        let id = self.entries.len();
        self.entries.push((set, self.head[cell as usize]));
        self.head[cell as usize] = id as u32;
        self.cells.push(cell);
        self.counts.push(BigUint::default());
        id
    }
}

/// The per-cell facts the set update reads: which states may be held here (bit j: a trace
/// that has met j keyframes may stand here, i.e. segment j+1 is free or this cell is on its
/// line) and which regions contain the cell (bit j: keyframe j+1's).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
struct Class {
    hold: u128,
    region: u128,
}

/// The set of met-keyframe counts after stepping onto a cell of class `class` from `set`.
fn advance(set: u128, class: Class, n: usize) -> u128 {
    let mut next = 0u128;
    let mut rest = set;
    while rest != 0 {
        let mut j = rest.trailing_zeros() as usize;
        rest &= rest - 1;
        loop {
            if class.hold >> j & 1 == 0 {
                break;
            }
            next |= 1 << j;
            if j < n && class.region >> j & 1 == 1 {
                j += 1;
            } else {
                break;
            }
        }
    }
    next
}

/// Interned sets and their transitions by class.
struct Sets {
    masks: Vec<u128>,
    ids: HashMap<u128, u32>,
    /// `next[set * classes + class]`: the next set id, [`NONE`] for the empty set,
    /// `UNKNOWN` before it is computed.
    next: Vec<u32>,
    classes: Vec<Class>,
    n: usize,
}

const UNKNOWN: u32 = u32::MAX - 1;

impl Sets {
    fn intern(&mut self, mask: u128) -> u32 {
        if mask == 0 {
            return NONE;
        }
        if let Some(&id) = self.ids.get(&mask) {
            return id;
        }
        let id = self.masks.len() as u32;
        self.masks.push(mask);
        self.ids.insert(mask, id);
        self.next
            .extend(std::iter::repeat_n(UNKNOWN, self.classes.len()));
        id
    }

    fn step(&mut self, set: u32, class: u32) -> u32 {
        let k = set as usize * self.classes.len() + class as usize;
        let cached = self.next[k];
        if cached != UNKNOWN {
            return cached;
        }
        let mask = advance(
            self.masks[set as usize],
            self.classes[class as usize],
            self.n,
        );
        let id = self.intern(mask);
        self.next[k] = id;
        id
    }

    fn highest(&self, set: u32) -> usize {
        127 - self.masks[set as usize].leading_zeros() as usize
    }

    fn done(&self, set: u32) -> bool {
        self.masks[set as usize] >> self.n & 1 == 1
    }
}

/// Per cell, its class id; and the classes.
fn classify(problem: &TraceProblem) -> (Vec<u32>, Vec<Class>) {
    let n = problem.keyframes();
    let free: u128 = (0..=n)
        .filter(|&j| j == n || problem.lines[j].is_none())
        .fold(0, |m, j| m | 1 << j);
    let mut hold = vec![free; problem.cells()];
    let mut region = vec![0u128; problem.cells()];
    for (k, cells) in problem.regions.iter().enumerate() {
        for &c in cells {
            region[c as usize] |= 1 << k;
        }
    }
    for (k, line) in problem.lines.iter().enumerate() {
        // Segment k+1 (ending at keyframe k+1, index k) is held by traces that met k keyframes.
        if let Some(cells) = line {
            for &c in cells {
                hold[c as usize] |= 1 << k;
            }
        }
    }
    let mut ids: HashMap<Class, u32> = HashMap::new();
    let mut classes = Vec::new();
    let of_cell = hold
        .iter()
        .zip(&region)
        .map(|(&hold, &region)| {
            let class = Class { hold, region };
            *ids.entry(class).or_insert_with(|| {
                classes.push(class);
                classes.len() as u32 - 1
            })
        })
        .collect();
    (of_cell, classes)
}

/// Steps still needed from each cell by a trace that has met `k` keyframes, for every `k`
/// (index `k`): through the remaining regions in order, then to the end; lines ignored, so a
/// lower bound. `u32::MAX` where impossible.
fn remaining(problem: &TraceProblem) -> Vec<Vec<u32>> {
    let bfs = |sources: &[(u32, u32)]| distances(problem.neighbors, sources);
    let n = problem.keyframes();
    let mut rem = vec![Vec::new(); n + 1];
    rem[n] = bfs(&[(problem.end, 0)]);
    for k in (0..n).rev() {
        let sources: Vec<(u32, u32)> = problem.regions[k]
            .iter()
            .map(|&c| (c, rem[k + 1][c as usize]))
            .filter(|&(_, d)| d != u32::MAX)
            .collect();
        rem[k] = bfs(&sources);
    }
    rem
}

/// The exact number of traces of `problem`. A problem with more than [`MAX_KEYFRAMES`]
/// keyframes, or with `lines` of another length than `regions`, is malformed and has none
/// (callers check both first).
pub(super) fn count_traces(problem: &TraceProblem) -> BigUint {
    let n = problem.keyframes();
    if n > MAX_KEYFRAMES || problem.lines.len() != n || problem.cells() == 0 {
        return BigUint::default();
    }
    let (class_of, classes) = classify(problem);
    let rem = remaining(problem);
    let mut sets = Sets {
        masks: Vec::new(),
        ids: HashMap::new(),
        next: Vec::new(),
        classes,
        n,
    };
    let mut total = BigUint::default();
    let budget = problem.max_steps as u64;
    let fits = |sets: &Sets, cell: u32, set: u32, t: u64| {
        let r = rem[sets.highest(set)][cell as usize];
        r != u32::MAX && t + u64::from(r) <= budget
    };
    let first = sets.intern(1);
    let start_set = sets.step(first, class_of[problem.start as usize]);
    let mut layer = Layer::new(problem.cells());
    let mut next = Layer::new(problem.cells());
    if start_set != NONE && fits(&sets, problem.start, start_set, 0) {
        let s = layer.slot(problem.start, start_set);
        layer.counts[s] = BigUint::from(1u32);
        if problem.start == problem.end && sets.done(start_set) {
            total = BigUint::from(1u32);
        }
    }
    for t in 1..=budget {
        if layer.entries.is_empty() {
            break;
        }
        for e in 0..layer.entries.len() {
            let cell = layer.cells[e];
            let set = layer.entries[e].0;
            for &m in &problem.neighbors[6 * cell as usize..6 * cell as usize + 6] {
                if m == NONE {
                    continue;
                }
                let to = sets.step(set, class_of[m as usize]);
                if to == NONE || !fits(&sets, m, to, t) {
                    continue;
                }
                let s = next.slot(m, to);
                next.counts[s] += &layer.counts[e];
            }
        }
        for e in 0..next.entries.len() {
            if next.cells[e] == problem.end && sets.done(next.entries[e].0) {
                total += &next.counts[e];
            }
        }
        std::mem::swap(&mut layer, &mut next);
        next.clear();
    }
    total
}

/// log2 of a positive count, `None` for zero.
pub(super) fn log2(count: &BigUint) -> Option<f64> {
    let bits = count.bits();
    if bits == 0 {
        return None;
    }
    let shift = bits.saturating_sub(64);
    let top = &(count >> shift);
    let top = top.iter_u64_digits().next().unwrap_or(0) as f64;
    Some(top.log2() + shift as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A `w` × `h` × 1 grid with face neighbours; cell (x, y) is `y * w + x`.
    fn grid(w: u32, h: u32) -> Vec<u32> {
        let mut nb = Vec::new();
        for y in 0..h {
            for x in 0..w {
                let at = |dx: i64, dy: i64| {
                    let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                    if nx < 0 || ny < 0 || nx >= w as i64 || ny >= h as i64 {
                        NONE
                    } else {
                        (ny as u32) * w + nx as u32
                    }
                };
                nb.extend([at(1, 0), at(-1, 0), at(0, 1), at(0, -1), NONE, NONE]);
            }
        }
        nb
    }

    /// Whether a walk satisfies the keyframes, straight from the definition: some
    /// non-decreasing meeting times with every line segment on its cells.
    fn satisfies(walk: &[u32], regions: &[Vec<u32>], lines: &[Option<Vec<u32>>]) -> bool {
        fn from(
            k: usize,
            t: usize,
            walk: &[u32],
            regions: &[Vec<u32>],
            lines: &[Option<Vec<u32>>],
        ) -> bool {
            if k == regions.len() {
                return true;
            }
            for u in t..walk.len() {
                if let Some(line) = &lines[k] {
                    if !line.contains(&walk[u]) {
                        return false;
                    }
                }
                if regions[k].contains(&walk[u]) && from(k + 1, u, walk, regions, lines) {
                    return true;
                }
            }
            false
        }
        from(0, 0, walk, regions, lines)
    }

    /// Every walk of at most `max` steps from start to end, checked one by one.
    fn brute_force(p: &TraceProblem) -> u64 {
        fn walk(p: &TraceProblem, path: &mut Vec<u32>, count: &mut u64) {
            let at = path[path.len() - 1];
            if at == p.end && satisfies(path, p.regions, p.lines) {
                *count += 1;
            }
            if path.len() > p.max_steps {
                return;
            }
            for &m in &p.neighbors[6 * at as usize..6 * at as usize + 6] {
                if m != NONE {
                    path.push(m);
                    walk(p, path, count);
                    path.pop();
                }
            }
        }
        let mut count = 0;
        walk(p, &mut vec![p.start], &mut count);
        count
    }

    /// Grid width and height, start, end, regions, lines and step budget.
    type Small = (
        u32,
        u32,
        u32,
        u32,
        Vec<Vec<u32>>,
        Vec<Option<Vec<u32>>>,
        usize,
    );

    fn arb_problem() -> impl Strategy<Value = Small> {
        (2u32..4, 2u32..4)
            .prop_flat_map(|(w, h)| {
                let cells = w * h;
                let region = prop::collection::vec(0..cells, 1..3);
                let line = prop::option::of(prop::collection::vec(0..cells, 1..5));
                (
                    Just(w),
                    Just(h),
                    0..cells,
                    0..cells,
                    prop::collection::vec(region, 0..4),
                    prop::collection::vec(line, 0..4),
                    0usize..8,
                )
            })
            .prop_map(|(w, h, s, e, regions, mut lines, steps)| {
                lines.resize(regions.len(), None);
                if let Some(first) = lines.first_mut() {
                    *first = None;
                }
                (w, h, s, e, regions, lines, steps)
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// The search counts exactly the walks the definition accepts, on small grids where
        /// every walk can be enumerated.
        #[test]
        fn counts_equal_brute_force_enumeration((w, h, start, end, regions, lines, steps) in arb_problem()) {
            let nb = grid(w, h);
            let p = TraceProblem { neighbors: &nb, start, end, regions: &regions, lines: &lines, max_steps: steps };
            prop_assert_eq!(count_traces(&p), BigUint::from(brute_force(&p)));
        }
    }

    #[test]
    fn walks_in_an_open_grid_are_counted_without_overflow() {
        // Closed walks on a 40 x 40 grid up to 200 steps: far beyond 64 bits.
        let nb = grid(40, 40);
        let start = 20 * 40 + 20;
        let p = TraceProblem {
            neighbors: &nb,
            start,
            end: start,
            regions: &[],
            lines: &[],
            max_steps: 200,
        };
        let count = count_traces(&p);
        let bits = log2(&count).unwrap();
        assert!(bits > 300.0 && bits < 400.0, "{bits}");
        // Two steps: out and back along each of the four directions, plus the empty walk.
        let p = TraceProblem { max_steps: 2, ..p };
        assert_eq!(count_traces(&p), BigUint::from(5u32));
    }

    #[test]
    fn log2_is_exact_for_powers_of_two_and_none_for_zero() {
        assert_eq!(log2(&BigUint::default()), None);
        assert_eq!(log2(&BigUint::from(1u32)), Some(0.0));
        assert_eq!(log2(&(BigUint::from(1u32) << 300u32)), Some(300.0));
        let three = log2(&(BigUint::from(3u32) << 100u32)).unwrap();
        assert!((three - 100.0 - 3f64.log2()).abs() < 1e-12);
    }
}
