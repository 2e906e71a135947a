//! Where the robot can work: the reach every layout keeps the teaching's targets within.

use serde::{Deserialize, Serialize};

/// Where the robot can work: the tool centre point (TCP) poses a task needs must lie within
/// `max` of the shoulder and at least `min_radial` from the vertical axis of the robot base.
///
/// The defaults are the Panda's: its shoulder (joint 2) is 0.333 m above the base; the arm
/// reaches 0.855 m from there to the wrist flange, and the TCP sits 0.103 m beyond the flange,
/// so with the hand pointing down a TCP target at 0.8 m still leaves the elbow bent; closer
/// than 0.25 m to the base's axis the hand meets the arm's own first links.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Reach {
    /// The shoulder in the robot base frame (metres).
    pub shoulder: [f64; 3],
    /// Farthest a TCP target may be from the shoulder (metres).
    pub max: f64,
    /// Nearest a TCP target may be to the robot base's vertical axis (metres).
    pub min_radial: f64,
}

impl Default for Reach {
    fn default() -> Self {
        Reach {
            shoulder: [0.0, 0.0, 0.333],
            max: 0.8,
            min_radial: 0.25,
        }
    }
}

impl Reach {
    /// Checks the values; the error names the field.
    pub fn validate(&self) -> Result<(), (String, String)> {
        if self.shoulder.iter().any(|v| !v.is_finite()) {
            return Err(("shoulder".into(), "must be finite".into()));
        }
        if !self.max.is_finite() || self.max <= 0.0 {
            return Err((
                "max".into(),
                format!("must be finite and > 0, got {}", self.max),
            ));
        }
        if !self.min_radial.is_finite() || self.min_radial < 0.0 || self.min_radial >= self.max {
            return Err((
                "min_radial".into(),
                format!(
                    "must be finite, >= 0 and below max ({}), got {}",
                    self.max, self.min_radial
                ),
            ));
        }
        Ok(())
    }
}
