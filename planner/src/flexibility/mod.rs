//! How much freedom a spec leaves the planner (thesis §3.2.5), measured two ways.
//!
//! **Bits of freedom** ([`Workspace::freedom`]). The thesis defines the flexibility of a spec
//! as the number of execution traces that satisfy it (Definition 3.2.1). Here a trace is a
//! walk of the tool centre point over a lattice of the workspace (`lattice`): cubic cells
//! of [`FreedomOptions::resolution`] within the robot's reach and above its base, without the
//! cells whose centre lies inside furniture (objects at the places the task file gives them).
//! A trace starts and ends at the TCP of the robot's ready configuration, meets every
//! keyframe's region (`regions`: the cells its grounded TSR reaches) in order, keeps every
//! `move_in_line` segment on the cells of the straight lines between its two keyframes'
//! regions, and takes at most the task's step budget (`route`: a fixed multiple of the
//! shortest walk along the task's teaching route, the same for every spec of a task). Traces
//! are counted exactly (`count`); the measure is log2 of the count, in bits. Adding a
//! keyframe or a line can only remove traces (Lemma 3.2.1), so a spec with a redundant
//! keyframe or an unintended line has fewer bits than the least restrictive one. Each
//! keyframe's share of the loss is the bits the spec gains without it (and without the lines
//! that end or start at it); each line's, the bits it gains without that line. Shares overlap
//! and do not add up to the loss. The lattice traces positions only: rotation bounds count
//! through the positions they let the TCP take (a TSR's offset turning), gripper commands not
//! at all. A region is made of whole cells, so a TSR a few millimetres across counts one cell
//! or several depending on where the cell borders fall: two specs whose keyframes differ by
//! millimetres can differ by a few bits (the specs learned from the simulated teacher's
//! demonstration of pick_place have 118.9 bits, the truth 116.6).
//!
//! **What the planner gains** (`gains`). Over randomized scenes of the task, the budgeted
//! planner's success rate and the best and median execution time and joint-path length it
//! finds, beside those of the nominal-first candidate in the same scenes.

mod count;
mod gains;
mod lattice;
mod regions;
mod route;

use crate::robot::Robot;
use akl_scene::Task;
use akl_tsr::nalgebra::Vector3;
use akl_tsr::{Constraint, TaskSpec};
use count::{count_traces, log2, TraceProblem, MAX_KEYFRAMES};
use num_bigint::BigUint;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;

pub use gains::{planner_gains, GainOptions, Gains, SceneFailure, Spread};
pub use lattice::Lattice;

/// Why a spec's flexibility cannot be measured.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum FlexibilityError {
    /// The spec cannot be grounded in the task's world.
    #[error("{0}")]
    Grounding(String),
    /// The spec has more keyframes than a count handles.
    #[error("the spec has {0} keyframes; bits of freedom are counted for at most {MAX_KEYFRAMES}")]
    TooManyKeyframes(usize),
    /// The start, or a point of the task's teaching route, is not a cell of the lattice.
    #[error("{0}")]
    Workspace(String),
    /// An option is out of range.
    #[error("{0}")]
    Options(String),
    /// A randomized scene could not be made.
    #[error("{0}")]
    Scene(String),
}

/// Settings of the bits-of-freedom measure.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreedomOptions {
    /// Edge length of a lattice cell (metres).
    ///
    /// 5 cm: of 4, 5 and 6 cm (at a slack of 1.25), the finest at which a whole report (the
    /// spec, the unconstrained lattice and every share) stays within a second per built-in
    /// task on the reference machine: 4 cm took up to 2.9 s (BENCHMARKS.md). A 5 cm cell still
    /// separates the shelves, blocks, scanners and clamp of the built-in tasks.
    pub resolution: f64,
    /// The step budget of a trace as a multiple of the shortest walk along the task's
    /// teaching route.
    ///
    /// 1.25: at 1.5 a report took up to 1.9 s at 5 cm; at 1.25 every ground truth with a
    /// redundant keyframe or an unintended line still has traces (each removes bits rather
    /// than every trace), which the tests check, and so do the specs AKL, KD and mACL learn
    /// from the simulated teacher's demonstrations of the built-in tasks (default profile,
    /// seed 0; measured with `akl flexibility`).
    pub slack: f64,
}

impl Default for FreedomOptions {
    fn default() -> Self {
        FreedomOptions {
            resolution: 0.05,
            slack: 1.25,
        }
    }
}

/// Configurations sampled to measure the robot's reach.
const REACH_SAMPLES: usize = 4096;

/// The farthest the TCP gets from the robot base, over [`REACH_SAMPLES`] configurations drawn
/// uniformly within the joint limits (seeded, so always the same), plus one cell of margin.
fn reach(robot: &Robot, margin: f64) -> f64 {
    let mut rng = ChaCha8Rng::seed_from_u64(0);
    let mut q = vec![0.0; robot.dof()];
    let mut farthest: f64 = 0.0;
    for _ in 0..REACH_SAMPLES {
        for (v, [lo, hi]) in q.iter_mut().zip(robot.joint_limits()) {
            *v = rng.gen_range(*lo..=*hi);
        }
        farthest = farthest.max(robot.tcp_pose(&q).translation.vector.norm());
    }
    farthest + margin
}

/// A task's lattice, start and end cell and step budget: what every count of a spec of this
/// task shares.
#[derive(Debug, Clone)]
pub struct Workspace {
    task: Task,
    lattice: Lattice,
    start: u32,
    route_steps: usize,
    max_steps: usize,
}

/// Each keyframe's region and, per keyframe, the line cells of the segment ending at it.
type SpecCells = (Vec<Vec<u32>>, Vec<Option<Vec<u32>>>);

/// A keyframe's or line's share of the bits a spec loses.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Share {
    /// The keyframe (for a line, the keyframe it ends at).
    pub keyframe: usize,
    /// Cells of its region (for a line, of the line).
    pub cells: usize,
    /// Bits of the spec without it (`None`: no trace).
    pub bits_without: Option<f64>,
    /// Bits it costs: `bits_without` minus the spec's bits (`None` when either has no trace).
    pub share: Option<f64>,
}

/// The bits-of-freedom report of a spec.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Freedom {
    /// Lattice resolution (metres).
    pub resolution: f64,
    /// Cells of the lattice.
    pub cells: usize,
    /// Steps of the shortest walk along the task's teaching route.
    pub route_steps: usize,
    /// Most steps a trace may take.
    pub max_steps: usize,
    /// Traces of the spec, exactly (decimal).
    #[serde(serialize_with = "decimal")]
    pub traces: BigUint,
    /// log2 of `traces` (`None`: no trace satisfies the spec).
    pub bits: Option<f64>,
    /// Bits of the task's lattice with no keyframe at all: every closed walk within budget.
    pub unconstrained_bits: Option<f64>,
    /// Per keyframe, its share of the loss.
    pub keyframes: Vec<Share>,
    /// Per `move_in_line` segment, its share of the loss.
    pub lines: Vec<Share>,
}

fn decimal<S: serde::Serializer>(v: &BigUint, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&v.to_string())
}

/// Bits gained from `bits` to `without` (`None` if either has no trace).
fn gained(without: Option<f64>, bits: Option<f64>) -> Option<f64> {
    Some(without? - bits?)
}

impl Workspace {
    /// The lattice of `task`'s world for `robot`, the start (the TCP at the ready
    /// configuration) and the task's step budget.
    pub fn new(
        robot: &Robot,
        task: &Task,
        options: &FreedomOptions,
    ) -> Result<Workspace, FlexibilityError> {
        if !(options.resolution.is_finite() && options.resolution >= 0.005) {
            return Err(FlexibilityError::Options(format!(
                "the lattice resolution must be at least 0.005 m, got {}",
                options.resolution
            )));
        }
        if !(options.slack.is_finite() && options.slack >= 1.0) {
            return Err(FlexibilityError::Options(format!(
                "the step budget's slack must be at least 1, got {}",
                options.slack
            )));
        }
        let base = task.world.robot_base;
        let start_pose = base * robot.tcp_pose(robot.ready());
        let start_point: Vector3<f64> = start_pose.translation.vector;
        let lattice = Lattice::new(
            &task.world,
            &base,
            reach(robot, options.resolution),
            &start_point,
            options.resolution,
        );
        let start = lattice.cell_at(&start_point).ok_or_else(|| {
            FlexibilityError::Workspace(
                "the TCP at the ready configuration is inside furniture".into(),
            )
        })?;
        let route_steps = route::route_steps(&lattice, task, start)?;
        let max_steps = (options.slack * route_steps as f64).ceil() as usize;
        Ok(Workspace {
            task: task.clone(),
            lattice,
            start,
            route_steps,
            max_steps,
        })
    }

    /// The lattice.
    pub fn lattice(&self) -> &Lattice {
        &self.lattice
    }

    /// Most steps a trace may take.
    pub fn max_steps(&self) -> usize {
        self.max_steps
    }

    /// Each keyframe's region and each segment's line cells, `spec` grounded on the objects'
    /// places in the task file.
    fn regions(&self, spec: &TaskSpec) -> Result<SpecCells, FlexibilityError> {
        if spec.keyframes.len() > MAX_KEYFRAMES {
            return Err(FlexibilityError::TooManyKeyframes(spec.keyframes.len()));
        }
        let grounded = spec
            .ground(&self.task.world.object_poses())
            .map_err(|e| FlexibilityError::Grounding(e.to_string()))?;
        let regions: Vec<Vec<u32>> = grounded
            .keyframes
            .iter()
            .map(|k| regions::keyframe_cells(&self.lattice, &k.tsr))
            .collect();
        let lines = grounded
            .keyframes
            .iter()
            .enumerate()
            .map(|(k, kf)| match kf.constraint {
                Constraint::MoveInLine if k > 0 => Some(regions::line_cells(
                    &self.lattice,
                    &regions[k - 1],
                    &regions[k],
                )),
                _ => None,
            })
            .collect();
        Ok((regions, lines))
    }

    fn count(&self, regions: &[Vec<u32>], lines: &[Option<Vec<u32>>]) -> BigUint {
        count_traces(&TraceProblem {
            neighbors: self.lattice.neighbors(),
            start: self.start,
            end: self.start,
            regions,
            lines,
            max_steps: self.max_steps,
        })
    }

    /// The exact number of traces that satisfy `spec`.
    pub fn traces(&self, spec: &TaskSpec) -> Result<BigUint, FlexibilityError> {
        let (regions, lines) = self.regions(spec)?;
        Ok(self.count(&regions, &lines))
    }

    /// log2 of the number of traces that satisfy `spec` (`None`: none does).
    pub fn bits(&self, spec: &TaskSpec) -> Result<Option<f64>, FlexibilityError> {
        Ok(log2(&self.traces(spec)?))
    }

    /// The full report: the spec's traces and bits, the lattice's bits without any keyframe,
    /// and every keyframe's and line's share of the loss.
    pub fn freedom(&self, spec: &TaskSpec) -> Result<Freedom, FlexibilityError> {
        let (regions, lines) = self.regions(spec)?;
        let traces = self.count(&regions, &lines);
        let bits = log2(&traces);
        let unconstrained_bits = log2(&self.count(&[], &[]));
        let n = regions.len();
        let keyframes = (0..n)
            .map(|k| {
                let mut r = regions.clone();
                let mut l = lines.clone();
                r.remove(k);
                l.remove(k);
                // The line that started at keyframe k now has no start: it goes too.
                if k < l.len() {
                    l[k] = None;
                }
                let without = log2(&self.count(&r, &l));
                Share {
                    keyframe: k,
                    cells: regions[k].len(),
                    bits_without: without,
                    share: gained(without, bits),
                }
            })
            .collect();
        let lines_report = (0..n)
            .filter_map(|k| {
                let cells = lines[k].as_ref()?.len();
                let mut l = lines.clone();
                l[k] = None;
                let without = log2(&self.count(&regions, &l));
                Some(Share {
                    keyframe: k,
                    cells,
                    bits_without: without,
                    share: gained(without, bits),
                })
            })
            .collect();
        Ok(Freedom {
            resolution: self.lattice.resolution(),
            cells: self.lattice.len(),
            route_steps: self.route_steps,
            max_steps: self.max_steps,
            traces,
            bits,
            unconstrained_bits,
            keyframes,
            lines: lines_report,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use akl_scene::builtin;
    use akl_tsr::pose::pose_from_xyz;
    use akl_tsr::{Bounds, Keyframe, KeyframeKind, Tsr, WORLD_FRAME};
    use proptest::prelude::*;

    fn truth(name: &str) -> (Task, TaskSpec) {
        let task = builtin::task(name).unwrap().unwrap();
        let truth = task.truth.clone().unwrap();
        (task, truth)
    }

    /// The truth with a via-point keyframe 10 cm above the middle of its first free segment.
    fn with_redundant_keyframe(task: &Task, spec: &TaskSpec) -> TaskSpec {
        let grounded = spec.ground(&task.world.object_poses()).unwrap();
        let a = grounded.keyframes[0].tsr.nominal().translation.vector;
        let b = grounded.keyframes[1].tsr.nominal().translation.vector;
        let mid = 0.5 * (a + b) + Vector3::new(0.0, 0.0, 0.1);
        let mut out = spec.clone();
        out.keyframes.insert(
            1,
            Keyframe {
                kind: KeyframeKind::Constraint,
                reference: WORLD_FRAME.into(),
                tsr: Tsr::new(
                    pose_from_xyz([mid.x, mid.y, mid.z]),
                    akl_tsr::Pose::identity(),
                    Bounds::symmetric(0.005, 0.05),
                ),
                gripper: spec.keyframes[0].gripper,
                constraint: Constraint::None,
                t: None,
                frame: None,
            },
        );
        out
    }

    #[test]
    fn each_truth_has_more_bits_than_itself_with_a_redundant_keyframe_or_an_unintended_line() {
        let robot = Robot::panda().unwrap();
        for name in builtin::names() {
            let (task, truth) = truth(name);
            let ws = Workspace::new(&robot, &task, &FreedomOptions::default()).unwrap();
            let report = ws.freedom(&truth).unwrap();
            let bits = report.bits.unwrap_or_else(|| panic!("{name}: no trace"));
            assert!(bits > 0.0, "{name}");
            assert!(report.unconstrained_bits.unwrap() > bits, "{name}");
            for share in report.keyframes.iter().chain(&report.lines) {
                assert!(share.share.unwrap() >= 0.0, "{name}: {share:?}");
            }
            assert_eq!(report.keyframes.len(), truth.keyframes.len());
            let truths_lines = truth.line_count();
            assert_eq!(report.lines.len(), truths_lines, "{name}");

            let redundant = with_redundant_keyframe(&task, &truth);
            let fewer = ws.traces(&redundant).unwrap();
            assert!(fewer < report.traces, "{name}: a via-point keyframe");
            assert!(
                fewer > BigUint::default(),
                "{name}: a via-point leaves no trace"
            );

            assert_eq!(truth.keyframes[1].constraint, Constraint::None, "{name}");
            let mut lined = truth.clone();
            lined.keyframes[1].constraint = Constraint::MoveInLine;
            let fewer = ws.traces(&lined).unwrap();
            assert!(fewer < report.traces, "{name}: an unintended line");
            assert!(
                fewer > BigUint::default(),
                "{name}: the line leaves no trace"
            );
            println!(
                "{name}: {bits:.1} bits; with a via-point {:?}; with a line {:?}",
                log2(&ws.traces(&redundant).unwrap()),
                log2(&fewer)
            );
        }
    }

    #[test]
    fn a_wider_tsr_has_more_bits() {
        let robot = Robot::panda().unwrap();
        let (task, truth) = truth("pick_place");
        let ws = Workspace::new(&robot, &task, &FreedomOptions::default()).unwrap();
        let mut wide = truth.clone();
        wide.keyframes[1].tsr.bw = Bounds::symmetric(0.06, 0.05);
        assert!(ws.traces(&wide).unwrap() > ws.traces(&truth).unwrap());
    }

    /// A keyframe with a region of half-width `half` around world point `at`.
    fn via(at: [f64; 3], half: f64, constraint: Constraint) -> Keyframe {
        Keyframe {
            kind: KeyframeKind::Constraint,
            reference: WORLD_FRAME.into(),
            tsr: Tsr::new(
                pose_from_xyz(at),
                akl_tsr::Pose::identity(),
                Bounds::symmetric(half, 0.05),
            ),
            gripper: akl_tsr::Gripper::Open,
            constraint,
            t: None,
            frame: None,
        }
    }

    fn arb_keyframe() -> impl Strategy<Value = ([f64; 3], f64, bool)> {
        (
            (0.25..0.65f64, -0.45..0.45f64, 0.15..0.55f64),
            0.0..0.12f64,
            any::<bool>(),
        )
            .prop_map(|((x, y, z), half, line)| ([x, y, z], half, line))
    }

    fn coarse() -> &'static (Task, Workspace) {
        static COARSE: std::sync::OnceLock<(Task, Workspace)> = std::sync::OnceLock::new();
        COARSE.get_or_init(|| {
            let robot = Robot::panda().unwrap();
            let task = builtin::task("pick_place").unwrap().unwrap();
            let options = FreedomOptions {
                resolution: 0.1,
                slack: 1.6,
            };
            let ws = Workspace::new(&robot, &task, &options).unwrap();
            (task, ws)
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(48))]

        /// Lemma 3.2.1 on the lattice: a spec with one more keyframe (inserted anywhere it does
        /// not split a line) or one more line never has more traces.
        #[test]
        fn adding_a_keyframe_or_a_line_never_adds_traces(
            base in prop::collection::vec(arb_keyframe(), 1..4),
            extra in arb_keyframe(),
            at in any::<prop::sample::Index>(),
            add_line in any::<bool>(),
        ) {
            let (_, ws) = coarse();
            let keyframes: Vec<Keyframe> = base
                .iter()
                .enumerate()
                .map(|(i, &(p, half, line))| {
                    via(p, half, if line && i > 0 { Constraint::MoveInLine } else { Constraint::None })
                })
                .collect();
            let spec = TaskSpec::new("pick_place", "test", keyframes);
            let before = ws.traces(&spec).unwrap();
            let mut more = spec.clone();
            if add_line {
                let free: Vec<usize> = (1..more.keyframes.len())
                    .filter(|&k| more.keyframes[k].constraint == Constraint::None)
                    .collect();
                if free.is_empty() {
                    return Ok(());
                }
                more.keyframes[free[at.index(free.len())]].constraint = Constraint::MoveInLine;
            } else {
                let slots: Vec<usize> = (0..=more.keyframes.len())
                    .filter(|&k| k == more.keyframes.len() || more.keyframes[k].constraint == Constraint::None)
                    .collect();
                let k = slots[at.index(slots.len())];
                more.keyframes.insert(k, via(extra.0, extra.1, Constraint::None));
            }
            let after = ws.traces(&more).unwrap();
            prop_assert!(after <= before, "{after} > {before}");
        }
    }

    #[test]
    fn bad_options_and_specs_are_refused_by_name() {
        let robot = Robot::panda().unwrap();
        let (task, truth) = truth("inspection");
        let e = Workspace::new(
            &robot,
            &task,
            &FreedomOptions {
                resolution: 0.0,
                ..FreedomOptions::default()
            },
        )
        .unwrap_err();
        assert!(e.to_string().contains("resolution"), "{e}");
        let mut buried = task.clone();
        let last = buried.teaching.steps.len() - 1;
        buried.teaching.steps[last] = akl_scene::TeachStep::Move {
            to: pose_from_xyz([0.35, 0.0, -0.02]),
            relative_to: WORLD_FRAME.into(),
        };
        let e = Workspace::new(&robot, &buried, &FreedomOptions::default()).unwrap_err();
        assert!(
            e.to_string()
                .contains(&format!("teaching.steps[{last}]: its target is outside")),
            "{e}"
        );
        let ws = Workspace::new(&robot, &task, &FreedomOptions::default()).unwrap();
        let mut ghost = truth;
        ghost.keyframes[2].reference = "ghost".into();
        let e = ws.traces(&ghost).unwrap_err();
        assert!(e.to_string().contains("`ghost`"), "{e}");
    }
}
