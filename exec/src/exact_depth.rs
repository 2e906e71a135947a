//! The exact shape behind every collider, so that a contact reading can be confirmed.
//!
//! rapier reads contacts in single precision, and between two convex polyhedra its reading can
//! be centimetres off: the prism inside a simulated cylinder ([`crate::convert`]) was read
//! 6.2 mm deep into a gripper knuckle that a distance query put 5.1 mm away, and such readings
//! failed a third of the UR5e's bottles trials with 0 N contacts. A reading deep enough to be
//! a collision is therefore measured again between the exact shapes the task and the robot
//! give (no prism, no single precision) at the bodies' simulated poses.

use crate::convert::from_sim;
use akl_planner::collision::ExactShape;
use akl_tsr::Pose;
use rapier3d::prelude::{ColliderHandle, ColliderSet, RigidBodySet};
use std::collections::HashMap;

/// The exact shape of each collider and its frame in the collider's body frame.
#[derive(Debug, Clone, Default)]
pub(crate) struct ExactShapes {
    shapes: HashMap<ColliderHandle, (ExactShape, Pose)>,
}

impl ExactShapes {
    /// Records that `collider` stands for `shape`, whose frame is `origin` in the body frame.
    pub(crate) fn insert(&mut self, collider: ColliderHandle, shape: ExactShape, origin: Pose) {
        self.shapes.insert(collider, (shape, origin));
    }

    /// The exact shapes of colliders `a` and `b` and their world poses, from their bodies'
    /// current poses; `None` when either has no exact shape.
    fn placed(
        &self,
        colliders: &ColliderSet,
        bodies: &RigidBodySet,
        [a, b]: [ColliderHandle; 2],
    ) -> Option<[(&ExactShape, Pose); 2]> {
        let one = |c: ColliderHandle| {
            let (shape, origin) = self.shapes.get(&c)?;
            let body = colliders.get(c)?.parent()?;
            Some((shape, from_sim(bodies.get(body)?.position()) * origin))
        };
        Some([one(a)?, one(b)?])
    }

    /// How deep the exact shapes of the colliders `pair` interpenetrate at their bodies'
    /// current poses (metres, 0 when apart); `None` when either has no exact shape.
    pub(crate) fn depth(
        &self,
        colliders: &ColliderSet,
        bodies: &RigidBodySet,
        pair: [ColliderHandle; 2],
    ) -> Option<f64> {
        let [(sa, pa), (sb, pb)] = self.placed(colliders, bodies, pair)?;
        sa.penetration(&pa, sb, &pb)
    }

    /// A certified lower bound on the distance between the exact shapes of the colliders
    /// `pair` at their bodies' current poses (metres, 0 when they touch); `None` when either
    /// has no exact shape.
    pub(crate) fn distance(
        &self,
        colliders: &ColliderSet,
        bodies: &RigidBodySet,
        pair: [ColliderHandle; 2],
    ) -> Option<f64> {
        let [(sa, pa), (sb, pb)] = self.placed(colliders, bodies, pair)?;
        sa.distance(&pa, sb, &pb)
    }
}
