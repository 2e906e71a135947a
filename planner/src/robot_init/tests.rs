use super::*;
use crate::robot::quirks::ARM;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("akl-init-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn options() -> InitOptions {
    InitOptions {
        samples: 200,
        seed: 1,
    }
}

/// The Panda's URDF as Franka publishes it: the guess matches the built-in folder where that
/// was measured, and the written folder loads.
#[test]
fn the_fer_is_guessed_as_the_built_in_panda_is_set_up() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../robots/panda");
    let packages = [PackagePath {
        name: "franka_description".into(),
        dir: repo.clone(),
    }];
    let out = scratch("fer").join("fer");
    let g = guess(&repo.join("fer.urdf"), &packages, &out, &options()).unwrap();
    assert_eq!(g.config.tcp_link, "fer_hand_tcp");
    assert!(g.tcp.added.is_none());
    assert_eq!(g.config.flange_link, "fer_link8");
    assert_eq!(g.config.gripper.joints, ["fer_finger_joint1"]);
    assert!((g.config.gripper.open_width - 0.08).abs() < 1e-12);
    assert_eq!(g.config.ik.solver, IkSolverKind::Panda);
    assert_eq!(
        g.config.gripper.hand_links,
        ["fer_hand", "fer_leftfinger", "fer_rightfinger"]
    );
    assert_eq!(g.config.collision.mount_links, ["fer_link0", "fer_link1"]);
    assert_eq!(g.config.velocity_limits[0], 2.175);
    write(&g, &out).unwrap();
    let robot = Robot::load_with(&out, &packages).unwrap();
    let tcp = robot.tcp_pose(robot.ready());
    assert!((tcp.rotation * Vector3::z()).z < -0.99, "{tcp:?}");
    assert!(matches!(write(&g, &out), Err(InitError::Exists(_))));
    std::fs::remove_dir_all(out.parent().unwrap()).unwrap();
}

use akl_tsr::nalgebra::Vector3;

/// A URDF without a TCP link gets one between the pads, written into the folder's copy.
#[test]
fn a_tcp_link_is_added_between_the_pads_when_the_urdf_has_none() {
    let dir = scratch("arm6");
    let urdf = ARM.replace(
        r#"<joint name="tcp_joint" type="fixed"><parent link="hand"/><child link="tcp"/>
    <origin xyz="0 0 0.07"/></joint>
  <link name="tcp"/>"#,
        "",
    );
    assert!(!urdf.contains("tcp_joint"));
    std::fs::write(dir.join("arm6.urdf"), &urdf).unwrap();
    let out = dir.join("out");
    let g = guess(&dir.join("arm6.urdf"), &[], &out, &options()).unwrap();
    assert_eq!(g.config.tcp_link, "akl_tcp");
    assert!(g.tcp.added.is_some());
    assert_eq!(
        (g.tcp.xyz, g.tcp.rpy),
        ([0.0, 0.0, 0.07], [0.0; 3]),
        "{:?}",
        g.tcp
    );
    assert_eq!(g.config.gripper.joints, ["left_joint"]);
    assert_eq!(g.config.ik.solver, IkSolverKind::Trac);
    write(&g, &out).unwrap();
    let robot = Robot::load(&out).unwrap();
    assert_eq!(robot.links()[robot.tcp_link()].name, "akl_tcp");
    assert!(robot.continuous_joints()[0]);
    let written = std::fs::read_to_string(out.join("robot.toml")).unwrap();
    assert!(
        written.starts_with("# Written by `akl robot init`"),
        "{written}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_xacro_file_is_refused_with_the_command_that_expands_it() {
    let e = guess(
        Path::new("robot.urdf.xacro"),
        &[],
        Path::new("out"),
        &options(),
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("xacro robot.urdf.xacro > robot.urdf"), "{e}");
}
