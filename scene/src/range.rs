//! Randomization ranges: how far an object or a rigid group may be moved from its place.

use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// How far an object or a rigid group may be moved from where it is carried to: offsets along
/// x and y of what carries it (the world's axes for things on unmoved furniture; metres) and a
/// turn about the vertical through its centre (a group's: the mean of its members' centres;
/// radians).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Range {
    /// Offset along x, `[min, max]`.
    #[serde(default)]
    pub x: [f64; 2],
    /// Offset along y, `[min, max]`.
    #[serde(default)]
    pub y: [f64; 2],
    /// Turn about the vertical, `[min, max]`.
    #[serde(default)]
    pub yaw: [f64; 2],
}

/// Randomization ranges by object or group name.
pub type Ranges = BTreeMap<String, Range>;

/// Rigid groups by name: furniture the randomization moves as one body.
pub type Groups = BTreeMap<String, Vec<String>>;

impl Range {
    /// Checks each interval is finite and ordered, and the turn within ±π; the error names
    /// the interval.
    pub fn validate(&self) -> Result<(), (String, String)> {
        for (name, [lo, hi]) in [("x", self.x), ("y", self.y), ("yaw", self.yaw)] {
            if !lo.is_finite() || !hi.is_finite() || lo > hi {
                return Err((
                    name.into(),
                    format!("[{lo}, {hi}] must be finite with min <= max"),
                ));
            }
        }
        let [lo, hi] = self.yaw;
        if lo < -std::f64::consts::PI || hi > std::f64::consts::PI {
            return Err((
                "yaw".into(),
                format!("[{lo}, {hi}] must lie within [-pi, pi]"),
            ));
        }
        Ok(())
    }

    /// Whether every interval is a single value: such a range moves nothing relative to what
    /// carries it in a way that differs between draws.
    pub fn is_constant(&self) -> bool {
        [self.x, self.y, self.yaw].iter().all(|[lo, hi]| lo == hi)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_intervals_are_named() {
        let r = Range {
            x: [0.0, 0.0],
            y: [0.02, -0.02],
            yaw: [0.0, 0.0],
        };
        assert_eq!(r.validate().unwrap_err().0, "y");
        let r = Range {
            x: [f64::NAN, 0.0],
            ..Range::default()
        };
        assert_eq!(r.validate().unwrap_err().0, "x");
        let r = Range {
            yaw: [-4.0, 0.0],
            ..Range::default()
        };
        assert_eq!(r.validate().unwrap_err().0, "yaw");
    }

    #[test]
    fn only_single_value_intervals_are_constant() {
        let r = Range {
            x: [-0.03, 0.03],
            ..Range::default()
        };
        assert!(!r.is_constant() && Range::default().is_constant());
        let shifted = Range {
            x: [0.02, 0.02],
            ..Range::default()
        };
        assert!(shifted.is_constant());
    }
}
