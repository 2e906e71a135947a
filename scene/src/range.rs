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

    /// The range in words, e.g. `x ±0.03, y ±0.03, yaw ±0.10`.
    pub fn describe(&self) -> String {
        let one = |name: &str, [lo, hi]: [f64; 2], digits: usize| {
            if lo == -hi {
                format!("{name} ±{hi:.digits$}")
            } else {
                format!("{name} [{lo:.digits$}, {hi:.digits$}]")
            }
        };
        format!(
            "{}, {}, {}",
            one("x", self.x, 3),
            one("y", self.y, 3),
            one("yaw", self.yaw, 2)
        )
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
    fn ranges_read_as_words() {
        let r = Range {
            x: [-0.03, 0.03],
            y: [-0.05, 0.02],
            yaw: [-0.1, 0.1],
        };
        assert_eq!(r.describe(), "x ±0.030, y [-0.050, 0.020], yaw ±0.10");
        assert!(!r.is_constant() && Range::default().is_constant());
    }
}
