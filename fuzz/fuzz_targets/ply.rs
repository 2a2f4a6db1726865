//! The PLY reader (ASCII and binary).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = scene::formats::ply::parse_ply(data, std::path::Path::new("input.ply"));
});
