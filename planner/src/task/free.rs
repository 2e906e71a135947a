//! Reaching a keyframe by free motion (goals, RRT-Connect, shortcutting), lifting a held
//! object off its support, and checking that the next step can follow an event.

use super::{
    backed_off, centred_in_hand, grasp_width, line_error, Event, GoalPaths, PlannedLine, Planner,
};
use crate::collision::{Checker, Held, Hit, Scene};
use crate::contact_rules::{Allowances, Step};
use crate::error::PlanError;
use crate::goal::{find_fitted_goals, GoalFailure};
use crate::line::plan_line;
use crate::plan::{LinePoses, SegmentKind};
use crate::rrt::{rrt_connect, RrtResult};
use crate::shortcut::shortcut;
use crate::space::Space;
use akl_tsr::{Keyframe, Pose};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use std::time::Instant;

impl Planner<'_> {
    /// Lifts a held object that still rests on its support, back along the tool axis.
    pub(super) fn lift_resting(&mut self, i: usize) -> Result<(), PlanError> {
        let Some(support) = self.holding.as_ref().and_then(|h| h.resting_on.clone()) else {
            return Ok(());
        };
        let started = Instant::now();
        let up = backed_off(&self.tcp_world(&self.q), self.options.approach_distance);
        let allow = Step {
            resting_on: Some(&support),
            ..Step::default()
        }
        .allowances();
        let lift = self
            .line_to(&up, &allow)
            .map_err(|f| line_error(i, format!("lift before keyframe {i}"), &f))?;
        if let Some(h) = self.holding.as_mut() {
            h.resting_on = None;
        }
        self.push_line(SegmentKind::Lift, i, lift, started.elapsed().as_secs_f64())
    }

    /// Free motion to keyframe `i` (and the approach, for grasps and releases); returns the
    /// approach path so that the lift or retreat can go back along it.
    pub(super) fn reach_by_free_motion(
        &mut self,
        kf: &Keyframe,
        i: usize,
        event: Option<&Event>,
        next: Option<&Keyframe>,
        started: Instant,
    ) -> Result<Option<Vec<Vec<f64>>>, PlanError> {
        self.lift_resting(i)?;
        let scene = self.scene();
        let checker = Checker::new(self.robot, &self.model, &scene).counting(self.probes);
        let free_allow = Step::default().allowances();
        let at_allow = Step::at(event).allowances();
        let at_space = Space {
            checker: &checker,
            width: self.width,
            held: self.held(),
            allow: &at_allow,
        };
        let free_space = Space {
            checker: &checker,
            width: self.width,
            held: self.held(),
            allow: &free_allow,
        };
        let base = self.base();
        let approach_distance = self.options.approach_distance;
        let line_options = self.options.line;
        let mut lookahead_rng = next
            .and_then(|n| self.sampled_stream(n))
            .unwrap_or_else(|| ChaCha8Rng::seed_from_u64(self.options.seed ^ (i as u64 + 1)));
        let this = &*self;
        let accept = |pose: &Pose, q: &[f64]| -> Result<GoalPaths, String> {
            if let Some(hit) = at_space.check(q) {
                return Err(hit.to_string());
            }
            if let Some(Event::Grasp { object }) = event {
                this.check_closing(&this.world, object, pose)?;
            }
            let approach = match event {
                Some(_) => {
                    let pre = backed_off(pose, approach_distance);
                    let mut back = plan_line(&at_space, q, pose, &pre, &base, &line_options)
                        .map_err(|f| format!("approach: {f}"))?;
                    back.reverse();
                    Some(back)
                }
                None => None,
            };
            let free_goal = approach
                .as_ref()
                .and_then(|a| a.first().cloned())
                .unwrap_or_else(|| q.to_vec());
            if let Some(hit) = free_space.check(&free_goal) {
                return Err(format!("before the approach: {hit}"));
            }
            if let Some(path) = &approach {
                this.check_after_event(event, pose, path, next.is_some())?;
            }
            let next_line = match next {
                Some(next_kf) => {
                    Some(this.lookahead_line(event, pose, q, next_kf, &mut lookahead_rng)?)
                }
                None => None,
            };
            Ok(GoalPaths {
                free_goal,
                approach,
                next_line,
            })
        };
        let mut rng = self.rng.clone();
        let mut own = self.sampled_stream(kf);
        let fit = |pose: &Pose| match event {
            Some(Event::Grasp { object }) => this.fit_grasp(&kf.tsr, object, pose),
            Some(Event::Release { support, .. }) => this.fit_release(&kf.tsr, support, pose),
            None => *pose,
        };
        let candidates = find_fitted_goals(
            self.robot,
            &kf.tsr,
            &base,
            &self.q,
            &self.options.goals,
            own.as_mut().unwrap_or(&mut rng),
            fit,
            accept,
        )
        .map_err(|failure| match failure {
            GoalFailure::Unreachable { tried } => PlanError::Unreachable { keyframe: i, tried },
            GoalFailure::Rejected {
                tried,
                solutions,
                blocker,
            } => PlanError::NoCollisionFreeIk {
                keyframe: i,
                tried,
                solutions,
                blocker,
            },
        })?;
        let goals: Vec<Vec<f64>> = candidates
            .iter()
            .map(|c| c.data.free_goal.clone())
            .collect();
        let segment = format!("free motion to keyframe {i}");
        let path = match rrt_connect(&self.q, &goals, &free_space, &self.options.rrt, &mut rng) {
            RrtResult::Found { path, goal, .. } => {
                let path = shortcut(path, &free_space, self.options.shortcut_attempts, &mut rng);
                (path, goal)
            }
            RrtResult::Exhausted { iterations } => {
                return Err(PlanError::BudgetExhausted {
                    keyframe: i,
                    segment,
                    iterations,
                })
            }
        };
        self.rng = rng;
        let (free_path, goal) = path;
        let chosen = candidates[goal].clone();
        self.push(
            SegmentKind::Free,
            i,
            free_path,
            None,
            Allowances::default(),
            started.elapsed().as_secs_f64(),
        );
        if let Some(approach) = &chosen.data.approach {
            let from = self.tcp_world(&approach[0]);
            let line = PlannedLine {
                path: approach.clone(),
                poses: LinePoses {
                    from,
                    to: chosen.pose,
                },
                allow: at_allow.clone(),
            };
            self.push_line(SegmentKind::Approach, i, line, 0.0)?;
        }
        self.pending_line = chosen.data.next_line;
        Ok(chosen.data.approach)
    }

    /// Checks the way back along `approach` after the keyframe's event: lifting a grasped
    /// object (unless a line follows) or retreating from a released one.
    pub(super) fn check_after_event(
        &self,
        event: Option<&Event>,
        pose: &Pose,
        approach: &[Vec<f64>],
        line_follows: bool,
    ) -> Result<(), String> {
        match event {
            Some(Event::Grasp { object }) if !line_follows => {
                let o = self
                    .world
                    .object(object)
                    .ok_or_else(|| format!("no object `{object}`"))?;
                let held = Held::new(
                    object,
                    o.shape.clone(),
                    centred_in_hand(pose, &o.pose, &o.shape),
                    &self.model.margins(),
                );
                let width = grasp_width(&o.shape, &o.pose, pose).min(self.robot.open_width());
                let mut world = self.world.clone();
                let support = world.support_of(object).map(|s| s.name.clone());
                world.objects.retain(|x| x.name != *object);
                let scene = Scene::new(&world, &[]);
                let checker = Checker::new(self.robot, &self.model, &scene).counting(self.probes);
                let allow = Step {
                    resting_on: support.as_deref(),
                    ..Step::default()
                }
                .allowances();
                if let Some(hit) = chain_hit(&checker, approach, width, Some(&held), &allow) {
                    return Err(format!("lift: {hit}"));
                }
                Ok(())
            }
            Some(Event::Release { .. }) if !line_follows => {
                let Some(h) = &self.holding else {
                    return Ok(());
                };
                let mut world = self.world.clone();
                if let Some(o) = world.object_mut(&h.held.name) {
                    o.pose = pose * h.held.in_tcp;
                }
                let scene = Scene::new(&world, &[]);
                let checker = Checker::new(self.robot, &self.model, &scene).counting(self.probes);
                let allow = Step {
                    released: Some(&h.held.name),
                    ..Step::default()
                }
                .allowances();
                let open = self.robot.open_width();
                if let Some(hit) = chain_hit(&checker, approach, open, None, &allow) {
                    return Err(format!("retreat: {hit}"));
                }
                Ok(())
            }
            _ => Ok(()),
        }
    }
}

/// The first collision on the chain of edges through `points` from the last back to the first
/// (opening `width`, holding `held`, under `allow`): every edge starts where the one before it
/// ended, so only the chain's first point gets a check of its own.
fn chain_hit(
    checker: &Checker,
    points: &[Vec<f64>],
    width: f64,
    held: Option<&Held>,
    allow: &Allowances,
) -> Option<Hit> {
    points.windows(2).rev().enumerate().find_map(|(k, w)| {
        if k == 0 {
            checker.edge(&w[1], &w[0], width, held, allow)
        } else {
            checker.screened_edge(&w[1], &w[0], width, held, allow, 0)
        }
    })
}

#[cfg(test)]
mod chain_tests {
    use super::chain_hit;
    use crate::collision::tests::plate_just_within_the_margin;
    use crate::collision::{Checker, Hit, RobotCollision, Scene};
    use crate::contact_rules::Allowances;
    use crate::robot::Robot;

    /// A chain is checked from its last point back: that point keeps its whole margin (a
    /// plate just within it is found), though no edge of the chain ends there.
    #[test]
    fn a_chain_checks_its_first_point() {
        let robot = Robot::panda().unwrap();
        let model = RobotCollision::new(&robot);
        let ready = robot.ready().to_vec();
        let world = plate_just_within_the_margin(&robot, &model, &ready);
        let scene = Scene::new(&world, &[]);
        let checker = Checker::new(&robot, &model, &scene);
        let lifted = |by: f64| {
            let mut q = ready.clone();
            q[1] -= by;
            q
        };
        let none = Allowances::default();
        let away = [lifted(0.3), lifted(0.15)];
        assert_eq!(chain_hit(&checker, &away, 0.08, None, &none), None);
        let chain = [lifted(0.3), lifted(0.15), ready];
        match chain_hit(&checker, &chain, 0.08, None, &none) {
            Some(Hit::World(_, object)) => assert_eq!(object, "plate"),
            other => panic!("expected the plate, got {other:?}"),
        }
    }
}
