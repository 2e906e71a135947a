//! A JSONL demonstration: `read_jsonl`, what `read_demo_file` runs on a file that is not MCAP.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = akl_learn::read_jsonl(text);
    }
});
