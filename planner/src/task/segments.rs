//! The plan as it grows: timed segments and gripper events appended in order.

use super::{PlannedLine, Planner};
use crate::contact_rules::Allowances;
use crate::error::PlanError;
use crate::hand::PUSH_SHARE;
use crate::plan::{LinePoses, Segment, SegmentKind};
use crate::timing;
use crate::timing::Timing;

/// Times a timed line that strays from its line is planned again with denser waypoints
/// (see `push_line`).
const LINE_REFINEMENTS: usize = 2;

impl Planner<'_> {
    pub(super) fn push(
        &mut self,
        kind: SegmentKind,
        keyframe: usize,
        waypoints: Vec<Vec<f64>>,
        line: Option<LinePoses>,
        allowed: Allowances,
        planning_time: f64,
    ) {
        let (vmax, amax) = self.options.limits(self.robot);
        let timing = if kind == SegmentKind::Free {
            timing::linear(&waypoints, &vmax, &amax)
        } else {
            timing::cubic(&waypoints, &vmax, &amax)
        };
        self.push_timed(
            kind,
            keyframe,
            waypoints,
            timing,
            line,
            allowed,
            planning_time,
        );
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn push_timed(
        &mut self,
        kind: SegmentKind,
        keyframe: usize,
        waypoints: Vec<Vec<f64>>,
        timing: Timing,
        line: Option<LinePoses>,
        allowed: Allowances,
        planning_time: f64,
    ) {
        if let Some(last) = waypoints.last() {
            self.q = last.clone();
        }
        let start = self.t;
        self.t += timing.duration();
        self.segments.push(Segment {
            kind,
            keyframe,
            start,
            end: self.t,
            planning_time,
            width: self.width,
            holding: self.holding.as_ref().map(|h| h.held.name.clone()),
            allowed,
            line,
            waypoints,
            timing,
        });
    }

    /// Appends a straight segment and checks that it keeps to its line. A timed line that
    /// strays (the joint-space spline between IK waypoints bulges near a wrist or elbow that
    /// turns fast) is planned again with waypoints twice as dense, up to [`LINE_REFINEMENTS`]
    /// times: measured on 1,000 randomized inspection trials, one line in a thousand strayed
    /// 1.07 mm at the default spacing.
    pub(super) fn push_line(
        &mut self,
        kind: SegmentKind,
        i: usize,
        line: PlannedLine,
        planning_time: f64,
    ) -> Result<(), PlanError> {
        let mut line = line;
        let mut options = self.options.line;
        let mut refinement = 0;
        loop {
            let (to, allow) = (line.poses.to, line.allow.clone());
            self.push(
                kind,
                i,
                line.path,
                Some(line.poses),
                line.allow,
                planning_time,
            );
            let strayed = match self.verify_line(i) {
                Ok(()) => return Ok(()),
                Err(e) if refinement == LINE_REFINEMENTS => return Err(e),
                Err(e) => e,
            };
            let Some(segment) = self.segments.pop() else {
                return Err(strayed);
            };
            self.t = segment.start;
            if let Some(start) = segment.waypoints.first() {
                self.q = start.clone();
            }
            options.position_step *= 0.5;
            options.rotation_step *= 0.5;
            line = self.line_with(&to, &allow, &options).map_err(|_| strayed)?;
            refinement += 1;
        }
    }

    /// The arm stands still while the fingers move to `new_width`, pushing what they close on
    /// across `offset` metres to their midline; `allowed` are the contacts of the grasp or
    /// release under way.
    ///
    /// Each finger moves at the gripper's speed until one pad touches, then both at
    /// [`PUSH_SHARE`] of it while the touching pad pushes the object: the far pad then has
    /// twice the offset to close at twice that share of the speed, which takes the offset's
    /// worth of (1/share − 1) fingers' travel longer than closing on a centred object. Without
    /// it a grasp 15 mm off the pipe's axis (a drawn grasp 9 mm off, perceived 6 mm off) ran
    /// out of time with one pad still 2 mm away (UR5e, learned assembly, trial 18).
    pub(super) fn gripper_segment(
        &mut self,
        i: usize,
        new_width: f64,
        offset: f64,
        allowed: Allowances,
    ) {
        let travel = (0.5 * (new_width - self.width).abs() + offset * (1.0 / PUSH_SHARE - 1.0))
            / self.robot.finger_speed()
            / self.options.speed_scale;
        self.width = new_width;
        let q = self.q.clone();
        self.push_timed(
            SegmentKind::Gripper,
            i,
            vec![q],
            Timing::Hold {
                duration: travel + self.options.gripper_settle / self.options.speed_scale,
            },
            None,
            allowed,
            0.0,
        );
    }
}
