//! A robot folder's `self_tables.bin`: `StoredTables::parse`, what loading the folder runs
//! on its bytes; whatever it accepts must write back to the same bytes.
#![no_main]

use akl_planner::collision::StoredTables;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(tables) = StoredTables::parse(data) {
        assert_eq!(tables.to_bytes(), data);
    }
});
