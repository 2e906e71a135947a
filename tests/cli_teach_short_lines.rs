//! Teaching and learning through the `akl` binary, the real detector and dialogue, on tasks
//! shaped unlike the built-in ones: a 10 cm descent into a fixture and a 12 cm pull of a handle
//! are asked about and learned as `move_in_line`; an answer list of the wrong length is refused
//! with the questions listed; answers keyed by time; `akl learn` uses a recording's answers
//! unless given others.

mod common;

use common::{akl_in, assert_refused, frames_only, json, scratch, stderr, stdout};
use std::io::Write;
use std::path::Path;
use std::process::{Command, Output, Stdio};

/// A task whose one required line is `length` metres long: `descend`, a peg lowered straight
/// into a fixture after a free reach above it, or `pull`, a handle pulled straight out of a
/// cabinet (off the stand it rests on) right after it is grasped.
fn short_line_task(kind: &str, length: f64) -> String {
    let table = r#"{"name": "table", "shape": {"type": "box", "size": [1.2, 1.4, 0.04]},
        "pose": {"p": [0.35, 0, -0.02], "q": [0, 0, 0, 1]}, "movable": false, "mass": 0.0, "friction": 0.6}"#;
    let home = r#"{"action": "move", "to": {"p": [0.307, 0.0, 0.487], "q": [1, 0, 0, 0]}, "relative_to": "world"}"#;
    let (objects, steps) = match kind {
        "descend" => (
            r#"{"name": "peg", "shape": {"type": "cylinder", "radius": 0.01, "length": 0.08},
                "pose": {"p": [0.45, 0.3, 0.04], "q": [0, 0, 0, 1]}, "movable": true, "mass": 0.05, "friction": 0.6},
               {"name": "fixture", "shape": {"type": "box", "size": [0.08, 0.08, 0.06]},
                "pose": {"p": [0.5, -0.25, 0.03], "q": [0, 0, 0, 1]}, "movable": false, "mass": 0.0, "friction": 0.6}"#
                .to_string(),
            format!(
                r#"{{"action": "grasp", "object": "peg", "tcp": {{"p": [0, 0, 0.03], "q": [1, 0, 0, 0]}}}},
                   {{"action": "move", "to": {{"p": [0, 0, {above}], "q": [1, 0, 0, 0]}}, "relative_to": "fixture"}},
                   {{"action": "line", "to": {{"p": [0, 0, 0.06], "q": [1, 0, 0, 0]}}, "relative_to": "fixture"}},
                   {{"action": "release", "on": "fixture", "place": {{"p": [0, 0, 0.03], "q": [0, 0, 0, 1]}}}}"#,
                above = 0.06 + length
            ),
        ),
        _ => (
            r#"{"name": "cabinet", "shape": {"type": "box", "size": [0.3, 0.4, 0.3]},
                "pose": {"p": [0.77, 0.0, 0.15], "q": [0, 0, 0, 1]}, "movable": false, "mass": 0.0, "friction": 0.6},
               {"name": "stand", "shape": {"type": "box", "size": [0.04, 0.12, 0.19]},
                "pose": {"p": [0.59, 0.0, 0.095], "q": [0, 0, 0, 1]}, "movable": false, "mass": 0.0, "friction": 0.6},
               {"name": "handle", "shape": {"type": "box", "size": [0.02, 0.1, 0.02]},
                "pose": {"p": [0.59, 0.0, 0.2], "q": [0, 0, 0, 1]}, "movable": true, "mass": 0.05, "friction": 0.6}"#
                .to_string(),
            format!(
                r#"{{"action": "grasp", "object": "handle", "tcp": {{"p": [0, 0, 0.01], "q": [1, 0, 0, 0]}}}},
                   {{"action": "line", "to": {{"p": [{x}, 0, 0.21], "q": [1, 0, 0, 0]}}, "relative_to": "world"}},
                   {{"action": "release", "on": "table", "place": {{"p": [{on_table}, 0.0, 0.22], "q": [0, 0, 0, 1]}}}}"#,
                x = 0.59 - length,
                on_table = 0.24 - length
            ),
        ),
    };
    format!(
        r#"{{"akl_task": 1, "name": "{kind}", "description": "A short required line.",
            "world": {{"robot_base": {{"p": [0, 0, 0], "q": [0, 0, 0, 1]}}, "objects": [{table}, {objects}]}},
            "goals": [],
            "teaching": {{"start": {{"p": [0.307, 0.0, 0.487], "q": [1, 0, 0, 0]}}, "steps": [{steps}, {home}]}}}}"#
    )
}

/// Writes the task `kind` of `length` into `dir` as `<kind>.json`.
fn write_task(dir: &Path, kind: &str, length: f64) {
    std::fs::write(
        dir.join(format!("{kind}.json")),
        short_line_task(kind, length),
    )
    .unwrap();
}

/// How many keyframes of the spec file `path` are `move_in_line`.
fn lines_in(path: &Path) -> usize {
    let spec: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    spec["keyframes"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|k| k["constraint"] == "move_in_line")
        .count()
}

/// The simulated teacher (default profile, oracle answers) teaches `<kind>.json` into
/// `out`: the summary.
fn teach_sim(dir: &Path, kind: &str, out: &str) -> serde_json::Value {
    let task = format!("{kind}.json");
    let o = akl_in(dir, &["teach", "--task", &task, "-o", out, "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    json(&o)
}

/// `akl teach --teacher stdin --task <kind>.json --answers answers -o out --json` fed `stream`.
fn teach_stream(dir: &Path, kind: &str, stream: &str, answers: &str, out: &str) -> Output {
    let task = format!("{kind}.json");
    let mut child = Command::new(env!("CARGO_BIN_EXE_akl"))
        .args([
            "teach",
            "--teacher",
            "stdin",
            "--task",
            &task,
            "--answers",
            answers,
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
    // A refused answer list ends the session early: the rest of the stream goes unread.
    let _ = child.stdin.take().unwrap().write_all(stream.as_bytes());
    child.wait_with_output().unwrap()
}

/// The time of the first query a JSONL recording holds.
fn first_query_time(recording: &str) -> f64 {
    recording
        .lines()
        .filter_map(|l| serde_json::from_str::<serde_json::Value>(l).ok())
        .find(|v| v["event"] == "query")
        .and_then(|v| v["t"].as_f64())
        .expect("a query")
}

#[test]
fn a_ten_and_a_twelve_centimetre_required_line_are_asked_about_and_learned() {
    let dir = scratch("short-lines");
    for (kind, length) in [("descend", 0.10), ("pull", 0.12), ("descend", 0.12)] {
        write_task(&dir, kind, length);
        let summary = teach_sim(&dir, kind, "demo.jsonl");
        assert_eq!(summary["queries"], 1, "{kind} {length}: {summary}");
        assert_eq!(summary["answers"]["yes"], 1, "{kind} {length}: {summary}");
        assert_eq!(
            lines_in(&dir.join("demo.spec.json")),
            1,
            "{kind} {length}: {summary}"
        );
    }
}

#[test]
fn an_answer_list_must_fit_the_questions_and_may_key_them_by_time() {
    let dir = scratch("answer-list");
    write_task(&dir, "descend", 0.10);
    teach_sim(&dir, "descend", "sim.jsonl");
    let recorded = std::fs::read_to_string(dir.join("sim.jsonl")).unwrap();
    let stream = frames_only(&recorded);
    let asked_at = first_query_time(&recorded);

    // One question, two answers: refused, the question listed with its time and position.
    let o = teach_stream(&dir, "descend", &stream, "yes,no", "two.jsonl");
    let listed = format!("question 1 at t = {asked_at:.2} s, hand at (");
    assert_refused(&o, &[&listed, "unused: no"]);
    assert!(!dir.join("two.jsonl").exists());

    // No answer for it: refused, listing it.
    let o = teach_stream(&dir, "descend", &stream, "", "none.jsonl");
    assert_refused(
        &o,
        &[&format!("question 1 at t = {asked_at:.2} s has no answer")],
    );

    // An answer keyed by a time off every question's: refused; keyed by the question's: taken.
    let off = format!("{:.1}:yes", asked_at + 3.0);
    let o = teach_stream(&dir, "descend", &stream, &off, "off.jsonl");
    assert_eq!(o.status.code(), Some(2), "{}", stdout(&o));
    let keyed = format!("{:.1}:yes", asked_at);
    let o = teach_stream(&dir, "descend", &stream, &keyed, "keyed.jsonl");
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(json(&o)["answers"]["yes"], 1);
    assert_eq!(lines_in(&dir.join("keyed.spec.json")), 1);
}

#[test]
fn learn_uses_the_recorded_answers_unless_given_others() {
    let dir = scratch("recorded-answers");
    write_task(&dir, "pull", 0.12);
    teach_sim(&dir, "pull", "sim.jsonl");
    let learn = |demo: &str, extra: &[&str]| {
        let mut args = vec![
            "learn",
            demo,
            "--task",
            "pull.json",
            "-o",
            "s.json",
            "--json",
        ];
        args.extend_from_slice(extra);
        let o = akl_in(&dir, &args);
        assert!(o.status.success(), "{}", stderr(&o));
        (json(&o), lines_in(&dir.join("s.json")))
    };
    // The recording's detector states and its "yes".
    let (out, lines) = learn("sim.jsonl", &[]);
    assert_eq!(
        (out["replayed_detector"].as_bool(), lines),
        (Some(false), 1)
    );
    // Without the detector's states, replayed with the recorded answers.
    let recorded = std::fs::read_to_string(dir.join("sim.jsonl")).unwrap();
    let stateless: String = recorded
        .lines()
        .map(|l| {
            format!(
                "{}\n",
                l.replace(",\"constrained\":true", "")
                    .replace(",\"constrained\":false", "")
            )
        })
        .collect();
    std::fs::write(dir.join("stateless.jsonl"), stateless).unwrap();
    let (out, lines) = learn("stateless.jsonl", &[]);
    assert_eq!(out["replayed_with"], "the recording's answers", "{out}");
    assert_eq!(lines, 1);
    // Told otherwise: the given "no" replaces the recorded "yes".
    let (out, lines) = learn("sim.jsonl", &["--answers", "no"]);
    assert_eq!(out["replayed_with"], "the answers given", "{out}");
    assert_eq!(lines, 0);
    // Frames alone have no answers to use.
    std::fs::write(dir.join("frames.jsonl"), frames_only(&recorded)).unwrap();
    let o = akl_in(&dir, &["learn", "frames.jsonl", "--task", "pull.json"]);
    assert_refused(&o, &["--answers"]);
}
