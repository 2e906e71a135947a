//! TSRs relaxed as far as verification allows, beyond the thesis: its keyframes keep fixed
//! bounds (±5 mm, ±0.05 rad), while the task may allow far more (the yaw of a grasp on a square
//! block, where on a shelf a part may go). A wider region leaves the planner more execution
//! traces (Definition 3.2.1), which the bits of freedom count.
//!
//! **Search.** Keyframe by keyframe, axis by axis (x, y, z, roll, pitch, yaw), upper bound then
//! lower, each bound is pushed away from the nominal pose: first to its limit
//! ([`RelaxOptions::position_limit`], [`RelaxOptions::angle_limits`]), and if that fails, by
//! [`RelaxOptions::depth`] steps of bisection between the last bound that passed and the
//! first that failed. A probe runs the search trials on the spec with that axis of that
//! keyframe confined to the slice the probe would add (from the bound already accepted to the
//! candidate), every other bound as accepted so far: with goals drawn uniformly across the
//! region (see [`crate::trials::verifying`]), every trial's goal then lands where the
//! candidate is new, instead of mostly where earlier probes already tested. Slices never
//! tested are never kept. The search is greedy: earlier axes widen first, later ones within
//! what the earlier allowed.
//!
//! **Verification.** The relaxed spec then runs [`RelaxOptions::verify`] trials on seeds the
//! search never used. If one fails, the widening is halved (every bound moved halfway back
//! toward the spec's) and verified on the next fresh seeds, at most
//! [`RelaxOptions::back_offs`] times; if none passes, no relaxed spec is returned. The search
//! accepts a slice after a handful of trials, so a slice that fails one trial in twenty is often
//! accepted, and with dozens of bounds the searched spec nearly always fails its first
//! verification. Narrowing only the keyframe whose halving made the failed trial pass was
//! tried and lost: a failed trial often passes after narrowing any keyframe (its goals are
//! drawn anew), so the blame is noise, and six such rounds verified one truth of three against
//! three of three with two rounds of halving everything (BENCHMARKS.md, "Relaxation"), since
//! raised to four when the placements became precise (see [`RelaxOptions::default`]).
//!
//! **Trial count and depth.** Chosen by measurement on the three ground truths
//! (`cargo test --release -p akl-validate --test relax relax_survey -- --ignored --nocapture`,
//! BENCHMARKS.md "Relaxation"): see [`RelaxOptions::default`].

use crate::trials::{run_trials, Outcome, Stop, Trials};
use crate::ValidateError;
use akl_exec::trial::ExecOptions;
use akl_planner::flexibility::{FreedomOptions, Workspace};
use akl_planner::Robot;
use akl_scene::Task;
use akl_tsr::tsr::COORDINATE_NAMES;
use akl_tsr::TaskSpec;
use serde::Serialize;
use std::cell::Cell;
use std::f64::consts::{FRAC_PI_2, PI};

/// How a spec is relaxed.
#[derive(Debug, Clone, PartialEq)]
pub struct RelaxOptions {
    /// The trials every probe runs (the search seeds).
    pub search: Trials,
    /// The trials the relaxed spec must pass, on seeds the search does not use; a back-off
    /// round r uses the `count` seeds from `seed + r × count`.
    pub verify: Trials,
    /// Bisection steps per bound once its limit has failed.
    pub depth: usize,
    /// Farthest a position bound is pushed from the nominal pose (metres).
    pub position_limit: f64,
    /// Farthest the roll, pitch and yaw bounds are pushed from the nominal (radians).
    pub angle_limits: [f64; 3],
    /// Times a relaxation that fails its verification is halved and verified again.
    pub back_offs: usize,
    /// Execution settings.
    pub exec: ExecOptions,
}

impl Default for RelaxOptions {
    /// 10 search trials per probe and 4 bisection steps (a bound found to within 1/16 of its
    /// range: 6 mm of position, 0.1 rad of roll or pitch, 0.2 rad of yaw), chosen by
    /// measurement (BENCHMARKS.md, "Relaxation"); 30 verification trials on seeds from
    /// 1,000,000; limits of 10 cm, π/2 for roll and pitch and π for yaw; four back-offs (two
    /// verified every truth until placements went onto 4 cm mats, after which pick_place and
    /// assembly failed every round of two and first passed at an eighth of the widening).
    fn default() -> Self {
        RelaxOptions {
            search: Trials {
                count: 10,
                seed: 0,
                jobs: 1,
            },
            verify: Trials {
                count: 30,
                seed: 1_000_000,
                jobs: 1,
            },
            depth: 4,
            position_limit: 0.10,
            angle_limits: [FRAC_PI_2, FRAC_PI_2, PI],
            back_offs: 4,
            exec: ExecOptions::default(),
        }
    }
}

impl RelaxOptions {
    /// Checks the counts, limits and that verification seeds stay clear of the search's.
    pub fn check(&self) -> Result<(), ValidateError> {
        self.search.check()?;
        self.verify.check()?;
        let limits_ok = self.position_limit.is_finite()
            && self.position_limit > 0.0
            && self.angle_limits.iter().all(|a| a.is_finite() && *a > 0.0);
        if !limits_ok {
            return Err(ValidateError::Options(
                "relaxation limits must be positive and finite".into(),
            ));
        }
        let span = |t: &Trials, rounds: usize| {
            let end = t.seed.saturating_add((t.count * rounds) as u64);
            (t.seed, end)
        };
        let (s0, s1) = span(&self.search, 1);
        let (v0, v1) = span(&self.verify, self.back_offs + 1);
        if s0 < v1 && v0 < s1 {
            return Err(ValidateError::Options(format!(
                "verification seeds {v0}..{v1} overlap the search seeds {s0}..{s1}"
            )));
        }
        Ok(())
    }

    /// The most trials relaxing `spec` can take: its own search trials, every probe of
    /// every bound, every verification round (early stops make it fewer).
    pub fn most_trials(&self, spec: &TaskSpec) -> usize {
        let probes = 1 + spec.keyframes.len() * 12 * (self.depth + 1);
        probes * self.search.count + (self.back_offs + 1) * self.verify.count
    }

    /// How far the bound on `axis` (0–5) may be pushed from the nominal pose.
    fn limit(&self, axis: usize) -> f64 {
        if axis < 3 {
            self.position_limit
        } else {
            self.angle_limits[axis - 3]
        }
    }
}

/// Which end of an interval.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Side {
    /// The upper bound.
    Max,
    /// The lower bound.
    Min,
}

impl Side {
    fn index(self) -> usize {
        match self {
            Side::Min => 0,
            Side::Max => 1,
        }
    }
}

/// What the search did with one bound.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BoundSearch {
    /// The keyframe.
    pub keyframe: usize,
    /// The axis: x, y, z, roll, pitch or yaw.
    pub axis: &'static str,
    /// Which bound.
    pub side: Side,
    /// The bound in the spec.
    pub from: f64,
    /// The bound the search kept.
    pub to: f64,
    /// Probes run.
    pub probes: usize,
    /// Trials run over those probes.
    pub trials: usize,
    /// Why the first rejected probe failed, if one was.
    pub stopped_by: Option<String>,
}

impl BoundSearch {
    /// Whether the bound moved.
    pub fn widened(&self) -> bool {
        self.to != self.from
    }
}

/// One verification of a relaxed spec on fresh seeds.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Verification {
    /// Share of the search's widening kept (1, then halved at each back-off).
    pub kept: f64,
    /// The trials' first seed.
    pub seed: u64,
    /// What they gave (stopped at the first failure).
    pub outcome: Outcome,
}

/// The result of a relaxation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Relaxation {
    /// The relaxed spec that passed its verification, or `None` when no verification passed.
    pub relaxed: Option<TaskSpec>,
    /// What the search found, before verification.
    pub searched: TaskSpec,
    /// Every bound searched, in order.
    pub bounds: Vec<BoundSearch>,
    /// Bits of freedom of the spec.
    pub bits_before: Option<f64>,
    /// Bits of freedom of the relaxed spec (of the searched one when none was verified).
    pub bits_after: Option<f64>,
    /// Every verification round.
    pub verifications: Vec<Verification>,
    /// Trials run in all (search and verification).
    pub trials: usize,
}

impl Relaxation {
    /// Bits of freedom gained, when both counts have traces.
    pub fn bits_gained(&self) -> Option<f64> {
        Some(self.bits_after? - self.bits_before?)
    }
}

/// `spec` with keyframe `k`'s `axis` confined to `[a, b]` (in either order).
fn confined(spec: &TaskSpec, k: usize, axis: usize, a: f64, b: f64) -> TaskSpec {
    let mut out = spec.clone();
    out.keyframes[k].tsr.bw.0[axis] = [a.min(b), a.max(b)];
    out
}

/// `from` with every bound moved the share `kept` of the way to `to`'s.
fn blend(from: &TaskSpec, to: &TaskSpec, kept: f64) -> TaskSpec {
    let mut out = to.clone();
    for (o, f) in out.keyframes.iter_mut().zip(&from.keyframes) {
        for (bo, bf) in o.tsr.bw.0.iter_mut().zip(f.tsr.bw.0) {
            for (v, v0) in bo.iter_mut().zip(bf) {
                *v = v0 + kept * (*v - v0);
            }
        }
    }
    out
}

/// Relaxes `spec` on `task`; `progress` is called after every probe and verification with
/// the trials run so far and an upper bound of the total.
pub fn relax(
    robot: &Robot,
    task: &Task,
    spec: &TaskSpec,
    options: &RelaxOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Relaxation, ValidateError> {
    options.check()?;
    let workspace = Workspace::new(robot, task, &FreedomOptions::default())?;
    let bits_before = workspace.bits(spec)?;
    let bounds_count = spec.keyframes.len() * 12;
    let upper = options.most_trials(spec);
    let trials = Cell::new(0);
    let probe = |candidate: &TaskSpec, on: &Trials| -> Result<Outcome, ValidateError> {
        let outcome = run_trials(
            robot,
            task,
            candidate,
            &options.exec,
            on,
            Stop::AtFirstFailure,
        )?;
        trials.set(trials.get() + outcome.run);
        progress(trials.get(), upper);
        Ok(outcome)
    };
    let own = probe(spec, &options.search)?;
    if !own.all_passed() {
        return Err(ValidateError::SpecFails(
            own.first_failure_text().unwrap_or_default(),
        ));
    }
    let mut relaxed = spec.clone();
    let mut bounds = Vec::with_capacity(bounds_count);
    for k in 0..spec.keyframes.len() {
        for (axis, name) in COORDINATE_NAMES.iter().enumerate() {
            for side in [Side::Max, Side::Min] {
                let from = relaxed.keyframes[k].tsr.bw.0[axis][side.index()];
                let limit = match side {
                    Side::Max => options.limit(axis),
                    Side::Min => -options.limit(axis),
                };
                let mut search = BoundSearch {
                    keyframe: k,
                    axis: name,
                    side,
                    from,
                    to: from,
                    probes: 0,
                    trials: 0,
                    stopped_by: None,
                };
                let room = match side {
                    Side::Max => limit > from,
                    Side::Min => limit < from,
                };
                if room {
                    let before = trials.get();
                    let mut good = from;
                    let mut bad = limit;
                    let mut candidate = limit;
                    for step in 0..=options.depth {
                        let slice = confined(&relaxed, k, axis, good, candidate);
                        let outcome = probe(&slice, &options.search)?;
                        search.probes += 1;
                        if outcome.all_passed() {
                            good = candidate;
                            if step == 0 {
                                break;
                            }
                        } else {
                            bad = candidate;
                            if search.stopped_by.is_none() {
                                search.stopped_by = outcome.first_failure_text();
                            }
                        }
                        candidate = 0.5 * (good + bad);
                    }
                    relaxed.keyframes[k].tsr.bw.0[axis][side.index()] = good;
                    search.to = good;
                    search.trials = trials.get() - before;
                }
                bounds.push(search);
            }
        }
    }
    let mut verifications = Vec::new();
    let mut verified = None;
    let mut kept = 1.0;
    for round in 0..=options.back_offs {
        let candidate = blend(spec, &relaxed, kept);
        let fresh = Trials {
            seed: options
                .verify
                .seed
                .saturating_add((round * options.verify.count) as u64),
            ..options.verify
        };
        let outcome = probe(&candidate, &fresh)?;
        let passed = outcome.all_passed();
        verifications.push(Verification {
            kept,
            seed: fresh.seed,
            outcome,
        });
        if passed {
            verified = Some(candidate);
            break;
        }
        kept *= 0.5;
    }
    let bits_after = workspace.bits(verified.as_ref().unwrap_or(&relaxed))?;
    if let Some(v) = verified.as_mut() {
        v.method = format!("{}+relaxed", spec.method);
    }
    Ok(Relaxation {
        relaxed: verified,
        searched: relaxed,
        bounds,
        bits_before,
        bits_after,
        verifications,
        trials: trials.get(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_scene::builtin;

    #[test]
    fn a_blend_moves_every_bound_part_of_the_way() {
        let task = builtin::task("pick_place").unwrap().unwrap();
        let spec = task.truth.clone().unwrap();
        let mut wide = spec.clone();
        wide.keyframes[1].tsr.bw.0[0] = [-0.045, 0.085];
        let half = blend(&spec, &wide, 0.5);
        let [lo, hi] = half.keyframes[1].tsr.bw.0[0];
        assert!((lo + 0.025).abs() < 1e-12 && (hi - 0.045).abs() < 1e-12);
        assert_eq!(blend(&spec, &wide, 1.0), wide);
        assert_eq!(blend(&spec, &wide, 0.0), spec);
        let slice = confined(&spec, 2, 5, 0.3, 0.05);
        assert_eq!(slice.keyframes[2].tsr.bw.0[5], [0.05, 0.3]);
    }

    #[test]
    fn verification_seeds_must_stay_clear_of_the_search() {
        let mut options = RelaxOptions::default();
        assert!(options.check().is_ok());
        options.verify.seed = 5;
        let e = options.check().unwrap_err().to_string();
        assert!(e.contains("overlap"), "{e}");
        options.verify.seed = 10;
        assert!(options.check().is_ok());
        options.search.seed = 95;
        assert!(options.check().is_err(), "back-off rounds reach seed 100");
    }
}
