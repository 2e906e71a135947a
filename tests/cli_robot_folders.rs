//! Robot folders through the binary: a stock-like description's problems are refused when the
//! robot is loaded (exit 2), each named, all at once.

mod common;

use common::{akl, assert_refused, json, scratch, stderr, stdout};
use std::path::{Path, PathBuf};

/// A copy of the built-in Panda's folder with its URDF and `robot.toml` edited, the meshes
/// found in the repository's `robots/panda`.
fn panda_folder(
    name: &str,
    urdf_name: &str,
    edit_urdf: impl Fn(&str) -> String,
    edit_toml: impl Fn(&str) -> String,
) -> PathBuf {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("robots/panda");
    let dir = scratch(name);
    let urdf = std::fs::read_to_string(repo.join("fer.urdf")).unwrap();
    std::fs::write(dir.join(urdf_name), edit_urdf(&urdf)).unwrap();
    let toml = std::fs::read_to_string(repo.join("robot.toml"))
        .unwrap()
        .replace("urdf = \"fer.urdf\"", &format!("urdf = \"{urdf_name}\""))
        .replace(
            "franka_description = \".\"",
            &format!("franka_description = {:?}", repo.display().to_string()),
        );
    std::fs::write(dir.join("robot.toml"), edit_toml(&toml)).unwrap();
    dir
}

fn info(dir: &Path) -> std::process::Output {
    akl(&["robot", "info", "--robot", dir.to_str().unwrap()])
}

#[test]
fn a_revolute_finger_is_refused_when_the_robot_is_loaded() {
    let dir = panda_folder(
        "folder-knuckle",
        "fer.urdf",
        |u| {
            u.replace(
                r#"<joint name="fer_finger_joint1" type="prismatic">"#,
                r#"<joint name="fer_finger_joint1" type="revolute">"#,
            )
        },
        str::to_string,
    );
    let out = info(&dir);
    assert_refused(
        &out,
        &[
            "robot.toml: [gripper]",
            "`fer_leftfinger` turns",
            "parallel linkage",
        ],
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn every_contradiction_with_the_urdf_is_listed() {
    let dir = panda_folder("folder-contradictions", "fer.urdf", str::to_string, |t| {
        t.replace(
            "velocity_limits = [2.175, 2.175,",
            "velocity_limits = [10.0, 2.175,",
        )
        .replace("flange_link = \"fer_link8\"", "flange_link = \"tool0\"")
    });
    let out = info(&dir);
    let e = assert_refused(&out, &["2 problems"]);
    assert!(
        e.contains("10 rad/s for `fer_joint1` exceeds its URDF limit of 2.175"),
        "{e}"
    );
    assert!(
        e.contains("flange_link: `tool0` is not a link of the URDF"),
        "{e}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_xacro_file_is_named_with_the_command_that_expands_it() {
    let dir = panda_folder(
        "folder-xacro",
        "fer.urdf.xacro",
        |u| {
            u.replacen(
                "<robot ",
                r#"<robot xmlns:xacro="http://www.ros.org/wiki/xacro" "#,
                1,
            )
        },
        str::to_string,
    );
    let out = info(&dir);
    assert_refused(
        &out,
        &["fer.urdf.xacro", "xacro robot.urdf.xacro > robot.urdf"],
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_folder_without_robot_toml_is_named() {
    let dir = scratch("folder-no-toml");
    let out = info(&dir);
    assert_refused(
        &out,
        &[
            &dir.join("robot.toml").display().to_string(),
            "robots/README.md",
        ],
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// `akl robot tables` writes a folder's self-collision tables, which the folder's robot then
/// reads (the same bytes as the built-in Panda's, whose folder it copies); a corrupt file is
/// refused, naming it.
#[test]
fn a_folder_reads_the_tables_written_for_it_and_refuses_a_corrupt_file() {
    let dir = panda_folder("folder-tables", "fer.urdf", str::to_string, str::to_string);
    let before = stdout(&info(&dir));
    assert!(
        before.contains("0 read from self_tables.bin, the rest filled as checks reach them"),
        "{before}"
    );
    let out = akl(&[
        "robot",
        "tables",
        "--robot",
        dir.to_str().unwrap(),
        "--json",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(json(&out)["tables"], 3);
    let file = dir.join("self_tables.bin");
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("robots/panda/self_tables.bin");
    assert!(
        std::fs::read(&file).unwrap() == std::fs::read(repo).unwrap(),
        "the folder's tables differ from robots/panda/self_tables.bin"
    );
    let after = stdout(&info(&dir));
    assert!(after.contains("all read from self_tables.bin"), "{after}");
    let bytes = std::fs::read(&file).unwrap();
    std::fs::write(&file, &bytes[..bytes.len() - 3]).unwrap();
    let out = info(&dir);
    assert_refused(
        &out,
        &["self_tables.bin: truncated or corrupt: the file ends within"],
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// The built-in Panda's tables go to a file named with --output, and are computed by at
/// least one thread (nothing is written otherwise).
#[test]
fn the_built_in_robots_tables_need_an_output_file_and_a_thread() {
    let out = akl(&["robot", "tables"]);
    assert_refused(&out, &["--output"]);
    let dir = scratch("tables-no-thread");
    let file = dir.join("self_tables.bin");
    let out = akl(&[
        "robot",
        "tables",
        "-o",
        file.to_str().unwrap(),
        "--jobs",
        "0",
    ]);
    assert_refused(&out, &["--jobs"]);
    assert!(!file.exists());
    std::fs::remove_dir_all(dir).unwrap();
}
