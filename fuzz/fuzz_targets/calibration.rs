//! A calibration file: `Calibration::from_json`, what `Calibration::load` runs on its text.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = akl_learn::Calibration::from_json(text);
    }
});
