//! `akl robot info`, `akl robot fk` and `akl robot ik`.

use super::print_json;
use crate::cli::{RobotArg, RobotCommand};
use crate::exit::{CliError, CliResult};
use crate::table::{vec3, Table};
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
    }
}

/// The robot named by `--robot`, or the built-in Panda.
pub(crate) fn load(arg: &RobotArg) -> Result<Robot, CliError> {
    match &arg.robot {
        Some(dir) => Robot::load(dir).map_err(CliError::input),
        None => Robot::panda().map_err(CliError::internal),
    }
}

/// Parses comma-separated numbers; the error names the flag and the bad item.
fn numbers(text: &str, flag: &str) -> Result<Vec<f64>, CliError> {
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
fn joints(text: &str, flag: &str, robot: &Robot) -> Result<Vec<f64>, CliError> {
    let q = numbers(text, flag)?;
    robot
        .check_joints(&q)
        .map_err(|e| CliError::input(format!("{flag}: {e}")))?;
    Ok(q)
}

#[derive(Serialize)]
struct JointInfo {
    name: String,
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
    margins: akl_planner::config::CollisionConfig,
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
            akl_planner::config::IkSolverKind::Panda => "panda (analytic, q7 searched)".into(),
            akl_planner::config::IkSolverKind::Dls => "dls (damped least squares, restarts)".into(),
        },
        tcp_link: c.tcp_link.clone(),
        flange_link: c.flange_link.clone(),
        joints: robot
            .joint_names()
            .iter()
            .enumerate()
            .map(|(i, name)| JointInfo {
                name: name.clone(),
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
        links: links
            .iter()
            .map(|l| LinkInfo {
                name: l.name.clone(),
                parent: l.parent.map(|p| links[p].name.clone()),
                shapes: l.shapes.clone(),
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
        table.row(vec![
            (i + 1).to_string(),
            j.name.clone(),
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
    println!();
    let mut shapes = Table::new(["link", "parent", "collision shapes"]);
    for l in &summary.links {
        let described: Vec<String> = l.shapes.iter().map(|s| describe(&s.geometry)).collect();
        shapes.row(vec![
            l.name.clone(),
            l.parent.clone().unwrap_or_else(|| "-".into()),
            if described.is_empty() {
                "-".into()
            } else {
                described.join("; ")
            },
        ]);
    }
    print!("{}", shapes.render());
    Ok(())
}

fn describe(g: &Geometry) -> String {
    match *g {
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
