//! TSRs relaxed as far as verification allows, beyond the thesis: its keyframes keep fixed
//! bounds (±5 mm, ±0.05 rad), while the task may allow far more (the yaw of a grasp on a square
//! block, where on a mat a part may go). A wider region leaves the planner more execution
//! traces (Definition 3.2.1).
//!
//! **Screening, keyframe by keyframe.** For each keyframe, each axis (x, y, z, roll, pitch,
//! yaw) is widened symmetrically about the nominal pose to the largest of
//! [`RelaxOptions::levels`] (shares of the axis' limit) that passes a *screening*: up to
//! [`RelaxOptions::screen`] trials on seeds no other probe uses, stopped at the first *excess*
//! failure — a trial the candidate fails and the spec as screened before the probe passes on
//! the same seed. A failure the unrelaxed spec shares is the spec's own and is not blamed on
//! the widening, so a spec that fails one trial in a thousand is not held back by its own rare
//! failures, and a widening that breaks one trial in three is dropped after about three
//! trials. A widening is also dropped when planning its trials takes more collision probes
//! than [`RelaxOptions::max_effort`] times the spec's own: most poses of such a region are ones
//! the planner must try and reject, a freedom it can hardly use, and every later trial would
//! pay for it.
//!
//! **One gate for what screening kept.** Screening lets mildly harmful widenings through (20
//! clean trials accept a widening that fails 5 % of trials a third of the time), so the spec
//! with every kept widening is then **gated**: the deployment gate ([`akl_stats::gate`]) on
//! fresh seeds, given up as undecided once it can no longer pass
//! ([`crate::trials::run_gated_to_pass`]). A gate that does not pass blames each failed trial
//! on the keyframes whose widening, undone alone, lets that trial pass on its seed (on every
//! widened keyframe when none does, and on none when the spec as given fails that seed too:
//! the spec's own failure); only those widenings are halved, and dropped after
//! [`RelaxOptions::back_offs`] halvings, and the rest is gated again. Only a gated spec is
//! returned: whenever the relaxation is interrupted, the spec returned has passed the gate on
//! seeds the search never used. Gating once, rather than once per keyframe, costs the fewest
//! trials when screening was right, and a keyframe whose widening fails is found by a few
//! trials of the failed seeds rather than by a gate of its own.
//!
//! **Gain.** The bits of execution traces (a 5 cm lattice, [`akl_planner::flexibility`]) do not
//! see a wider turn or a millimetre, so the gain is also measured as the log-volume of every
//! TSR: `Σ log2(new width / old width)` over its six axes, one bit for each doubling.

use crate::trials::{run_each, run_gated, run_gated_to_pass, verifying, Outcome};
use crate::ValidateError;
use akl_exec::batch::trial_seed;
use akl_exec::ExecOptions;
use akl_planner::flexibility::{FreedomOptions, Workspace};
use akl_planner::Robot;
use akl_scene::Task;
use akl_stats::{Decision, Gate, GateOptions};
use akl_tsr::{TaskSpec, Tsr, COORDINATE_NAMES};
use serde::Serialize;
use std::collections::{BTreeSet, HashMap};
use std::f64::consts::{FRAC_PI_2, PI};
use std::sync::atomic::{AtomicU64, AtomicUsize, Ordering};
use std::sync::{Mutex, PoisonError};

/// How a spec is relaxed.
#[derive(Debug, Clone, PartialEq)]
pub struct RelaxOptions {
    /// Seed of the search's first probe trial (probe p screens on its own seeds after it).
    pub seed: u64,
    /// Seed of the first gate's trials; every gate runs on seeds after the last one's, none of
    /// them the search's (see [`RelaxOptions::check`]).
    pub gate_seed: u64,
    /// Trials run in parallel.
    pub jobs: usize,
    /// Most screening trials of one widening.
    pub screen: usize,
    /// The widths tried for each axis, as shares of its limit, widest first.
    pub levels: Vec<f64>,
    /// Farthest a position bound is pushed from the nominal pose (metres).
    pub position_limit: f64,
    /// Farthest the roll, pitch and yaw bounds are pushed from the nominal (radians).
    pub angle_limits: [f64; 3],
    /// Times a keyframe's widening that fails its gate is halved and gated again.
    pub back_offs: usize,
    /// Most collision-checking work planning a trial of a widened spec may take, as a multiple
    /// of the spec's own (its mean collision probes per trial over its gate). A widening past
    /// it is rejected in screening: a region most of whose poses the planner must try and
    /// reject claims a freedom the planner can hardly use, and makes every later trial dearer.
    pub max_effort: f64,
    /// The gate every kept widening passes.
    pub gate: GateOptions,
    /// Execution settings; its interrupt stops the relaxation (the best gated spec is kept).
    pub exec: ExecOptions,
}

impl Default for RelaxOptions {
    /// Screening of 20 trials; levels of the whole limit, a quarter and a sixteenth (±10 cm,
    /// 2.5 cm, 6 mm of position; ±π/2, 0.39, 0.1 rad of roll and pitch; ±π, 0.79, 0.2 rad of
    /// yaw); twice the spec's own planning effort at most; two back-offs; the deployment
    /// gate's success and confidence (0.99 at 95 %) but at most 299 trials, so a widening
    /// passes only with no failure at all: the pass boundary is the deployment gate's, and
    /// what it lets through is what the deployment gate passes on fresh seeds (computed
    /// exactly: a spec failing 0.3 % of trials passes this gate 41 % of the time and the
    /// deployment gate then 98 %; one failing 0.7 %, 12 % and 55 %; one failing 0.03 %, 91 %).
    /// With at most 628 trials, the relaxed inspection spec passed with 2 failures and was then
    /// undecided on fresh seeds. Gates on seeds from 1,000,000. Chosen by measurement on the
    /// three ground truths (BENCHMARKS.md, "Relaxation").
    fn default() -> Self {
        RelaxOptions {
            seed: 0,
            gate_seed: 1_000_000,
            jobs: 1,
            screen: 20,
            levels: vec![1.0, 0.25, 0.0625],
            position_limit: 0.10,
            angle_limits: [FRAC_PI_2, FRAC_PI_2, PI],
            back_offs: 2,
            max_effort: 2.0,
            gate: GateOptions {
                max_trials: 299,
                ..GateOptions::default()
            },
            exec: ExecOptions::default(),
        }
    }
}

impl RelaxOptions {
    /// Checks the counts, limits, levels and that gate seeds stay clear of the search's.
    pub fn check(&self, spec: &TaskSpec) -> Result<(), ValidateError> {
        let bad = |m: &str| Err(ValidateError::Options(m.to_string()));
        if self.jobs == 0 {
            return bad("needs at least one job");
        }
        if self.screen == 0 {
            return bad("--screen: needs at least one trial");
        }
        if !(self.max_effort.is_finite() && self.max_effort >= 1.0) {
            return bad("--max-effort must be at least 1 (the spec's own effort)");
        }
        let limits_ok = self.position_limit.is_finite()
            && self.position_limit > 0.0
            && self.angle_limits.iter().all(|a| a.is_finite() && *a > 0.0);
        if !limits_ok {
            return bad("relaxation limits must be positive and finite");
        }
        if self.levels.is_empty() || self.levels.iter().any(|l| !(*l > 0.0 && *l <= 1.0)) {
            return bad("relaxation levels must lie in (0, 1]");
        }
        Gate::new(self.gate).map_err(|e| ValidateError::Options(e.to_string()))?;
        let search_end = self
            .seed
            .saturating_add((self.most_probes(spec) * self.screen) as u64);
        let gates = 1 + self.most_widening_gates(spec);
        let gate_end = self
            .gate_seed
            .saturating_add((gates * self.gate.max_trials) as u64);
        if self.seed < gate_end && self.gate_seed < search_end {
            return Err(ValidateError::Options(format!(
                "gate seeds {}..{gate_end} overlap the search seeds {}..{search_end}",
                self.gate_seed, self.seed
            )));
        }
        Ok(())
    }

    /// The most probes relaxing `spec` can run: every level of every axis of every keyframe.
    pub fn most_probes(&self, spec: &TaskSpec) -> usize {
        spec.keyframes.len() * 6 * self.levels.len()
    }

    /// The most gates of widenings a relaxation runs: one per halving or drop of every
    /// keyframe, the one that passes, and two more for gates whose failures were all the
    /// spec's own (the same widenings gated again on fresh seeds).
    pub fn most_widening_gates(&self, spec: &TaskSpec) -> usize {
        spec.keyframes.len() * (self.back_offs + 1) + 3
    }

    /// How far axis `axis` (0–5) may be widened either side of the nominal pose.
    fn limit(&self, axis: usize) -> f64 {
        if axis < 3 {
            self.position_limit
        } else {
            self.angle_limits[axis - 3]
        }
    }
}

/// One widening tried.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Probe {
    /// The keyframe.
    pub keyframe: usize,
    /// The axis: x, y, z, roll, pitch or yaw.
    pub axis: &'static str,
    /// The bounds before.
    pub from: [f64; 2],
    /// The bounds tried.
    pub to: [f64; 2],
    /// Screening trials run. For a rejected widening this depends on timing when several
    /// jobs run (trials under way when the rejecting one ended still finish); whether it is
    /// kept does not.
    pub trials: usize,
    /// Planning's collision-checking work per screening trial, as a multiple of the spec's own.
    pub effort: f64,
    /// Whether the widening passed its screening (and was kept for the keyframe's gate).
    pub kept: bool,
    /// The excess failure that rejected it, if one did.
    pub rejected_by: Option<String>,
}

/// One gate on fresh seeds: of the spec as given, or of what screening kept.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct GateRound {
    /// For each keyframe, the share of its screened widening gated (1, halved at each of its
    /// back-offs, 0 once dropped); empty for the spec as given.
    pub shares: Vec<f64>,
    /// The keyframes the gate's failures were blamed on (see the module documentation): their
    /// widenings are halved for the next gate.
    pub blamed: Vec<usize>,
    /// The trials' first seed.
    pub seed: u64,
    /// The gate's decision (`None`: interrupted).
    pub decision: Option<Decision>,
    /// The trials it read.
    pub outcome: Outcome,
}

/// What a relaxation did, as it goes (for streamed progress).
#[derive(Debug, Clone, PartialEq)]
pub enum Event<'a> {
    /// A probe's screening ended.
    Probe(&'a Probe),
    /// A gate decided (or was interrupted).
    Gate(&'a GateRound),
}

/// The result of a relaxation.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Relaxation {
    /// The widest spec that passed the gate on fresh seeds, or `None` when no widening did.
    pub relaxed: Option<TaskSpec>,
    /// Every probe, in order.
    pub probes: Vec<Probe>,
    /// Every gate, in order.
    pub gates: Vec<GateRound>,
    /// TSR log-volume gained per keyframe by the relaxed spec (bits, see the module docs).
    pub volume_gain: Vec<f64>,
    /// Bits of execution traces of the spec.
    pub bits_before: Option<f64>,
    /// Bits of execution traces of the relaxed spec (the spec's when none was gated).
    pub bits_after: Option<f64>,
    /// Trials run in all (screening and gates).
    pub trials: usize,
    /// Whether it was interrupted (Ctrl-C): `relaxed` is the best gated spec so far.
    pub interrupted: bool,
}

impl Relaxation {
    /// Bits of execution traces gained, when both counts have traces.
    pub fn bits_gained(&self) -> Option<f64> {
        Some(self.bits_after? - self.bits_before?)
    }

    /// TSR log-volume gained over every keyframe (bits).
    pub fn volume_gained(&self) -> f64 {
        self.volume_gain.iter().sum()
    }
}

/// `Σ log2(width in to / width in from)` over the six axes: one bit per doubling of a width
/// (an axis of zero width in `from` counts nothing).
pub fn volume_gain_bits(from: &Tsr, to: &Tsr) -> f64 {
    from.bw
        .0
        .iter()
        .zip(to.bw.0)
        .filter(|([lo, hi], _)| hi > lo)
        .map(|([lo, hi], [lo2, hi2])| ((hi2 - lo2) / (hi - lo)).log2())
        .sum()
}

/// What screening a widening found.
#[derive(Debug, Default)]
struct Screening {
    /// Trials run.
    run: usize,
    /// Collision probes planning took over them.
    probes: u64,
    /// The excess failure, or the excess effort, that rejected the widening.
    rejected_by: Option<String>,
}

/// `from` with each keyframe's bounds moved its share of `shares` of the way to `to`'s.
fn blend(from: &TaskSpec, to: &TaskSpec, shares: &[f64]) -> TaskSpec {
    let mut out = from.clone();
    for ((o, t), share) in out.keyframes.iter_mut().zip(&to.keyframes).zip(shares) {
        for (ob, tb) in o.tsr.bw.0.iter_mut().zip(t.tsr.bw.0) {
            for (v, v1) in ob.iter_mut().zip(tb) {
                *v += share * (v1 - *v);
            }
        }
    }
    out
}

/// The keyframes of `candidate` (widened from `spec` where `shares` is positive) that the
/// trials failed on `failed_seeds` are blamed on (`passes` says whether each spec passes its
/// seed's trial). A seed the spec as given fails too is the spec's own failure and blames
/// nothing; otherwise the keyframes whose widening, undone alone, lets the trial pass are
/// blamed, or every widened keyframe when none does (the widenings fail together). The replays
/// go to `passes` in two rounds, the spec's and then every undoing's, so each round can run in
/// parallel.
fn blame(
    spec: &TaskSpec,
    candidate: &TaskSpec,
    shares: &[f64],
    failed_seeds: &[u64],
    passes: impl Fn(&[(TaskSpec, u64)]) -> Result<Vec<bool>, ValidateError>,
) -> Result<Vec<usize>, ValidateError> {
    let widened: Vec<usize> = (0..shares.len()).filter(|k| shares[*k] > 0.0).collect();
    let own = passes(
        &failed_seeds
            .iter()
            .map(|seed| (spec.clone(), *seed))
            .collect::<Vec<_>>(),
    )?;
    let blamable: Vec<u64> = failed_seeds
        .iter()
        .zip(own)
        .filter_map(|(seed, own_passes)| own_passes.then_some(*seed))
        .collect();
    let undoings: Vec<(TaskSpec, u64)> = blamable
        .iter()
        .flat_map(|seed| {
            widened.iter().map(move |&k| {
                let mut undone = candidate.clone();
                undone.keyframes[k] = spec.keyframes[k].clone();
                (undone, *seed)
            })
        })
        .collect();
    let undone_passes = passes(&undoings)?;
    let mut blamed = BTreeSet::new();
    for per_seed in undone_passes.chunks(widened.len().max(1)) {
        let rescued: Vec<usize> = widened
            .iter()
            .zip(per_seed)
            .filter_map(|(k, p)| p.then_some(*k))
            .collect();
        if rescued.is_empty() {
            blamed.extend(&widened);
        } else {
            blamed.extend(rescued);
        }
    }
    Ok(blamed.into_iter().collect())
}

/// Halves the share of every blamed keyframe's widening, dropping it (share 0) once it has been
/// halved more than `back_offs` times.
fn back_off(shares: &mut [f64], halvings: &mut [usize], blamed: &[usize], back_offs: usize) {
    for &k in blamed {
        halvings[k] += 1;
        shares[k] = if halvings[k] > back_offs {
            0.0
        } else {
            0.5 * shares[k]
        };
    }
}

/// Whether keyframe `k` has the same bounds in both specs.
fn same_keyframe(a: &TaskSpec, b: &TaskSpec, k: usize) -> bool {
    a.keyframes[k].tsr.bw == b.keyframes[k].tsr.bw
}

/// Relaxes `spec` on `task`; `report` is called with each probe and gate as it ends.
pub fn relax(
    robot: &Robot,
    task: &Task,
    spec: &TaskSpec,
    options: &RelaxOptions,
    report: &(dyn Fn(Event) + Sync),
) -> Result<Relaxation, ValidateError> {
    options.check(spec)?;
    let gate = Gate::new(options.gate).map_err(|e| ValidateError::Options(e.to_string()))?;
    let workspace = Workspace::new(robot, task, &FreedomOptions::default())?;
    let exec = verifying(&options.exec);
    let interrupted = || exec.interrupt.raised();
    let trials = AtomicUsize::new(0);
    // Whether a spec (by its JSON) passed its trial on a seed, each (spec, seed) run once.
    let earlier = Mutex::new(HashMap::<(String, u64), bool>::new());
    // Whether each spec passes its seed's trial, those not yet known run in parallel; a
    // trial an interrupt kept from running counts as failed (and is not remembered).
    let replay = |asked: &[(TaskSpec, u64)]| -> Result<Vec<bool>, ValidateError> {
        let keys: Vec<(String, u64)> = asked
            .iter()
            .map(|(spec, seed)| (spec.to_json(), *seed))
            .collect();
        let todo: Vec<usize> = {
            let earlier = earlier.lock().unwrap_or_else(PoisonError::into_inner);
            (0..asked.len())
                .filter(|i| !earlier.contains_key(&keys[*i]))
                .collect()
        };
        let unknown: Vec<(&TaskSpec, u64)> =
            todo.iter().map(|i| (&asked[*i].0, asked[*i].1)).collect();
        let ran = run_each(robot, task, &exec, &unknown, options.jobs, &|_| false)?;
        let mut earlier = earlier.lock().unwrap_or_else(PoisonError::into_inner);
        for (i, report) in todo.into_iter().zip(ran) {
            if let Some(report) = report {
                trials.fetch_add(1, Ordering::Relaxed);
                earlier.insert(keys[i].clone(), report.passed);
            }
        }
        Ok(keys
            .iter()
            .map(|key| earlier.get(key).copied().unwrap_or(false))
            .collect())
    };
    let mut next_seed = options.seed;
    // Screens `candidate` against `base`, planning at most `budget` collision probes per
    // trial on average: the trials run, the probes planning took, the excess failure or the
    // excess effort that rejected it, if one did. The trials run `jobs` at a time until one
    // fails or the probes pass the budget; a failure the base shares is not held against the
    // candidate, and the trials not yet run are then run. Whether a widening is kept thus
    // depends only on its seeds, not on which of them ran first.
    let mut screen = |candidate: &TaskSpec,
                      base: &TaskSpec,
                      budget: f64|
     -> Result<Screening, ValidateError> {
        let first = next_seed;
        next_seed = next_seed.saturating_add(options.screen as u64);
        let most = budget * options.screen as f64;
        let mut screening = Screening::default();
        let mut pending: Vec<u64> = (0..options.screen).map(|i| trial_seed(first, i)).collect();
        while !pending.is_empty() && !interrupted() {
            let asked: Vec<(&TaskSpec, u64)> = pending.iter().map(|s| (candidate, *s)).collect();
            let spent = AtomicU64::new(screening.probes);
            let ran = run_each(robot, task, &exec, &asked, options.jobs, &|t| {
                let probes = spent.fetch_add(t.plan_probes, Ordering::SeqCst) + t.plan_probes;
                !t.passed || probes as f64 > most
            })?;
            let mut failed = Vec::new();
            let mut left = Vec::new();
            for (seed, report) in pending.iter().zip(ran) {
                match report {
                    Some(t) => {
                        trials.fetch_add(1, Ordering::Relaxed);
                        screening.run += 1;
                        screening.probes += t.plan_probes;
                        if !t.passed {
                            failed.push(t);
                        }
                    }
                    None => left.push(*seed),
                }
            }
            let base_passes = replay(
                &failed
                    .iter()
                    .map(|t| (base.clone(), t.seed))
                    .collect::<Vec<_>>(),
            )?;
            if let Some(t) = failed
                .iter()
                .zip(base_passes)
                .find_map(|(t, p)| p.then_some(t))
            {
                let why = t.root().map_or(String::new(), |f| {
                    format!("{} (seed {}): {}", f.cause, t.seed, f.detail)
                });
                screening.rejected_by = Some(why);
                return Ok(screening);
            }
            // The probes only grow: once past the screening's budget it cannot pass.
            if screening.probes as f64 > most {
                screening.rejected_by = Some(format!(
                    "planning took {} collision probes in {} trial(s), more than {:.0} × the spec's own allow in {} (--max-effort)",
                    screening.probes, screening.run, options.max_effort, options.screen
                ));
                return Ok(screening);
            }
            pending = left;
        }
        Ok(screening)
    };
    let mut gate_seed = options.gate_seed;
    let mut gate_round =
        |candidate: &TaskSpec, shares: &[f64]| -> Result<GateRound, ValidateError> {
            let seed = gate_seed;
            gate_seed = gate_seed.saturating_add(gate.options().max_trials as u64);
            // The spec's own gate is the deployment gate; a widening's stops once it can no
            // longer pass, as only a pass would keep it.
            let gated = match shares.is_empty() {
                true => run_gated(
                    robot,
                    task,
                    candidate,
                    &options.exec,
                    &gate,
                    seed,
                    options.jobs,
                    false,
                    &|_| {},
                )?,
                false => run_gated_to_pass(
                    robot,
                    task,
                    candidate,
                    &options.exec,
                    &gate,
                    seed,
                    options.jobs,
                )?,
            };
            trials.fetch_add(gated.outcome.run, Ordering::Relaxed);
            Ok(GateRound {
                shares: shares.to_vec(),
                blamed: Vec::new(),
                seed,
                decision: gated.decision,
                outcome: gated.outcome,
            })
        };

    // The spec itself must pass the gate: widenings are judged against it.
    let own = gate_round(spec, &[])?;
    report(Event::Gate(&own));
    match own.decision {
        // Interrupted during its gate: nothing was gated, the search does not start.
        Some(Decision::Passes) | None => {}
        Some(d) => {
            return Err(ValidateError::SpecFails(format!(
                "the gate {} it ({}/{} passed){}",
                match d {
                    Decision::Fails => "fails",
                    _ => "cannot decide on",
                },
                own.outcome.passed,
                own.outcome.run,
                own.outcome
                    .first_failure_text()
                    .map_or(String::new(), |f| format!("; first failure: {f}"))
            )))
        }
    }
    // Collision probes per trial the spec itself takes, the unit of --max-effort.
    let own_effort = own.outcome.probes_per_trial().max(1.0);
    let budget = options.max_effort * own_effort;
    let mut gated: Option<TaskSpec> = None;
    let mut probes = Vec::new();
    let mut gates = vec![own];
    let searched = if interrupted() {
        0
    } else {
        spec.keyframes.len()
    };
    // Every keyframe screened in turn, each probe against the spec as screened so far.
    let mut screened = spec.clone();
    'keyframes: for k in 0..searched {
        for (axis, name) in COORDINATE_NAMES.iter().enumerate() {
            let from = screened.keyframes[k].tsr.bw.0[axis];
            for level in &options.levels {
                if interrupted() {
                    break 'keyframes;
                }
                let w = level * options.limit(axis);
                let to = [from[0].min(-w), from[1].max(w)];
                if to == from {
                    continue;
                }
                let mut candidate = screened.clone();
                candidate.keyframes[k].tsr.bw.0[axis] = to;
                let screening = screen(&candidate, &screened, budget)?;
                let kept = screening.rejected_by.is_none() && screening.run == options.screen;
                let probe = Probe {
                    keyframe: k,
                    axis: name,
                    from,
                    to,
                    trials: screening.run,
                    effort: screening.probes as f64 / (screening.run.max(1) as f64 * own_effort),
                    kept,
                    rejected_by: screening.rejected_by,
                };
                report(Event::Probe(&probe));
                probes.push(probe);
                if kept {
                    screened = candidate;
                    break;
                }
            }
        }
    }
    // What screening kept, gated whole; each failure is blamed on the keyframes whose widening,
    // undone alone, lets the failed trial pass, and only those are halved.
    let mut shares: Vec<f64> = (0..spec.keyframes.len())
        .map(|k| f64::from(u8::from(!same_keyframe(&screened, spec, k))))
        .collect();
    let mut halvings = vec![0usize; spec.keyframes.len()];
    for _ in 0..options.most_widening_gates(spec) {
        if interrupted() || shares.iter().all(|s| *s == 0.0) {
            break;
        }
        let candidate = blend(spec, &screened, &shares);
        let mut round = gate_round(&candidate, &shares)?;
        let decision = round.decision;
        if decision.is_some_and(|d| d != Decision::Passes) {
            round.blamed = blame(
                spec,
                &candidate,
                &shares,
                &round.outcome.failed_seeds,
                replay,
            )?;
            back_off(&mut shares, &mut halvings, &round.blamed, options.back_offs);
        }
        report(Event::Gate(&round));
        gates.push(round);
        match decision {
            Some(Decision::Passes) => {
                gated = Some(candidate);
                break;
            }
            // Interrupted during the gate.
            None => break,
            Some(_) => {}
        }
    }
    let best = gated.as_ref().unwrap_or(spec);
    let relaxed = gated.as_ref().map(|g| {
        let mut r = g.clone();
        r.method = format!("{}+relaxed", spec.method);
        r
    });
    let volume_gain = spec
        .keyframes
        .iter()
        .zip(&best.keyframes)
        .map(|(a, b)| volume_gain_bits(&a.tsr, &b.tsr))
        .collect();
    Ok(Relaxation {
        bits_before: workspace.bits(spec)?,
        bits_after: workspace.bits(best)?,
        relaxed,
        probes,
        gates,
        volume_gain,
        trials: trials.load(Ordering::Relaxed),
        interrupted: interrupted(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_scene::builtin;
    use std::cell::Cell;

    /// The pick_place truth, and the same with keyframe 1 wider along x and keyframe 3 in yaw.
    fn truth_and_widened() -> (TaskSpec, TaskSpec) {
        let task = builtin::task("pick_place").unwrap().unwrap();
        let spec = task.truth.clone().unwrap();
        let mut wide = spec.clone();
        wide.keyframes[1].tsr.bw.0[0] = [-0.045, 0.085];
        wide.keyframes[3].tsr.bw.0[5] = [-0.85, 0.85];
        (spec, wide)
    }

    #[test]
    fn a_blend_moves_each_keyframe_its_share_of_the_way() {
        let (spec, mut wide) = truth_and_widened();
        wide.keyframes[2].tsr.bw.0[0] = [-0.045, 0.085];
        let blended = blend(&spec, &wide, &[1.0, 0.5, 0.0, 0.25]);
        let [lo, hi] = blended.keyframes[1].tsr.bw.0[0];
        assert!((lo + 0.025).abs() < 1e-12 && (hi - 0.045).abs() < 1e-12);
        assert_eq!(blended.keyframes[2], spec.keyframes[2]);
        let [lo, hi] = blended.keyframes[3].tsr.bw.0[5];
        assert!((lo + 0.25).abs() < 1e-12 && (hi - 0.25).abs() < 1e-12);
        assert_eq!(blended.keyframes[0], spec.keyframes[0]);
        assert_eq!(blend(&spec, &wide, &[0.0; 4]), spec);
        assert_eq!(blend(&spec, &wide, &[1.0; 4]), wide);
    }

    #[test]
    fn failures_are_blamed_on_the_widening_whose_undoing_passes_them() {
        let (spec, wide) = truth_and_widened();
        let shares = [0.0, 1.0, 0.0, 1.0];
        // Seed 7 passes once keyframe 3 is narrow again, seed 9 only with both narrow, seed 11
        // fails even as the spec is given (its own failure).
        let passes_one = |s: &TaskSpec, seed: u64| {
            let narrow = |k: usize| s.keyframes[k] == spec.keyframes[k];
            match seed {
                7 => narrow(3),
                9 => narrow(1) && narrow(3),
                _ => false,
            }
        };
        let runs = Cell::new(0);
        let passes = |asked: &[(TaskSpec, u64)]| {
            runs.set(runs.get() + asked.len());
            Ok(asked.iter().map(|(s, seed)| passes_one(s, *seed)).collect())
        };
        assert_eq!(blame(&spec, &wide, &shares, &[7], passes).unwrap(), vec![3]);
        // The spec as given, then one trial per widened keyframe.
        assert_eq!(runs.get(), 3);
        assert_eq!(
            blame(&spec, &wide, &shares, &[9], passes).unwrap(),
            vec![1, 3]
        );
        runs.set(0);
        assert!(blame(&spec, &wide, &shares, &[11], passes)
            .unwrap()
            .is_empty());
        // The spec's own failure is not replayed with any widening undone.
        assert_eq!(runs.get(), 1);
        assert_eq!(
            blame(&spec, &wide, &shares, &[11, 7], passes).unwrap(),
            vec![3]
        );
    }

    #[test]
    fn a_blamed_widening_is_halved_then_dropped() {
        let mut shares = [1.0, 1.0, 0.0];
        let mut halvings = [0; 3];
        back_off(&mut shares, &mut halvings, &[1], 2);
        assert_eq!(shares, [1.0, 0.5, 0.0]);
        back_off(&mut shares, &mut halvings, &[1], 2);
        assert_eq!(shares, [1.0, 0.25, 0.0]);
        back_off(&mut shares, &mut halvings, &[0, 1], 2);
        assert_eq!(shares, [0.5, 0.0, 0.0]);
    }

    #[test]
    fn a_doubled_width_is_one_bit() {
        let task = builtin::task("pick_place").unwrap().unwrap();
        let tsr = task.truth.clone().unwrap().keyframes[0].tsr.clone();
        let mut wider = tsr.clone();
        let [lo, hi] = wider.bw.0[5];
        wider.bw.0[5] = [2.0 * lo, 2.0 * hi];
        assert!((volume_gain_bits(&tsr, &wider) - 1.0).abs() < 1e-12);
        wider.bw.0[0] = [4.0 * wider.bw.0[0][0], 4.0 * wider.bw.0[0][1]];
        assert!((volume_gain_bits(&tsr, &wider) - 3.0).abs() < 1e-12);
        assert_eq!(volume_gain_bits(&tsr, &tsr), 0.0);
    }

    #[test]
    fn gate_seeds_must_stay_clear_of_the_search() {
        let task = builtin::task("pick_place").unwrap().unwrap();
        let spec = task.truth.clone().unwrap();
        let mut options = RelaxOptions::default();
        assert!(options.check(&spec).is_ok());
        options.gate_seed = 5;
        let e = options.check(&spec).unwrap_err().to_string();
        assert!(e.contains("overlap"), "{e}");
        options.levels = vec![1.5];
        assert!(options.check(&spec).is_err());
    }
}
