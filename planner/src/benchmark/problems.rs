//! The problem file shared with other planners: named scenes of boxes, cylinders and spheres,
//! and problems that each ask for a path between two configurations in one scene (the format
//! `../shared/peers/README.md` documents, which VAMP's runner reads too).

use akl_scene::{Object, Shape, World};
use akl_tsr::nalgebra::{Quaternion, Translation3, UnitQuaternion};
use akl_tsr::pose::{pose_from_xyz_rpy, QUATERNION_NORM_TOLERANCE};
use akl_tsr::Pose;
use serde::Deserialize;
use std::collections::{BTreeMap, HashSet};
use std::path::{Path, PathBuf};

/// How far apart (radians) an obstacle's two statements of its rotation may be: the shared
/// MotionBenchMaker file's agree to 5e-8 rad; anything beyond 1e-5 rad is a file whose two
/// rotations say different things.
const ROTATION_AGREEMENT: f64 = 1e-5;

/// A problem set: scenes by name and the problems posed in them.
#[derive(Debug, Clone, Deserialize)]
pub struct ProblemFile {
    /// Obstacles of each scene, by scene name.
    pub scenes: BTreeMap<String, Vec<Obstacle>>,
    /// The problems, in file order.
    pub problems: Vec<Problem>,
}

/// One planning problem: a path from `start` to `goal` in `scene`.
#[derive(Debug, Clone, Deserialize)]
pub struct Problem {
    /// The set it belongs to (e.g. `bookshelf_thin`); results are summarized per set.
    pub set: String,
    /// Unique identifier (e.g. `bookshelf_thin/3`).
    pub id: String,
    /// The scene it is posed in (a key of [`ProblemFile::scenes`]).
    pub scene: String,
    /// Start configuration (radians, base to tip).
    pub start: Vec<f64>,
    /// Goal configuration (radians, base to tip).
    pub goal: Vec<f64>,
}

/// One obstacle of a scene, posed in the robot base frame.
#[derive(Debug, Clone, Deserialize)]
pub struct Obstacle {
    /// Name, unique within its scene.
    pub name: String,
    /// Shape and size.
    #[serde(flatten)]
    pub shape: ObstacleShape,
    /// Position of the shape's centre (metres).
    pub position: [f64; 3],
    /// Orientation as a quaternion, x, y, z, w.
    #[serde(default)]
    pub quat_xyzw: Option<[f64; 4]>,
    /// Orientation as roll, pitch and yaw about the fixed x, y and z axes (URDF's `rpy`).
    #[serde(default)]
    pub euler_xyz: Option<[f64; 3]>,
}

/// The shape of an obstacle, tagged by `kind`.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum ObstacleShape {
    /// A box given by its half side lengths.
    Box {
        /// Half side lengths along x, y and z (metres).
        half_extents: [f64; 3],
    },
    /// A cylinder along its z axis.
    Cylinder {
        /// Radius (metres).
        radius: f64,
        /// Full length (metres).
        length: f64,
    },
    /// A sphere.
    Sphere {
        /// Radius (metres).
        radius: f64,
    },
}

/// Why a problem file cannot be used.
#[non_exhaustive]
#[derive(Debug, thiserror::Error)]
pub enum ProblemFileError {
    /// The file could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The reason.
        source: std::io::Error,
    },
    /// The file is not JSON of the problem format.
    #[error("{}: line {line}, column {column}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// Line of the error (1-based).
        line: usize,
        /// Column of the error (1-based).
        column: usize,
        /// What is wrong.
        message: String,
    },
    /// An obstacle has an impossible size or pose.
    #[error("{}: scene {scene}, obstacle {obstacle}: {message}", path.display())]
    Obstacle {
        /// The file.
        path: PathBuf,
        /// The scene.
        scene: String,
        /// The obstacle's name.
        obstacle: String,
        /// What is wrong.
        message: String,
    },
    /// A problem names a scene the file lacks, repeats an id or has the wrong joints.
    #[error("{}: problem {id}: {message}", path.display())]
    Problem {
        /// The file.
        path: PathBuf,
        /// The problem's id.
        id: String,
        /// What is wrong.
        message: String,
    },
}

impl ProblemFile {
    /// Reads and checks a problem file for a robot with `dof` joints.
    pub fn load(path: &Path, dof: usize) -> Result<ProblemFile, ProblemFileError> {
        let text = std::fs::read_to_string(path).map_err(|source| ProblemFileError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        ProblemFile::parse(&text, path, dof)
    }

    /// Parses and checks the text of a problem file (`path` names it in errors).
    pub fn parse(text: &str, path: &Path, dof: usize) -> Result<ProblemFile, ProblemFileError> {
        let file: ProblemFile =
            serde_json::from_str(text).map_err(|e| ProblemFileError::Parse {
                path: path.to_path_buf(),
                line: e.line(),
                column: e.column(),
                message: e.to_string(),
            })?;
        file.check(path, dof)?;
        Ok(file)
    }

    fn check(&self, path: &Path, dof: usize) -> Result<(), ProblemFileError> {
        for (scene, obstacles) in &self.scenes {
            let mut names = HashSet::new();
            for o in obstacles {
                let fail = |message: String| ProblemFileError::Obstacle {
                    path: path.to_path_buf(),
                    scene: scene.clone(),
                    obstacle: o.name.clone(),
                    message,
                };
                if !names.insert(o.name.as_str()) {
                    return Err(fail("a second obstacle of this name in the scene".into()));
                }
                o.object().map_err(fail)?;
            }
        }
        let mut ids = HashSet::new();
        for p in &self.problems {
            let fail = |message: String| ProblemFileError::Problem {
                path: path.to_path_buf(),
                id: p.id.clone(),
                message,
            };
            if !ids.insert(p.id.as_str()) {
                return Err(fail("a second problem with this id".into()));
            }
            if !self.scenes.contains_key(&p.scene) {
                return Err(fail(format!("scene {:?} is not in the file", p.scene)));
            }
            for (what, q) in [("start", &p.start), ("goal", &p.goal)] {
                if q.len() != dof {
                    return Err(fail(format!(
                        "{what} has {} joint values, the robot has {dof} joints",
                        q.len()
                    )));
                }
                if q.iter().any(|v| !v.is_finite()) {
                    return Err(fail(format!(
                        "{what} has a joint value that is not a number"
                    )));
                }
            }
        }
        Ok(())
    }

    /// The world of scene `name` (fixed obstacles, the robot base at the origin), if the file
    /// has that scene.
    pub(crate) fn world(&self, name: &str) -> Option<World> {
        let obstacles = self.scenes.get(name)?;
        Some(World {
            robot_base: Pose::identity(),
            // Checked when the file was loaded.
            objects: obstacles.iter().filter_map(|o| o.object().ok()).collect(),
        })
    }
}

impl Obstacle {
    /// The obstacle as a fixed object of a world, or what is wrong with it.
    fn object(&self) -> Result<Object, String> {
        let positive = |what: &str, v: f64| {
            if v.is_finite() && v > 0.0 {
                Ok(v)
            } else {
                Err(format!("{what} {v} is not a positive length"))
            }
        };
        let shape = match self.shape {
            ObstacleShape::Box { half_extents } => {
                let mut size = [0.0; 3];
                for (s, h) in size.iter_mut().zip(half_extents) {
                    *s = 2.0 * positive("half extent", h)?;
                }
                Shape::Box { size }
            }
            ObstacleShape::Cylinder { radius, length } => Shape::Cylinder {
                radius: positive("radius", radius)?,
                length: positive("length", length)?,
            },
            ObstacleShape::Sphere { radius } => Shape::Sphere {
                radius: positive("radius", radius)?,
            },
        };
        if self.position.iter().any(|v| !v.is_finite()) {
            return Err("position is not a point".into());
        }
        Ok(Object {
            name: self.name.clone(),
            shape,
            pose: Translation3::from(self.position) * self.rotation()?,
            movable: false,
            mass: 0.0,
            friction: 0.5,
        })
    }

    /// The orientation from whichever of the two statements is present, refusing two that
    /// disagree.
    fn rotation(&self) -> Result<UnitQuaternion<f64>, String> {
        let from_euler = self
            .euler_xyz
            .map(|rpy| {
                if rpy.iter().all(|v| v.is_finite()) {
                    Ok(pose_from_xyz_rpy([0.0; 3], rpy).rotation)
                } else {
                    Err("euler_xyz is not a rotation".to_string())
                }
            })
            .transpose()?;
        let from_quaternion = self
            .quat_xyzw
            .map(|[x, y, z, w]| {
                let q = Quaternion::new(w, x, y, z);
                let norm = q.norm();
                if norm.is_finite() && (norm - 1.0).abs() <= QUATERNION_NORM_TOLERANCE {
                    Ok(UnitQuaternion::from_quaternion(q))
                } else {
                    Err(format!("quat_xyzw has length {norm}, not 1"))
                }
            })
            .transpose()?;
        match (from_quaternion, from_euler) {
            (Some(q), Some(e)) if q.angle_to(&e) > ROTATION_AGREEMENT => Err(format!(
                "quat_xyzw and euler_xyz are rotations {:.2e} rad apart",
                q.angle_to(&e)
            )),
            (Some(q), _) => Ok(q),
            (None, Some(e)) => Ok(e),
            (None, None) => Ok(UnitQuaternion::identity()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const SMALL: &str = r#"{
        "scenes": {"s": [
            {"name": "b", "kind": "box", "position": [0.5, 0, 0.2], "quat_xyzw": [0, 0, 0.7071068, 0.7071068],
             "euler_xyz": [0, 0, 1.5707963], "half_extents": [0.1, 0.2, 0.3]},
            {"name": "c", "kind": "cylinder", "position": [0.4, 0.3, 0.1], "radius": 0.05, "length": 0.2},
            {"name": "s", "kind": "sphere", "position": [0.3, -0.3, 0.5], "euler_xyz": [0.1, 0, 0], "radius": 0.1}]},
        "problems": [{"set": "a", "id": "a/1", "index_in_set": 0, "scene": "s",
                      "start": [0, 0, 0], "goal": [1, 1, 1]}]}"#;

    fn parse(text: &str) -> Result<ProblemFile, ProblemFileError> {
        ProblemFile::parse(text, Path::new("p.json"), 3)
    }

    #[test]
    fn a_file_becomes_fixed_objects_of_the_sizes_and_poses_it_gives() {
        let file = parse(SMALL).unwrap();
        let world = file.world("s").unwrap();
        assert_eq!(world.objects.len(), 3);
        let b = &world.objects[0];
        assert_eq!(
            b.shape,
            Shape::Box {
                size: [0.2, 0.4, 0.6]
            }
        );
        // A quarter turn about z takes the box's x axis to the world's y axis.
        let x = b.pose.rotation * akl_tsr::nalgebra::Vector3::x();
        assert!((x - akl_tsr::nalgebra::Vector3::y()).norm() < 1e-6);
        assert!(!b.movable);
        assert_eq!(
            world.objects[1].shape,
            Shape::Cylinder {
                radius: 0.05,
                length: 0.2
            }
        );
        let s = &world.objects[2];
        assert!((s.pose.rotation.angle() - 0.1).abs() < 1e-12);
        assert!(file.world("missing").is_none());
    }

    #[test]
    fn bad_files_are_refused_naming_what_is_wrong() {
        let cases = [
            (
                SMALL.replace("0.7071068, 0.7071068", "0.28, 0.96"),
                "scene s, obstacle b: quat_xyzw and euler_xyz",
            ),
            (
                SMALL.replace("\"radius\": 0.05", "\"radius\": -0.05"),
                "obstacle c: radius -0.05",
            ),
            (
                SMALL.replace("\"scene\": \"s\"", "\"scene\": \"t\""),
                "problem a/1: scene \"t\"",
            ),
            (
                SMALL.replace("[1, 1, 1]", "[1, 1]"),
                "problem a/1: goal has 2 joint values",
            ),
            (
                SMALL.replace("\"name\": \"c\"", "\"name\": \"b\""),
                "obstacle b: a second obstacle",
            ),
            (SMALL.replace("\"sphere\"", "\"cone\""), "p.json: line"),
            (
                SMALL.replace("0, 0, 0.7071068, 0.7071068", "0, 0, 1.5, 1.5"),
                "quat_xyzw has length",
            ),
        ];
        for (text, expected) in cases {
            let e = parse(&text).unwrap_err().to_string();
            assert!(e.contains(expected), "{e} lacks {expected}");
        }
    }

    /// The shared MotionBenchMaker file states every rotation twice; the two agree under the
    /// URDF reading of `euler_xyz`, which is what confirms that reading.
    #[test]
    fn the_shared_motionbenchmaker_file_loads() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../benches/problems/mbm_panda.json");
        let file = ProblemFile::load(&path, 7).unwrap();
        assert_eq!(file.problems.len(), 349);
        assert_eq!(file.scenes.len(), 349);
    }
}
