//! End-to-end tests of `akl task` and `akl spec` through the binary.

mod common;
use common::*;

fn truth_text() -> String {
    std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tasks/inspection.truth.json"
    ))
    .unwrap()
}

#[test]
fn task_list_shows_the_study_tasks_and_bottles() {
    let o = akl(&["task", "list"]);
    assert!(o.status.success());
    let out = stdout(&o);
    for name in ["pick_place", "inspection", "assembly", "bottles"] {
        assert!(out.contains(name), "{out}");
    }
    let o = akl(&["task", "list", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v.as_array().unwrap().len(), 4);
}

#[test]
fn task_show_prints_objects_goals_and_steps() {
    let o = akl(&["task", "show", "inspection"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(
        out.contains("scanner_2")
            && out.contains("scan(part over scanner_1, scanner_2, scanner_3)")
            && out.contains("on(part, mat)")
            && out.contains("straight line"),
        "{out}"
    );
    let o = akl(&["task", "show", "assembly", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["akl_task"], 1);
}

#[test]
fn task_show_lists_every_range_group_and_fixed_relation() {
    let o = akl(&["task", "show", "assembly"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    let range_row = out
        .lines()
        .find(|l| l.trim_start().starts_with("clamp "))
        .unwrap_or_else(|| panic!("no row for the clamp group: {out}"));
    assert!(
        range_row.contains("rail, clamp_left, clamp_right, clamp_top")
            && range_row.contains("[-0.06, 0.06]")
            && range_row.contains("[-0.2, 0.2]"),
        "{range_row}"
    );
    for name in ["shelf_1", "shelf_2", "block", "pipe"] {
        assert!(
            out.lines()
                .any(|l| l.trim_start().starts_with(&format!("{name} ")) && l.contains('[')),
            "no range row for {name}: {out}"
        );
    }
    assert!(out.contains("min_gap"), "{out}");
    assert!(
        out.contains(
            "clamp_left, clamp_right, clamp_top, rail: moved as one body by group `clamp`"
        ),
        "{out}"
    );
    assert!(out.contains("table, world: not moved"), "{out}");
    let o = akl(&["task", "show", "assembly", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["groups"]["clamp"].as_array().unwrap().len(), 4);
    assert_eq!(v["randomize"]["clamp"]["yaw"][1], 0.2);
    assert_eq!(v["min_gap"], 0.055);
    assert_eq!(v["goals"][1]["inside"]["holder"], "clamp_top");
}

/// A task file with a bad value fails with exit code 2 and names the file and the field.
#[test]
fn bad_task_file_values_name_the_field_and_exit_2() {
    let dir = scratch("bad-task");
    let good = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tasks/inspection.json"
    ))
    .unwrap();
    let cases = [
        (
            "height",
            "\"height\": [0.02, 0.08]",
            "\"height\": [0.08, 0.02]",
            "goals[0] (scan).height",
        ),
        (
            "min_gap",
            "\"min_gap\": 0.055",
            "\"min_gap\": -1",
            "min_gap",
        ),
        (
            "group",
            "[\"scanner_1\", \"scanner_2\", \"scanner_3\"]},",
            "[\"scanner_1\", \"part\", \"scanner_3\"]},",
            "groups.scanners[1]",
        ),
        (
            "range",
            "\"scanners\": {\"x\": [-0.08, 0.08]",
            "\"scanners\": {\"x\": [0.08, -0.08]",
            "randomize.scanners.x",
        ),
    ];
    for (name, from, to, field) in cases {
        let text = good.replacen(from, to, 1);
        assert_ne!(text, good, "{name}: the edit did not apply");
        let path = dir.join(format!("{name}.json"));
        std::fs::write(&path, text).unwrap();
        let o = akl(&["task", "show", path.to_str().unwrap()]);
        assert_refused(&o, &[path.to_str().unwrap(), field]);
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn task_show_reads_a_task_file_by_path() {
    let o = akl(&["task", "show", "tasks/pick_place.json"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

#[test]
fn an_unknown_task_is_bad_input() {
    let o = akl(&["task", "show", "juggling"]);
    assert_refused(&o, &["unknown task `juggling`"]);
}

#[test]
fn spec_check_passes_the_inspection_truth_with_four_keyframes() {
    let o = akl(&["spec", "check", "tasks/inspection.truth.json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.contains("keyframes:   4"), "{out}");
    assert!(out.contains("move_in_line on keyframes 1→2"), "{out}");
    let o = akl(&["spec", "check", "tasks/inspection.truth.json", "--json"]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["keyframes"], 4);
    assert_eq!(v["constraint"], 2);
}

#[test]
fn spec_show_prints_a_row_per_keyframe() {
    let o = akl(&["spec", "show", "tasks/assembly.truth.json"]);
    assert!(o.status.success());
    let out = stdout(&o);
    assert_eq!(
        out.lines().filter(|l| l.contains("combined")).count(),
        2,
        "{out}"
    );
}

/// Each broken spec fails with exit code 2 and one line naming the file and the problem.
#[test]
fn broken_specs_give_one_clear_line_and_exit_code_2() {
    let dir = scratch("broken");
    let good = truth_text();
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "malformed",
            good.replacen("\"keyframes\": [", "\"keyframes\": [[", 1),
            "line",
        ),
        (
            "version",
            good.replacen("\"akl_spec\": 1", "\"akl_spec\": 2", 1),
            "unsupported spec version 2",
        ),
        (
            "nan",
            good.replacen("[-0.005, 0.005]", "[NaN, 0.005]", 1),
            "non-finite number `NaN`",
        ),
        (
            "inverted",
            good.replacen("[-0.005, 0.005]", "[0.005, -0.005]", 1),
            "min 0.005 > max -0.005",
        ),
        (
            "reference",
            good.replacen("\"reference\": \"part\"", "\"reference\": \"widget\"", 1),
            "unknown reference object `widget`",
        ),
    ];
    for (name, text, expected) in cases {
        assert_ne!(text, good, "{name}: the edit did not apply");
        let path = dir.join(format!("{name}.json"));
        std::fs::write(&path, text).unwrap();
        let o = akl(&["spec", "check", path.to_str().unwrap()]);
        let err = assert_refused(&o, &[path.to_str().unwrap(), expected]);
        assert_eq!(err.lines().count(), 1, "{name}: {err}");
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_missing_spec_file_is_bad_input() {
    let o = akl(&["spec", "check", "no/such/spec.json"]);
    assert_refused(&o, &["no/such/spec.json"]);
}

#[test]
fn a_reader_that_went_away_ends_akl_quietly() {
    use std::os::fd::{FromRawFd, OwnedFd};
    use std::os::unix::process::ExitStatusExt;
    let mut fds = [0; 2];
    // SAFETY: pipe writes two new file descriptors into the array given.
    assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0, "pipe failed");
    // SAFETY: both descriptors were just opened and are owned by nobody else.
    let (reader, writer) = unsafe { (OwnedFd::from_raw_fd(fds[0]), OwnedFd::from_raw_fd(fds[1])) };
    drop(reader);
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_akl"))
        .args(["task", "list"])
        .stdout(writer)
        .output()
        .expect("the akl binary runs");
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
    assert_eq!(o.status.signal(), Some(libc::SIGPIPE), "{:?}", o.status);
}

/// The pick_place task file with `block_a` moved by `dz` metres, written to `dir/name`.
fn pick_place_with_block_a_moved(dir: &std::path::Path, name: &str, dz: f64) -> String {
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tasks/pick_place.json"),
    )
    .unwrap();
    let mut task: serde_json::Value = serde_json::from_str(&text).unwrap();
    for o in task["world"]["objects"].as_array_mut().unwrap() {
        if o["name"] == "block_a" {
            let z = o["pose"]["p"][2].as_f64().unwrap();
            o["pose"]["p"][2] = (z + dz).into();
        }
    }
    let path = dir.join(name);
    std::fs::write(&path, task.to_string()).unwrap();
    path.to_str().unwrap().to_string()
}

#[test]
fn a_scene_that_does_not_stand_still_or_interpenetrates_is_refused_at_load() {
    let dir = scratch("task-unsettled");
    let floating = pick_place_with_block_a_moved(&dir, "floating.json", 0.05);
    let o = akl(&["task", "show", &floating]);
    assert_refused(
        &o,
        &["block_a does not stay where it is put", "fell 5.0 cm"],
    );
    let sunk = pick_place_with_block_a_moved(&dir, "sunk.json", -0.01);
    let o = akl(&["task", "show", &sunk]);
    assert_refused(&o, &["`shelf_1` and `block_a` interpenetrate"]);
    // Every command that loads a task checks it.
    let o = akl(&[
        "execute",
        "tasks/pick_place.truth.json",
        "--task",
        &floating,
    ]);
    assert_refused(&o, &["block_a does not stay"]);
}

#[test]
fn a_task_with_a_mesh_object_runs_and_a_bad_mesh_is_named() {
    let o = akl(&["task", "show", "tasks/examples/hex_part.json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stdout(&o).contains("mesh hex_prism.stl (0.058×0.050×0.070)"),
        "{}",
        stdout(&o)
    );
    let o = akl(&[
        "execute",
        "tasks/examples/hex_part.truth.json",
        "--task",
        "tasks/examples/hex_part.json",
        "--randomize",
        "4",
    ]);
    assert!(o.status.success(), "{}{}", stdout(&o), stderr(&o));

    let dir = scratch("task-bad-mesh");
    let text = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tasks/examples/hex_part.json"),
    )
    .unwrap();
    std::fs::write(dir.join("missing.json"), &text).unwrap();
    let o = akl(&["task", "show", dir.join("missing.json").to_str().unwrap()]);
    assert_refused(&o, &["world.objects[4] (part).shape", "hex_prism.stl"]);
    std::fs::write(dir.join("hex_prism.stl"), "solid x\nendsolid x\n").unwrap();
    let o = akl(&["task", "show", dir.join("missing.json").to_str().unwrap()]);
    assert_refused(&o, &["hex_prism.stl"]);
}
