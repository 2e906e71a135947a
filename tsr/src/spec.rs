//! Task specifications: the versioned `spec.json` format, its validation and grounding.

use crate::error::{FileError, SpecError};
use crate::keyframe::{Constraint, Keyframe};
use crate::pose::Pose;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// The `akl_spec` version this build reads and writes.
pub const SPEC_VERSION: u32 = 1;

/// The reference name of the fixed world frame: keyframes grounded on it never move.
pub const WORLD_FRAME: &str = "world";

/// An ordered sequence of keyframes that specifies a task (thesis §3.2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TaskSpec {
    /// Format version; always [`SPEC_VERSION`].
    pub akl_spec: u32,
    /// Name of the task the spec is for.
    pub task: String,
    /// How the spec was made: `akl`, `kd`, `macl`, `truth`, ...
    pub method: String,
    /// The keyframes, in execution order.
    pub keyframes: Vec<Keyframe>,
}

#[derive(Deserialize)]
struct VersionProbe {
    akl_spec: Option<serde_json::Value>,
}

impl TaskSpec {
    /// A spec of the current version.
    pub fn new(
        task: impl Into<String>,
        method: impl Into<String>,
        keyframes: Vec<Keyframe>,
    ) -> Self {
        TaskSpec {
            akl_spec: SPEC_VERSION,
            task: task.into(),
            method: method.into(),
            keyframes,
        }
    }

    /// Parses and validates a spec from JSON text.
    pub fn from_json(text: &str) -> Result<Self, SpecError> {
        let probe: VersionProbe =
            serde_json::from_str(text).map_err(|e| SpecError::from_json(&e, text))?;
        match &probe.akl_spec {
            Some(v) if v.as_u64() == Some(u64::from(SPEC_VERSION)) => {}
            Some(v) => {
                return Err(SpecError::UnsupportedVersion {
                    found: v.to_string(),
                    expected: SPEC_VERSION,
                })
            }
            None => {
                return Err(SpecError::UnsupportedVersion {
                    found: "missing (no `akl_spec` field)".into(),
                    expected: SPEC_VERSION,
                })
            }
        }
        let spec: TaskSpec =
            serde_json::from_str(text).map_err(|e| SpecError::from_json(&e, text))?;
        spec.validate()?;
        Ok(spec)
    }

    /// Reads, parses and validates a spec file; errors name the file.
    pub fn load(path: &Path) -> Result<Self, FileError<SpecError>> {
        let wrap = |source| FileError {
            path: path.to_path_buf(),
            source,
        };
        let text = std::fs::read_to_string(path).map_err(|e| wrap(SpecError::Io(e)))?;
        Self::from_json(&text).map_err(wrap)
    }

    /// The spec as pretty-printed JSON.
    pub fn to_json(&self) -> String {
        crate::io::to_readable_json(self).expect("a spec always serializes")
    }

    /// Writes the spec atomically (never a half-written file).
    pub fn save(&self, path: &Path) -> std::io::Result<()> {
        crate::io::write_atomic(path, self.to_json().as_bytes())
    }

    /// Checks the invariants the JSON shape cannot express; errors name the keyframe and field.
    pub fn validate(&self) -> Result<(), SpecError> {
        let invalid = |location: String, problem: String| SpecError::Invalid { location, problem };
        if self.akl_spec != SPEC_VERSION {
            return Err(SpecError::UnsupportedVersion {
                found: self.akl_spec.to_string(),
                expected: SPEC_VERSION,
            });
        }
        if self.task.trim().is_empty() {
            return Err(invalid("task".into(), "is empty".into()));
        }
        if self.keyframes.is_empty() {
            return Err(invalid(
                "keyframes".into(),
                "a spec needs at least one keyframe".into(),
            ));
        }
        for (i, kf) in self.keyframes.iter().enumerate() {
            let at = |field: &str| format!("keyframes[{i}].{field}");
            if kf.reference.trim().is_empty() {
                return Err(invalid(at("reference"), "is empty".into()));
            }
            kf.tsr
                .bw
                .validate()
                .map_err(|p| invalid(at("tsr.bw"), p.to_string()))?;
            for (name, pose) in [("tsr.t0_w", &kf.tsr.t0_w), ("tsr.tw_e", &kf.tsr.tw_e)] {
                if !pose_is_finite(pose) {
                    return Err(invalid(at(name), "holds a non-finite number".into()));
                }
            }
            if let Some(t) = kf.t {
                if !t.is_finite() || t < 0.0 {
                    return Err(invalid(
                        at("t"),
                        format!("must be a finite time >= 0, got {t}"),
                    ));
                }
            }
            if i == 0 && kf.constraint == Constraint::MoveInLine {
                return Err(invalid(
                    at("constraint"),
                    "the first keyframe cannot be move_in_line: a line needs a previous keyframe to start from"
                        .into(),
                ));
            }
        }
        Ok(())
    }

    /// How many segments are `move_in_line`: the constraints a spec asks of the planner.
    pub fn line_count(&self) -> usize {
        self.keyframes
            .iter()
            .filter(|k| k.constraint == Constraint::MoveInLine)
            .count()
    }

    /// The distinct reference objects the keyframes are grounded on.
    pub fn references(&self) -> BTreeSet<&str> {
        self.keyframes
            .iter()
            .map(|k| k.reference.as_str())
            .collect()
    }

    /// Checks that every reference is the world frame or one of `objects`.
    pub fn check_references<'a>(
        &self,
        objects: impl IntoIterator<Item = &'a str>,
    ) -> Result<(), SpecError> {
        let known: BTreeSet<&str> = objects.into_iter().collect();
        for (i, kf) in self.keyframes.iter().enumerate() {
            if kf.reference != WORLD_FRAME && !known.contains(kf.reference.as_str()) {
                return Err(SpecError::UnknownReference {
                    keyframe: i,
                    reference: kf.reference.clone(),
                    known: known.iter().map(|s| s.to_string()).collect(),
                });
            }
        }
        Ok(())
    }

    /// The spec with every keyframe's `t0_w` rebound to its reference object's pose in
    /// `object_poses` (thesis §3.2.4), so targets follow the objects wherever they now are.
    pub fn ground(&self, object_poses: &BTreeMap<String, Pose>) -> Result<TaskSpec, SpecError> {
        self.check_references(object_poses.keys().map(String::as_str))?;
        let mut grounded = self.clone();
        for kf in &mut grounded.keyframes {
            if let Some(pose) = object_poses.get(&kf.reference) {
                kf.tsr = kf.tsr.rebased(*pose);
            }
        }
        Ok(grounded)
    }
}

fn pose_is_finite(pose: &Pose) -> bool {
    pose.translation.vector.iter().all(|v| v.is_finite())
        && pose
            .rotation
            .quaternion()
            .coords
            .iter()
            .all(|v| v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::keyframe::{Gripper, KeyframeKind};
    use crate::pose::{pose_from_xyz_rpy, position_distance};
    use crate::tsr::{Bounds, Tsr};
    use proptest::prelude::*;

    fn keyframe(reference: &str, constraint: Constraint) -> Keyframe {
        Keyframe {
            kind: KeyframeKind::Interaction,
            reference: reference.into(),
            tsr: Tsr::new(
                pose_from_xyz_rpy([0.5, 0.2, 0.1], [0.0, 0.0, 0.3]),
                pose_from_xyz_rpy([0.0, 0.0, 0.05], [std::f64::consts::PI, 0.0, 0.0]),
                Bounds::symmetric(0.01, 0.05),
            ),
            gripper: Gripper::Closed,
            constraint,
            t: Some(1.5),
            frame: Some(150),
        }
    }

    fn spec() -> TaskSpec {
        TaskSpec::new(
            "demo",
            "akl",
            vec![
                keyframe("part", Constraint::None),
                keyframe("shelf", Constraint::MoveInLine),
            ],
        )
    }

    #[test]
    fn round_trips_through_json() {
        let s = spec();
        assert_eq!(
            TaskSpec::from_json(&s.to_json()).unwrap().keyframes.len(),
            2
        );
    }

    fn err(text: &str) -> String {
        TaskSpec::from_json(text).unwrap_err().to_string()
    }

    fn edited(from: &str, to: &str) -> String {
        let json = spec().to_json();
        assert!(json.contains(from), "{from} not in {json}");
        json.replacen(from, to, 1)
    }

    #[test]
    fn rejects_an_unknown_version() {
        let e = err(&edited("\"akl_spec\": 1", "\"akl_spec\": 7"));
        assert!(e.contains("unsupported spec version 7"), "{e}");
        let e = err("{\"task\": \"x\"}");
        assert!(e.contains("missing"), "{e}");
    }

    #[test]
    fn rejects_nan_with_its_position() {
        let e = err(&edited("\"t\": 1.5", "\"t\": NaN"));
        assert!(
            e.contains("non-finite number `NaN`") && e.contains("line"),
            "{e}"
        );
    }

    #[test]
    fn rejects_inverted_bounds() {
        let e = err(&edited("[-0.01, 0.01]", "[0.02, 0.01]"));
        assert!(
            e.contains("keyframes[0].tsr.bw") && e.contains("min 0.02 > max 0.01"),
            "{e}"
        );
    }

    #[test]
    fn rejects_unknown_enum_values_naming_the_line() {
        let e = err(&edited("\"kind\": \"interaction\"", "\"kind\": \"grasp\""));
        assert!(
            e.contains("unknown variant `grasp`") && e.starts_with("line"),
            "{e}"
        );
        let e = err(&edited("\"gripper\": \"closed\"", "\"gripper\": \"shut\""));
        assert!(e.contains("unknown variant `shut`"), "{e}");
        let e = err(&edited(
            "\"constraint\": \"none\"",
            "\"constraint\": \"circle\"",
        ));
        assert!(e.contains("unknown variant `circle`"), "{e}");
    }

    #[test]
    fn rejects_a_quaternion_that_is_not_unit() {
        let json = spec().to_json();
        let v: serde_json::Value = serde_json::from_str(&json).unwrap();
        let mut v = v;
        v["keyframes"][0]["tsr"]["t0_w"]["q"] = serde_json::json!([0.0, 0.0, 0.5, 0.5]);
        let e = err(&serde_json::to_string_pretty(&v).unwrap());
        assert!(e.contains("not unit length"), "{e}");
    }

    #[test]
    fn rejects_a_first_keyframe_that_moves_in_line() {
        let mut s = spec();
        s.keyframes[0].constraint = Constraint::MoveInLine;
        let e = TaskSpec::from_json(&s.to_json()).unwrap_err().to_string();
        assert!(e.contains("keyframes[0].constraint"), "{e}");
    }

    #[test]
    fn grounding_moves_targets_with_their_objects() {
        let s = spec();
        let part = pose_from_xyz_rpy([0.4, -0.1, 0.2], [0.0, 0.0, 1.0]);
        let shelf = pose_from_xyz_rpy([0.3, 0.3, 0.0], [0.0, 0.0, 0.0]);
        let poses = BTreeMap::from([("part".to_string(), part), ("shelf".to_string(), shelf)]);
        let g = s.ground(&poses).unwrap();
        let expected = part * s.keyframes[0].tsr.tw_e;
        assert!(position_distance(&g.keyframes[0].tsr.nominal(), &expected) < 1e-12);
    }

    #[test]
    fn grounding_names_an_unknown_reference() {
        let poses = BTreeMap::from([("part".to_string(), Pose::identity())]);
        let e = spec().ground(&poses).unwrap_err().to_string();
        assert!(e.contains("keyframes[1]") && e.contains("`shelf`"), "{e}");
    }

    proptest! {
        #[test]
        fn json_round_trip_is_lossless(x in -2.0..2.0f64, yaw in -3.0..3.0f64, t in 0.0..100.0f64) {
            let mut s = spec();
            s.keyframes[0].tsr.t0_w = pose_from_xyz_rpy([x, 0.1, 0.2], [0.1, 0.2, yaw]);
            s.keyframes[1].t = Some(t);
            let back = TaskSpec::from_json(&s.to_json()).unwrap();
            prop_assert!(position_distance(&back.keyframes[0].tsr.t0_w, &s.keyframes[0].tsr.t0_w) < 1e-12);
            prop_assert!(back.keyframes[0].tsr.t0_w.rotation.angle_to(&s.keyframes[0].tsr.t0_w.rotation) < 1e-9);
            prop_assert_eq!(back.keyframes[1].t, Some(t));
            prop_assert_eq!(&back.keyframes[0].kind, &s.keyframes[0].kind);
        }
    }
}
