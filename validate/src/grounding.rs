//! Grounding sensitivity: can the task's randomization tell a keyframe's reference object from
//! every other object? A pass means little for a keyframe whose reference could be swapped for
//! another without any trial noticing.
//!
//! For every keyframe and every other object (and the world), the keyframe is re-grounded on
//! that object with its offset recomputed so that, in the nominal execution, its world pose is
//! unchanged; the re-grounded spec is then judged by the deployment gate (goals drawn across
//! the TSRs, [`crate::trials::run_gated`]). The alternative is
//! - **distinguished** when the gate fails it: validation would reject a spec grounded on it;
//! - **not distinguished** when the gate passes it: a spec grounded on it would be deployed;
//! - **undecided** when the gate cannot tell within its trials (it fails some 0.2–2 %);
//! - **equivalent** when the two objects are held in one fixed relation: by the task's
//!   randomization (a group, an object riding on what moves it, things nothing moves; see
//!   [`akl_scene::Task::fixed_relations`]) or by the spec itself (an object an earlier keyframe
//!   put down, grounded on its reference, stays where that reference puts it). These are not
//!   executed.
//!
//! A gate, not a fixed share of a fixed number of trials: an alternative failing 90 % of
//! trials read "distinguished" by a bar of 18 of 20 only two times in three, while the gate
//! fails it at its first or second trial nearly always; and the gate's verdict is the question
//! a user has: would validation catch this wrong grounding?
//!
//! "Nominal execution" is the spec grounded on the task file's placements, keyframe by
//! keyframe, with every object released where its release keyframe puts it; so a keyframe
//! after a placement is re-grounded on the placed object where it then stands.

use crate::trials::run_gated;
use akl_exec::report::Cause;
use akl_exec::{ExecError, ExecOptions};
use akl_planner::Robot;
use akl_scene::Task;
use akl_stats::{Decision, Gate, GateOptions, PassRate};
use akl_tsr::{Gripper, Pose, TaskSpec, WORLD_FRAME};
use serde::Serialize;
use std::collections::BTreeMap;

/// How the sensitivity is measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GroundingOptions {
    /// The gate each alternative is judged by.
    pub gate: GateOptions,
    /// Seed of the first trial (the same trials for every alternative).
    pub seed: u64,
    /// Trials in parallel.
    pub jobs: usize,
}

impl Default for GroundingOptions {
    /// The deployment gate's defaults, from seed 0, on one core.
    fn default() -> Self {
        GroundingOptions {
            gate: GateOptions::default(),
            seed: 0,
            jobs: 1,
        }
    }
}

/// What the trials say of one alternative reference.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(rename_all = "snake_case", tag = "verdict")]
pub enum Verdict {
    /// The gate fails it: the randomization tells it from the reference.
    Distinguished,
    /// It is held in a fixed relation with the reference; not executed.
    Equivalent {
        /// Why, in words.
        because: String,
    },
    /// The gate passes it: the randomization cannot tell it from the reference.
    NotDistinguished,
    /// The gate could not decide within its trials, or was interrupted.
    Undecided,
}

/// One alternative reference of a keyframe.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Alternative {
    /// The object (or `world`) the keyframe was re-grounded on.
    pub reference: String,
    /// The verdict.
    #[serde(flatten)]
    pub verdict: Verdict,
    /// Trials the gate read (0 for an equivalent one).
    pub trials: usize,
    /// Trials failed.
    pub failed: usize,
    /// The pass rate with its 95 % interval (none for an equivalent one).
    pub pass_rate: Option<PassRate>,
    /// How many failed trials had each root cause (these add up to `failed`).
    pub causes: BTreeMap<Cause, usize>,
}

/// The alternatives of one keyframe.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct KeyframeGroundings {
    /// The keyframe's index.
    pub keyframe: usize,
    /// Its reference in the spec.
    pub reference: String,
    /// Every other object and the world.
    pub alternatives: Vec<Alternative>,
}

/// The grounding sensitivity of a whole spec, as far as the check got.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Groundings {
    /// Whether the check was stopped (Ctrl-C) before it had measured every alternative: then
    /// `keyframes` holds what it measured, the last alternative possibly undecided.
    pub interrupted: bool,
    /// Every keyframe, in order, with its alternatives.
    pub keyframes: Vec<KeyframeGroundings>,
}

impl KeyframeGroundings {
    /// The alternatives the randomization does not tell from the reference.
    pub fn not_distinguished(&self) -> impl Iterator<Item = &Alternative> {
        self.alternatives
            .iter()
            .filter(|a| a.verdict == Verdict::NotDistinguished)
    }
}

/// The world pose of every object (and `world`) as each keyframe of `spec` is reached in the
/// nominal execution on `task`'s own placements.
pub fn nominal_poses(task: &Task, spec: &TaskSpec) -> Vec<BTreeMap<String, Pose>> {
    let mut poses = task.world.object_poses();
    poses.insert(WORLD_FRAME.to_string(), Pose::identity());
    let mut held: Option<(String, Pose)> = None;
    let mut gripper = Gripper::Open;
    let mut out = Vec::with_capacity(spec.keyframes.len());
    for kf in &spec.keyframes {
        out.push(poses.clone());
        let Some(reference) = poses.get(&kf.reference) else {
            continue;
        };
        let tcp = reference * kf.tsr.tw_e;
        match (gripper, kf.gripper) {
            (Gripper::Open, Gripper::Closed) => {
                held = poses
                    .get(&kf.reference)
                    .map(|o| (kf.reference.clone(), tcp.inverse() * o));
            }
            (Gripper::Closed, Gripper::Open) => {
                if let Some((name, in_tcp)) = held.take() {
                    poses.insert(name, tcp * in_tcp);
                }
            }
            _ => {}
        }
        gripper = kf.gripper;
    }
    out
}

/// `spec` with keyframe `k` grounded on `other` instead, its offset recomputed so that its
/// world pose in `poses` (the nominal poses as keyframe `k` is reached) is unchanged.
pub fn regrounded(
    spec: &TaskSpec,
    k: usize,
    other: &str,
    poses: &BTreeMap<String, Pose>,
) -> Option<TaskSpec> {
    let kf = spec.keyframes.get(k)?;
    let from = poses.get(&kf.reference)?;
    let to = poses.get(other)?;
    let mut wrong = spec.clone();
    let w = &mut wrong.keyframes[k];
    w.tsr.tw_e = to.inverse() * from * kf.tsr.tw_e;
    w.tsr.t0_w = *to;
    w.reference = other.to_string();
    Some(wrong)
}

/// Why `a` and `b` stay in one fixed relation by keyframe `k`, if they do: the task's
/// randomization holds them together, or an earlier keyframe of `spec` put one down grounded on
/// something held together with the other.
pub fn equivalence(task: &Task, spec: &TaskSpec, k: usize, a: &str, b: &str) -> Option<String> {
    let relations = task.fixed_relations().ok()?;
    let class_of = |name: &str| -> Vec<String> {
        relations
            .iter()
            .find(|r| r.members.iter().any(|m| m == name))
            .map_or_else(|| vec![name.to_string()], |r| r.members.clone())
    };
    if let Some(r) = relations
        .iter()
        .find(|r| r.members.iter().any(|m| m == a) && r.members.iter().any(|m| m == b))
    {
        return Some(r.because.clone());
    }
    // Objects put down so far, and what each was put down on.
    let mut placed: Vec<(String, String)> = Vec::new();
    let mut holding: Option<&str> = None;
    let mut gripper = Gripper::Open;
    for kf in spec.keyframes.iter().take(k) {
        match (gripper, kf.gripper) {
            (Gripper::Open, Gripper::Closed) => holding = Some(&kf.reference),
            (Gripper::Closed, Gripper::Open) => {
                if let Some(object) = holding.take() {
                    placed.retain(|(o, _)| o != object);
                    placed.push((object.to_string(), kf.reference.clone()));
                }
            }
            _ => {}
        }
        gripper = kf.gripper;
    }
    // The class of a name, grown by what was put down on a member of it.
    let grown = |name: &str| -> Vec<String> {
        let mut class = class_of(name);
        loop {
            let before = class.len();
            for (object, on) in &placed {
                if class.contains(on) && !class.contains(object) {
                    class.push(object.clone());
                }
                if class.contains(object) && !class.contains(on) {
                    class.extend(class_of(on));
                }
            }
            if class.len() == before {
                return class;
            }
        }
    };
    grown(a).iter().any(|n| n == b).then(|| {
        let (object, on) = placed
            .iter()
            .rev()
            .find(|(o, on)| (o == a || o == b) || grown(on).iter().any(|n| n == a || n == b))
            .cloned()
            .unwrap_or_default();
        format!("{object} was put down grounded on {on} earlier in the spec")
    })
}

/// Measures every keyframe's grounding sensitivity; `progress` is called after each
/// alternative with (done, total). Once `exec.interrupt` is raised no further alternative is
/// measured, and the result, [`Groundings::interrupted`], holds those that were.
pub fn check_groundings(
    robot: &Robot,
    task: &Task,
    spec: &TaskSpec,
    exec: &ExecOptions,
    options: &GroundingOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Groundings, ExecError> {
    spec.validate()?;
    spec.check_references(task.world.names())?;
    let gate = Gate::new(options.gate).map_err(|e| ExecError::Options(e.to_string()))?;
    let poses = nominal_poses(task, spec);
    let names: Vec<String> = task
        .world
        .names()
        .map(String::from)
        .chain([WORLD_FRAME.to_string()])
        .collect();
    let total = spec.keyframes.len() * (names.len() - 1);
    let mut done = 0;
    let mut out = Vec::with_capacity(spec.keyframes.len());
    let mut interrupted = false;
    for (k, kf) in spec.keyframes.iter().enumerate() {
        let mut alternatives = Vec::new();
        for other in names.iter().filter(|n| **n != kf.reference) {
            if exec.interrupt.raised() {
                interrupted = true;
                break;
            }
            let alternative = match equivalence(task, spec, k, &kf.reference, other) {
                Some(because) => Alternative {
                    reference: other.clone(),
                    verdict: Verdict::Equivalent { because },
                    trials: 0,
                    failed: 0,
                    pass_rate: None,
                    causes: BTreeMap::new(),
                },
                None => {
                    let wrong = regrounded(spec, k, other, &poses[k]).ok_or_else(|| {
                        ExecError::Options(format!("keyframe {k}: cannot re-ground on {other}"))
                    })?;
                    let alternative = measure(robot, task, &wrong, exec, &gate, options, other)?;
                    if exec.interrupt.raised() {
                        interrupted = true;
                        if alternative.trials == 0 {
                            break;
                        }
                    }
                    alternative
                }
            };
            alternatives.push(alternative);
            done += 1;
            progress(done, total);
        }
        if !alternatives.is_empty() {
            out.push(KeyframeGroundings {
                keyframe: k,
                reference: kf.reference.clone(),
                alternatives,
            });
        }
        if interrupted {
            break;
        }
    }
    Ok(Groundings {
        interrupted,
        keyframes: out,
    })
}

/// Judges `wrong` (re-grounded on `other`) by `gate` on the check's trials.
fn measure(
    robot: &Robot,
    task: &Task,
    wrong: &TaskSpec,
    exec: &ExecOptions,
    gate: &Gate,
    options: &GroundingOptions,
    other: &str,
) -> Result<Alternative, ExecError> {
    let gated = run_gated(
        robot,
        task,
        wrong,
        exec,
        gate,
        options.seed,
        options.jobs,
        false,
        &|_| {},
    )?;
    let o = gated.outcome;
    Ok(Alternative {
        reference: other.to_string(),
        verdict: match gated.decision {
            Some(Decision::Fails) => Verdict::Distinguished,
            Some(Decision::Passes) => Verdict::NotDistinguished,
            Some(Decision::Undecided) | None => Verdict::Undecided,
        },
        trials: o.run,
        failed: o.run - o.passed,
        pass_rate: Some(o.pass_rate),
        causes: o.failures,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_scene::builtin;
    use akl_tsr::pose::position_distance;

    #[test]
    fn a_check_interrupted_before_it_starts_measures_nothing() {
        use akl_exec::Interrupt;
        use std::sync::atomic::AtomicBool;
        static RAISED: AtomicBool = AtomicBool::new(true);
        let robot = Robot::panda().unwrap();
        let task = builtin::task("pick_place").unwrap().unwrap();
        let spec = task.truth.clone().unwrap();
        let exec = ExecOptions {
            interrupt: Interrupt::on(&RAISED),
            ..ExecOptions::default()
        };
        let options = GroundingOptions::default();
        let g = check_groundings(&robot, &task, &spec, &exec, &options, &|_, _| {}).unwrap();
        assert!(g.interrupted && g.keyframes.is_empty(), "{g:?}");
    }

    #[test]
    fn a_regrounded_keyframe_keeps_its_nominal_world_pose() {
        let task = builtin::task("pick_place").unwrap().unwrap();
        let spec = task.truth.clone().unwrap();
        let poses = nominal_poses(&task, &spec);
        for k in 0..spec.keyframes.len() {
            let before = poses[k][&spec.keyframes[k].reference] * spec.keyframes[k].tsr.tw_e;
            for other in ["block_b", "shelf_1", WORLD_FRAME] {
                let wrong = regrounded(&spec, k, other, &poses[k]).unwrap();
                let after = poses[k][other] * wrong.keyframes[k].tsr.tw_e;
                assert!(position_distance(&before, &after) < 1e-9);
                assert_eq!(wrong.keyframes[k].reference, other);
            }
        }
    }

    #[test]
    fn a_placed_block_stands_where_its_release_put_it() {
        let task = builtin::task("pick_place").unwrap().unwrap();
        let spec = task.truth.clone().unwrap();
        let poses = nominal_poses(&task, &spec);
        let start = task.world.object("block_a").unwrap().pose;
        assert_eq!(poses[1]["block_a"], start);
        let shelf = task.world.object("shelf_2").unwrap().pose;
        let placed = poses[2]["block_a"];
        assert!(
            shelf
                .inverse()
                .transform_point(&placed.translation.vector.into())
                .z
                > 0.0
        );
        assert!(position_distance(&placed, &start) > 0.3);
    }

    #[test]
    fn equivalence_follows_the_randomization_and_earlier_placements() {
        let task = builtin::task("pick_place").unwrap().unwrap();
        let spec = task.truth.clone().unwrap();
        // block_b's release (keyframe 3) on mat_b or on block_a, which keyframe 1 put on mat_a,
        // and mat_a moves with mat_b.
        let why = equivalence(&task, &spec, 3, "mat_b", "block_a").unwrap();
        assert!(why.contains("block_a"), "{why}");
        assert!(equivalence(&task, &spec, 3, "mat_b", "mat_a").is_some());
        assert!(equivalence(&task, &spec, 1, "mat_a", "block_a").is_none());
        assert!(equivalence(&task, &spec, 3, "mat_b", "shelf_2").is_none());
        assert!(equivalence(&task, &spec, 3, "mat_b", "shelf_1").is_none());
        assert!(equivalence(&task, &spec, 0, "table", WORLD_FRAME).is_some());
        let inspection = builtin::task("inspection").unwrap().unwrap();
        let truth = inspection.truth.clone().unwrap();
        assert!(equivalence(&inspection, &truth, 1, "scanner_2", "scanner_1").is_some());
        assert!(equivalence(&inspection, &truth, 1, "scanner_2", "shelf_2").is_none());
    }
}
