//! A planning problem file (`akl bench planning`): `ProblemFile::parse` for a 7-joint robot,
//! what `ProblemFile::load` runs on the file's text.
#![no_main]

use akl_planner::benchmark::ProblemFile;
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = ProblemFile::parse(text, Path::new("problems.json"), 7);
    }
});
