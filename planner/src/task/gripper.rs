//! Grasps and releases: approaching, closing or opening, and backing off.

use super::{
    backed_off, centred_in_hand, centring_offset, grasp_width, line_error, Holding, PlannedLine,
    Planner,
};
use crate::collision::Held;
use crate::contact_rules::Step;
use crate::error::PlanError;
use crate::plan::{GripperAction, GripperEvent, LinePoses, SegmentKind};
use akl_tsr::WORLD_FRAME;
use std::time::Instant;

impl Planner<'_> {
    pub(super) fn grasp(
        &mut self,
        i: usize,
        object: &str,
        approach: Option<Vec<Vec<f64>>>,
        next_line: bool,
    ) -> Result<(), PlanError> {
        let tcp = self.tcp_world(&self.q);
        let o = self
            .world
            .object(object)
            .ok_or_else(|| PlanError::Grounding(format!("no object `{object}`")))?
            .clone();
        let width = grasp_width(&o.shape, &o.pose, &tcp);
        if width > self.robot.open_width() {
            return Err(PlanError::Invalid {
                keyframe: i,
                reason: format!(
                    "`{object}` is {width:.3} m wide between the fingers; the gripper opens {:.3} m",
                    self.robot.open_width()
                ),
            });
        }
        let support = self.world.support_of(object).map(|s| s.name.clone());
        let in_tcp = centred_in_hand(&tcp, &o.pose, &o.shape);
        let offset = centring_offset(&o.shape, &o.pose, &tcp);
        self.events.push(GripperEvent {
            t: self.t,
            action: GripperAction::Close,
            keyframe: i,
            object: object.to_string(),
            support: support.clone(),
            width,
            object_pose: in_tcp,
        });
        self.holding = Some(Holding {
            held: Held::new(object, o.shape, in_tcp, &self.model.margins()),
            resting_on: support.clone(),
        });
        let resting = Step {
            resting_on: support.as_deref(),
            ..Step::default()
        }
        .allowances();
        let closing = Step {
            grasping: Some(object),
            resting_on: support.as_deref(),
            ..Step::default()
        };
        self.gripper_segment(i, width, offset, closing.allowances());
        if next_line {
            return Ok(());
        }
        let started = Instant::now();
        let lift = match approach {
            Some(mut path) => {
                path.reverse();
                let to = self.tcp_world(&path[path.len() - 1]);
                PlannedLine {
                    path,
                    poses: LinePoses { from: tcp, to },
                    allow: resting,
                }
            }
            None => {
                let up = backed_off(&tcp, self.options.approach_distance);
                self.line_to(&up, &resting)
                    .map_err(|f| line_error(i, format!("lift after keyframe {i}"), &f))?
            }
        };
        if let Some(h) = self.holding.as_mut() {
            h.resting_on = None;
        }
        self.push_line(SegmentKind::Lift, i, lift, started.elapsed().as_secs_f64())
    }

    pub(super) fn release(
        &mut self,
        i: usize,
        support: &str,
        approach: Option<Vec<Vec<f64>>>,
        next_line: bool,
    ) -> Result<(), PlanError> {
        let tcp = self.tcp_world(&self.q);
        let Some((name, in_tcp)) = self
            .holding
            .as_ref()
            .map(|h| (h.held.name.clone(), h.held.in_tcp))
        else {
            return Err(PlanError::Invalid {
                keyframe: i,
                reason: "the gripper opens while holding nothing".into(),
            });
        };
        let placed = tcp * in_tcp;
        self.events.push(GripperEvent {
            t: self.t,
            action: GripperAction::Open,
            keyframe: i,
            object: name.clone(),
            support: (support != WORLD_FRAME).then(|| support.to_string()),
            width: self.robot.open_width(),
            object_pose: placed,
        });
        let beneath = self.beneath(support);
        let released = Step {
            released: Some(&name),
            placing_on: Some(support),
            beneath: beneath.as_deref(),
            ..Step::default()
        }
        .allowances();
        self.gripper_segment(i, self.robot.open_width(), 0.0, released);
        self.holding = None;
        if let Some(o) = self.world.object_mut(&name) {
            o.pose = placed;
        }
        if next_line {
            self.just_released = Some(name);
            return Ok(());
        }
        let started = Instant::now();
        let allow = Step {
            released: Some(&name),
            ..Step::default()
        }
        .allowances();
        let retreat = match approach {
            Some(mut path) => {
                path.reverse();
                let to = self.tcp_world(&path[path.len() - 1]);
                PlannedLine {
                    path,
                    poses: LinePoses { from: tcp, to },
                    allow,
                }
            }
            None => {
                let up = backed_off(&tcp, self.options.approach_distance);
                self.line_to(&up, &allow)
                    .map_err(|f| line_error(i, format!("retreat after keyframe {i}"), &f))?
            }
        };
        self.push_line(
            SegmentKind::Retreat,
            i,
            retreat,
            started.elapsed().as_secs_f64(),
        )
    }
}
