//! A robot: its URDF model (urdf-rs + k), compiled kinematics, limits, gripper, collision
//! settings and inverse kinematics solver. The Panda is built into the binary.

use crate::collision::pair_table::PairTable;
use crate::collision::{ElementBalls, StoredTables};
use crate::config::{IkSolverKind, RobotConfig};
use crate::enclosure;
use crate::error::{IkError, JointsError, MeshFailure, RobotError, UrdfError};
use crate::fk::{ArmJoints, Drive, Kinematics, Link, Motion, UrdfJoints};
use crate::geometry::LinkShape;
use crate::hand::HandModel;
use crate::ik::{DlsIk, IkSolver, PandaIk, TracIk};
use crate::meshes::{read_link_meshes, EmbeddedFiles, LinkMesh, MeshFiles, PackagePath};
use crate::urdf_load;
use akl_tsr::Pose;
use sha2::{Digest, Sha256};
use std::path::Path;
use std::sync::{Arc, Mutex, OnceLock};

/// One embedded mesh of the Panda: its path in `robots/panda` and its bytes.
macro_rules! panda_mesh {
    ($path:literal) => {
        ($path, include_bytes!(concat!("../../robots/panda/", $path)))
    };
}

/// The Panda's `robot.toml`, embedded so the binary works from any directory.
pub(crate) const PANDA_TOML: &str = include_str!("../../robots/panda/robot.toml");
/// The Panda's URDF (franka_description's `fer.urdf`), embedded.
pub(crate) const PANDA_URDF: &str = include_str!("../../robots/panda/fer.urdf");
/// The Panda's self-collision table values, computed ahead by `akl robot tables`.
const PANDA_TABLES: &[u8] = include_bytes!("../../robots/panda/self_tables.bin");

/// The file of a robot folder that holds its self-collision table values.
pub const STORED_TABLES_FILE: &str = "self_tables.bin";

/// The tables stored in `bytes`, read from `path` (named in the error).
fn stored_tables(bytes: &[u8], path: std::path::PathBuf) -> Result<StoredTables, RobotError> {
    StoredTables::parse(bytes).map_err(|source| RobotError::StoredTables { path, source })
}

/// The Panda's meshes, embedded, by their path in `robots/panda`.
const PANDA_MESHES: EmbeddedFiles = &[
    panda_mesh!("meshes/robot_arms/fer/collision/link0.stl"),
    panda_mesh!("meshes/robot_arms/fer/collision/link1.stl"),
    panda_mesh!("meshes/robot_arms/fer/collision/link2.stl"),
    panda_mesh!("meshes/robot_arms/fer/collision/link3.stl"),
    panda_mesh!("meshes/robot_arms/fer/collision/link4.stl"),
    panda_mesh!("meshes/robot_arms/fer/collision/link5.stl"),
    panda_mesh!("meshes/robot_arms/fer/collision/link6.stl"),
    panda_mesh!("meshes/robot_arms/fer/collision/link7.stl"),
    panda_mesh!("meshes/robot_arms/fer/visual/link0.dae"),
    panda_mesh!("meshes/robot_arms/fer/visual/link1.dae"),
    panda_mesh!("meshes/robot_arms/fer/visual/link2.dae"),
    panda_mesh!("meshes/robot_arms/fer/visual/link3.dae"),
    panda_mesh!("meshes/robot_arms/fer/visual/link4.dae"),
    panda_mesh!("meshes/robot_arms/fer/visual/link5.dae"),
    panda_mesh!("meshes/robot_arms/fer/visual/link6.dae"),
    panda_mesh!("meshes/robot_arms/fer/visual/link7.dae"),
    panda_mesh!("meshes/robot_ee/franka_hand_white/collision/hand.stl"),
    panda_mesh!("meshes/robot_ee/franka_hand_white/visual/hand.dae"),
    panda_mesh!("meshes/robot_ee/franka_hand_white/visual/finger.dae"),
];

/// The built-in Panda's meshes and the hulls enclosing them, made once per process (reading
/// and fitting them takes a tenth of a second; tests build the Panda hundreds of times).
static PANDA_GEOMETRY: OnceLock<Result<LinkGeometry, Vec<MeshFailure>>> = OnceLock::new();

/// A robot's meshes and, per link, the grown hull that encloses them.
#[derive(Debug, Clone)]
struct LinkGeometry {
    meshes: Arc<[LinkMesh]>,
    enclosures: Vec<(usize, Option<LinkShape>)>,
}

impl LinkGeometry {
    /// Reads the URDF's meshes and grows each meshed link's hull.
    fn read(
        urdf: &urdf_rs::Robot,
        kin: &Kinematics,
        files: &MeshFiles,
    ) -> Result<Self, Vec<MeshFailure>> {
        let meshes = read_link_meshes(urdf, kin, files)?;
        let mut links: Vec<usize> = meshes.iter().map(|m| m.link).collect();
        links.sort_unstable();
        links.dedup();
        let enclosures = links
            .into_iter()
            .map(|link| {
                let own: Vec<&LinkMesh> = meshes.iter().filter(|m| m.link == link).collect();
                let tolerance = if swung_by_gripper(kin, link) {
                    enclosure::LINKAGE_HULL_TOLERANCE
                } else {
                    enclosure::HULL_TOLERANCE
                };
                (link, enclosure::enclose_within(&own, tolerance))
            })
            .collect();
        Ok(LinkGeometry {
            meshes: meshes.into(),
            enclosures,
        })
    }
}

/// Whether a revolute joint the gripper opening drives moves `link` (its own joint or one
/// nearer the root): the link is part of a linkage that swings as the gripper closes.
fn swung_by_gripper(kin: &Kinematics, mut link: usize) -> bool {
    let links = kin.links();
    loop {
        if let Motion::Revolute {
            drive: Drive::Width { .. },
            ..
        } = links[link].motion
        {
            return true;
        }
        match links[link].parent {
            Some(parent) => link = parent,
            None => return false,
        }
    }
}

/// Whether loading checks that the simulation can drive the gripper.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum GripperCheck {
    /// Refuse a gripper the simulation cannot drive (every robot that plans).
    Simulated,
    /// Take any gripper (a description being inspected).
    Skipped,
}

/// Distinct-solution spacing used by [`Robot::ik_solutions`] callers by default (radians).
pub(crate) const SOLUTION_SPACING: f64 = 0.1;

/// A loaded robot. Poses taken and returned are in the robot's base frame; joint vectors are
/// arm configurations in [`Robot::joint_names`] order.
#[derive(Debug)]
pub struct Robot {
    config: RobotConfig,
    source: String,
    urdf: urdf_rs::Robot,
    chain: k::Chain<f64>,
    kin: Kinematics,
    arm: ArmJoints,
    ik: IkSolver,
    flange: usize,
    hand_links: Vec<usize>,
    mount_links: Vec<usize>,
    allowed_pairs: Vec<(usize, usize)>,
    meshes: Arc<[LinkMesh]>,
    /// [`Robot::digest`], computed on first use.
    digest: OnceLock<String>,
    /// The collision model's distance tables, per self margin (its bits), shared by every
    /// model built for this robot so that what one plan computes serves the next.
    pair_tables: Mutex<Vec<(u64, PairTables)>>,
    /// Table values computed ahead (`self_tables.bin`), taken by the tables they fit.
    stored_tables: StoredTables,
    /// The balls of every collision element, made by the first collision model built for this
    /// robot and shared by the rest (a trial builds one).
    element_balls: OnceLock<ElementBalls>,
}

/// The distance tables of a collision model's self pairs, in the model's pair order.
pub(crate) type PairTables = Arc<[Option<PairTable>]>;

impl Robot {
    /// The built-in Franka Emika Panda (`robots/panda`).
    pub fn panda() -> Result<Robot, RobotError> {
        Robot::panda_with(PANDA_TOML)
    }

    /// The built-in Panda with another `robot.toml` (e.g. another IK solver or margins).
    pub(crate) fn panda_with(toml_text: &str) -> Result<Robot, RobotError> {
        let mut robot = Robot::build(
            toml_text,
            Path::new("robots/panda/robot.toml"),
            PANDA_URDF,
            Path::new("robots/panda/fer.urdf"),
            &[],
            Some(PANDA_MESHES),
            GripperCheck::Simulated,
        )?;
        robot.stored_tables = stored_tables(
            PANDA_TABLES,
            Path::new("robots/panda").join(STORED_TABLES_FILE),
        )?;
        Ok(robot)
    }

    /// Loads the robot folder `dir`: its `robot.toml` and the URDF that names.
    pub fn load(dir: &Path) -> Result<Robot, RobotError> {
        Robot::load_with(dir, &[])
    }

    /// Loads the robot folder `dir`, finding the URDF's `package://` meshes in `packages`
    /// first (then in the folder's `[packages]` and `ROS_PACKAGE_PATH`).
    pub fn load_with(dir: &Path, packages: &[PackagePath]) -> Result<Robot, RobotError> {
        let toml_path = dir.join("robot.toml");
        let read = |path: &Path| {
            std::fs::read_to_string(path).map_err(|source| RobotError::Io {
                path: path.to_path_buf(),
                source,
            })
        };
        if dir.is_dir() && !toml_path.exists() {
            return Err(RobotError::Config {
                path: toml_path,
                message: "not found: a robot folder holds robot.toml (its fields: robots/README.md) and the URDF it names".into(),
            });
        }
        let toml_text = read(&toml_path)?;
        let config = RobotConfig::from_toml(&toml_text).map_err(|e| RobotError::Config {
            path: toml_path.clone(),
            message: e.to_string(),
        })?;
        let urdf_path = dir.join(&config.urdf);
        let urdf_text = read(&urdf_path)?;
        let mut robot = Robot::build(
            &toml_text,
            &toml_path,
            &urdf_text,
            &urdf_path,
            packages,
            None,
            GripperCheck::Simulated,
        )?;
        let tables_path = dir.join(STORED_TABLES_FILE);
        if tables_path.exists() {
            let bytes = std::fs::read(&tables_path).map_err(|source| RobotError::Io {
                path: tables_path.clone(),
                source,
            })?;
            robot.stored_tables = stored_tables(&bytes, tables_path)?;
        }
        Ok(robot)
    }

    /// Builds a robot from the texts of its `robot.toml` and URDF; the paths name them in
    /// errors and locate the URDF's meshes on disk (the tests of stock-URDF quirks).
    #[cfg(test)]
    pub(crate) fn from_texts(
        toml_text: &str,
        toml_path: &Path,
        urdf_text: &str,
        urdf_path: &Path,
    ) -> Result<Robot, RobotError> {
        Robot::build(
            toml_text,
            toml_path,
            urdf_text,
            urdf_path,
            &[],
            None,
            GripperCheck::Simulated,
        )
    }

    /// Builds a robot whose gripper the simulation may be unable to drive, for inspecting a
    /// description before its folder is written (`akl robot init`); never for planning.
    pub(crate) fn provisional(
        toml_text: &str,
        toml_path: &Path,
        urdf_text: &str,
        urdf_path: &Path,
        packages: &[PackagePath],
    ) -> Result<Robot, RobotError> {
        Robot::build(
            toml_text,
            toml_path,
            urdf_text,
            urdf_path,
            packages,
            None,
            GripperCheck::Skipped,
        )
    }

    fn build(
        toml_text: &str,
        toml_path: &Path,
        urdf_text: &str,
        urdf_path: &Path,
        packages: &[PackagePath],
        embedded: Option<EmbeddedFiles>,
        gripper: GripperCheck,
    ) -> Result<Robot, RobotError> {
        let config_err = |message: String| RobotError::Config {
            path: toml_path.to_path_buf(),
            message,
        };
        let urdf_err = |message: String| RobotError::Urdf {
            path: urdf_path.to_path_buf(),
            message,
        };
        let config = RobotConfig::from_toml(toml_text).map_err(|e| config_err(e.to_string()))?;
        config.validate().map_err(|e| config_err(e.to_string()))?;
        if urdf_path.extension().is_some_and(|e| e == "xacro") {
            return Err(urdf_err(UrdfError::Xacro.to_string()));
        }
        let urdf = urdf_load::parse(urdf_text).map_err(|e| urdf_err(e.to_string()))?;
        let chain = urdf_load::chain(&urdf);
        let joints = UrdfJoints::of(&urdf);
        let (mut kin, arm) =
            Kinematics::compile(&chain, &config.tcp_link, &config.gripper.joints, &joints)
                .map_err(|e| urdf_err(e.to_string()))?;
        let robot_dir = toml_path.parent().unwrap_or(Path::new(""));
        let files = MeshFiles::new(
            robot_dir,
            urdf_path.parent().unwrap_or(Path::new("")),
            packages,
            &config
                .packages
                .iter()
                .map(|(k, v)| (k.clone(), v.clone()))
                .collect::<Vec<_>>(),
            embedded,
        );
        let geometry = match embedded {
            Some(_) => PANDA_GEOMETRY
                .get_or_init(|| LinkGeometry::read(&urdf, &kin, &files))
                .clone(),
            None => LinkGeometry::read(&urdf, &kin, &files),
        }
        .map_err(|failures| RobotError::Meshes {
            urdf: urdf_path.to_path_buf(),
            failures,
        })?;
        for (link, shape) in &geometry.enclosures {
            kin.add_shapes(*link, shape.iter().cloned());
        }
        let (flange, hand_links, mount_links, allowed_pairs) =
            check_against_urdf(&config, &urdf, &kin, &arm).map_err(|problems| {
                config_err(match problems.len() {
                    1 => problems.concat(),
                    n => format!(
                        "{n} problems:{}",
                        problems
                            .iter()
                            .map(|p| format!("\n  {p}"))
                            .collect::<String>()
                    ),
                })
            })?;
        // Where the robot stands, before any solver reads the kinematics.
        if let Some(mount) = &config.mount {
            kin.set_mount(mount.pose());
        }
        let dls = DlsIk::new(arm.limits.clone());
        let ik = match config.ik.solver {
            IkSolverKind::Panda => IkSolver::Panda {
                analytic: Box::new(
                    PandaIk::from_kinematics(&kin, &arm.limits)
                        .map_err(|e| urdf_err(format!("ik solver `panda`: {e}")))?,
                ),
                dls,
            },
            IkSolverKind::Dls => IkSolver::Dls(dls),
            IkSolverKind::Trac => IkSolver::Trac(TracIk::new(arm.limits.clone())),
        };
        let mut robot = Robot {
            source: toml_path
                .parent()
                .map_or_else(String::new, |p| p.display().to_string()),
            config,
            urdf,
            chain,
            kin,
            arm,
            ik,
            flange,
            hand_links,
            mount_links,
            allowed_pairs,
            meshes: geometry.meshes,
            digest: OnceLock::new(),
            pair_tables: Mutex::new(Vec::new()),
            stored_tables: StoredTables::default(),
            element_balls: OnceLock::new(),
        };
        // A linkage's opening is mapped to its knuckle angle through the pads' gap.
        if let Some(map) = crate::hand::linkage_width_map(&robot) {
            robot.kin.set_width_map(map);
        }
        // A gripper the simulation cannot drive is refused now, not when a trial runs.
        if gripper == GripperCheck::Simulated {
            HandModel::build(&robot).map_err(|source| RobotError::Gripper {
                path: toml_path.to_path_buf(),
                source,
            })?;
        }
        Ok(robot)
    }

    /// The URDF's collision and visual meshes, each in its link's frame (empty when the URDF
    /// gives only primitives).
    pub fn meshes(&self) -> &[LinkMesh] {
        &self.meshes
    }

    /// The distance tables of the collision model with self margin `self_margin`: the ones
    /// built earlier for this robot, else those `build` makes (kept for the next model).
    pub(crate) fn pair_tables(
        &self,
        self_margin: f64,
        build: impl FnOnce() -> PairTables,
    ) -> PairTables {
        let mut cache = self.pair_tables.lock().unwrap_or_else(|e| e.into_inner());
        let key = self_margin.to_bits();
        if let Some((_, tables)) = cache.iter().find(|(k, _)| *k == key) {
            return tables.clone();
        }
        let tables = build();
        cache.push((key, tables.clone()));
        tables
    }

    /// The balls of every collision element (`collision::model`): the ones made for an
    /// earlier model of this robot, else those `build` makes.
    pub(crate) fn element_balls(&self, build: impl FnOnce() -> ElementBalls) -> &ElementBalls {
        self.element_balls.get_or_init(build)
    }

    /// Self-collision table values computed ahead (empty if the robot has none).
    pub(crate) fn stored_tables(&self) -> &StoredTables {
        &self.stored_tables
    }

    /// SHA-256 (hex) of everything the robot is built from: `robot.toml`, the URDF and every
    /// mesh. Two runs are comparable only on robots with the same digest. Computed once, as
    /// the meshes hold tens of thousands of numbers and every batch of trials reports it.
    pub fn digest(&self) -> &str {
        self.digest.get_or_init(|| {
            let mut hasher = Sha256::new();
            hasher.update(format!("{:?}\n{:?}\n", self.config, self.urdf));
            for m in self.meshes.iter() {
                hasher.update(format!("{} {:?} {}\n", m.link, m.role, m.uri));
                for v in &m.mesh.vertices {
                    for x in v.coords.iter() {
                        hasher.update(x.to_le_bytes());
                    }
                }
                for t in &m.mesh.triangles {
                    for i in t {
                        hasher.update(i.to_le_bytes());
                    }
                }
            }
            hasher
                .finalize()
                .iter()
                .map(|b| format!("{b:02x}"))
                .collect()
        })
    }

    /// The robot's name from `robot.toml`.
    pub fn name(&self) -> &str {
        &self.config.name
    }

    /// Where the robot was loaded from (a folder, or `robots/panda` for the built-in one).
    pub fn source(&self) -> &str {
        &self.source
    }

    /// The parsed `robot.toml`.
    pub fn config(&self) -> &RobotConfig {
        &self.config
    }

    /// The parsed URDF.
    pub fn urdf(&self) -> &urdf_rs::Robot {
        &self.urdf
    }

    /// The k kinematic tree (the reference forward kinematics).
    pub fn chain(&self) -> &k::Chain<f64> {
        &self.chain
    }

    /// The compiled kinematics used for planning.
    pub fn kinematics(&self) -> &Kinematics {
        &self.kin
    }

    /// Number of arm joints.
    pub fn dof(&self) -> usize {
        self.kin.dof()
    }

    /// Arm joint names, base to tip.
    pub fn joint_names(&self) -> &[String] {
        &self.arm.names
    }

    /// `[lower, upper]` position limits of the arm joints.
    pub fn joint_limits(&self) -> &[[f64; 2]] {
        &self.arm.limits
    }

    /// Velocity limits of the arm joints.
    pub fn velocity_limits(&self) -> &[f64] {
        &self.config.velocity_limits
    }

    /// Acceleration limits of the arm joints.
    pub fn acceleration_limits(&self) -> &[f64] {
        &self.config.acceleration_limits
    }

    /// The ready configuration plans start from.
    pub fn ready(&self) -> &[f64] {
        &self.config.ready
    }

    /// All links, parents first, with their collision geometry (shape and pose in the link).
    pub fn links(&self) -> &[Link] {
        self.kin.links()
    }

    /// Index of the TCP link in [`Robot::links`].
    pub fn tcp_link(&self) -> usize {
        self.kin.tcp_index()
    }

    /// Indices of the hand links (hand and fingers).
    pub fn hand_links(&self) -> &[usize] {
        &self.hand_links
    }

    /// Indices of the links that may touch the surface the robot stands on.
    pub fn mount_links(&self) -> &[usize] {
        &self.mount_links
    }

    /// Link index pairs never checked against each other.
    pub(crate) fn allowed_pairs(&self) -> &[(usize, usize)] {
        &self.allowed_pairs
    }

    /// Every joint the gripper's opening moves: those `robot.toml` lists, then the URDF
    /// joints that mimic one of them.
    pub fn finger_joints(&self) -> &[String] {
        &self.arm.fingers
    }

    /// Whether each arm joint is continuous (turns without end; planned over `[-2π, 2π]`,
    /// its range in [`Robot::joint_limits`]).
    pub fn continuous_joints(&self) -> &[bool] {
        &self.arm.continuous
    }

    /// Whether arm joint `i` can stand at one angle and at that angle a whole turn further,
    /// both within its planned range: a continuous joint, or a revolute joint whose limits
    /// span more than a turn (UR's descriptions bound every joint to a turn either way).
    fn turns(&self, i: usize) -> bool {
        let [lo, hi] = self.arm.limits[i];
        self.arm.continuous[i] || (self.arm.revolute[i] && hi - lo > std::f64::consts::TAU)
    }

    /// Moves each joint of `q` that [turns](Robot::turns) by whole turns to the angle nearest
    /// `seed`'s that stays within its planned range (left as it is when no other turn does).
    /// A solver's restarts land on either turn at random, and the far one is the same pose a
    /// whole turn of the joint away: a planner given it must swing the link all the way round,
    /// through whatever it passes (a UR5e's upper arm through the table).
    fn nearest_turns(&self, mut q: Vec<f64>, seed: &[f64]) -> Vec<f64> {
        use std::f64::consts::TAU;
        for (i, v) in q.iter_mut().enumerate() {
            let Some(s) = seed.get(i).filter(|_| self.turns(i)) else {
                continue;
            };
            let [lo, hi] = self.arm.limits[i];
            let near = *v + ((s - *v) / TAU).round() * TAU;
            *v = [near, near + TAU, near - TAU, *v]
                .into_iter()
                .filter(|a| (lo..=hi).contains(a))
                .min_by(|a, b| (a - s).abs().total_cmp(&(b - s).abs()))
                .unwrap_or(*v);
        }
        q
    }

    /// Gripper opening width when open (metres).
    pub fn open_width(&self) -> f64 {
        self.config.gripper.open_width
    }

    /// Seconds the gripper takes to go from fully open to closed (or back): each of the two
    /// fingers travels half the opening at the finger speed.
    pub fn gripper_travel_time(&self) -> f64 {
        self.open_width() / 2.0 / self.finger_speed()
    }

    /// How fast each finger moves (metres per second).
    pub fn finger_speed(&self) -> f64 {
        self.config.gripper.speed
    }

    /// Checks a configuration: right length, finite, within the limits; the error names the
    /// joint.
    pub fn check_joints(&self, q: &[f64]) -> Result<(), JointsError> {
        if q.len() != self.dof() {
            return Err(JointsError::Count {
                names: self.joint_names().to_vec(),
                got: q.len(),
            });
        }
        for (i, (v, [lo, hi])) in q.iter().zip(self.joint_limits()).enumerate() {
            if !v.is_finite() {
                return Err(JointsError::NotFinite {
                    index: i,
                    name: self.arm.names[i].clone(),
                });
            }
            if v < lo || v > hi {
                return Err(JointsError::OutsideLimits {
                    index: i,
                    name: self.arm.names[i].clone(),
                    value: *v,
                    lo: *lo,
                    hi: *hi,
                });
            }
        }
        Ok(())
    }

    /// Base-frame pose of every link for arm configuration `q` and gripper opening
    /// `width`, in [`Robot::links`] order: what drives kinematic bodies in a simulation.
    pub fn link_poses(&self, q: &[f64], width: f64) -> Vec<Pose> {
        self.kin.link_poses(q, width)
    }

    /// The TCP pose for `q`.
    pub fn tcp_pose(&self, q: &[f64]) -> Pose {
        self.kin.tcp_pose(q)
    }

    /// The flange pose for `q`.
    pub fn flange_pose(&self, q: &[f64]) -> Pose {
        self.kin.link_poses(q, 0.0)[self.flange]
    }

    /// The arm configuration nearest `seed` that puts the TCP at `tcp`, or
    /// [`IkError::Unreachable`].
    pub fn ik(&self, tcp: &Pose, seed: &[f64]) -> Result<Vec<f64>, IkError> {
        if seed.len() != self.dof() || seed.iter().any(|v| !v.is_finite()) {
            return Err(IkError::BadSeed(format!(
                "expected {} finite joint values",
                self.dof()
            )));
        }
        self.ik
            .nearest(&self.kin, tcp, seed)
            .map(|q| self.nearest_turns(q, seed))
    }

    /// Up to `max` distinct configurations that put the TCP at `tcp`, nearest `seed` first.
    pub fn ik_solutions(&self, tcp: &Pose, seed: &[f64], max: usize) -> Vec<Vec<f64>> {
        let found = self
            .ik
            .solutions(&self.kin, tcp, seed, max, SOLUTION_SPACING);
        if !(0..self.dof()).any(|i| self.turns(i)) {
            return found;
        }
        // Solutions a whole turn apart become one once moved to the turn nearest the seed.
        let mut all: Vec<Vec<f64>> = Vec::with_capacity(found.len());
        for q in found.into_iter().map(|q| self.nearest_turns(q, seed)) {
            if all
                .iter()
                .all(|s| crate::ik::analytic::max_step(s, &q) > SOLUTION_SPACING)
            {
                all.push(q);
            }
        }
        let distance =
            |q: &Vec<f64>| -> f64 { q.iter().zip(seed).map(|(a, b)| (a - b).powi(2)).sum() };
        all.sort_by(|a, b| distance(a).total_cmp(&distance(b)));
        all
    }

    /// A configuration for `tcp` no joint of which is more than `max_joint_step` from
    /// `previous`, for following a path without jumps.
    pub(crate) fn ik_continuous(
        &self,
        tcp: &Pose,
        previous: &[f64],
        max_joint_step: f64,
    ) -> Option<Vec<f64>> {
        self.ik
            .continuous(&self.kin, tcp, previous, max_joint_step)
            .map(|q| self.nearest_turns(q, previous))
    }

    /// The inverse kinematics solver.
    #[cfg(test)]
    pub(crate) fn ik_solver(&self) -> &IkSolver {
        &self.ik
    }
}

/// The links `robot.toml` names, as indices: the flange, hand links, mount links and
/// allowed pairs.
type NamedLinks = (usize, Vec<usize>, Vec<usize>, Vec<(usize, usize)>);

/// Checks `robot.toml` against the URDF (lengths of the joint arrays, velocities within the
/// URDF's, the ready pose within the limits, every link it names) and finds the links it
/// names; every problem found is returned, one line each.
fn check_against_urdf(
    config: &RobotConfig,
    urdf: &urdf_rs::Robot,
    kin: &Kinematics,
    arm: &ArmJoints,
) -> Result<NamedLinks, Vec<String>> {
    let mut problems = Vec::new();
    let dof = kin.dof();
    for (name, values) in [
        ("ready", &config.ready),
        ("velocity_limits", &config.velocity_limits),
        ("acceleration_limits", &config.acceleration_limits),
    ] {
        if values.len() != dof {
            problems.push(format!(
                "{name} has {} values but the arm has {dof} joints ({})",
                values.len(),
                arm.names.join(", ")
            ));
        }
    }
    // robot.toml may slow a joint down, never speed it past what its URDF allows.
    for (name, v) in arm.names.iter().zip(&config.velocity_limits) {
        let urdf_limit = urdf
            .joints
            .iter()
            .find(|j| j.name == *name)
            .map(|j| j.limit.velocity)
            .filter(|l| *l > 0.0);
        if let Some(limit) = urdf_limit.filter(|l| v > l) {
            problems.push(format!(
                "velocity_limits: {v} rad/s for `{name}` exceeds its URDF limit of {limit} rad/s"
            ));
        }
    }
    for (i, (v, [lo, hi])) in config.ready.iter().zip(&arm.limits).enumerate() {
        if v < lo || v > hi {
            problems.push(format!(
                "ready[{i}] = {v} is outside the limits [{lo}, {hi}] of `{}`",
                arm.names[i]
            ));
        }
    }
    let mut link = |name: &str, field: &str| {
        let found = kin.link_index(name);
        if found.is_none() {
            problems.push(format!("{field}: `{name}` is not a link of the URDF"));
        }
        found.unwrap_or(0)
    };
    let flange = link(&config.flange_link, "flange_link");
    let names = |list: &[String], field: &str, link: &mut dyn FnMut(&str, &str) -> usize| {
        list.iter().map(|n| link(n, field)).collect::<Vec<_>>()
    };
    let hand_links = names(&config.gripper.hand_links, "gripper.hand_links", &mut link);
    let mount_links = names(
        &config.collision.mount_links,
        "collision.mount_links",
        &mut link,
    );
    let allowed_pairs = config
        .collision
        .allowed_pairs
        .iter()
        .map(|[a, b]| {
            (
                link(a, "collision.allowed_pairs"),
                link(b, "collision.allowed_pairs"),
            )
        })
        .collect();
    if problems.is_empty() {
        Ok((flange, hand_links, mount_links, allowed_pairs))
    } else {
        Err(problems)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn panda_dir() -> std::path::PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../robots/panda")
    }

    #[test]
    fn the_folder_and_the_embedded_panda_agree() {
        let embedded = Robot::panda().unwrap();
        let loaded = Robot::load(&panda_dir()).unwrap();
        assert_eq!(embedded.joint_names(), loaded.joint_names());
        assert_eq!(embedded.dof(), 7);
        assert_eq!(embedded.finger_joints().len(), 2);
        assert!(matches!(embedded.ik_solver(), IkSolver::Panda { .. }));
    }

    /// The unchecked link pairs of `robot.toml` that are neither next to each other in the
    /// chain nor the two fingers cannot meet: the hulls of their meshes (which hold the
    /// meshes) intersect in none of 20,000 random configurations with random openings.
    #[test]
    fn the_unchecked_link_pairs_never_meet() {
        use parry3d_f64::math::Vector;
        use parry3d_f64::shape::ConvexPolyhedron;
        use rand::{Rng, SeedableRng};
        let robot = Robot::panda().unwrap();
        let links = robot.links();
        let hulls: Vec<Option<ConvexPolyhedron>> = (0..links.len())
            .map(|i| {
                let points: Vec<Vector> = robot
                    .meshes()
                    .iter()
                    .filter(|m| m.link == i)
                    .flat_map(|m| &m.mesh.vertices)
                    .map(|v| Vector::new(v.x, v.y, v.z))
                    .collect();
                ConvexPolyhedron::from_convex_hull(&points)
            })
            .collect();
        // The nearest ancestor of a link that has meshes.
        let meshed_parent = |mut i: usize| loop {
            match links[i].parent {
                Some(p) if hulls[p].is_some() => return Some(p),
                Some(p) => i = p,
                None => return None,
            }
        };
        let fingers: Vec<usize> = robot
            .hand_links()
            .iter()
            .copied()
            .filter(|&i| robot.finger_joints().contains(&links[i].joint))
            .collect();
        let pairs: Vec<(usize, usize)> = robot
            .allowed_pairs()
            .iter()
            .copied()
            .filter(|&(a, b)| {
                meshed_parent(a) != Some(b)
                    && meshed_parent(b) != Some(a)
                    && !(fingers.contains(&a) && fingers.contains(&b))
            })
            .collect();
        assert_eq!(pairs.len(), 22, "the pairs ruled out by measurement");
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(2026);
        for _ in 0..20_000 {
            let q: Vec<f64> = robot
                .joint_limits()
                .iter()
                .map(|[lo, hi]| rng.gen_range(*lo..*hi))
                .collect();
            let poses = robot.link_poses(&q, rng.gen_range(0.0..robot.open_width()));
            for &(a, b) in &pairs {
                let (Some(ha), Some(hb)) = (&hulls[a], &hulls[b]) else {
                    continue;
                };
                let meet = parry3d_f64::query::intersection_test(
                    &crate::parry_convert::pose(&poses[a]),
                    ha,
                    &crate::parry_convert::pose(&poses[b]),
                    hb,
                )
                .is_ok_and(|r| r.intersecting);
                assert!(
                    !meet,
                    "{} and {} meet at {q:?}",
                    links[a].name, links[b].name
                );
            }
        }
    }

    #[test]
    fn robot_toml_agrees_with_the_urdf_velocity_limits() {
        let robot = Robot::panda().unwrap();
        for (name, v) in robot.joint_names().iter().zip(robot.velocity_limits()) {
            let joint = robot
                .urdf()
                .joints
                .iter()
                .find(|j| j.name == *name)
                .unwrap();
            assert_eq!(joint.limit.velocity, *v, "{name}");
        }
    }

    fn with_toml(edit: impl Fn(String) -> String) -> Result<Robot, RobotError> {
        Robot::panda_with(&edit(PANDA_TOML.to_string()))
    }

    #[test]
    fn configuration_errors_name_the_file_and_field() {
        let e = with_toml(|t| t.replace("tcp_link = \"fer_hand_tcp\"", "tcp_link = \"nose\""))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("robots/panda/fer.urdf") && e.contains("`nose`"),
            "{e}"
        );
        let e =
            with_toml(|t| t.replace("acceleration_limits = [15.0, ", "acceleration_limits = ["))
                .unwrap_err()
                .to_string();
        assert!(
            e.contains("robots/panda/robot.toml") && e.contains("acceleration_limits has 6"),
            "{e}"
        );
        let e = with_toml(|t| t.replace("arm_margin = 0.01", "arm_margin = -1.0"))
            .unwrap_err()
            .to_string();
        assert!(e.contains("collision.arm_margin"), "{e}");
        let e = with_toml(|t| t.replace("name = \"panda\"", "name = 3"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("robots/panda/robot.toml") && e.contains("line"),
            "{e}"
        );
    }

    #[test]
    fn every_mesh_that_cannot_be_found_is_listed() {
        let dir = std::env::temp_dir().join(format!("akl-robot-meshes-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("robot.toml"),
            PANDA_TOML.replace("franka_description = \".\"", ""),
        )
        .unwrap();
        std::fs::write(dir.join("fer.urdf"), PANDA_URDF).unwrap();
        let e = Robot::load(&dir).unwrap_err();
        let RobotError::Meshes { urdf, failures } = &e else {
            panic!("{e}")
        };
        assert_eq!(urdf, &dir.join("fer.urdf"));
        // Nine collision and eleven visual elements, one line each.
        assert_eq!(failures.len(), 20, "{e}");
        assert!(failures.iter().any(|f| f.link == "fer_rightfinger"));
        assert!(failures
            .iter()
            .all(|f| f.problem.contains("--package-path franka_description=DIR")));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_folder_without_robot_toml_says_what_a_robot_folder_holds() {
        let dir = std::env::temp_dir().join(format!("akl-robot-empty-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let e = Robot::load(&dir).unwrap_err().to_string();
        assert!(
            e.contains("robot.toml") && e.contains("holds robot.toml"),
            "{e}"
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_missing_folder_is_named() {
        let e = Robot::load(Path::new("/nonexistent/robot"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("/nonexistent/robot/robot.toml") && e.contains("cannot read"),
            "{e}"
        );
    }

    #[test]
    fn velocity_limits_may_not_exceed_the_urdf() {
        let e = with_toml(|t| t.replace("velocity_limits = [2.175,", "velocity_limits = [10.0,"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("fer_joint1") && e.contains("exceeds its URDF limit of 2.175"),
            "{e}"
        );
        assert!(
            with_toml(|t| t.replace("velocity_limits = [2.175,", "velocity_limits = [1.0,"))
                .is_ok()
        );
    }

    #[test]
    fn the_dls_solver_can_be_chosen() {
        let robot = with_toml(|t| t.replace("solver = \"panda\"", "solver = \"dls\"")).unwrap();
        assert!(matches!(robot.ik_solver(), IkSolver::Dls(_)));
    }
}

#[cfg(test)]
#[path = "robot_quirks.rs"]
pub(crate) mod quirks;
