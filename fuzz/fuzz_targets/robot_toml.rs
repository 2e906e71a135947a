//! A robot folder's `robot.toml`: `RobotConfig::from_toml` and `RobotConfig::validate`, what
//! `Robot::load` runs on its text before reading the URDF it names.
#![no_main]

use akl_planner::RobotConfig;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        if let Ok(config) = RobotConfig::from_toml(text) {
            let _ = config.validate();
        }
    }
});
