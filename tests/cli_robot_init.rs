//! `akl robot init` through the binary: a stock URDF becomes a robot folder that loads.

mod common;

use common::{akl, assert_refused, json, scratch, stderr, stdout};
use std::path::Path;

#[test]
fn the_fer_urdf_becomes_a_folder_that_loads() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("robots/panda");
    let out = scratch("init-fer").join("fer");
    let package = format!("franka_description={}", repo.display());
    let urdf = repo.join("fer.urdf");
    let args = |json: bool| {
        let mut a = vec![
            "robot".to_string(),
            "init".into(),
            urdf.display().to_string(),
            "--package-path".into(),
            package.clone(),
            "-o".into(),
            out.display().to_string(),
            "--samples".into(),
            "200".into(),
        ];
        if json {
            a.push("--json".into());
        }
        a
    };
    let run = |json: bool| {
        let a = args(json);
        akl(&a.iter().map(String::as_str).collect::<Vec<_>>())
    };
    let o = run(true);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let v = json(&o);
    assert_eq!(v["config"]["tcp_link"], "fer_hand_tcp");
    assert_eq!(v["config"]["ik"]["solver"], "panda");
    assert_eq!(v["structure"]["gripper"], "parallel");
    assert!(v["load_error"].is_null());
    let info = akl(&["robot", "info", "--robot", &out.display().to_string()]);
    assert_eq!(info.status.code(), Some(0), "{}", stderr(&info));
    assert!(stdout(&info).contains("7 arm joints"), "{}", stdout(&info));
    // A second run does not overwrite the folder.
    let again = run(false);
    assert_refused(&again, &["already exists"]);
    std::fs::remove_dir_all(out.parent().unwrap()).unwrap();
}

#[test]
fn a_gripper_the_simulation_cannot_drive_is_written_but_refused_on_load() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("robots/panda");
    let dir = scratch("init-knuckle");
    // The FER with revolute fingers: no gripper the simulation can drive.
    let urdf = std::fs::read_to_string(repo.join("fer.urdf"))
        .unwrap()
        .replace(r#"type="prismatic""#, r#"type="revolute""#);
    std::fs::write(dir.join("fer.urdf"), urdf).unwrap();
    let out = dir.join("out");
    let o = akl(&[
        "robot",
        "init",
        &dir.join("fer.urdf").display().to_string(),
        "--package-path",
        &format!("franka_description={}", repo.display()),
        "-o",
        &out.display().to_string(),
        "--samples",
        "50",
    ]);
    assert_refused(&o, &["was written but does not load", "[gripper]"]);
    assert!(out.join("robot.toml").exists());
    std::fs::remove_dir_all(dir).unwrap();
}
