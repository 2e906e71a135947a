//! Fitting a drawn goal pose to what the hand and the held object allow, within the keyframe's
//! region, before inverse kinematics.
//!
//! A region is drawn from uniformly, but part of it may be unusable by this robot for a reason
//! known before any configuration is sought: a linkage gripper's bars sweep in above its pads
//! as it closes, so a grasp drawn deep on an object can have them press its top edge
//! ([`closing_clearance`]); and a release drawn low can sink the held object into its support,
//! by how much depending on where the grasp left the object in the hand. Rejecting such a
//! draw and drawing again wastes most draws when the usable part is thin (the Robotiq 2F-85
//! grasping inspection's part, whose region reaches 35 mm below the part's top while its inner
//! knuckles clear it only down to about 27 mm). Instead a draw is moved along the region's
//! coordinate that undoes the problem, by the least amount that does, when that stays within
//! the region:
//!
//! - a grasp whose linkage would come within the held object's margin of the object is moved
//!   back along the approach (the region's axis nearest the tool's −z) to the deepest pose
//!   where it clears, found by bisection;
//! - a release whose held object would sink deeper than [`PRESS_DEPTH`] into its support is
//!   raised (along the region's axis nearest the vertical) until the object rests on the
//!   support's top; when the region does not reach that high, the object is first levelled
//!   (within the region's roll and pitch bounds): an object the grasp left tilted in the hand
//!   reaches lower by its tilt times its half width.
//!
//! A draw the move cannot fit is left as drawn, for the goal's checks to reject. A draw that
//! needs no move is left exactly as drawn, so robots whose draws all fit (prismatic fingers,
//! releases at heights that clear the support) plan as before.

use super::{centred_in_hand, grasp_width, Planner};
use crate::contact_rules::PRESS_DEPTH;
use crate::hand::{closing_clearance, ClosingClearance};
use akl_scene::World;
use akl_tsr::nalgebra::Vector3;
use akl_tsr::{Pose, Tsr};

/// Precision (metres) of the bisection that moves a grasp back until its linkage clears.
pub(crate) const GRASP_FIT_TOLERANCE: f64 = 2.5e-4;

/// Least cosine between the direction a pose must move and the region axis that moves it: a
/// region whose nearest axis is further off than 45° is left as drawn.
const MIN_AXIS_COSINE: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// The region coordinate (0–2: x, y, z of its frame) whose axis lies nearest `direction`
/// (world frame, unit), and the cosine between them (signed: negative when the axis points
/// against `direction`); `None` when no axis lies within 45° of it.
fn nearest_axis(tsr: &Tsr, direction: &Vector3<f64>) -> Option<(usize, f64)> {
    (0..3)
        .map(|k| {
            let axis = tsr.t0_w.rotation * Vector3::ith(k, 1.0);
            (k, axis.dot(direction))
        })
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .filter(|(_, cos)| cos.abs() >= MIN_AXIS_COSINE)
}

/// `pose` moved by `distance` along world `direction` through region coordinate `k` (whose
/// axis makes cosine `cos` with `direction`), or `None` when that leaves the region.
fn moved(tsr: &Tsr, pose: &Pose, k: usize, cos: f64, distance: f64) -> Option<Pose> {
    let mut c = tsr.coordinates(pose);
    let to = c[k] + distance / cos;
    let [lo, hi] = tsr.bw.0[k];
    // Round-off may put the region's edge itself a hair outside it.
    let slack = 1e-12;
    if to < lo - slack || to > hi + slack {
        return None;
    }
    c[k] = to.clamp(lo, hi);
    Some(tsr.pose_at(&c))
}

impl Planner<'_> {
    /// How close the linkage comes to `object` of `world` while the gripper closes on it with the TCP at
    /// `tcp` (world frame): the least of [`closing_clearance`] over the object as it stands
    /// (closing down to the object's width across the pads) and as the squeeze leaves it in
    /// the hand (turned flat on the pads, closing down to its narrower width then). `None`
    /// when the gripper has no linkage or there is no such object.
    ///
    /// A linkage's bars move with the opening only, relative to the TCP, so the clearance
    /// depends on the TCP pose, not on the arm configuration reaching it: it is measured with
    /// the arm at its ready configuration and the object moved with the TCP.
    pub(super) fn linkage_clearance(
        &self,
        world: &World,
        object: &str,
        tcp: &Pose,
    ) -> Option<ClosingClearance> {
        let hand = self.hand.as_ref()?;
        let o = world.object(object)?;
        let q = self.robot.ready();
        let at_ready = self.robot.tcp_pose(q) * tcp.inverse();
        let open = self.robot.open_width();
        let squeezed = *tcp * centred_in_hand(tcp, &o.pose, &o.shape);
        [o.pose, squeezed]
            .iter()
            .filter_map(|pose| {
                let width = grasp_width(&o.shape, pose, tcp).min(open);
                closing_clearance(self.robot, hand, q, width, &o.shape, &(at_ready * pose))
            })
            .min_by(|a, b| a.clearance.total_cmp(&b.clearance))
    }

    /// Whether the linkage clears `object` of `world` with the TCP at `tcp` by the held object's margin
    /// (true when there is no linkage).
    fn linkage_clears(&self, world: &World, object: &str, tcp: &Pose) -> bool {
        self.linkage_clearance(world, object, tcp)
            .is_none_or(|c| c.clearance >= self.model.margins().held)
    }

    /// A grasp of `object` drawn at `pose` from `tsr` (world frame), moved back along the
    /// approach to the deepest pose within the region where the linkage clears the object (to
    /// [`GRASP_FIT_TOLERANCE`]); as drawn when it already clears or no pose back along the
    /// approach within the region does.
    pub(super) fn fit_grasp(&self, tsr: &Tsr, object: &str, pose: &Pose) -> Pose {
        if self.linkage_clears(&self.world, object, pose) {
            return *pose;
        }
        let back = pose.rotation * -Vector3::z();
        let Some((k, cos)) = nearest_axis(tsr, &back) else {
            return *pose;
        };
        // The furthest move back the region allows along its coordinate k.
        let c = tsr.coordinates(pose)[k];
        let [lo, hi] = tsr.bw.0[k];
        let room = (if cos > 0.0 { hi - c } else { c - lo }) * cos.abs();
        let fits = |d: f64| {
            moved(tsr, pose, k, cos, d).filter(|p| self.linkage_clears(&self.world, object, p))
        };
        let Some(mut best) = fits(room) else {
            return *pose;
        };
        let (mut short, mut long) = (0.0, room);
        while long - short > GRASP_FIT_TOLERANCE {
            let mid = 0.5 * (short + long);
            match fits(mid) {
                Some(p) => {
                    best = p;
                    long = mid;
                }
                None => short = mid,
            }
        }
        best
    }

    /// A release onto `support` drawn at `pose` from `tsr` (world frame), when the held object
    /// would sink into the support deeper than [`PRESS_DEPTH`] (its centre above the support's
    /// outline): raised within the region until the object rests on the support's top; when the
    /// region does not reach that high, first levelled (the region's roll and pitch turned,
    /// within their bounds, to stand the object's most upright axis vertical: a tilted object
    /// reaches lower) and then raised. As drawn otherwise, or when neither fits.
    pub(super) fn fit_release(&self, tsr: &Tsr, support: &str, pose: &Pose) -> Pose {
        let (Some(held), Some(s)) = (self.held(), self.world.object(support)) else {
            return *pose;
        };
        let top = s.shape.top(&s.pose);
        let sink = |p: &Pose| top - held.shape.bottom(&(p * held.in_tcp));
        let centre = s
            .pose
            .inverse_transform_point(&(pose * held.in_tcp).translation.vector.into());
        if sink(pose) <= PRESS_DEPTH || !s.shape.outline_contains(centre.x, centre.y, 0.0) {
            return *pose;
        }
        let Some((k, cos)) = nearest_axis(tsr, &Vector3::z()) else {
            return *pose;
        };
        let raised = |p: &Pose| moved(tsr, p, k, cos, sink(p).max(0.0));
        raised(pose)
            .or_else(|| raised(&levelled(tsr, pose, &held.in_tcp)))
            .unwrap_or(*pose)
    }
}

/// Gauss–Newton steps [`levelled`] takes.
const LEVELLING_STEPS: usize = 4;

/// `pose` (of region `tsr`) with its roll and pitch coordinates turned, within their bounds,
/// so that the axis of an object held at `in_tcp` that stands most upright points straight
/// up (as near as the bounds allow): a few Gauss–Newton steps on the axis's horizontal part.
fn levelled(tsr: &Tsr, pose: &Pose, in_tcp: &Pose) -> Pose {
    let up = |c: &[f64; 6]| -> Vector3<f64> {
        let r = (tsr.pose_at(c) * in_tcp).rotation;
        (0..3)
            .map(|i| r * Vector3::ith(i, 1.0))
            .map(|a| a * a.z.signum())
            .max_by(|a, b| a.z.total_cmp(&b.z))
            .unwrap_or_else(Vector3::z)
    };
    let mut c = tsr.coordinates(pose);
    let h = 1e-6;
    for _ in 0..LEVELLING_STEPS {
        let r0 = up(&c).xy();
        let column = |i: usize| {
            let mut d = c;
            d[i] += h;
            (up(&d).xy() - r0) / h
        };
        let j = akl_tsr::nalgebra::Matrix2::from_columns(&[column(3), column(4)]);
        let Some(step) = j.try_inverse().map(|inv| inv * r0) else {
            break;
        };
        for (i, s) in [(3, step.x), (4, step.y)] {
            let [lo, hi] = tsr.bw.0[i];
            c[i] = (c[i] - s).clamp(lo, hi);
        }
    }
    tsr.pose_at(&c)
}

#[cfg(test)]
mod tests {
    use super::super::Holding;
    use super::*;
    use crate::collision::Held;
    use crate::options::PlanOptions;
    use crate::robot::Robot;
    use akl_scene::{builtin, Object, Shape};
    use akl_tsr::nalgebra::{Translation3, UnitQuaternion};
    use akl_tsr::Bounds;
    use std::cell::Cell;

    /// Inspection's part held from above with the TCP `above` its centre, tilted `tilt`
    /// radians about the TCP's x axis in the hand.
    fn part_in_hand(planner: &mut Planner, above: f64, tilt: f64) {
        let part = planner.world.object("part").unwrap().shape.clone();
        let in_tcp = Pose::from_parts(
            Translation3::new(0.0, 0.0, above),
            UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI + tilt),
        );
        let margins = planner.model.margins();
        planner.holding = Some(Holding {
            held: Held::new("part", part, in_tcp, &margins),
            resting_on: None,
        });
    }

    /// How deep the held part, released at `pose`, sinks into the mat's top.
    fn sink(planner: &Planner, pose: &Pose) -> f64 {
        let held = planner.held().unwrap();
        let mat = planner.world.object("mat").unwrap();
        mat.shape.top(&mat.pose) - held.shape.bottom(&(pose * held.in_tcp))
    }

    /// Inspection's release region (keyframe 3 of its truth) in its world.
    fn release_region(world: &World) -> Tsr {
        let task = builtin::task("inspection").unwrap().unwrap();
        let truth = task.truth.unwrap();
        truth.ground(&world.object_poses()).unwrap().keyframes[3]
            .tsr
            .clone()
    }

    #[test]
    fn a_release_drawn_low_is_raised_onto_the_support_within_its_region() {
        let robot = Robot::panda().unwrap();
        let task = builtin::task("inspection").unwrap().unwrap();
        let (options, probes) = (PlanOptions::default(), Cell::new(0));
        let mut p = Planner::new(&robot, task.world.clone(), &options, &probes);
        let tsr = release_region(&p.world);
        // Held 24 mm above its centre (26 mm below its top): the region's lower half sinks it.
        part_in_hand(&mut p, 0.024, 0.0);
        let low = tsr.pose_at(&[0.001, -0.002, -0.005, 0.0, 0.0, 0.02]);
        assert!(sink(&p, &low) > 0.008);
        let fitted = p.fit_release(&tsr, "mat", &low);
        assert!(tsr.contains(&fitted));
        assert!(sink(&p, &fitted).abs() < 1e-9, "{}", sink(&p, &fitted));
        // Only the height moved.
        let (c, d) = (tsr.coordinates(&low), tsr.coordinates(&fitted));
        for k in [0, 1, 3, 4, 5] {
            assert!((c[k] - d[k]).abs() < 1e-9, "{c:?} {d:?}");
        }
        // A release that already clears the support is left exactly as drawn.
        let high = tsr.pose_at(&[0.0, 0.0, 0.005, 0.0, 0.0, 0.0]);
        assert!(sink(&p, &high) < PRESS_DEPTH);
        assert_eq!(p.fit_release(&tsr, "mat", &high), high);
        // Held 30 mm above its centre, the part cannot be set down within the region: the
        // draw is left for the goal's checks to reject.
        part_in_hand(&mut p, 0.03, 0.0);
        assert_eq!(p.fit_release(&tsr, "mat", &low), low);
    }

    #[test]
    fn a_release_the_region_cannot_raise_enough_is_levelled_first() {
        let robot = Robot::panda().unwrap();
        let task = builtin::task("inspection").unwrap().unwrap();
        let (options, probes) = (PlanOptions::default(), Cell::new(0));
        let mut p = Planner::new(&robot, task.world.clone(), &options, &probes);
        let tsr = release_region(&p.world);
        // Tilted 0.04 rad in the hand, a corner of the part reaches 1 mm lower: at 24.5 mm
        // above its centre the region is 0.5 mm too low for it, level it is not.
        part_in_hand(&mut p, 0.0245, 0.04);
        let drawn = tsr.pose_at(&[0.0, 0.0, 0.0, 0.0, 0.0, 0.01]);
        let (k, cos) = nearest_axis(&tsr, &Vector3::z()).unwrap();
        assert!(moved(&tsr, &drawn, k, cos, sink(&p, &drawn)).is_none());
        let fitted = p.fit_release(&tsr, "mat", &drawn);
        assert!(tsr.contains(&fitted));
        assert!(sink(&p, &fitted).abs() < 1e-9, "{}", sink(&p, &fitted));
        let up = (fitted * p.held().unwrap().in_tcp).rotation * Vector3::z();
        assert!(up.z > 1.0 - 1e-9, "{up:?}");
    }

    #[test]
    fn a_grasp_drawn_too_deep_for_the_linkage_moves_back_to_the_deepest_that_clears() {
        let robot = crate::robot::quirks::linkage_arm_with_bars();
        let tcp = robot.tcp_pose(robot.ready());
        // A tall box between the pads, its top 4 cm up into the hand (the bars sweep it).
        let grasp = 0.012;
        let shape = Shape::Box {
            size: [0.01, grasp, 0.3],
        };
        let block = Object {
            name: "block".into(),
            shape,
            pose: tcp * Pose::translation(0.0, 0.0, -0.04 + 0.15),
            movable: true,
            mass: 0.1,
            friction: 0.6,
        };
        let world = World {
            robot_base: Pose::identity(),
            objects: vec![block],
        };
        let (options, probes) = (PlanOptions::default(), Cell::new(0));
        let p = Planner::new(&robot, world, &options, &probes);
        let margin = p.model.margins().held;
        let region = |back: f64| {
            let mut bw = Bounds::point();
            bw.0[2] = [-back, 0.0];
            Tsr::new(tcp, Pose::identity(), bw)
        };
        let tsr = region(0.1);
        assert!(!p.linkage_clears(&p.world, "block", &tcp));
        let fitted = p.fit_grasp(&tsr, "block", &tcp);
        assert!(tsr.contains(&fitted));
        assert!(p.linkage_clears(&p.world, "block", &fitted));
        // Back along the approach only, and no further than the bisection's tolerance.
        let back = tsr.coordinates(&fitted)[2];
        assert!(back < -0.01, "{back}");
        let deeper = tsr.pose_at(&[0.0, 0.0, back + 2.0 * GRASP_FIT_TOLERANCE, 0.0, 0.0, 0.0]);
        assert!(!p.linkage_clears(&p.world, "block", &deeper));
        let c = p.linkage_clearance(&p.world, "block", &fitted).unwrap();
        assert!(
            c.clearance >= margin && c.clearance < margin + 0.002,
            "{c:?}"
        );
        // A region too short to clear leaves the draw as it is; so does a draw that clears.
        assert_eq!(p.fit_grasp(&region(0.01), "block", &tcp), tcp);
        assert_eq!(p.fit_grasp(&tsr, "block", &fitted), fitted);
    }

    #[test]
    fn prismatic_fingers_have_no_linkage_to_fit() {
        let robot = Robot::panda().unwrap();
        let task = builtin::task("inspection").unwrap().unwrap();
        let (options, probes) = (PlanOptions::default(), Cell::new(0));
        let p = Planner::new(&robot, task.world.clone(), &options, &probes);
        let truth = task.truth.unwrap();
        let tsr = truth.ground(&p.world.object_poses()).unwrap().keyframes[0]
            .tsr
            .clone();
        let deep = tsr.pose_at(&[0.0, 0.0, -0.005, 0.0, 0.0, 0.0]);
        assert!(p.linkage_clearance(&p.world, "part", &deep).is_none());
        assert_eq!(p.fit_grasp(&tsr, "part", &deep), deep);
    }
}
