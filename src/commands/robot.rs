//! `akl robot info`, `akl robot fk` and `akl robot ik`.

use super::print_json;
use crate::cli::{RobotArg, RobotCommand};
use crate::exit::{CliError, CliResult};
use crate::table::{vec3, Table};
use akl_planner::{stand_off, MeshRole, StandOff};
use akl_planner::{Geometry, IkError, Robot};
use akl_tsr::rpy::rpy_from_rotation;
use akl_tsr::{Pose, PoseJson};
use serde::Serialize;

pub(super) fn run(cmd: RobotCommand) -> CliResult {
    match cmd {
        RobotCommand::Info { robot, json } => info(&robot, json),
        RobotCommand::Fk {
            joints,
            robot,
            json,
        } => fk(&joints, &robot, json),
        RobotCommand::Ik {
            pose,
            seed_joints,
            robot,
            json,
        } => ik(&pose, seed_joints.as_deref(), &robot, json),
        RobotCommand::Check(args) => super::robot_check::run(&args),
        RobotCommand::Init(args) => super::robot_init::run(&args),
        RobotCommand::Tables {
            robot,
            output,
            jobs,
            json,
        } => super::robot_tables::run(&robot, output.as_deref(), jobs, json),
    }
}

/// The robot named by `--robot`, or the built-in Panda.
pub(crate) fn load(arg: &RobotArg) -> Result<Robot, CliError> {
    match &arg.robot {
        Some(dir) => Robot::load_with(dir, &arg.package_path).map_err(CliError::input),
        None => Robot::panda().map_err(CliError::internal),
    }
}

/// Parses comma-separated numbers; the error names the flag and the bad item.
pub(super) fn numbers(text: &str, flag: &str) -> Result<Vec<f64>, CliError> {
    text.split(',')
        .map(|item| {
            let item = item.trim();
            item.parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .ok_or_else(|| CliError::input(format!("{flag}: `{item}` is not a finite number")))
        })
        .collect()
}

/// A joint list checked against the robot (length, limits).
pub(super) fn joints(text: &str, flag: &str, robot: &Robot) -> Result<Vec<f64>, CliError> {
    let q = numbers(text, flag)?;
    robot
        .check_joints(&q)
        .map_err(|e| CliError::input(format!("{flag}: {e}")))?;
    Ok(q)
}

#[derive(Serialize)]
struct JointInfo {
    name: String,
    /// A continuous joint: lower and upper are the range planned over, not limits.
    continuous: bool,
    lower: f64,
    upper: f64,
    velocity: f64,
    acceleration: f64,
    ready: f64,
}

#[derive(Serialize)]
struct LinkInfo {
    name: String,
    parent: Option<String>,
    shapes: Vec<akl_planner::LinkShape>,
    /// The URDF's mesh files of the link, collision and visual.
    meshes: Vec<MeshInfo>,
    /// How far the collision model stands off the link's meshes.
    stand_off: Option<StandOff>,
}

#[derive(Serialize)]
struct MeshInfo {
    role: MeshRole,
    uri: String,
    triangles: usize,
}

#[derive(Serialize)]
struct Info {
    name: String,
    source: String,
    ik_solver: String,
    tcp_link: String,
    flange_link: String,
    joints: Vec<JointInfo>,
    finger_joints: Vec<String>,
    open_width: f64,
    hand_links: Vec<String>,
    margins: akl_planner::CollisionConfig,
    /// Where the robot stands in the task's robot base frame (`None`: at the robot base).
    mount: Option<akl_planner::MountConfig>,
    /// The self-collision tables, and how many were read from `self_tables.bin`.
    self_tables: akl_planner::collision::TableSummary,
    links: Vec<LinkInfo>,
}

fn info(arg: &RobotArg, json: bool) -> CliResult {
    let robot = load(arg)?;
    let links = robot.links();
    let c = robot.config();
    let summary = Info {
        name: robot.name().to_string(),
        source: robot.source().to_string(),
        ik_solver: match c.ik.solver {
            akl_planner::IkSolverKind::Panda => "panda (analytic, q7 searched)".into(),
            akl_planner::IkSolverKind::Dls => "dls (damped least squares, restarts)".into(),
            akl_planner::IkSolverKind::Trac => {
                "trac (damped least squares and Levenberg-Marquardt racing, restarts)".into()
            }
        },
        tcp_link: c.tcp_link.clone(),
        flange_link: c.flange_link.clone(),
        joints: robot
            .joint_names()
            .iter()
            .enumerate()
            .map(|(i, name)| JointInfo {
                name: name.clone(),
                continuous: robot.continuous_joints()[i],
                lower: robot.joint_limits()[i][0],
                upper: robot.joint_limits()[i][1],
                velocity: robot.velocity_limits()[i],
                acceleration: robot.acceleration_limits()[i],
                ready: robot.ready()[i],
            })
            .collect(),
        finger_joints: robot.finger_joints().to_vec(),
        open_width: robot.open_width(),
        hand_links: robot
            .hand_links()
            .iter()
            .map(|&i| links[i].name.clone())
            .collect(),
        margins: c.collision.clone(),
        mount: c.mount,
        self_tables: akl_planner::collision::RobotCollision::new(&robot).table_summary(),
        links: links
            .iter()
            .enumerate()
            .map(|(i, l)| LinkInfo {
                name: l.name.clone(),
                parent: l.parent.map(|p| links[p].name.clone()),
                shapes: l.shapes.clone(),
                meshes: robot
                    .meshes()
                    .iter()
                    .filter(|m| m.link == i)
                    .map(|m| MeshInfo {
                        role: m.role,
                        uri: m.uri.clone(),
                        triangles: m.mesh.triangles.len(),
                    })
                    .collect(),
                stand_off: link_stand_off(&robot, i),
            })
            .collect(),
    };
    if json {
        return print_json(&summary);
    }
    println!(
        "{} ({}), {} arm joints, IK solver {}",
        summary.name,
        summary.source,
        summary.joints.len(),
        summary.ik_solver
    );
    println!(
        "TCP link {}, flange link {}",
        summary.tcp_link, summary.flange_link
    );
    println!();
    let mut table = Table::new([
        "#",
        "joint",
        "lower",
        "upper",
        "velocity",
        "acceleration",
        "ready",
    ]);
    for (i, j) in summary.joints.iter().enumerate() {
        let continuous = if j.continuous { " (continuous)" } else { "" };
        table.row(vec![
            (i + 1).to_string(),
            format!("{}{continuous}", j.name),
            format!("{:.4}", j.lower),
            format!("{:.4}", j.upper),
            format!("{}", j.velocity),
            format!("{}", j.acceleration),
            format!("{:.4}", j.ready),
        ]);
    }
    print!("{}", table.render());
    println!();
    println!(
        "gripper: {} (opens {} m); hand links: {}",
        summary.finger_joints.join(", "),
        summary.open_width,
        summary.hand_links.join(", ")
    );
    let m = &summary.margins;
    println!(
        "margins: arm {} m, hand {} m, held object {} m, between links {} m",
        m.arm_margin, m.hand_margin, m.held_margin, m.self_margin
    );
    match &summary.mount {
        Some(at) => println!(
            "mount: xyz {:?} m, rpy {:?} rad in the task's robot base frame",
            at.xyz, at.rpy
        ),
        None => println!("mount: at the task's robot base"),
    }
    let t = &summary.self_tables;
    println!(
        "self-collision tables: {} link pair(s), {} nodes; {}",
        t.tables,
        t.nodes,
        if t.tables == 0 {
            "none".to_string()
        } else if t.stored == t.tables {
            format!("all read from {}", akl_planner::STORED_TABLES_FILE)
        } else {
            format!(
                "{} read from {}, the rest filled as checks reach them (`akl robot tables` writes them ahead)",
                t.stored,
                akl_planner::STORED_TABLES_FILE
            )
        }
    );
    println!();
    let mut shapes = Table::new([
        "link",
        "parent",
        "collision model",
        "meshes",
        "stand-off mean / max (mm)",
    ]);
    for l in &summary.links {
        let described: Vec<String> = l.shapes.iter().map(|s| describe(&s.geometry)).collect();
        let meshes: usize = l.meshes.iter().map(|m| m.triangles).sum();
        shapes.row(vec![
            l.name.clone(),
            l.parent.clone().unwrap_or_else(|| "-".into()),
            if described.is_empty() {
                "-".into()
            } else {
                described.join("; ")
            },
            if l.meshes.is_empty() {
                "-".into()
            } else {
                format!("{} ({meshes} triangles)", l.meshes.len())
            },
            l.stand_off.map_or_else(
                || "-".into(),
                |s| format!("{:.1} / {:.1}", 1e3 * s.mean, 1e3 * s.max),
            ),
        ]);
    }
    if let Some((mean, max)) = overall(&summary.links) {
        println!(
            "collision model: per link, the hull of its collision meshes grown to hold every vertex of its collision and visual meshes; it stands off them {:.1} mm on average, {:.1} mm at most",
            1e3 * mean,
            1e3 * max
        );
    }
    print!("{}", shapes.render());
    Ok(())
}

/// How far link `link`'s grown hull stands off its meshes (sampled every 5 mm).
fn link_stand_off(robot: &Robot, link: usize) -> Option<StandOff> {
    let meshes: Vec<_> = robot.meshes().iter().filter(|m| m.link == link).collect();
    let hull = robot.links()[link]
        .shapes
        .iter()
        .find(|s| s.role == akl_planner::ShapeRole::Enclosure)?;
    stand_off(hull, &meshes, 0.005)
}

/// The mean (weighted equally per link) and largest stand-off over the links that have one.
fn overall(links: &[LinkInfo]) -> Option<(f64, f64)> {
    let all: Vec<StandOff> = links.iter().filter_map(|l| l.stand_off).collect();
    (!all.is_empty()).then(|| {
        (
            all.iter().map(|s| s.mean).sum::<f64>() / all.len() as f64,
            all.iter().map(|s| s.max).fold(0.0, f64::max),
        )
    })
}

fn describe(g: &Geometry) -> String {
    match *g {
        Geometry::RoundHull(ref h) => format!(
            "hull of {} vertices + {:.1} mm",
            h.vertices.len(),
            1e3 * h.border
        ),
        Geometry::Capsule { radius, length } => format!("capsule r {radius} × {length}"),
        Geometry::Box { size } => format!("box {}×{}×{}", size[0], size[1], size[2]),
        Geometry::Cylinder { radius, length } => format!("cylinder r {radius} × {length}"),
        Geometry::Sphere { radius } => format!("sphere r {radius}"),
    }
}

/// A pose for printing: position, quaternion [x, y, z, w] and roll-pitch-yaw in degrees.
fn pose_line(pose: &Pose) -> String {
    let q = PoseJson::from_pose(pose).q;
    let rpy = rpy_from_rotation(&pose.rotation).map(f64::to_degrees);
    format!(
        "{}  q [{:.4}, {:.4}, {:.4}, {:.4}]  rpy [{:.1}, {:.1}, {:.1}] deg",
        vec3(&pose.translation.vector),
        q[0],
        q[1],
        q[2],
        q[3],
        rpy[0],
        rpy[1],
        rpy[2]
    )
}

#[derive(Serialize)]
struct Kinematics {
    joints: Vec<f64>,
    tcp: PoseJson,
    flange: PoseJson,
}

fn fk(text: &str, arg: &RobotArg, json: bool) -> CliResult {
    let robot = load(arg)?;
    let q = joints(text, "--joints", &robot)?;
    let tcp = robot.tcp_pose(&q);
    let flange = robot.flange_pose(&q);
    if json {
        return print_json(&Kinematics {
            joints: q,
            tcp: PoseJson::from_pose(&tcp),
            flange: PoseJson::from_pose(&flange),
        });
    }
    println!("tcp     {}", pose_line(&tcp));
    println!("flange  {}", pose_line(&flange));
    Ok(())
}

fn ik(pose_text: &str, seed_text: Option<&str>, arg: &RobotArg, json: bool) -> CliResult {
    let robot = load(arg)?;
    let v = numbers(pose_text, "--pose")?;
    let [x, y, z, qx, qy, qz, qw] = v[..] else {
        return Err(CliError::input(format!(
            "--pose: expected 7 numbers x,y,z,qx,qy,qz,qw, got {}",
            v.len()
        )));
    };
    let target = PoseJson {
        p: [x, y, z],
        q: [qx, qy, qz, qw],
    }
    .to_pose()
    .map_err(|e| CliError::input(format!("--pose: {e}")))?;
    let seed = match seed_text {
        Some(text) => joints(text, "--seed-joints", &robot)?,
        None => robot.ready().to_vec(),
    };
    let q = robot.ik(&target, &seed).map_err(|e| match e {
        IkError::Unreachable => CliError::internal(format!(
            "unreachable: no configuration within the joint limits puts the TCP at {}",
            pose_line(&target)
        )),
        IkError::BadSeed(m) => CliError::input(format!("--seed-joints: {m}")),
        other => CliError::internal(other),
    })?;
    let tcp = robot.tcp_pose(&q);
    if json {
        return print_json(&Kinematics {
            flange: PoseJson::from_pose(&robot.flange_pose(&q)),
            tcp: PoseJson::from_pose(&tcp),
            joints: q,
        });
    }
    let names = robot.joint_names();
    let mut table = Table::new(["joint", "position (rad)"]);
    for (name, v) in names.iter().zip(&q) {
        table.row(vec![name.clone(), format!("{v:.6}")]);
    }
    print!("{}", table.render());
    let joined: Vec<String> = q.iter().map(|v| format!("{v:.6}")).collect();
    println!("joints  {}", joined.join(","));
    println!("tcp     {}", pose_line(&tcp));
    Ok(())
}
