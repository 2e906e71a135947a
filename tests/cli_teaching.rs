//! End-to-end tests of `akl calibrate`, `akl teach`, `akl learn` and `akl score` through the
//! binary: files written, exit codes, live teaching from standard input with answers typed on a
//! pseudo-terminal, and recordings that survive SIGKILL and end cleanly on Ctrl-C.

use std::io::Write;
use std::path::Path;
use std::process::{Child, ChildStdin, Command, Stdio};

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
    assert_refused(&o, &["circle"]);
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
        assert_refused(&o, &[needle]);
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
    assert_refused(&o, &["--answers"]);
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

/// A driver streaming inspection's demonstration into `akl teach --teacher stdin`, recording
/// into an MCAP file, paced by the test: nothing here waits for the clock.
struct Driver {
    child: Child,
    stdin: ChildStdin,
    /// The stream's lines not fed yet.
    rest: std::vec::IntoIter<String>,
    /// The last frame fed, as JSON.
    last: serde_json::Value,
}

impl Driver {
    /// Starts the recording into `dir/out` and feeds the stream's header and its frames up to
    /// `until` seconds (with their keyframe marks).
    fn start(dir: &Path, out: &str, until: f64) -> Driver {
        let stream = driver_stream(dir, "inspection");
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
        let stdin = child.stdin.take().unwrap();
        let lines: Vec<String> = stream.lines().map(str::to_string).collect();
        let mut driver = Driver {
            child,
            stdin,
            rest: lines.into_iter(),
            last: serde_json::Value::Null,
        };
        while driver.last["t"].as_f64().is_none_or(|t| t < until) {
            assert!(driver.feed_one(), "the stream ended before {until} s");
        }
        driver
    }

    /// Feeds the next line of the stream, or once it is all fed, the last frame again 10 ms
    /// later; false when the recorder no longer reads.
    fn feed_one(&mut self) -> bool {
        let line = match self.rest.next() {
            Some(line) => line,
            None => {
                let t = self.last["t"].as_f64().unwrap() + 0.01;
                self.last["t"] = serde_json::json!(t);
                self.last.to_string()
            }
        };
        if let Ok(value) = serde_json::from_str::<serde_json::Value>(&line) {
            if value.get("t").is_some() {
                self.last = value;
            }
        }
        self.stdin
            .write_all(format!("{line}\n").as_bytes())
            .and_then(|()| self.stdin.flush())
            .is_ok()
    }

    /// Waits until the recording `path` holds, in complete chunks, frames up to `seconds`, and
    /// returns how many frames it holds. The recorder flushes as it goes, so this is a matter
    /// of it catching up with the frames fed; it fails if the recorder exits.
    fn recorded_until(&mut self, path: &Path, seconds: f64) -> usize {
        loop {
            if let Ok(loaded) = akl_learn::read_demo_file(path) {
                if loaded.demo.times.last().is_some_and(|t| *t >= seconds) {
                    return loaded.demo.len();
                }
            }
            if let Some(status) = self.child.try_wait().unwrap() {
                panic!("the recorder exited ({status}) before {seconds} s were recorded");
            }
            std::thread::yield_now();
        }
    }
}

#[test]
fn a_killed_recording_keeps_all_but_its_last_second() {
    let dir = scratch("kill");
    // Six seconds fed (past the grasp at 4.6 s); the recorder closes a chunk every second.
    let mut driver = Driver::start(&dir, "k.mcap", 6.0);
    let flushed = driver.recorded_until(&dir.join("k.mcap.partial"), 4.9);
    driver.child.kill().unwrap();
    driver.child.wait().unwrap();
    assert!(!dir.join("k.mcap").exists());
    let o = akl_in(
        &dir,
        &["learn", "k.mcap.partial", "--method", "kd", "--json"],
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(text(&o.stderr).contains("truncated"), "{}", text(&o.stderr));
    // Nothing written before the kill is lost: at least the 4.9 s seen, at 100 Hz.
    let frames = json(&o)["frames"].as_u64().unwrap() as usize;
    assert!(
        frames >= flushed && flushed >= 490,
        "{frames} frames, {flushed} seen"
    );
}

#[test]
fn ctrl_c_ends_a_recording_cleanly() {
    let dir = scratch("sigint");
    let mut driver = Driver::start(&dir, "c.mcap", 6.0);
    driver.recorded_until(&dir.join("c.mcap.partial"), 4.9);
    // SAFETY: sending a signal to our own child process.
    assert_eq!(
        unsafe { libc::kill(driver.child.id() as i32, libc::SIGINT) },
        0
    );
    // The recorder looks at the flag between frames: feed frames until it stops reading (the
    // stream's own, then its last frame held).
    let mut fed = 0;
    while driver.feed_one() {
        fed += 1;
        assert!(fed < 1_000_000, "the recorder never stopped");
    }
    let Driver { child, stdin, .. } = driver;
    drop(stdin);
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
