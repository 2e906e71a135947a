//! Grounding a release on a large support through the `akl` binary, the real detector and
//! dialogue: a block slid 40 cm along a large tracked table and let go there, 28 cm from the
//! table's centre, is grounded on the table — from a recording without shapes (the rule for
//! unknown shapes), with shapes declared in its header (the task world's support rule), and
//! with the table given as a mesh file.

mod common;

use common::{akl_in, assert_refused, json, scratch, stderr};
use std::io::Write;
use std::path::Path;
use std::process::{Command, Output, Stdio};

/// Recording rate (Hz).
const RATE: f64 = 100.0;
/// Where the block starts, and where it is slid to (its centre; it is 5 cm tall, on a table
/// whose top is at z = 0).
const START: [f64; 3] = [0.55, 0.2, 0.025];
const END: [f64; 3] = [0.55, -0.2, 0.025];

/// One frame line: the tool centre point at `tcp` (pointing down), the gripper, the block at
/// `block`, the table and a flat mat that stay put.
fn frame(t: f64, tcp: [f64; 3], closed: bool, block: [f64; 3]) -> String {
    let pose =
        |p: [f64; 3], q: &str| format!(r#"{{"p": [{}, {}, {}], "q": {q}}}"#, p[0], p[1], p[2]);
    format!(
        r#"{{"t": {t:.2}, "ee": {}, "gripper": "{}", "objects": {{"block": {}, "mat": {}, "table": {}}}}}"#,
        pose(tcp, "[1, 0, 0, 0]"),
        if closed { "closed" } else { "open" },
        pose(block, "[0, 0, 0, 1]"),
        pose([0.1, -0.45, 0.005], "[0, 0, 0, 1]"),
        pose([0.35, 0.0, -0.02], "[0, 0, 0, 1]"),
    )
}

/// Minimum-jerk progress at fraction `s` of a move.
fn smooth(s: f64) -> f64 {
    s * s * s * (10.0 - 15.0 * s + 6.0 * s * s)
}

/// The demonstration after `header`: the hand swings down onto the block along a curve,
/// grasps it, slides it 40 cm in a straight line along the table, lets go and swings up.
fn stream(header: &str) -> String {
    let mut lines = vec![header.to_string()];
    let mut t = 0.0;
    let mut push = |tcp: [f64; 3], closed: bool, block: [f64; 3]| {
        lines.push(frame(t, tcp, closed, block));
        t += 1.0 / RATE;
    };
    let above = |p: [f64; 3]| [p[0], p[1], p[2] + 0.005];
    let lerp = |a: [f64; 3], b: [f64; 3], s: f64| std::array::from_fn(|i| a[i] + (b[i] - a[i]) * s);
    // A quadratic curve from `a` to `b` bulging through `via`.
    let curve =
        |a: [f64; 3], via: [f64; 3], b: [f64; 3], s: f64| lerp(lerp(a, via, s), lerp(via, b, s), s);
    let (grasp_at, release_at) = (above(START), above(END));
    for i in 0..=200 {
        let s = smooth(i as f64 / 200.0);
        push(
            curve([0.3, 0.35, 0.4], [0.6, 0.4, 0.3], grasp_at, s),
            false,
            START,
        );
    }
    for i in 0..60 {
        push(grasp_at, i >= 30, START);
    }
    for i in 1..=200 {
        let tcp = lerp(grasp_at, release_at, smooth(i as f64 / 200.0));
        push(tcp, true, [tcp[0], tcp[1], tcp[2] - 0.005]);
    }
    for i in 0..60 {
        push(release_at, i < 30, END);
    }
    for i in 1..=200 {
        let s = smooth(i as f64 / 200.0);
        push(
            curve(release_at, [0.6, -0.35, 0.3], [0.3, -0.3, 0.4], s),
            false,
            END,
        );
    }
    lines.join("\n") + "\n"
}

/// `akl teach --teacher stdin` fed `input` in `dir`, every question answered yes.
fn teach(dir: &Path, input: &str, out: &str) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_akl"))
        .args([
            "teach",
            "--teacher",
            "stdin",
            "--answers",
            "all-yes",
            "-o",
            out,
            "--json",
        ])
        .current_dir(dir)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // A refused header ends the session before the stream is read: the rest goes unread.
    let _ = child.stdin.take().unwrap().write_all(input.as_bytes());
    child.wait_with_output().unwrap()
}

/// The reference of the spec's release (the open-gripper keyframe at the end of the slide).
fn release_reference(spec: &Path) -> String {
    let spec: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(spec).unwrap()).unwrap();
    let release = spec["keyframes"]
        .as_array()
        .unwrap()
        .iter()
        .find(|k| k["gripper"] == "open" && k["kind"] != "constraint")
        .unwrap_or_else(|| panic!("no release in {spec}"));
    release["reference"].as_str().unwrap().to_string()
}

/// An OBJ file of a box of `size` centred on the origin: corner i has bit 0, 1, 2 of i set
/// on its +x, +y, +z side; two triangles per face.
fn box_obj(size: [f64; 3]) -> String {
    let mut text: String = (0..8)
        .map(|i: usize| {
            let c = |axis: usize| (if i >> axis & 1 == 1 { 0.5 } else { -0.5 }) * size[axis];
            format!("v {} {} {}\n", c(0), c(1), c(2))
        })
        .collect();
    for [a, b, c, d] in [
        [0, 2, 6, 4],
        [1, 3, 7, 5],
        [0, 1, 5, 4],
        [2, 3, 7, 6],
        [0, 1, 3, 2],
        [4, 5, 7, 6],
    ] {
        text += &format!(
            "f {} {} {}\nf {} {} {}\n",
            a + 1,
            b + 1,
            c + 1,
            a + 1,
            c + 1,
            d + 1
        );
    }
    text
}

const HEADER: &str = r#"{"akl_demo": 1, "task": "slide", "frame": "world"}"#;

#[test]
fn a_block_slid_along_a_large_table_without_shapes_is_grounded_on_the_table() {
    let dir = scratch("slide-bare");
    let o = teach(&dir, &stream(HEADER), "slide.jsonl");
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(json(&o)["queries"], 1, "{}", json(&o));
    assert_eq!(release_reference(&dir.join("slide.spec.json")), "table");
    // `akl learn` on the recording grounds it the same way.
    let o = akl_in(&dir, &["learn", "slide.jsonl", "-o", "again.json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(release_reference(&dir.join("again.json")), "table");
}

#[test]
fn declared_shapes_ground_the_slide_by_the_support_rule_and_are_kept_in_the_recording() {
    let dir = scratch("slide-shapes");
    let header = r#"{"akl_demo": 1, "task": "slide", "frame": "world", "shapes": {
        "block": {"type": "box", "size": [0.05, 0.05, 0.05]},
        "mat": {"type": "box", "size": [0.2, 0.2, 0.01]},
        "table": {"type": "box", "size": [1.2, 1.4, 0.04]}}}"#
        .replace('\n', " ");
    let o = teach(&dir, &stream(&header), "slide.jsonl");
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(release_reference(&dir.join("slide.spec.json")), "table");
    let recorded = std::fs::read_to_string(dir.join("slide.jsonl")).unwrap();
    let first: serde_json::Value = serde_json::from_str(recorded.lines().next().unwrap()).unwrap();
    assert_eq!(first["shapes"]["table"]["size"][1], 1.4, "{first}");

    // The table as a mesh file, next to the recording.
    std::fs::write(dir.join("table.obj"), box_obj([1.2, 1.4, 0.04])).unwrap();
    let meshed = header.replace(
        r#""table": {"type": "box", "size": [1.2, 1.4, 0.04]}"#,
        r#""table": {"type": "mesh", "file": "table.obj"}"#,
    );
    let o = teach(&dir, &stream(&meshed), "mesh.jsonl");
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(release_reference(&dir.join("mesh.spec.json")), "table");
}

#[test]
fn a_bad_shape_in_the_header_is_refused_naming_the_line_and_object() {
    let dir = scratch("slide-bad-shape");
    for (shapes, says) in [
        (
            r#"{"table": {"type": "box", "size": [1.2, -1, 0.04]}}"#,
            "`table`",
        ),
        (
            r#"{"tabel": {"type": "box", "size": [1.2, 1.4, 0.04]}}"#,
            "`tabel`",
        ),
        (
            r#"{"table": {"type": "mesh", "file": "missing.obj"}}"#,
            "missing.obj",
        ),
    ] {
        let header = HEADER.replace('}', &format!(r#", "shapes": {shapes}}}"#));
        let o = teach(&dir, &stream(&header), "bad.jsonl");
        assert_refused(&o, &["line 1", says]);
        std::fs::write(dir.join("bad-file.jsonl"), stream(&header)).unwrap();
        let o = akl_in(&dir, &["learn", "bad-file.jsonl", "--answers", "all-yes"]);
        assert_refused(&o, &["bad-file.jsonl", "line 1", says]);
    }
}
