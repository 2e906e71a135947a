//! End-to-end tests of `akl calibrate`, `akl teach`, `akl learn` and `akl score` through the
//! binary: files written, exit codes, live teaching from standard input with answers typed on a
//! pseudo-terminal, and recordings that survive SIGKILL and end cleanly on Ctrl-C.

use std::io::Write;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

mod common;
use common::*;

#[test]
fn teach_learn_and_score_every_builtin_task() {
    let dir = scratch("teach");
    for task in ["pick_place", "inspection", "assembly"] {
        let demo = format!("{task}.mcap");
        let o = akl_in(&dir, &["teach", "--task", task, "--seed", "3", "-o", &demo]);
        assert!(o.status.success(), "{}", text(&o.stderr));
        assert!(text(&o.stdout).contains("learned with AKL"));
        assert!(dir.join(&demo).exists() && !dir.join(format!("{demo}.partial")).exists());
        let spec = format!("{task}.spec.json");
        let o = akl_in(&dir, &["score", &spec, "--truth", task, "--json"]);
        assert!(o.status.success(), "{}", text(&o.stderr));
        assert_eq!(json(&o)["success"], true, "{task}: {}", text(&o.stdout));
        for method in ["akl", "kd", "macl"] {
            let out = format!("{task}.{method}.json");
            let o = akl_in(
                &dir,
                &["learn", &demo, "--method", method, "-o", &out, "--json"],
            );
            assert!(o.status.success(), "{method}: {}", text(&o.stderr));
            assert_eq!(json(&o)["spec"]["method"], method);
            assert!(dir.join(&out).exists());
        }
    }
}

#[test]
fn calibrate_a_simulated_teacher_and_teach_with_it() {
    let dir = scratch("calibrate");
    let o = akl_in(
        &dir,
        &[
            "calibrate",
            "--simulate",
            "--seed",
            "2",
            "-o",
            "cal.json",
            "--json",
        ],
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    let report = json(&o);
    let s = &report["separation"];
    assert_eq!(s["line_right"], s["line_points"]);
    assert_eq!(s["circle_right"], s["circle_points"]);
    let o = akl_in(
        &dir,
        &[
            "teach",
            "--task",
            "inspection",
            "--calibration",
            "cal.json",
            "-o",
            "d.jsonl",
        ],
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    let header = std::fs::read_to_string(dir.join("d.jsonl")).unwrap();
    assert!(header.lines().next().unwrap().contains("cal.json"));
    // Line and circle files: a calibration from recordings, and degenerate input.
    std::fs::write(dir.join("still.jsonl"), still_demo()).unwrap();
    let o = akl_in(
        &dir,
        &[
            "calibrate",
            "--line",
            "d.jsonl",
            "--circle",
            "still.jsonl",
            "-o",
            "c2.json",
        ],
    );
    assert_eq!(o.status.code(), Some(2), "{}", text(&o.stdout));
    assert!(text(&o.stderr).contains("circle"), "{}", text(&o.stderr));
    assert!(!dir.join("c2.json").exists());
}

fn still_demo() -> String {
    let mut s = String::from("{\"akl_demo\": 1, \"task\": \"still\", \"frame\": \"world\"}\n");
    for i in 0..100 {
        s.push_str(&format!(
            "{{\"t\": {}, \"ee\": {{\"p\": [0.4, 0, 0.3], \"q\": [1, 0, 0, 0]}}, \"gripper\": \"open\"}}\n",
            i as f64 * 0.01
        ));
    }
    s
}

#[test]
fn bad_input_is_named_and_exits_2() {
    let dir = scratch("bad");
    std::fs::write(
        dir.join("bad.jsonl"),
        "{\"akl_demo\": 1, \"task\": \"t\", \"frame\": \"world\"}\n{\"t\": 0.0}\n",
    )
    .unwrap();
    let cases: [(&[&str], &str); 11] = [
        (&["learn", "bad.jsonl"], "bad.jsonl: line 2"),
        (&["learn", "missing.mcap"], "missing.mcap"),
        (&["learn", "bad.jsonl", "--method", "okl"], "unknown method"),
        (&["teach", "-o", "x.mcap"], "--task"),
        (
            &[
                "teach",
                "--task",
                "inspection",
                "--profile",
                "sloppy",
                "-o",
                "x.mcap",
            ],
            "sloppy",
        ),
        (
            &["teach", "--task", "inspection", "-o", "x.txt"],
            ".mcap or .jsonl",
        ),
        (
            &[
                "teach",
                "--task",
                "inspection",
                "--rate",
                "5000",
                "-o",
                "x.mcap",
            ],
            "5000 Hz",
        ),
        (&["learn", "bad.jsonl", "--bounds", "0.01"], "--bounds"),
        (
            &["learn", "bad.jsonl", "-o", "no/such/folder/s.json"],
            "no/such/folder/s.json: cannot write the spec there (no such folder)",
        ),
        (
            &["calibrate", "--simulate", "-o", "no/such/folder/c.json"],
            "no/such/folder/c.json: cannot write the calibration there",
        ),
        (&["calibrate", "--simulate", "-o", "."], "is a folder"),
    ];
    for (args, needle) in cases {
        let o = akl_in(&dir, args);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", text(&o.stderr));
        assert!(
            text(&o.stderr).contains(needle),
            "{args:?}: {}",
            text(&o.stderr)
        );
    }
    assert!(!dir.join("x.mcap").exists() && !dir.join("x.txt").exists());
}

#[test]
fn a_driver_streams_frames_on_stdin() {
    let dir = scratch("stdin");
    let stream = driver_stream(&dir, "inspection");
    assert!(!stream.contains("constrained"));
    let mut child = Command::new(env!("CARGO_BIN_EXE_akl"))
        .args([
            "teach",
            "--teacher",
            "stdin",
            "--answers",
            "yes",
            "-o",
            "live.mcap",
            "--json",
        ])
        .current_dir(&dir)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    child
        .stdin
        .take()
        .unwrap()
        .write_all(stream.as_bytes())
        .unwrap();
    let o = child.wait_with_output().unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    let summary = json(&o);
    assert_eq!(summary["task"], "inspection");
    assert_eq!(summary["queries"], 1, "{summary}");
    let o = akl_in(
        &dir,
        &["score", "live.spec.json", "--truth", "inspection", "--json"],
    );
    assert_eq!(json(&o)["success"], true);
}

#[test]
fn a_stream_recorded_without_the_detector_is_replayed_by_learn() {
    let dir = scratch("replay");
    std::fs::write(dir.join("raw.jsonl"), driver_stream(&dir, "inspection")).unwrap();
    let o = akl_in(&dir, &["learn", "raw.jsonl"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o.stderr).contains("--answers"), "{}", text(&o.stderr));
    let o = akl_in(
        &dir,
        &[
            "learn",
            "raw.jsonl",
            "--answers",
            "yes",
            "-o",
            "s.json",
            "--json",
        ],
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(json(&o)["replayed_detector"], true);
    let o = akl_in(
        &dir,
        &["score", "s.json", "--truth", "inspection", "--json"],
    );
    assert_eq!(json(&o)["success"], true);
}

#[test]
fn questions_are_answered_on_the_terminal() {
    let dir = scratch("tty");
    // Read the question off the terminal, then type the answer.
    let Asked {
        child,
        mut pty,
        feeder,
        seen,
    } = teach_until_asked(&dir, "tty.jsonl");
    assert!(
        seen.contains("Do I have to move in a straight line there?"),
        "{seen}"
    );
    assert!(
        seen.contains("[y] yes") && seen.contains("nearest:"),
        "{seen}"
    );
    // A stray key asks again; one key answers, no Enter needed.
    pty.master.write_all(b"x").unwrap();
    pty.master.write_all(b"y").unwrap();
    feeder.join().unwrap().unwrap();
    let o = child.wait_with_output().unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    let summary = json(&o);
    assert_eq!(summary["answers"]["yes"], 1, "{summary}");
    let recorded = std::fs::read_to_string(dir.join("tty.jsonl")).unwrap();
    assert!(recorded.contains("\"event\":\"answer\",\"value\":\"yes\""));
}

fn wait_for(path: &Path, bytes: u64) {
    let start = Instant::now();
    while std::fs::metadata(path).map_or(0, |m| m.len()) < bytes {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "{} never grew",
            path.display()
        );
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// Starts a real-time simulated teaching of `inspection` into `dir/out` and returns once about
/// six seconds of it are recorded (past the grasp at 4.6 s), with the seconds since start.
fn teach_for_six_seconds(dir: &Path, out: &str) -> (Child, f64) {
    let child = Command::new(env!("CARGO_BIN_EXE_akl"))
        .args([
            "teach",
            "--task",
            "inspection",
            "--realtime",
            "-o",
            out,
            "--json",
        ])
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let started = Instant::now();
    wait_for(&dir.join(format!("{out}.partial")), 1);
    std::thread::sleep(Duration::from_secs(6));
    (child, started.elapsed().as_secs_f64())
}

#[test]
fn a_killed_recording_keeps_all_but_its_last_second() {
    let dir = scratch("kill");
    let (mut child, before_kill) = teach_for_six_seconds(&dir, "k.mcap");
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(!dir.join("k.mcap").exists());
    let o = akl_in(
        &dir,
        &["learn", "k.mcap.partial", "--method", "kd", "--json"],
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("truncated"), "{}", text(&o.stderr));
    let frames = json(&o)["frames"].as_u64().unwrap() as f64;
    // 100 Hz: everything but the last second (and the start-up before the first frame).
    assert!(
        frames / 100.0 >= before_kill - 2.5,
        "{frames} frames after {before_kill} s"
    );
}

#[test]
fn ctrl_c_ends_a_recording_cleanly() {
    let dir = scratch("sigint");
    let (child, _) = teach_for_six_seconds(&dir, "c.mcap");
    // SAFETY: sending a signal to our own child process.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    let o = child.wait_with_output().unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(json(&o)["stopped_early"], true);
    assert!(dir.join("c.mcap").exists() && !dir.join("c.mcap.partial").exists());
    let o = akl_in(&dir, &["learn", "c.mcap", "--method", "kd"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        !text(&o.stderr).contains("truncated"),
        "{}",
        text(&o.stderr)
    );
}
