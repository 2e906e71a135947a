//! Exact one-dimensional total variation denoising (TVD), Condat's direct algorithm.
//!
//! Given a signal `y` of `n` samples and `λ ≥ 0`, [`denoise`] returns the unique minimizer of
//!
//! ```text
//!     ½ Σ_k (x_k − y_k)²  +  λ Σ_k |x_{k+1} − x_k|
//! ```
//!
//! **λ convention**: `λ` multiplies the plain (unnormalized) sum of absolute jumps, with the
//! fidelity term halved, as in Condat (2013) and Rudin–Osher–Fatemi. `λ` has the unit of the
//! signal times samples: a plateau of `m` samples moves by at most `λ / m` towards its
//! neighbours, so a lone spike of height `h` is flattened once `λ ≥ h / 2`. Doubling the
//! sampling rate of a signal therefore calls for doubling `λ` to get the same smoothing.
//!
//! **Cost.** O(1) memory beyond the output. Time is O(n) in practice but quadratic in the
//! worst case, as Condat notes: after every jump the scan restarts right after the last
//! position where a bound was pinned (`kminus` / `kplus`), so the samples between it and the
//! scan head are visited again, and a signal can make every restart rescan nearly all of the
//! rest. Measured (`cargo bench -p akl-learn --bench learning -- tvd`, BENCHMARKS.md): 21–36
//! million samples per second on OKL's fitting-error signals of 1,000 to 100,000 samples,
//! against 0.33 million at 1,000 samples and 0.11 million at 4,000 on the harmonic decay
//! y_k = 1/(k+1) with λ = 0.5, whose time grows about fourfold per doubling. OKL denoises one
//! segment's errors at a time, a few thousand samples of near-piecewise-constant signal.
//!
//! Optimality (the test oracle): with `r_k = Σ_{i≤k} (y_i − x_i)`, `x` is the minimizer exactly
//! when `|r_k| ≤ λ` for every `k`, `r_{n−1} = 0`, and at every jump `r_k = −λ` if
//! `x_{k+1} > x_k` and `r_k = +λ` if `x_{k+1} < x_k`.
//!
//! Reference: L. Condat, "A Direct Algorithm for 1D Total Variation Denoising", IEEE Signal
//! Processing Letters 20(11), 2013 (revised 2017).

/// Denoises `y` with weight `lambda` (see the module docs); returns a signal of the same length.
///
/// A negative or non-finite `lambda` is treated as 0 (no smoothing).
pub fn denoise(y: &[f64], lambda: f64) -> Vec<f64> {
    let mut x = vec![0.0; y.len()];
    denoise_into(y, lambda, &mut x);
    x
}

/// [`denoise`] writing into `x` (which must have `y.len()` samples), allocating nothing.
///
/// # Panics
/// If `x.len() != y.len()` (a programming error, never input-driven).
pub(crate) fn denoise_into(y: &[f64], lambda: f64, x: &mut [f64]) {
    assert_eq!(x.len(), y.len(), "output length must equal input length");
    let n = y.len();
    if n == 0 {
        return;
    }
    let lam = if lambda.is_finite() && lambda > 0.0 {
        lambda
    } else {
        0.0
    };
    // The current segment starts at k0 and has been scanned up to k. Its value is sought in
    // [vmin, vmax]; umin / umax are the running sums r_k if the segment took the value vmin /
    // vmax. kminus / kplus are the last positions where vmin / vmax were pinned (umin = λ,
    // umax = −λ): where a drop / rise is placed once one becomes necessary. After a jump the
    // scan restarts right after it, in the state a fresh segment has after a drop or a rise.
    let mut s = Segment::start(y, lam);
    loop {
        if s.k == n - 1 {
            // Last sample: the running sum must end at exactly 0. If even the lower candidate
            // leaves a negative sum, the segment must drop after kminus; if even the upper one
            // leaves a positive sum, it must rise after kplus; otherwise it takes the value
            // that zeroes the sum. The scan then resumes after the jump: the samples between
            // the jump and the end are not settled yet.
            if s.umin < 0.0 {
                s.drop(y, x, lam);
            } else if s.umax > 0.0 {
                s.rise(y, x, lam);
            } else {
                let v = s.vmin + s.umin / (s.k - s.k0 + 1) as f64;
                x[s.k0..=s.k].fill(v);
                return;
            }
            continue;
        }
        let next = y[s.k + 1];
        if next + s.umin < s.vmin - lam {
            // Even the lowest admissible value leaves r_{k+1} < −λ: the segment drops.
            s.drop(y, x, lam);
        } else if next + s.umax > s.vmax + lam {
            // Even the highest admissible value leaves r_{k+1} > λ: the segment rises.
            s.rise(y, x, lam);
        } else {
            s.extend(y, lam);
        }
    }
}

/// The scan state of the segment being built (see [`denoise_into`]).
struct Segment {
    k: usize,
    k0: usize,
    kminus: usize,
    kplus: usize,
    vmin: f64,
    vmax: f64,
    umin: f64,
    umax: f64,
}

impl Segment {
    /// The first segment: no jump before it, so r_{-1} = 0.
    fn start(y: &[f64], lam: f64) -> Self {
        Segment {
            k: 0,
            k0: 0,
            kminus: 0,
            kplus: 0,
            vmin: y[0] - lam,
            vmax: y[0] + lam,
            umin: lam,
            umax: -lam,
        }
    }

    /// Ends the segment at kminus at value vmin (a drop follows, r = +λ there) and starts the
    /// next one right after.
    fn drop(&mut self, y: &[f64], x: &mut [f64], lam: f64) {
        x[self.k0..=self.kminus].fill(self.vmin);
        self.restart(self.kminus + 1);
        self.vmin = y[self.k];
        self.vmax = y[self.k] + 2.0 * lam;
        self.umin = lam;
        self.umax = -lam;
    }

    /// Ends the segment at kplus at value vmax (a rise follows, r = −λ there) and starts the
    /// next one right after.
    fn rise(&mut self, y: &[f64], x: &mut [f64], lam: f64) {
        x[self.k0..=self.kplus].fill(self.vmax);
        self.restart(self.kplus + 1);
        self.vmin = y[self.k] - 2.0 * lam;
        self.vmax = y[self.k];
        self.umin = lam;
        self.umax = -lam;
    }

    fn restart(&mut self, at: usize) {
        self.k0 = at;
        self.k = at;
        self.kminus = at;
        self.kplus = at;
    }

    /// Takes sample k+1 into the segment, tightening the candidate values where the running
    /// sums leave [−λ, λ].
    fn extend(&mut self, y: &[f64], lam: f64) {
        self.k += 1;
        self.umin += y[self.k] - self.vmin;
        self.umax += y[self.k] - self.vmax;
        let len = (self.k - self.k0 + 1) as f64;
        if self.umin >= lam {
            self.vmin += (self.umin - lam) / len;
            self.umin = lam;
            self.kminus = self.k;
        }
        if self.umax <= -lam {
            self.vmax += (self.umax + lam) / len;
            self.umax = -lam;
            self.kplus = self.k;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Checks the optimality conditions of the module docs; returns what failed.
    fn optimality_violation(y: &[f64], x: &[f64], lam: f64) -> Option<String> {
        let scale = y.iter().fold(1.0f64, |m, v| m.max(v.abs())) + lam;
        let tol = 1e-9 * scale * (y.len() as f64).max(1.0);
        let mut r = 0.0;
        for k in 0..y.len() {
            r += y[k] - x[k];
            if r.abs() > lam + tol {
                return Some(format!("|r_{k}| = {} > λ = {lam}", r.abs()));
            }
            if k + 1 < y.len() {
                if x[k + 1] > x[k] && (r + lam).abs() > tol {
                    return Some(format!("rise after {k} but r = {r} ≠ −λ"));
                }
                if x[k + 1] < x[k] && (r - lam).abs() > tol {
                    return Some(format!("drop after {k} but r = {r} ≠ +λ"));
                }
            }
        }
        if r.abs() > tol {
            return Some(format!("r_(n−1) = {r} ≠ 0"));
        }
        None
    }

    fn check(y: &[f64], lam: f64) {
        let x = denoise(y, lam);
        assert_eq!(x.len(), y.len());
        if let Some(e) = optimality_violation(y, &x, lam) {
            panic!("not optimal for y = {y:?}, λ = {lam}: {e}; x = {x:?}");
        }
    }

    #[test]
    fn empty_and_single_samples() {
        assert!(denoise(&[], 1.0).is_empty());
        assert_eq!(denoise(&[3.5], 1.0), vec![3.5]);
    }

    #[test]
    fn zero_lambda_is_the_identity() {
        let y = [1.0, -2.0, 5.0, 5.0, 0.5];
        assert_eq!(denoise(&y, 0.0), y.to_vec());
        assert_eq!(denoise(&y, -1.0), y.to_vec());
    }

    #[test]
    fn large_lambda_gives_the_mean() {
        let y = [1.0, 2.0, 3.0, 10.0];
        let x = denoise(&y, 100.0);
        for v in x {
            assert!((v - 4.0).abs() < 1e-12);
        }
    }

    #[test]
    fn a_step_shrinks_by_lambda_over_its_plateau_lengths() {
        // Plateaus of 3 and 2 samples, step 10: each moves λ/len towards the other.
        let y = [0.0, 0.0, 0.0, 10.0, 10.0];
        let x = denoise(&y, 0.6);
        let expected = [0.2, 0.2, 0.2, 9.7, 9.7];
        for (a, b) in x.iter().zip(expected) {
            assert!((a - b).abs() < 1e-12, "{x:?}");
        }
    }

    #[test]
    fn jumps_in_the_last_samples() {
        // The class of bug where the end of the signal is settled wrongly: a jump right before
        // the last sample, a jump two samples before it, and a last sample pulling the tail.
        check(&[0.0, 0.0, 0.0, 0.0, 10.0], 0.5);
        check(&[0.0, 0.0, 0.0, 0.0, -10.0], 0.5);
        check(&[0.0, 0.0, 0.0, 10.0, 10.0], 0.5);
        check(&[5.0, 5.0, 5.0, -3.0, 8.0], 0.5);
        check(&[0.0, 1.0, 0.0, 1.0, 0.0, 1.0, 0.0, 50.0], 0.3);
        check(&[3.0, 2.0, 1.0, 0.0, 1.0, 2.0, 30.0, -30.0], 1.0);
        check(&[1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 0.0], 0.1);
        let x = denoise(&[0.0, 0.0, 0.0, 0.0, 10.0], 0.5);
        assert!(
            (x[4] - 9.5).abs() < 1e-12 && (x[0] - 0.125).abs() < 1e-12,
            "{x:?}"
        );
    }

    #[test]
    fn every_short_signal_on_a_grid() {
        // All signals of up to 5 samples over {−2, …, 2}: small enough to be exhaustive.
        let values = [-2.0, -1.0, 0.0, 1.0, 2.0];
        for n in 1..=5usize {
            for code in 0..values.len().pow(n as u32) {
                let mut c = code;
                let y: Vec<f64> = (0..n)
                    .map(|_| {
                        let v = values[c % values.len()];
                        c /= values.len();
                        v
                    })
                    .collect();
                for lam in [0.0, 0.25, 0.5, 1.0, 3.0] {
                    check(&y, lam);
                }
            }
        }
    }

    fn arb_signal() -> impl Strategy<Value = Vec<f64>> {
        prop::collection::vec(
            prop_oneof![-1.0..1.0f64, (-20.0..20.0f64), Just(0.0),],
            1..120,
        )
    }

    proptest! {
        #[test]
        fn satisfies_the_optimality_conditions(y in arb_signal(), lam in 0.0..5.0f64) {
            let x = denoise(&y, lam);
            prop_assert_eq!(x.len(), y.len());
            let v = optimality_violation(&y, &x, lam);
            prop_assert!(v.is_none(), "{:?}", v);
        }

        #[test]
        fn piecewise_constant_with_a_tail_jump(
            head in prop::collection::vec(-1.0..1.0f64, 1..60),
            level in -10.0..10.0f64,
            tail in 1usize..4,
            lam in 0.01..2.0f64,
        ) {
            // A noisy plateau ending in a short plateau at another level: the end of the
            // signal decides the last jump.
            let mut y = head.clone();
            y.extend(std::iter::repeat_n(level, tail));
            let x = denoise(&y, lam);
            let v = optimality_violation(&y, &x, lam);
            prop_assert!(v.is_none(), "{:?}", v);
        }

        #[test]
        fn keeps_the_mean(y in arb_signal(), lam in 0.0..5.0f64) {
            let x = denoise(&y, lam);
            let (sy, sx): (f64, f64) = (y.iter().sum(), x.iter().sum());
            prop_assert!((sy - sx).abs() < 1e-8 * (1.0 + y.len() as f64 * 20.0));
        }
    }
}
