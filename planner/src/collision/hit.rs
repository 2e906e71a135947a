//! What a check found in collision.

use std::fmt;

/// What a check found in collision.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Hit {
    /// Two links of the robot.
    SelfCollision(String, String),
    /// A link and a world object.
    World(String, String),
    /// The held object and a world object.
    HeldWorld(String, String),
    /// The held object and a link.
    HeldRobot(String, String),
    /// A configuration outside the joint limits.
    Limits,
}

impl fmt::Display for Hit {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Hit::SelfCollision(a, b) => write!(f, "{a} with {b}"),
            Hit::World(l, o) => write!(f, "{l} with {o}"),
            Hit::HeldWorld(h, o) => write!(f, "held {h} with {o}"),
            Hit::HeldRobot(h, l) => write!(f, "held {h} with {l}"),
            Hit::Limits => f.write_str("joint limits"),
        }
    }
}
