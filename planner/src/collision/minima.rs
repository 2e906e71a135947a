//! The least node value of a full table over aligned blocks of 2^k × 2^k nodes, for every
//! k: a table bounds its pair over a whole box of its joints' values by reading at most
//! four blocks, where reading node by node would cost one read per node (and the twelfth
//! session's branch and bound, reading about 19 scattered nodes a call, lost more than it
//! saved).

/// Block minima of a grid of node values, level by level (level 0: the nodes themselves).
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Minima {
    /// Per level: rows, columns and the row-major minima.
    levels: Vec<(usize, usize, Vec<f32>)>,
}

impl Minima {
    /// The block minima of `values`, a row-major grid of `rows` × `columns` nodes.
    pub(super) fn new(rows: usize, columns: usize, values: &[f32]) -> Minima {
        debug_assert_eq!(values.len(), rows * columns);
        let mut levels = vec![(rows, columns, values.to_vec())];
        while let Some((r, c, below)) = levels.last().filter(|(r, c, _)| *r > 1 || *c > 1) {
            let (rows, columns) = (r.div_ceil(2), c.div_ceil(2));
            let mut level = vec![f32::INFINITY; rows * columns];
            for i in 0..*r {
                for j in 0..*c {
                    let at = &mut level[(i / 2) * columns + j / 2];
                    *at = at.min(below[i * c + j]);
                }
            }
            levels.push((rows, columns, level));
        }
        Minima { levels }
    }

    /// A value no greater than any node's in rows `r0..=r1` and columns `c0..=c1` (the
    /// least of at most four blocks that cover them).
    pub(super) fn least(&self, (r0, r1): (usize, usize), (c0, c1): (usize, usize)) -> f32 {
        let mut k = 0;
        while k + 1 < self.levels.len() && ((r1 >> k) - (r0 >> k) > 1 || (c1 >> k) - (c0 >> k) > 1)
        {
            k += 1;
        }
        let (_, columns, level) = &self.levels[k];
        let mut least = f32::INFINITY;
        for i in [r0 >> k, r1 >> k] {
            for j in [c0 >> k, c1 >> k] {
                least = least.min(level[i * columns + j]);
            }
        }
        least
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The least value over any range of rows and columns is at most every node's in
        /// it, and is some node's value in the blocks around it.
        #[test]
        fn the_least_is_a_lower_bound_over_the_range(
            rows in 1usize..40,
            columns in 1usize..40,
            seed in any::<u64>(),
            corners in any::<[u16; 4]>(),
        ) {
            let values: Vec<f32> = (0..rows * columns)
                .map(|i| ((i as u64).wrapping_mul(seed | 1).rotate_left(17) % 1000) as f32 - 300.0)
                .collect();
            let minima = Minima::new(rows, columns, &values);
            let pick = |a: u16, b: u16, n: usize| {
                let (a, b) = (a as usize % n, b as usize % n);
                (a.min(b), a.max(b))
            };
            let (r0, r1) = pick(corners[0], corners[1], rows);
            let (c0, c1) = pick(corners[2], corners[3], columns);
            let least = minima.least((r0, r1), (c0, c1));
            for i in r0..=r1 {
                for j in c0..=c1 {
                    prop_assert!(least <= values[i * columns + j]);
                }
            }
            prop_assert!(values.contains(&least));
        }
    }

    /// A range within one node reads that node.
    #[test]
    fn a_single_node_is_its_own_least() {
        let values = [3.0, 1.0, 4.0, 1.5, 5.0, 9.0];
        let minima = Minima::new(2, 3, &values);
        assert_eq!(minima.least((1, 1), (2, 2)), 9.0);
        assert_eq!(minima.least((0, 1), (0, 2)), 1.0);
        assert_eq!(minima.least((1, 1), (1, 2)), 5.0);
    }
}
