//! A URDF: `urdf_load::parse` (urdf-rs and the checks for what k cannot take) and, for a URDF
//! it accepts, the kinematic tree `Robot::load` builds from it.
#![no_main]

use akl_planner::urdf_load;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(robot) = urdf_load::parse(text) {
            let _ = urdf_load::chain(&robot);
        }
    }
});
