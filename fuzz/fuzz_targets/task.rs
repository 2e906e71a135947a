//! A task file: `Task::from_json`, the parsing and every check `Task::load` runs on the file's
//! text (the task's own layout included), without reading mesh files or a ground truth.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = akl_scene::Task::from_json(text);
    }
});
