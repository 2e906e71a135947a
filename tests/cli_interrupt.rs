//! End-to-end tests of stopping a run: SIGINT (Ctrl-C) or SIGTERM during `akl execute
//! --randomize 2000` stops starting trials, prints the summary of those that finished, writes
//! their report marked interrupted, and exits 130; `akl validate` and `akl relax` the same.

use std::io::Read;
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::mpsc;
use std::time::Duration;

mod common;
use common::*;

const ASKED: u64 = 2000;

/// The largest `N` of the progress bar's `N/2000 trials` in what the terminal showed.
fn trials_done(seen: &str) -> u64 {
    let marker = format!("/{ASKED} trials");
    seen.match_indices(&marker)
        .filter_map(|(at, _)| {
            let before = &seen[..at];
            let digits = before.len() - before.trim_end_matches(|c: char| c.is_ascii_digit()).len();
            before[before.len() - digits..].parse().ok()
        })
        .max()
        .unwrap_or(0)
}

/// Starts `akl execute` on the pick_place truth for 2000 trials on one job, its standard error
/// on a terminal so its progress bar shows; once two trials have finished sends `signal`, and
/// checks what it printed, what it wrote and how it exited.
fn stopped_by(signal: libc::c_int, name: &str) {
    let dir = scratch(name);
    let spec = Path::new(env!("CARGO_MANIFEST_DIR")).join("tasks/pick_place.truth.json");
    let asked = ASKED.to_string();
    let Pty { mut master, slave } = open_pty();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_akl"));
    cmd.args([
        "execute",
        spec.to_str().unwrap(),
        "--task",
        "pick_place",
        "--randomize",
        &asked,
        "--report",
        "r.json",
        "--jobs",
        "1",
    ])
    .current_dir(&dir)
    .stdout(Stdio::piped())
    .stderr(slave);
    let child = cmd.spawn().expect("the akl binary runs");
    // Our copy of the terminal's child end must go, or reading the other end never ends.
    drop(cmd);
    let (chunks, received) = mpsc::channel();
    let reader = std::thread::spawn(move || {
        let mut buf = [0u8; 4096];
        // Once the child's end is closed, reading ends with EIO.
        while let Ok(n) = master.read(&mut buf) {
            if n == 0 || chunks.send(text(&buf[..n])).is_err() {
                break;
            }
        }
    });
    let mut seen = String::new();
    while trials_done(&seen) < 2 {
        let chunk = received
            .recv_timeout(Duration::from_secs(120))
            .unwrap_or_else(|e| panic!("no progress ({e}): {seen}"));
        seen.push_str(&chunk);
    }
    let before = trials_done(&seen);
    // SAFETY: sending a signal to the child this test started and has not yet waited for.
    assert_eq!(unsafe { libc::kill(child.id() as libc::pid_t, signal) }, 0);
    let output = child.wait_with_output().unwrap();
    reader.join().unwrap();
    seen.extend(received.try_iter());
    assert_eq!(output.status.code(), Some(130), "{seen}");
    let out = stdout(&output);
    assert!(
        out.contains("interrupted: only the") && out.contains("failed: collision"),
        "the summary is printed: {out}"
    );
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("r.json")).unwrap()).unwrap();
    assert_eq!(report["interrupted"], true);
    let trials = report["trials"].as_u64().unwrap();
    assert!(before <= trials && trials < ASKED, "{before} then {trials}");
    assert!(
        seen.contains(&format!("interrupted: {trials} of {ASKED} trials finished")),
        "{seen}"
    );
    let listed: Vec<u64> = report["reports"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r["trial"].as_u64().unwrap())
        .collect();
    assert_eq!(
        listed,
        (0..trials).collect::<Vec<_>>(),
        "one job runs them in order"
    );
    let counted: u64 = report["failures"]
        .as_object()
        .unwrap()
        .values()
        .map(|n| n.as_u64().unwrap())
        .sum();
    assert_eq!(counted, trials - report["passed"].as_u64().unwrap());
    let left: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(left, ["r.json"], "no temporary file is left");
}

#[test]
fn ctrl_c_keeps_the_finished_trials_and_exits_130() {
    stopped_by(libc::SIGINT, "interrupt-sigint");
}

#[test]
fn sigterm_keeps_the_finished_trials_and_exits_130() {
    stopped_by(libc::SIGTERM, "interrupt-sigterm");
}

#[test]
fn help_documents_exit_code_130() {
    for command in ["execute", "compare", "eval", "validate", "relax"] {
        let help = stdout(&akl(&[command, "--help"]));
        assert!(
            help.contains("130 interrupted by SIGINT or SIGTERM"),
            "{command}: {help}"
        );
    }
}

/// Starts `akl args` in `dir` with its standard error on a terminal (so its progress bar
/// shows), sends SIGINT once what it has written there satisfies `ready`, and returns how it
/// exited and what it printed on standard output.
fn interrupted_when(
    dir: &Path,
    args: &[&str],
    ready: &dyn Fn(&str) -> bool,
) -> std::process::Output {
    let Pty { mut master, slave } = open_pty();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_akl"));
    cmd.args(args)
        .current_dir(dir)
        .stdout(Stdio::piped())
        .stderr(slave);
    let child = cmd.spawn().expect("the akl binary runs");
    drop(cmd);
    let (chunks, received) = mpsc::channel();
    let reader = std::thread::spawn(move || {
        let mut buf = [0u8; 4096];
        while let Ok(n) = master.read(&mut buf) {
            if n == 0 || chunks.send(text(&buf[..n])).is_err() {
                break;
            }
        }
    });
    let mut seen = String::new();
    while !ready(&seen) {
        let chunk = received
            .recv_timeout(Duration::from_secs(120))
            .unwrap_or_else(|e| panic!("never ready ({e}): {seen}"));
        seen.push_str(&chunk);
    }
    // SAFETY: sending a signal to the child this test started and has not yet waited for.
    assert_eq!(
        unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) },
        0
    );
    let output = child.wait_with_output().unwrap();
    reader.join().unwrap();
    output
}

#[test]
fn ctrl_c_stops_a_validation_with_the_trials_judged_so_far() {
    let dir = scratch("interrupt-validate");
    let spec = Path::new(env!("CARGO_MANIFEST_DIR")).join("tasks/pick_place.truth.json");
    // Once the gate has judged its first trials.
    let output = interrupted_when(
        &dir,
        &[
            "validate",
            spec.to_str().unwrap(),
            "--task",
            "pick_place",
            "--jobs",
            "1",
            "--report",
            "r.json",
            "--json",
        ],
        &|seen| trials_done(seen) >= 1,
    );
    assert_eq!(output.status.code(), Some(130), "{}", stderr(&output));
    let v = json(&output);
    assert_eq!(v["interrupted"], true, "{v}");
    assert_eq!(v["verdict"], serde_json::Value::Null, "{v}");
    assert_eq!(v["spec"]["decision"], serde_json::Value::Null, "{v}");
    let report: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("r.json")).unwrap()).unwrap();
    assert_eq!(report["interrupted"], true);
    assert_eq!(report["gate"]["decision"], serde_json::Value::Null);
    assert_eq!(report["trials"], v["spec"]["outcome"]["run"], "{report}");
    let left: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(left, ["r.json"], "no temporary file is left");
}

#[test]
fn ctrl_c_stops_a_relaxation_and_writes_at_most_a_gated_spec() {
    let dir = scratch("interrupt-relax");
    let spec = Path::new(env!("CARGO_MANIFEST_DIR")).join("tasks/pick_place.truth.json");
    let mut child = Command::new(env!("CARGO_BIN_EXE_akl"))
        .args([
            "relax",
            spec.to_str().unwrap(),
            "--task",
            "pick_place",
            "--jobs",
            "1",
            "-o",
            "relaxed.json",
        ])
        .current_dir(&dir)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the akl binary runs");
    // Its first line says what it will do; the gate of the spec (299 clean trials) follows.
    let mut out = std::io::BufReader::new(child.stdout.take().unwrap());
    let mut first = String::new();
    std::io::BufRead::read_line(&mut out, &mut first).unwrap();
    assert!(first.contains("screening up to"), "{first}");
    // SAFETY: sending a signal to the child this test started and has not yet waited for.
    assert_eq!(
        unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) },
        0
    );
    let mut rest = String::new();
    out.read_to_string(&mut rest).unwrap();
    let output = child.wait_with_output().unwrap();
    assert_eq!(output.status.code(), Some(130), "{}", stderr(&output));
    // Nothing passed a gate, so nothing is written.
    assert!(
        stderr(&output).contains("nothing written"),
        "{}",
        stderr(&output)
    );
    assert!(
        rest.contains("gate on the spec as given") && rest.contains("interrupted"),
        "{rest}"
    );
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
}
