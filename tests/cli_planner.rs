//! End-to-end tests of `akl robot` and `akl plan` through the binary.

use std::process::Output;

mod common;
use common::*;

/// Runs from a directory without the repository, to show the robot is built in.
fn akl_elsewhere(args: &[&str]) -> Output {
    akl_in(&std::env::temp_dir(), args)
}

const READY: &str =
    "0,-0.7853981633974483,0,-2.356194490192345,0,1.5707963267948966,0.7853981633974483";

#[test]
fn robot_info_lists_joints_limits_and_links() {
    let o = akl_elsewhere(&["robot", "info"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(
        out.contains("fer_joint7") && out.contains("-3.0718") && out.contains("hull of"),
        "{out}"
    );
    assert!(out.contains("stands off them"), "{out}");
    let v = json(&akl(&["robot", "info", "--json"]));
    assert_eq!(v["joints"].as_array().unwrap().len(), 7);
    assert_eq!(v["tcp_link"], "fer_hand_tcp");
    // Every meshed link reports how far its model stands off its meshes.
    for link in v["links"].as_array().unwrap() {
        if !link["meshes"].as_array().unwrap().is_empty() {
            let max = link["stand_off"]["max"].as_f64().unwrap();
            assert!((0.0..0.02).contains(&max), "{link}");
        }
    }
}

#[test]
fn fk_of_the_ready_pose_is_the_published_reference() {
    let o = akl(&["robot", "fk", "--joints", READY]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(
        out.contains("flange  [0.307, ") && out.contains("0.000, 0.590]"),
        "{out}"
    );
    let v = json(&akl(&["robot", "fk", "--joints", READY, "--json"]));
    let p = v["flange"]["p"].as_array().unwrap();
    assert!((p[0].as_f64().unwrap() - 0.30689).abs() < 1e-5);
    assert!((p[2].as_f64().unwrap() - 0.59028).abs() < 1e-5);
}

#[test]
fn ik_returns_joints_whose_fk_is_the_pose() {
    let v = json(&akl(&[
        "robot",
        "ik",
        "--pose",
        "0.45,0.25,0.2,1,0,0,0",
        "--json",
    ]));
    let joints: Vec<String> = v["joints"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap().to_string())
        .collect();
    let back = json(&akl(&[
        "robot",
        "fk",
        "--joints",
        &joints.join(","),
        "--json",
    ]));
    let p = back["tcp"]["p"].as_array().unwrap();
    let expected = [0.45, 0.25, 0.2];
    for (got, want) in p.iter().zip(expected) {
        assert!((got.as_f64().unwrap() - want).abs() < 1e-6);
    }
    let seeded = akl(&[
        "robot",
        "ik",
        "--pose",
        "0.45,0.25,0.2,1,0,0,0",
        "--seed-joints",
        READY,
    ]);
    assert!(seeded.status.success(), "{}", stderr(&seeded));
}

#[test]
fn an_unreachable_pose_says_so_with_exit_code_1() {
    let o = akl(&["robot", "ik", "--pose", "1.5,0,0.5,1,0,0,0"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("unreachable"), "{}", stderr(&o));
}

#[test]
fn malformed_robot_input_is_bad_input() {
    for (args, expected) in [
        (
            vec!["robot", "fk", "--joints", "0,0,0"],
            "expected 7 joint values",
        ),
        (
            vec!["robot", "fk", "--joints", "0,0,0,x,0,0,0"],
            "`x` is not a finite number",
        ),
        (
            vec!["robot", "fk", "--joints", "0,0,0,0,0,0,0"],
            "outside its limits",
        ),
        (
            vec!["robot", "ik", "--pose", "0.4,0,0.3,0,0,0,2"],
            "not unit length",
        ),
        (
            vec!["robot", "ik", "--pose", "0.4,0,0.3"],
            "expected 7 numbers",
        ),
        (
            vec!["robot", "info", "--robot", "no/such/robot"],
            "no/such/robot/robot.toml",
        ),
    ] {
        let o = akl(&args);
        assert_refused(&o, &[expected]);
    }
}

#[test]
fn another_robot_folder_is_loaded_at_run_time() {
    let dir = scratch("robot");
    let panda = concat!(env!("CARGO_MANIFEST_DIR"), "/robots/panda");
    let toml = std::fs::read_to_string(format!("{panda}/robot.toml")).unwrap();
    std::fs::write(
        dir.join("robot.toml"),
        toml.replace("name = \"panda\"", "name = \"numerical_panda\"")
            .replace("solver = \"panda\"", "solver = \"dls\"")
            .replace("franka_description = \".\"", ""),
    )
    .unwrap();
    std::fs::copy(format!("{panda}/fer.urdf"), dir.join("fer.urdf")).unwrap();
    let dir_arg = dir.to_str().unwrap();
    // The meshes are not in the copy: the package must be found elsewhere.
    let o = akl(&["robot", "info", "--robot", dir_arg]);
    assert_refused(&o, &["fer_link0", "--package-path"]);
    let package = format!("franka_description={panda}");
    let o = akl(&[
        "robot",
        "info",
        "--robot",
        dir_arg,
        "--package-path",
        &package,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("numerical_panda") && stdout(&o).contains("dls"));
    let o = akl(&[
        "robot",
        "ik",
        "--pose",
        "0.45,0.25,0.2,1,0,0,0",
        "--robot",
        dir_arg,
        "--package-path",
        &package,
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // ROS_PACKAGE_PATH finds the package too: a folder holding `franka_description`.
    let packages = dir.join("share");
    std::fs::create_dir_all(&packages).unwrap();
    std::os::unix::fs::symlink(panda, packages.join("franka_description")).unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_akl"))
        .args(["robot", "info", "--robot", dir_arg])
        .env("ROS_PACKAGE_PATH", &packages)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("fer_link5"), "{}", stdout(&o));
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn plan_prints_segments_and_writes_the_plan() {
    let dir = scratch("plan");
    let out = dir.join("plan.json");
    let o = akl(&[
        "plan",
        "tasks/inspection.truth.json",
        "--task",
        "inspection",
        "--seed",
        "3",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = stdout(&o);
    for word in [
        "free",
        "approach",
        "lift",
        "line",
        "retreat",
        "planning (ms)",
        "close on part",
    ] {
        assert!(text.contains(word), "{word}: {text}");
    }
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(plan["akl_plan"], 1);
    assert_eq!(plan["joint_names"].as_array().unwrap().len(), 7);
    assert_eq!(plan["events"].as_array().unwrap().len(), 2);
    let summary = json(&akl(&[
        "plan",
        "tasks/assembly.truth.json",
        "--task",
        "assembly",
        "--json",
    ]));
    let kinds: Vec<&str> = summary["segments"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| s["kind"].as_str().unwrap())
        .collect();
    assert!(kinds.contains(&"line"), "{kinds:?}");
    assert!(summary["duration"].as_f64().unwrap() > 0.0);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_budget_plans_more_candidates_keeps_the_quickest_and_is_reproducible() {
    let plan = |budget: &str| {
        json(&akl(&[
            "plan",
            "tasks/pick_place.truth.json",
            "--task",
            "pick_place",
            "--budget",
            budget,
            "--json",
        ]))
    };
    let single = plan("0");
    assert_eq!(single["candidates"], 1);
    assert_eq!(single["chosen_candidate"], 0);
    assert_eq!(single["duration"], single["nominal_duration"]);
    let searched = plan("100");
    // 1 + 100 ms / (3.8 ms x 4 keyframes)
    assert_eq!(searched["candidates"], 7);
    let (best, nominal) = (
        searched["duration"].as_f64().unwrap(),
        searched["nominal_duration"].as_f64().unwrap(),
    );
    assert!(best <= nominal, "{best} > {nominal}");
    assert_eq!(nominal, single["duration"].as_f64().unwrap());
    let again = plan("100");
    assert_eq!(again["duration"], searched["duration"]);
    assert_eq!(again["chosen_candidate"], searched["chosen_candidate"]);
}

#[test]
fn plan_input_errors_are_exit_code_2_and_planning_failures_exit_code_1() {
    let o = akl(&["plan", "no/such/spec.json", "--task", "inspection"]);
    assert_refused(&o, &["no/such/spec.json"]);
    let o = akl(&["plan", "tasks/inspection.truth.json", "--task", "juggling"]);
    assert_refused(&o, &["unknown task `juggling`"]);
    let o = akl(&[
        "plan",
        "tasks/inspection.truth.json",
        "--task",
        "inspection",
        "-o",
        "no/such/folder/plan.json",
    ]);
    assert_refused(
        &o,
        &["no/such/folder/plan.json: cannot write the plan there"],
    );
    let o = akl(&[
        "plan",
        "tasks/inspection.truth.json",
        "--task",
        "pick_place",
        "--any-task",
    ]);
    assert_refused(&o, &["unknown reference object"]);

    let dir = scratch("unplannable");
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tasks/inspection.truth.json"
    ))
    .unwrap();
    let far = text.replacen("\"p\": [0.0, 0.0, 0.0705]", "\"p\": [2.0, 0.0, 0.0705]", 1);
    assert_ne!(far, text);
    let spec = dir.join("far.json");
    std::fs::write(&spec, far).unwrap();
    let o = akl(&["plan", spec.to_str().unwrap(), "--task", "inspection"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("keyframe 3") && err.contains("unreachable"),
        "{err}"
    );
    assert_eq!(err.lines().count(), 1, "{err}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_speed_scale_slows_the_plan_and_the_report_records_it() {
    let duration = |scale: &str| {
        let o = akl(&[
            "plan",
            "tasks/pick_place.truth.json",
            "--task",
            "pick_place",
            "--speed-scale",
            scale,
            "--json",
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let v = json(&o);
        assert_eq!(
            v["speed_scale"].as_f64().unwrap(),
            scale.parse::<f64>().unwrap()
        );
        v["duration"].as_f64().unwrap()
    };
    let (full, half) = (duration("1"), duration("0.5"));
    // The whole plan is played twice as long.
    assert!(
        (half - 2.0 * full).abs() < 1e-6 * full,
        "{full} s, then {half} s"
    );
    let o = akl(&[
        "execute",
        "tasks/pick_place.truth.json",
        "--task",
        "pick_place",
        "--speed-scale",
        "0.5",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(json(&o)["settings"]["speed_scale"], 0.5);
    for bad in ["0", "1.5", "fast"] {
        let o = akl(&[
            "plan",
            "tasks/pick_place.truth.json",
            "--task",
            "pick_place",
            "--speed-scale",
            bad,
        ]);
        assert_refused(&o, &["--speed-scale"]);
    }
}

/// A problem file of two scenes: an empty one, and one where a wall stands between the start
/// and a goal (joint 1 turned by 1.2 rad) and across another (turned by 0.6 rad).
fn bench_problems(dir: &std::path::Path) -> std::path::PathBuf {
    let start = "[0, -0.785, 0, -2.356, 0, 1.571, 0.785]";
    let goal = "[1.2, -0.785, 0, -2.356, 0, 1.571, 0.785]";
    let text = format!(
        r#"{{"scenes": {{
              "empty": [],
              "wall": [{{"name": "wall", "kind": "box", "position": [0.4, 0.2, 0.55],
                        "quat_xyzw": [0, 0, 0, 1], "euler_xyz": [0, 0, 0],
                        "half_extents": [0.2, 0.01, 0.35]}},
                      {{"name": "ball", "kind": "sphere", "position": [-0.6, 0.6, 0.3], "radius": 0.05}},
                      {{"name": "can", "kind": "cylinder", "position": [0.3, 0.0, 1.2],
                        "radius": 0.05, "length": 0.2}}]}},
            "problems": [
              {{"set": "open", "id": "open/1", "scene": "empty", "start": {start}, "goal": {goal}}},
              {{"set": "walled", "id": "walled/1", "scene": "wall", "start": {start}, "goal": {goal}}},
              {{"set": "walled", "id": "walled/2", "scene": "wall", "start": {start},
                "goal": [0.6, -0.785, 0, -2.356, 0, 1.571, 0.785]}}]}}"#
    );
    let path = dir.join("problems.json");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn bench_planning_solves_each_valid_problem_and_writes_the_peer_runner_records() {
    let dir = scratch("bench-planning");
    let problems = bench_problems(&dir);
    let file = problems.to_str().unwrap();
    let o = akl(&["bench", "planning", file, "--seeds", "2", "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v = json(&o);
    let records = v.as_array().unwrap();
    assert_eq!(records.len(), 3);
    let fields = |r: &serde_json::Value| {
        let mut k: Vec<String> = r.as_object().unwrap().keys().cloned().collect();
        k.sort();
        k
    };
    assert_eq!(
        fields(&records[0]),
        [
            "goal_in_limits",
            "goal_valid",
            "id",
            "runs",
            "set",
            "start_in_limits",
            "start_valid",
            "straight_edge_free"
        ]
    );
    assert_eq!(
        fields(&records[0]["runs"][0]),
        [
            "found",
            "iterations",
            "length",
            "seed",
            "time_ns",
            "wall_ns",
            "waypoints"
        ]
    );
    // In the empty scene the straight edge is free and taken at once; the wall blocks it.
    assert_eq!(records[0]["straight_edge_free"], true);
    assert_eq!(records[0]["runs"][0]["iterations"], 0);
    assert_eq!(records[1]["straight_edge_free"], false);
    for r in &records[..2] {
        let runs = r["runs"].as_array().unwrap();
        assert_eq!(runs.len(), 2);
        assert!(runs.iter().all(|run| run["found"] == true), "{r}");
    }
    assert!(records[1]["runs"][0]["iterations"].as_u64().unwrap() > 0);
    // The second walled goal puts the forearm through the wall: judged, not run.
    let last = &records[2];
    assert_eq!(
        (&last["start_valid"], &last["goal_valid"]),
        (&true.into(), &false.into())
    );
    assert!(last["runs"].as_array().unwrap().is_empty());
    assert_eq!(last["straight_edge_free"], serde_json::Value::Null);
    // The text names the sets, and --against compares with a peer's records of the same file.
    let peer = dir.join("peer.json");
    std::fs::write(&peer, &o.stdout).unwrap();
    let o = akl(&[
        "bench",
        "planning",
        file,
        "--seeds",
        "1",
        "--against",
        peer.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(
        out.contains("open") && out.contains("walled") && out.contains("all"),
        "{out}"
    );
    assert!(out.contains("both valid") && out.contains("×"), "{out}");
    assert!(out.contains("walled/2  goal: fer_link5 with wall"), "{out}");
    // --set keeps one set.
    let v = json(&akl(&[
        "bench", "planning", file, "--seeds", "1", "--set", "open", "--json",
    ]));
    assert_eq!(v.as_array().unwrap().len(), 1);
}

#[test]
fn bench_planning_refuses_bad_problem_files_naming_the_problem() {
    let dir = scratch("bench-planning-bad");
    let problems = bench_problems(&dir);
    let text = std::fs::read_to_string(&problems).unwrap();
    let cases = [
        (
            text.replace("\"scene\": \"empty\"", "\"scene\": \"nowhere\""),
            "problem open/1: scene \"nowhere\"",
        ),
        (
            text.replace("\"radius\": 0.05}", "\"radius\": 0}"),
            "scene wall, obstacle ball: radius 0",
        ),
        (
            text.replace(
                "\"goal\": [1.2, -0.785, 0, -2.356, 0, 1.571, 0.785]",
                "\"goal\": [1.2]",
            ),
            "goal has 1 joint values",
        ),
        (
            text.replace("\"kind\": \"sphere\"", "\"kind\": \"cone\""),
            "bad3.json: line",
        ),
    ];
    for (i, (bad, expected)) in cases.iter().enumerate() {
        let path = dir.join(format!("bad{i}.json"));
        std::fs::write(&path, bad).unwrap();
        let o = akl(&["bench", "planning", path.to_str().unwrap()]);
        assert_refused(&o, &[expected]);
    }
    let file = problems.to_str().unwrap();
    for (args, expected) in [
        (vec!["--seeds", "0"], "--seeds"),
        (vec!["--max-iterations", "0"], "--max-iterations"),
        (vec!["--set", "nothing"], "--set nothing"),
        (
            vec!["--against", "/nonexistent/peer.json"],
            "peer.json: cannot read",
        ),
    ] {
        let mut all = vec!["bench", "planning", file];
        all.extend(args);
        let o = akl(&all);
        assert_refused(&o, &[expected]);
    }
}
