//! Single keystrokes from the controlling terminal.
//!
//! A teacher answers the learner's question with one key while holding the robot; waiting
//! for Enter would need a second hand. The terminal is switched to non-canonical mode without
//! echo only while a read waits for a key, so it is back to normal between questions and when
//! the program ends.

use std::fs::File;
use std::io::Read;
use std::os::fd::AsRawFd;

/// A terminal device read one keystroke at a time.
pub(crate) struct KeyReader {
    tty: File,
}

impl KeyReader {
    /// Reads keys from `tty` (an open terminal device).
    pub(crate) fn new(tty: File) -> Self {
        KeyReader { tty }
    }
}

/// Restores the terminal's settings when dropped, whatever the read returned.
struct ModeGuard {
    fd: i32,
    saved: libc::termios,
}

impl ModeGuard {
    /// Switches `fd` to non-canonical, no-echo mode; `None` if it is not a terminal.
    fn keystrokes(fd: i32) -> Option<ModeGuard> {
        // SAFETY: termios is plain data; tcgetattr fills it or fails without touching memory
        // beyond it.
        let mut saved: libc::termios = unsafe { std::mem::zeroed() };
        if unsafe { libc::tcgetattr(fd, &mut saved) } != 0 {
            return None;
        }
        let mut raw = saved;
        raw.c_lflag &= !(libc::ICANON | libc::ECHO);
        raw.c_cc[libc::VMIN] = 1;
        raw.c_cc[libc::VTIME] = 0;
        // SAFETY: fd is open and raw is a valid termios derived from its current settings.
        if unsafe { libc::tcsetattr(fd, libc::TCSANOW, &raw) } != 0 {
            return None;
        }
        Some(ModeGuard { fd, saved })
    }
}

impl Drop for ModeGuard {
    fn drop(&mut self) {
        // SAFETY: restores settings read from the same descriptor, which is still open.
        unsafe { libc::tcsetattr(self.fd, libc::TCSANOW, &self.saved) };
    }
}

impl Read for KeyReader {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let _mode = ModeGuard::keystrokes(self.tty.as_raw_fd());
        self.tty.read(buf)
    }
}
