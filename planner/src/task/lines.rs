//! Reaching a keyframe along a straight line (`move_in_line`), planning a line ahead, and
//! checking a timed line against its line.

use super::{centred_in_hand, grasp_width, line_error, Event, Holding, PlannedLine, Planner};
use crate::collision::{Checker, Held, Scene};
use crate::contact_rules::{Allowances, Step, ENTRY_CLEARANCE};
use crate::error::PlanError;
use crate::goal::GoalStrategy;
use crate::line::{distance_to_segment, plan_line, LineFailure, LineOptions};
use crate::plan::{LinePoses, SegmentKind};
use crate::space::Space;
use crate::timing::Timing;
use crate::{parry_convert, timing};
use akl_tsr::{Gripper, Keyframe, Pose};
use rand_chacha::ChaCha8Rng;
use std::time::Instant;

impl Planner<'_> {
    /// Plans a straight TCP line from the current configuration to `to` (world).
    pub(super) fn line_to(
        &self,
        to: &Pose,
        allow: &Allowances,
    ) -> Result<PlannedLine, LineFailure> {
        self.line_with(to, allow, &self.options.line)
    }

    /// [`Self::line_to`] with other line settings.
    pub(super) fn line_with(
        &self,
        to: &Pose,
        allow: &Allowances,
        options: &LineOptions,
    ) -> Result<PlannedLine, LineFailure> {
        let scene = self.scene();
        let checker = Checker::new(self.robot, &self.model, &scene).counting(self.probes);
        let space = Space {
            checker: &checker,
            width: self.width,
            held: self.held(),
            allow,
        };
        let from = self.tcp_world(&self.q);
        let path = plan_line(&space, &self.q, &from, to, &self.base(), options)?;
        Ok(PlannedLine {
            path,
            poses: LinePoses { from, to: *to },
            allow: allow.clone(),
        })
    }

    /// Allowances on a line that ends at keyframe `i` with `event`.
    pub(super) fn line_allowances(&self, event: Option<&Event>) -> Allowances {
        Step {
            released: self.just_released.as_deref(),
            resting_on: self.holding.as_ref().and_then(|h| h.resting_on.as_deref()),
            ..Step::at(event)
        }
        .allowances()
    }

    pub(super) fn reach_by_line(
        &mut self,
        kf: &Keyframe,
        i: usize,
        event: Option<&Event>,
        started: Instant,
    ) -> Result<(), PlanError> {
        let segment = format!("line to keyframe {i}");
        let mut planned = match self.pending_line.take() {
            Some(planned) => planned,
            None => {
                let allow = self.line_allowances(event);
                let goals = &self.options.goals;
                let mut own = self.sampled_stream(kf);
                let rng = own.as_mut().unwrap_or(&mut self.rng);
                let targets = crate::goal::tsr_poses(&kf.tsr, goals.poses, goals.strategy, rng);
                let mut first_failure = None;
                let mut cannot_close = None;
                let mut found: Option<(f64, PlannedLine)> = None;
                let mut planned_lines = 0;
                for target in &targets {
                    match self.line_to(target, &allow) {
                        Ok(planned) => {
                            if let (Some(Event::Grasp { object }), Some(_)) =
                                (event, planned.path.last())
                            {
                                if let Err(why) = self.check_closing(&self.world, object, target) {
                                    cannot_close.get_or_insert(why);
                                    continue;
                                }
                            }
                            planned_lines += 1;
                            let time = self.line_time(&planned.path);
                            if found.as_ref().is_none_or(|(best, _)| time < *best) {
                                found = Some((time, planned));
                            }
                            if self.options.goals.strategy != GoalStrategy::Spread
                                || planned_lines >= self.options.goals.enough
                            {
                                break;
                            }
                        }
                        Err(failure) => {
                            first_failure.get_or_insert(failure);
                        }
                    }
                }
                let found = found.map(|(_, planned)| planned);
                match (found, cannot_close, first_failure) {
                    (Some(planned), _, _) => planned,
                    // Lines were found, but the gripper could not close at their ends.
                    (None, Some(reason), _) => {
                        return Err(PlanError::Line {
                            keyframe: i,
                            segment,
                            reason,
                        })
                    }
                    (None, None, Some(failure)) => return Err(line_error(i, segment, &failure)),
                    (None, None, None) => {
                        return Err(PlanError::Unreachable {
                            keyframe: i,
                            tried: 0,
                        })
                    }
                }
            }
        };
        let entering = self.entered_fixtures(&planned.poses.to, &planned.allow);
        planned.allow.held_may_brush = Step {
            entering: &entering,
            ..Step::default()
        }
        .allowances()
        .held_may_brush;
        self.push_line(
            SegmentKind::Line,
            i,
            planned,
            started.elapsed().as_secs_f64(),
        )
    }

    /// The fixed objects a line ending with the TCP at `to` inserts the held object into: those
    /// within [`ENTRY_CLEARANCE`] of it there, but for what `allow` already lets it touch (its
    /// support). None when nothing is held.
    pub(super) fn entered_fixtures(&self, to: &Pose, allow: &Allowances) -> Vec<String> {
        let Some(held) = self.holding.as_ref().map(|h| &h.held) else {
            return Vec::new();
        };
        let (shape, local) = parry_convert::object_shape(&held.shape, 0.0);
        let at = to * held.in_tcp * local;
        self.world
            .objects
            .iter()
            .filter(|o| !o.movable && o.name != held.name)
            .filter(|o| !allow.held_may_touch.contains(&o.name))
            .filter(|o| {
                let (other, fix) = parry_convert::object_shape(&o.shape, 0.0);
                parry_convert::distance(&shape, &at, &other, &(o.pose * fix))
                    .is_some_and(|d| d < ENTRY_CLEARANCE)
            })
            .map(|o| o.name.clone())
            .collect()
    }

    /// Seconds a straight segment along `path` takes (timed as `push` times it).
    pub(super) fn line_time(&self, path: &[Vec<f64>]) -> f64 {
        let (vmax, amax) = self.options.limits(self.robot);
        timing::cubic(path, &vmax, &amax).duration()
    }

    /// Plans the line from a candidate of keyframe i (at `pose`, configuration `q`) to the
    /// next keyframe, with the state it will have after keyframe i's event.
    pub(super) fn lookahead_line(
        &self,
        event: Option<&Event>,
        pose: &Pose,
        q: &[f64],
        next: &Keyframe,
        rng: &mut ChaCha8Rng,
    ) -> Result<PlannedLine, String> {
        let mut world = self.world.clone();
        let mut holding = self.holding.clone();
        let mut width = self.width;
        if let Some(Event::Grasp { object }) = event {
            let o = self
                .world
                .object(object)
                .ok_or_else(|| format!("no object `{object}`"))?;
            width = grasp_width(&o.shape, &o.pose, pose).min(self.robot.open_width());
            holding = Some(Holding {
                held: Held::new(
                    object,
                    o.shape.clone(),
                    centred_in_hand(pose, &o.pose, &o.shape),
                    &self.model.margins(),
                ),
                resting_on: world.support_of(object).map(|s| s.name.clone()),
            });
        }
        let mut released = None;
        if let Some(Event::Release { .. }) = event {
            if let Some(h) = holding.take() {
                if let Some(o) = world.object_mut(&h.held.name) {
                    o.pose = pose * h.held.in_tcp;
                }
                width = self.robot.open_width();
                released = Some(h.held.name);
            }
        }
        let without: Vec<String> = holding.iter().map(|h| h.held.name.clone()).collect();
        world.objects.retain(|o| !without.contains(&o.name));
        let scene = Scene::new(&world, &[]);
        let checker = Checker::new(self.robot, &self.model, &scene).counting(self.probes);
        let next_closes = next.gripper == Gripper::Closed && holding.is_none();
        let next_opens = next.gripper == Gripper::Open && holding.is_some();
        let beneath = self.beneath(&next.reference);
        let allow = Step {
            grasping: next_closes.then_some(next.reference.as_str()),
            released: released.as_deref(),
            resting_on: holding.as_ref().and_then(|h| h.resting_on.as_deref()),
            placing_on: next_opens.then_some(next.reference.as_str()),
            beneath: beneath.as_deref(),
            ..Step::default()
        }
        .allowances();
        let space = Space {
            checker: &checker,
            width,
            held: holding.as_ref().map(|h| &h.held),
            allow: &allow,
        };
        let mut first = None;
        let mut closing = None;
        for target in crate::goal::tsr_poses(&next.tsr, 4, self.options.goals.strategy, rng) {
            match plan_line(&space, q, pose, &target, &self.base(), &self.options.line) {
                Ok(path) => {
                    if next_closes && !path.is_empty() {
                        if let Err(why) = self.check_closing(&world, &next.reference, &target) {
                            closing.get_or_insert(why);
                            continue;
                        }
                    }
                    return Ok(PlannedLine {
                        path,
                        poses: LinePoses {
                            from: *pose,
                            to: target,
                        },
                        allow: allow.clone(),
                    });
                }
                Err(f) => {
                    first.get_or_insert(f);
                }
            }
        }
        Err(match (closing, first) {
            (Some(why), _) => format!("next line: {why}"),
            (None, Some(f)) => format!("next line: {f}"),
            (None, None) => "next line: no target".into(),
        })
    }

    /// Checks that the last segment's timed trajectory keeps the TCP within the line
    /// tolerance, at every waypoint and halfway between waypoints.
    pub(super) fn verify_line(&self, i: usize) -> Result<(), PlanError> {
        let Some(segment) = self.segments.last() else {
            return Ok(());
        };
        let Some(line) = &segment.line else {
            return Ok(());
        };
        let (a, b) = (line.from.translation.vector, line.to.translation.vector);
        let Timing::Cubic { tangents, .. } = &segment.timing else {
            return Ok(());
        };
        let n = segment.waypoints.len();
        let worst = (0..2 * n.saturating_sub(1) + 1)
            .map(|k| {
                let q = timing::cubic_at(&segment.waypoints, tangents, 0.5 * k as f64);
                distance_to_segment(&self.tcp_world(&q).translation.vector, &a, &b)
            })
            .fold(0.0, f64::max);
        if worst > self.options.line.tolerance {
            return Err(PlanError::Line {
                keyframe: i,
                segment: format!("{} at keyframe {i}", segment.kind.name()),
                reason: format!(
                    "the TCP strays {:.2} mm from the line (tolerance {:.2} mm)",
                    worst * 1e3,
                    self.options.line.tolerance * 1e3
                ),
            });
        }
        Ok(())
    }
}
