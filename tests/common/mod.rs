//! Helpers the end-to-end tests share: running the `akl` binary, reading what it printed,
//! scratch folders and pseudo-terminals.
//!
//! Each test file is its own crate and uses only some of these, hence `dead_code` is allowed.
#![allow(dead_code)]

use std::os::fd::{FromRawFd, OwnedFd};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};

/// Runs `akl args` in `dir` and waits for it.
pub(crate) fn akl_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_akl"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("the akl binary runs")
}

/// Runs `akl args` at the repository root (where `tasks/` is) and waits for it.
pub(crate) fn akl(args: &[&str]) -> Output {
    akl_in(Path::new(env!("CARGO_MANIFEST_DIR")), args)
}

/// Bytes a command wrote, as text.
pub(crate) fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// What a command wrote on standard output.
pub(crate) fn stdout(o: &Output) -> String {
    text(&o.stdout)
}

/// What a command wrote on standard error.
pub(crate) fn stderr(o: &Output) -> String {
    text(&o.stderr)
}

/// Asserts that a command refused bad input as every command must: exit status 2, standard
/// error naming each of `names` (what is wrong, and where), and no panic. Returns what it wrote
/// on standard error, for further checks.
#[track_caller]
pub(crate) fn assert_refused(o: &Output, names: &[&str]) -> String {
    let err = stderr(o);
    assert_eq!(
        o.status.code(),
        Some(2),
        "standard error: {err}\nstandard output: {}",
        stdout(o)
    );
    for name in names {
        assert!(err.contains(name), "no `{name}` in: {err}");
    }
    assert!(!err.contains("panicked"), "{err}");
    err
}

/// A command's standard output parsed as JSON; a parse failure shows the output.
pub(crate) fn json(o: &Output) -> serde_json::Value {
    serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{e}: {}", stdout(o)))
}

/// An empty scratch folder unique to one test of this process.
pub(crate) fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("akl-e2e-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A pseudo-terminal pair: a child given the slave sees a terminal; the test reads what it
/// wrote, and types, on the master.
pub(crate) struct Pty {
    /// The test's end.
    pub master: std::fs::File,
    /// The child's end.
    pub slave: OwnedFd,
}

/// Opens a new pseudo-terminal pair.
pub(crate) fn open_pty() -> Pty {
    let (mut master, mut slave) = (0, 0);
    // SAFETY: openpty writes two new file descriptors into the pointers given.
    let rc = unsafe {
        libc::openpty(
            &mut master,
            &mut slave,
            std::ptr::null_mut(),
            std::ptr::null(),
            std::ptr::null(),
        )
    };
    assert_eq!(rc, 0, "openpty failed");
    // SAFETY: both descriptors were just opened and are owned by nobody else.
    unsafe {
        Pty {
            master: std::fs::File::from_raw_fd(master),
            slave: OwnedFd::from_raw_fd(slave),
        }
    }
}

/// A JSONL stream a robot driver would send: the frames and keyframe marks of a simulated
/// teaching, without the learner's own detector states and dialogue.
pub(crate) fn driver_stream(dir: &Path, task: &str) -> String {
    let o = akl_in(
        dir,
        &[
            "teach",
            "--task",
            task,
            "--answers",
            "all-yes",
            "-o",
            "src.jsonl",
        ],
    );
    assert!(o.status.success(), "{}", text(&o.stderr));
    frames_only(&std::fs::read_to_string(dir.join("src.jsonl")).unwrap())
}

/// The frames and keyframe marks of a recording, as a robot driver streams them: without the
/// detector states and the dialogue.
pub(crate) fn frames_only(recording: &str) -> String {
    recording
        .lines()
        .filter(|l| !l.contains("\"event\"") || l.contains("\"keyframe\""))
        .map(|l| {
            format!(
                "{}\n",
                l.replace(",\"constrained\":true", "")
                    .replace(",\"constrained\":false", "")
            )
        })
        .collect()
}

/// Starts `akl args` in `dir` with `pty` as its controlling terminal (so it can ask on
/// /dev/tty) and piped standard streams.
pub(crate) fn spawn_on_tty(dir: &Path, args: &[&str], pty: &Pty) -> Child {
    use std::os::fd::AsRawFd;
    use std::os::unix::process::CommandExt;
    let slave = pty.slave.as_raw_fd();
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_akl"));
    cmd.args(args)
        .current_dir(dir)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    // SAFETY: only async-signal-safe calls between fork and exec.
    unsafe {
        cmd.pre_exec(move || {
            if libc::setsid() < 0 || libc::ioctl(slave, libc::TIOCSCTTY, 0) < 0 {
                return Err(std::io::Error::last_os_error());
            }
            Ok(())
        });
    }
    cmd.spawn().unwrap()
}

/// A live teaching session (`akl teach --teacher stdin --json`) fed the inspection task's
/// driver stream, with its questions on a pseudo-terminal, stopped at its first question.
pub(crate) struct Asked {
    /// The running `akl`.
    pub child: Child,
    /// The terminal it asks on.
    pub pty: Pty,
    /// The thread writing the stream to its standard input.
    pub feeder: std::thread::JoinHandle<std::io::Result<()>>,
    /// What the terminal showed up to the first answer prompt.
    pub seen: String,
}

/// Starts a live teaching session in `dir` recording to `output` and reads the terminal up to
/// the first answer prompt.
pub(crate) fn teach_until_asked(dir: &Path, output: &str) -> Asked {
    use std::io::{Read, Write};
    let stream = driver_stream(dir, "inspection");
    let mut pty = open_pty();
    let mut child = spawn_on_tty(
        dir,
        &["teach", "--teacher", "stdin", "-o", output, "--json"],
        &pty,
    );
    let mut stdin = child.stdin.take().unwrap();
    let feeder = std::thread::spawn(move || stdin.write_all(stream.as_bytes()));
    let mut seen = String::new();
    let mut buf = [0u8; 4096];
    while !seen.contains("answer [y/n/?]") {
        let n = pty.master.read(&mut buf).unwrap();
        assert!(n > 0, "the terminal closed before a question: {seen}");
        seen.push_str(&text(&buf[..n]));
    }
    Asked {
        child,
        pty,
        feeder,
        seen,
    }
}
