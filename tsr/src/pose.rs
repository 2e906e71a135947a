//! Rigid poses and their JSON form `{"p": [x, y, z], "q": [x, y, z, w]}`.

use crate::error::PoseError;
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion};
use serde::{Deserialize, Deserializer, Serialize, Serializer};

/// A rigid transform in metres; the pose of a frame expressed in a parent frame.
pub type Pose = Isometry3<f64>;

/// How far a quaternion's norm may be from 1 before it is rejected as not a rotation.
///
/// Hand-written and rounded files carry norms like 0.9999; anything beyond this tolerance is
/// more likely a typo or a wrong component order than rounding.
pub const QUATERNION_NORM_TOLERANCE: f64 = 1e-3;

/// The serialized shape of a pose: position and a quaternion in ROS order `[x, y, z, w]`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoseJson {
    /// Position in metres.
    pub p: [f64; 3],
    /// Orientation as a unit quaternion `[x, y, z, w]`.
    pub q: [f64; 4],
}

impl PoseJson {
    /// Converts to a pose, rejecting non-finite numbers and quaternions that are not unit length.
    pub fn to_pose(&self) -> Result<Pose, PoseError> {
        if let Some(v) = self.p.iter().chain(self.q.iter()).find(|v| !v.is_finite()) {
            return Err(PoseError::NotFinite(*v));
        }
        let [x, y, z, w] = self.q;
        let norm = (x * x + y * y + z * z + w * w).sqrt();
        if (norm - 1.0).abs() > QUATERNION_NORM_TOLERANCE {
            return Err(PoseError::NotUnit { q: self.q, norm });
        }
        let rotation = UnitQuaternion::from_quaternion(Quaternion::new(w, x, y, z));
        Ok(Isometry3::from_parts(
            Translation3::new(self.p[0], self.p[1], self.p[2]),
            rotation,
        ))
    }

    /// The serialized form of a pose.
    pub fn from_pose(pose: &Pose) -> Self {
        let t = pose.translation.vector;
        let q = pose.rotation.quaternion().coords;
        PoseJson {
            p: [t.x, t.y, t.z],
            q: [q.x, q.y, q.z, q.w],
        }
    }
}

/// Serializes a pose as `{"p": [...], "q": [...]}`; use with `#[serde(with = "akl_tsr::pose::serde_pose")]`.
pub mod serde_pose {
    use super::*;

    /// Writes the pose in its JSON form.
    pub fn serialize<S: Serializer>(pose: &Pose, s: S) -> Result<S::Ok, S::Error> {
        PoseJson::from_pose(pose).serialize(s)
    }

    /// Reads and validates a pose (finite numbers, unit quaternion).
    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<Pose, D::Error> {
        PoseJson::deserialize(d)?
            .to_pose()
            .map_err(serde::de::Error::custom)
    }
}

/// Builds a pose from a position and roll-pitch-yaw angles (R = Rz·Ry·Rx).
pub fn pose_from_xyz_rpy(xyz: [f64; 3], rpy: [f64; 3]) -> Pose {
    Isometry3::from_parts(
        Translation3::new(xyz[0], xyz[1], xyz[2]),
        crate::rpy::rotation_from_rpy(rpy),
    )
}

/// Builds a pure translation.
pub fn pose_from_xyz(xyz: [f64; 3]) -> Pose {
    Isometry3::translation(xyz[0], xyz[1], xyz[2])
}

/// Straight-line distance between the origins of two poses, in metres.
pub fn position_distance(a: &Pose, b: &Pose) -> f64 {
    (a.translation.vector - b.translation.vector).norm()
}

/// Angle of the rotation that takes `a`'s orientation to `b`'s, in radians within [0, π].
pub fn rotation_distance(a: &Pose, b: &Pose) -> f64 {
    a.rotation.angle_to(&b.rotation)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_round_trip_keeps_the_pose() {
        let pose = pose_from_xyz_rpy([0.1, -0.2, 0.3], [0.4, -0.5, 2.0]);
        let json = serde_json::to_string(&PoseJson::from_pose(&pose)).unwrap();
        let back: PoseJson = serde_json::from_str(&json).unwrap();
        let back = back.to_pose().unwrap();
        assert!(position_distance(&pose, &back) < 1e-12);
        assert!(rotation_distance(&pose, &back) < 1e-9);
    }

    #[test]
    fn rejects_a_quaternion_that_is_not_unit_length() {
        let json = PoseJson {
            p: [0.0; 3],
            q: [0.0, 0.0, 0.0, 1.2],
        };
        let err = json.to_pose().unwrap_err();
        assert!(matches!(err, PoseError::NotUnit { .. }));
        assert!(err.to_string().contains("not unit length"), "{err}");
    }

    #[test]
    fn accepts_rounded_quaternions_and_normalizes_them() {
        let json = PoseJson {
            p: [0.0; 3],
            q: [0.6, 0.0, 0.0, 0.8003], // norm 1.00024: rounded, as hand-written files are
        };
        let pose = json.to_pose().unwrap();
        assert!((pose.rotation.quaternion().norm() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn rejects_non_finite_numbers() {
        let json = PoseJson {
            p: [f64::NAN, 0.0, 0.0],
            q: [0.0, 0.0, 0.0, 1.0],
        };
        assert!(matches!(json.to_pose(), Err(PoseError::NotFinite(v)) if v.is_nan()));
    }
}
