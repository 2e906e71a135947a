//! `akl robot init`: a robot folder guessed from a stock URDF. The joint tree gives the arm,
//! the gripper and the flange ([`Structure`]); the gripper's pads give the TCP (an existing
//! link there, else one added to the folder's copy of the URDF); the URDF gives the limits;
//! inverse kinematics gives a ready pose with the TCP pointing down in front of the base; and
//! random configurations give the link pairs that need no collision check ([`PairSummary`]).
//! Everything guessed is returned for printing, so the user can review it.

mod pairs;
mod structure;
mod tcp;

use crate::config::{CollisionConfig, GripperConfig, IkConfig, IkSolverKind, RobotConfig};
use crate::error::RobotError;
use crate::ik::PandaIk;
use crate::meshes::PackagePath;
use crate::robot::Robot;
use crate::urdf_load;
use serde::Serialize;
use std::path::{Path, PathBuf};
pub use structure::{GripperKind, Structure};
pub use tcp::TcpGuess;

/// Why a robot folder cannot be guessed or written.
#[non_exhaustive]
#[derive(Debug, thiserror::Error)]
pub enum InitError {
    /// A file cannot be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The reason.
        source: std::io::Error,
    },
    /// The URDF is not one the planner can use, or holds no arm.
    #[error("{}: {message}", path.display())]
    Urdf {
        /// The URDF.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// The description loads with the guessed settings only with errors (e.g. meshes that
    /// cannot be found).
    #[error("{0}")]
    Robot(#[from] RobotError),
    /// The output folder already holds a robot.
    #[error("{}: already exists; give another -o folder or remove it", .0.display())]
    Exists(PathBuf),
}

/// Settings of the guess.
#[derive(Debug, Clone)]
pub struct InitOptions {
    /// Random configurations drawn to find link pairs that never meet.
    pub samples: usize,
    /// Seed of those draws (the guess is the same for the same seed).
    pub seed: u64,
}

impl Default for InitOptions {
    fn default() -> Self {
        InitOptions {
            samples: 10_000,
            seed: 2026,
        }
    }
}

/// Everything `akl robot init` guessed.
#[derive(Debug, Clone, Serialize)]
pub struct Guess {
    /// The URDF read.
    pub urdf_path: PathBuf,
    /// The joint tree's reading.
    pub structure: Structure,
    /// The TCP.
    pub tcp: TcpGuess,
    /// The `robot.toml` to write.
    pub config: RobotConfig,
    /// How the unchecked link pairs were found: names of adjacent, never and always pairs,
    /// and how many stay checked.
    pub pairs: PairSummary,
    /// Things to review: values that are guesses rather than read from the URDF.
    pub notes: Vec<String>,
    /// The URDF text to write into the folder (the input, with the TCP link added if needed).
    #[serde(skip)]
    pub urdf_text: String,
}

/// The measured link pairs, by link name.
#[derive(Debug, Clone, Serialize)]
pub struct PairSummary {
    /// Links next to each other, and the fingers.
    pub adjacent: usize,
    /// Pairs that met in none of the samples.
    pub never: Vec<[String; 2]>,
    /// Pairs that met in every sample.
    pub always: Vec<[String; 2]>,
    /// Pairs left to check.
    pub checked: Vec<[String; 2]>,
    /// Random configurations drawn.
    pub samples: usize,
}

/// The margins written: the built-in Panda's (see `robots/panda/robot.toml` for why each), but
/// between links 5 mm instead of 1 cm. Each link's model already holds every vertex of its
/// meshes, so the margin between links only has to cover tracking; and arms are built with
/// links closer than 1 cm where they pass each other (the UR5e's upper arm passes over its
/// base with its models 4–10 mm apart, which a 1 cm margin forbids in most of its workspace).
fn default_collision() -> CollisionConfig {
    CollisionConfig {
        arm_margin: 0.01,
        hand_margin: 0.005,
        held_margin: 0.002,
        self_margin: 0.005,
        mount_links: Vec::new(),
        allowed_pairs: Vec::new(),
    }
}

/// Acceleration guessed per unit of velocity limit (URDF gives none): five times the
/// velocity limit per second, about the Panda's published accelerations on average.
const ACCELERATION_PER_VELOCITY: f64 = 5.0;

/// Guesses a robot folder for the URDF at `urdf_path` that will be written to `out`;
/// `packages` locate its `package://` meshes.
pub fn guess(
    urdf_path: &Path,
    packages: &[PackagePath],
    out: &Path,
    options: &InitOptions,
) -> Result<Guess, InitError> {
    let urdf_err = |message: String| InitError::Urdf {
        path: urdf_path.to_path_buf(),
        message,
    };
    if urdf_path.extension().is_some_and(|e| e == "xacro") {
        return Err(urdf_err(crate::error::UrdfError::Xacro.to_string()));
    }
    let text = std::fs::read_to_string(urdf_path).map_err(|source| InitError::Io {
        path: urdf_path.to_path_buf(),
        source,
    })?;
    let urdf = urdf_load::parse(&text).map_err(|e| urdf_err(e.to_string()))?;
    let structure = structure::structure(&urdf).map_err(urdf_err)?;
    let mut notes = Vec::new();
    let file_name = urdf_path
        .file_name()
        .map_or_else(|| "robot.urdf".into(), |n| n.to_string_lossy().into_owned());
    let limits: Vec<&urdf_rs::Joint> = structure
        .arm_joints
        .iter()
        .filter_map(|n| urdf.joints.iter().find(|j| j.name == *n))
        .collect();
    let velocity_limits: Vec<f64> = limits
        .iter()
        .map(|j| {
            if j.limit.velocity > 0.0 {
                j.limit.velocity
            } else {
                notes.push(format!(
                    "velocity_limits: `{}` has no velocity limit in the URDF; 1.0 written",
                    j.name
                ));
                1.0
            }
        })
        .collect();
    notes.push(format!(
        "acceleration_limits: the URDF gives none; {ACCELERATION_PER_VELOCITY} times each velocity limit per second written"
    ));
    let (open_width, speed) = tcp::opening(&urdf, &structure);
    let mut config = RobotConfig {
        name: urdf.name.clone(),
        urdf: file_name,
        tcp_link: structure.palm.clone(),
        flange_link: structure.flange.clone(),
        ready: tcp::middle_of_limits(&limits),
        acceleration_limits: velocity_limits
            .iter()
            .map(|v| v * ACCELERATION_PER_VELOCITY)
            .collect(),
        velocity_limits,
        ik: IkConfig {
            solver: IkSolverKind::Trac,
        },
        gripper: GripperConfig {
            joints: structure.gripper_joints.clone(),
            open_width,
            speed,
            hand_links: Vec::new(),
        },
        collision: default_collision(),
        packages: packages
            .iter()
            .map(|p| {
                let dir = std::fs::canonicalize(&p.dir).unwrap_or_else(|_| p.dir.clone());
                (p.name.clone(), dir.display().to_string())
            })
            .collect(),
        mount: None,
    };
    let toml_path = out.join("robot.toml");
    let provisional = |config: &RobotConfig, urdf_text: &str| {
        let toml_text = toml::to_string(config).map_err(|e| urdf_err(e.to_string()))?;
        Robot::provisional(&toml_text, &toml_path, urdf_text, urdf_path, packages)
            .map_err(InitError::from)
    };
    // The TCP: found from the hand of a robot whose TCP is the palm.
    let palm_robot = provisional(&config, &text)?;
    let tcp = tcp::guess_tcp(&palm_robot, &structure);
    notes.extend(tcp.note.clone());
    let urdf_text = match &tcp.added {
        Some(snippet) => tcp::add_to_urdf(&text, snippet),
        None => text.clone(),
    };
    config.tcp_link = tcp.link.clone();
    let robot = provisional(&config, &urdf_text)?;
    let links = robot.links();
    let palm = robot.kinematics().link_index(&structure.palm).unwrap_or(0);
    let below_palm = |mut i: usize| loop {
        if i == palm {
            return true;
        }
        match links[i].parent {
            Some(p) => i = p,
            None => return false,
        }
    };
    let shaped = |i: &usize| !links[*i].shapes.is_empty();
    config.gripper.hand_links = (0..links.len())
        .filter(|&i| below_palm(i))
        .filter(shaped)
        .map(|i| links[i].name.clone())
        .collect();
    config.collision.mount_links = tcp::mount_links(&robot)
        .into_iter()
        .filter(shaped)
        .map(|i| links[i].name.clone())
        .collect();
    let fingers: Vec<usize> = (0..links.len())
        .filter(|&i| robot.finger_joints().contains(&links[i].joint))
        .collect();
    let measured = pairs::measure(&robot, &fingers, options.samples, options.seed);
    let name = |&(a, b): &(usize, usize)| [links[a].name.clone(), links[b].name.clone()];
    config.collision.allowed_pairs = measured.allowed().iter().map(name).collect();
    let pairs = PairSummary {
        adjacent: measured.adjacent.len(),
        never: measured.never.iter().map(name).collect(),
        always: measured.always.iter().map(name).collect(),
        checked: measured.checked.iter().map(name).collect(),
        samples: measured.samples,
    };
    match tcp::ready_pose(&robot, &measured.checked) {
        Some(q) => config.ready = q,
        None => notes.push(
            "ready: no collision-free configuration points the TCP down in front of the base; the middle of the joint limits written".into(),
        ),
    }
    if PandaIk::from_kinematics(robot.kinematics(), robot.joint_limits()).is_ok() {
        config.ik.solver = IkSolverKind::Panda;
    }
    if structure.gripper == GripperKind::Linkage {
        notes.push(format!(
            "gripper: `{}` drives a linkage ({} joints): its opening is the gap between the fingertips' pads (the bounds of their collision meshes), mapped to the knuckle angle; check open_width against the gripper's stroke",
            structure.gripper_joints.join(", "),
            structure.finger_joints.len()
        ));
    }
    if structure.gripper == GripperKind::None {
        notes.push("gripper: none found (two prismatic fingers on one link, or a knuckle with mimic joints): the folder is refused when loaded".into());
    }
    Ok(Guess {
        urdf_path: urdf_path.to_path_buf(),
        structure,
        tcp,
        config,
        pairs,
        notes,
        urdf_text,
    })
}

/// Writes the guessed folder: `robot.toml` (with a header saying it was guessed) and the URDF.
/// Refuses a folder that already holds a `robot.toml`.
pub fn write(guess: &Guess, out: &Path) -> Result<(), InitError> {
    let toml_path = out.join("robot.toml");
    if toml_path.exists() {
        return Err(InitError::Exists(toml_path));
    }
    let io = |path: &Path| {
        let path = path.to_path_buf();
        move |source| InitError::Io { path, source }
    };
    std::fs::create_dir_all(out).map_err(io(out))?;
    let body = toml::to_string(&guess.config).map_err(|e| InitError::Urdf {
        path: guess.urdf_path.clone(),
        message: e.to_string(),
    })?;
    let header = format!(
        "# Written by `akl robot init` from {}: every value is a guess to review (fields:\n# robots/README.md).\n{}\n",
        guess.urdf_path.display(),
        guess
            .notes
            .iter()
            .map(|n| format!("# note: {n}\n"))
            .collect::<String>()
    );
    std::fs::write(&toml_path, header + &body).map_err(io(&toml_path))?;
    let urdf_out = out.join(&guess.config.urdf);
    std::fs::write(&urdf_out, &guess.urdf_text).map_err(io(&urdf_out))
}

#[cfg(test)]
mod tests;
