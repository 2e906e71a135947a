//! The object in the hand, as the checks see it.

use super::Margins;
use crate::parry_convert;
use akl_scene::Shape;
use akl_tsr::Pose;
use parry3d_f64::shape::SharedShape;

/// An object held in the hand: it moves rigidly with the TCP.
///
/// Against fixed objects (furniture, known where they are) it keeps the held margin, small
/// enough to set it down on a support and carry it into a fixture; against the arm's own
/// links and against movable objects the hand margin where that is larger. Where the object
/// sits in the hand is only as good as the perception the grasp was planned on (the
/// inspection part, grasped 2 mm off where the UR5e planner saw it, grazed the upper arm in 2
/// of 3,000 trials with the held margin, 2 mm), and a movable object is itself only where it
/// was perceived: the gap between the two carries both errors (σ = 2 mm each along world x
/// and y by default, so up to 2.8 mm across them; 1.6 mm measured over the UR5e's bottles
/// trials that passed within 3 cm of another bottle or the can). With the held margin alone
/// the UR5e carried a bottle 2.6 mm over the can's rim as planned, 2.0 mm as placed, at
/// 1.4 m/s, and the simulation's contact, which acts on what will close within a step,
/// pushed it out of the hand (bottles gate, 1 of 473 trials, seed 213).
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
    /// The object grown by [`Held::arm_margin`], for the checks against the arm and against
    /// movable objects.
    pub(super) near_arm: SharedShape,
    /// The clearance kept from the arm's own links and from movable objects (metres).
    pub(super) arm_margin: f64,
    /// Radius of a ball about the object's centre that holds the object itself.
    pub(super) core: f64,
    pub(super) radius: f64,
}

impl Held {
    /// An object of `shape` held with pose `in_tcp` in the TCP frame, kept the held margin of
    /// `margins` from fixed objects and the larger of the hand and held margins from the arm
    /// and from movable objects.
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
            radius: in_tcp.translation.vector.norm() + core + arm_margin,
        }
    }
}
