//! The gripper's actions during a run: closing when the plan closes (until both pads touch),
//! judging and welding what the pads closed on, carrying it while the weld holds (and noting
//! when it first slipped beyond the slip limit), letting go when the plan opens, and
//! remembering where released objects were let go.

use super::observations::{GraspEvent, Observations, ReleaseEvent};
use crate::arm::{FingerCommand, SimArm};
use crate::grasp::{measure, read_pads, square, strongest_push, GraspLimits, Weld};
use crate::world::{Owner, SimWorld};
use akl_planner::{GripperAction, Plan, SegmentKind};
use akl_tsr::{Pose, TaskSpec};

/// A gripper command of the plan.
#[derive(Debug, Clone)]
enum Command {
    /// Close at a keyframe, on the object the spec closes on; give up at `deadline`.
    Close {
        keyframe: usize,
        intended: String,
        deadline: f64,
    },
    /// Open at a keyframe.
    Open { keyframe: usize },
}

/// The closing under way.
#[derive(Debug, Clone)]
struct Closing {
    keyframe: usize,
    intended: String,
    deadline: f64,
}

/// An object in the hand.
#[derive(Debug, Clone)]
struct Holding {
    object: usize,
    weld: Option<Weld>,
    /// Its pose in the TCP frame when grasped.
    in_tcp: Pose,
    /// Index of its grasp in [`Observations::grasps`].
    event: usize,
}

/// The gripper's state over a run.
pub(super) struct Gripper {
    commands: Vec<(f64, Command)>,
    next: usize,
    closing: Option<Closing>,
    holding: Option<Holding>,
    limits: GraspLimits,
    grasp_force: f64,
    open_width: f64,
    slip_limit: f64,
    /// The robot's link names, to say which pushed a held object loose.
    link_names: Vec<String>,
}

impl Gripper {
    /// The gripper commands of `plan`, closing on the objects `spec` names; a held object
    /// moving more than `slip_limit` (metres) in the hand is noted as slipped. `link_names`
    /// are the robot's, by link index.
    pub(super) fn new(
        plan: &Plan,
        spec: &TaskSpec,
        limits: GraspLimits,
        grasp_force: f64,
        open_width: f64,
        slip_limit: f64,
        link_names: Vec<String>,
    ) -> Gripper {
        let mut commands: Vec<(f64, Command)> = plan
            .events
            .iter()
            .map(|e| {
                let command = match e.action {
                    GripperAction::Close => Command::Close {
                        keyframe: e.keyframe,
                        intended: spec
                            .keyframes
                            .get(e.keyframe)
                            .map_or_else(|| e.object.clone(), |k| k.reference.clone()),
                        deadline: plan
                            .segments
                            .iter()
                            .find(|s| s.kind == SegmentKind::Gripper && s.start >= e.t - 1e-9)
                            .map_or(e.t, |s| s.end),
                    },
                    GripperAction::Open => Command::Open {
                        keyframe: e.keyframe,
                    },
                };
                (e.t, command)
            })
            .collect();
        commands.sort_by(|a, b| a.0.total_cmp(&b.0));
        Gripper {
            commands,
            next: 0,
            closing: None,
            holding: None,
            limits,
            grasp_force,
            open_width,
            slip_limit,
            link_names,
        }
    }

    /// The object in the hand (index), if any.
    pub(super) fn held(&self) -> Option<usize> {
        self.holding.as_ref().map(|h| h.object)
    }

    /// Starts the commands due before `until`.
    pub(super) fn start_due(
        &mut self,
        until: f64,
        sim: &mut SimWorld,
        arm: &mut SimArm,
        obs: &mut Observations,
    ) {
        while let Some((at, command)) = self.commands.get(self.next).cloned() {
            if at > until {
                break;
            }
            self.next += 1;
            match command {
                Command::Close {
                    keyframe,
                    intended,
                    deadline,
                } => {
                    arm.command_fingers(FingerCommand::Grasp);
                    self.closing = Some(Closing {
                        keyframe,
                        intended,
                        deadline,
                    });
                }
                Command::Open { keyframe } => {
                    arm.command_fingers(FingerCommand::Width(self.open_width));
                    self.closing = None;
                    self.let_go(keyframe, sim, obs);
                }
            }
        }
    }

    fn let_go(&mut self, keyframe: usize, sim: &mut SimWorld, obs: &mut Observations) {
        let Some(h) = self.holding.take() else {
            return;
        };
        if let Some(weld) = h.weld {
            weld.release(sim);
        }
        obs.releases.push(ReleaseEvent {
            keyframe,
            object: sim.objects[h.object].name.clone(),
            t: sim.time(),
            bottom_at_release: bottom(sim, h.object),
            bottom_at_rest: None,
        });
    }

    /// After a physics step: ends a closing once both pads touch or its time is up, and
    /// carries the held object (weld load, slip).
    pub(super) fn after_step(
        &mut self,
        sim: &mut SimWorld,
        arm: &mut SimArm,
        obs: &mut Observations,
    ) {
        let t = sim.time();
        if let Some(closing) = self.closing.clone() {
            // The hand stopped because both pads touched before the step; the step may have
            // moved the object off one of them by a fraction of a millimetre (the last push
            // leaves it sliding). A real hand keeps squeezing until both pads bear on it, so
            // the closing goes on unless the pads still touch after the step.
            let pads = read_pads(sim, arm);
            let both_touch = pads.iter().all(|p| p.touches());
            if (arm.closed() && both_touch) || t >= closing.deadline {
                self.closing = None;
                let pads = pads.map(|p| p.object.filter(|_| p.touches()));
                self.close_on(closing, pads, sim, arm, obs);
            }
        }
        let tcp = arm.tcp(sim);
        if let Some(h) = self.holding.as_mut() {
            let event = &mut obs.grasps[h.event];
            if let Some(weld) = h.weld {
                let load = weld.load(sim);
                event.peak_load = event.peak_load.max(load.force);
                if weld.overloaded(&load) {
                    let pushed = strongest_push(sim, h.object).map_or(String::new(), |(by, f)| {
                        let name = match by {
                            Owner::Object(o) => sim.objects[o].name.as_str(),
                            Owner::Link(l) => self
                                .link_names
                                .get(l)
                                .map_or("a robot link", String::as_str),
                        };
                        format!(", as {name} pushed it with {f:.1} N")
                    });
                    event.broke_by = Some(format!("{}{pushed}", weld.overload_text(&load)));
                    weld.release(sim);
                    h.weld = None;
                    event.broke_at = Some(t);
                }
            }
            let now = tcp.inverse() * sim.object_pose(h.object);
            let slip = (now.translation.vector - h.in_tcp.translation.vector).norm();
            event.slip = event.slip.max(slip);
            if slip > self.slip_limit && event.slipped_at.is_none() {
                event.slipped_at = Some(t);
            }
        }
    }

    /// Judges what the pads closed on and welds it when the grasp is sound.
    fn close_on(
        &mut self,
        closing: Closing,
        pads: [Option<usize>; 2],
        sim: &mut SimWorld,
        arm: &mut SimArm,
        obs: &mut Observations,
    ) {
        arm.command_fingers(FingerCommand::Width(arm.width()));
        let name = |o: Option<usize>| o.map(|i| sim.objects[i].name.clone());
        let mut event = GraspEvent {
            keyframe: closing.keyframe,
            t: sim.time(),
            intended: closing.intended.clone(),
            pads: [name(pads[0]), name(pads[1])],
            measure: None,
            unsound: None,
            welded: false,
            squared: 0.0,
            broke_at: None,
            broke_by: None,
            slip: 0.0,
            slipped_at: None,
            peak_load: 0.0,
        };
        let object = match pads {
            [Some(a), Some(b)] if a == b => Some(a),
            _ => None,
        };
        if let Some(o) = object {
            for r in obs
                .releases
                .iter_mut()
                .filter(|r| r.object == sim.objects[o].name)
            {
                r.bottom_at_rest.get_or_insert(bottom(sim, o));
            }
            let m = measure(sim, arm, o);
            if sim.objects[o].name == closing.intended {
                event.unsound = m.unsound(&self.limits);
                if event.unsound.is_none() {
                    event.squared = square(sim, arm, o);
                    let weld = Weld::attach(sim, arm, o, &m, self.grasp_force);
                    event.welded = weld.is_some();
                    self.holding = Some(Holding {
                        object: o,
                        weld,
                        in_tcp: arm.tcp(sim).inverse() * sim.object_pose(o),
                        event: obs.grasps.len(),
                    });
                }
            }
            event.measure = Some(m);
        }
        obs.grasps.push(event);
    }

    /// At the end of the run: what is still in the hand, and where released objects rest.
    pub(super) fn finish(&self, sim: &SimWorld, obs: &mut Observations) {
        if let Some(h) = &self.holding {
            obs.still_held.push(sim.objects[h.object].name.clone());
        }
        for r in obs.releases.iter_mut() {
            if r.bottom_at_rest.is_none() {
                if let Some(i) = sim.object_index(&r.object) {
                    r.bottom_at_rest = Some(bottom(sim, i));
                }
            }
        }
    }
}

/// Height of an object's bottom in the simulation (metres).
fn bottom(sim: &SimWorld, object: usize) -> f64 {
    sim.template().objects[object]
        .shape
        .bottom(&sim.object_pose(object))
}
