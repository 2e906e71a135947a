//! The object in the hand, as the checks see it.

use crate::parry_convert;
use akl_scene::Shape;
use akl_tsr::Pose;
use parry3d_f64::shape::SharedShape;

/// An object held in the hand: it moves rigidly with the TCP.
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
    /// Radius of a ball about the object's centre that holds the object itself.
    pub(super) core: f64,
    pub(super) radius: f64,
}

impl Held {
    /// An object of `shape` held with pose `in_tcp` in the TCP frame, grown by `margin`.
    pub fn new(name: &str, shape: Shape, in_tcp: Pose, margin: f64) -> Held {
        let (grown, local) = parry_convert::object_shape(&shape, margin);
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
            core,
            radius: in_tcp.translation.vector.norm() + core + margin,
        }
    }
}
