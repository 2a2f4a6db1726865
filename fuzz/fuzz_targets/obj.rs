//! The OBJ mesh reader.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let _ = scene::formats::obj::parse_obj(&text, std::path::Path::new("input.obj"));
});
