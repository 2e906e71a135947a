//! End-to-end: the learner's suggestion reaches a person answering on the terminal, and is
//! recorded; a "yes" is not followed by it.

use std::io::{Read, Write};

mod common;
use common::*;

const SUGGESTION: &str = "Please do not move in a line unless the robot must move in a line.";

/// Teaches the inspection stream from standard input, typing `key` to the first question;
/// returns what the terminal showed after the answer, the summary and the recording.
fn answer_on_the_terminal(name: &str, key: u8) -> (String, serde_json::Value, String) {
    let dir = scratch(name);
    let Asked {
        child,
        mut pty,
        feeder,
        ..
    } = teach_until_asked(&dir, "tty.jsonl");
    let mut buf = [0u8; 4096];
    pty.master.write_all(&[key]).unwrap();
    feeder.join().unwrap().unwrap();
    let o = child.wait_with_output().unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    // The child has exited: what it wrote to the terminal after the answer is buffered in the
    // pseudo-terminal; read it without blocking once the buffer is empty.
    let fd = std::os::fd::AsRawFd::as_raw_fd(&pty.master);
    // SAFETY: fcntl on a descriptor this test owns.
    unsafe {
        let flags = libc::fcntl(fd, libc::F_GETFL);
        libc::fcntl(fd, libc::F_SETFL, flags | libc::O_NONBLOCK);
    }
    let mut after = String::new();
    while let Ok(n) = pty.master.read(&mut buf) {
        if n == 0 {
            break;
        }
        after.push_str(&text(&buf[..n]));
    }
    let recorded = std::fs::read_to_string(dir.join("tty.jsonl")).unwrap();
    (after, json(&o), recorded)
}

#[test]
fn after_no_the_suggestion_is_shown_and_recorded() {
    let (after, summary, recorded) = answer_on_the_terminal("suggest-no", b'n');
    assert!(after.contains(SUGGESTION), "{after}");
    assert_eq!(summary["answers"]["no"], 1, "{summary}");
    assert_eq!(summary["suggestions"], 1, "{summary}");
    assert!(recorded.contains("\"event\":\"suggestion\""));
}

#[test]
fn after_i_dont_know_the_suggestion_is_shown_and_after_yes_not() {
    let (after, summary, _) = answer_on_the_terminal("suggest-unknown", b'?');
    assert!(after.contains(SUGGESTION), "{after}");
    assert_eq!(summary["suggestions"], 1, "{summary}");
    let (after, summary, recorded) = answer_on_the_terminal("suggest-yes", b'y');
    assert!(!after.contains(SUGGESTION), "{after}");
    assert_eq!(summary["suggestions"], 0, "{summary}");
    assert!(!recorded.contains("\"event\":\"suggestion\""));
}
