//! The object in the hand, as the checks see it.

use super::Margins;
use crate::parry_convert;
use akl_scene::Shape;
use akl_tsr::Pose;
use parry3d_f64::shape::SharedShape;

/// An object held in the hand: it moves rigidly with the TCP.
///
/// Against the world it keeps the held margin, small enough to set it down on a support;
/// against the arm's own links the hand margin where that is larger: where the object sits
/// in the hand is only as good as the perception the grasp was planned on (the inspection
/// part, grasped 2 mm off where the UR5e planner saw it, grazed the upper arm in 2 of 3,000
/// trials with the held margin, 2 mm).
#[derive(Debug, Clone)]
pub struct Held {
    /// The object's name.
    pub name: String,
    /// The object's shape.
    pub shape: Shape,
    /// The object's pose in the TCP frame.
    pub in_tcp: Pose,
    pub(super) grown: SharedShape,
    pub(super) exact: SharedShape,
    pub(super) local: Pose,
    pub(super) margin: f64,
    /// The object grown by [`Held::arm_margin`], for the checks against the arm.
    pub(super) near_arm: SharedShape,
    /// The clearance kept from the arm's own links (metres).
    pub(super) arm_margin: f64,
    /// Radius of a ball about the object's centre that holds the object itself.
    pub(super) core: f64,
    pub(super) radius: f64,
}

impl Held {
    /// An object of `shape` held with pose `in_tcp` in the TCP frame, kept the held margin of
    /// `margins` from the world and the larger of the hand and held margins from the arm.
    pub fn new(name: &str, shape: Shape, in_tcp: Pose, margins: &Margins) -> Held {
        let margin = margins.held;
        let arm_margin = margins.hand.max(margin);
        let (grown, local) = parry_convert::object_shape(&shape, margin);
        let (near_arm, _) = parry_convert::object_shape(&shape, arm_margin);
        let (exact, _) = parry_convert::object_shape(&shape, 0.0);
        let core = shape.half_extents().norm();
        Held {
            name: name.to_string(),
            shape,
            in_tcp,
            grown,
            exact,
            local,
            margin,
            near_arm,
            arm_margin,
            core,
            radius: in_tcp.translation.vector.norm() + core + margin,
        }
    }
}
