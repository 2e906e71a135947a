//! A spec file (`spec.json`): `TaskSpec::from_json`, what `TaskSpec::load` runs on the file's text.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = akl_tsr::TaskSpec::from_json(text);
    }
});
