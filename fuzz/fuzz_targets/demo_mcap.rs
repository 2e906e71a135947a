//! An MCAP demonstration (what `akl teach` records): `read_mcap`, what `read_demo_file` runs on
//! a file that starts with the MCAP magic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = akl_learn::read_mcap(data);
});
