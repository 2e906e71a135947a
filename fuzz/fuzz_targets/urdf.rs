//! A URDF: `akl_planner::parse_urdf` (urdf-rs and the checks for what k cannot take) and,
//! for a URDF it accepts, the kinematic tree `Robot::load` builds from it (`urdf_chain`).
#![no_main]

use akl_planner::{parse_urdf, urdf_chain};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(robot) = parse_urdf(text) {
            let _ = urdf_chain(&robot);
        }
    }
});
