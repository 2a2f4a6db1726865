//! Texture images (EXR, PFM, HDR, PNG, JPEG, TGA, BMP): the first byte picks the extension.
#![no_main]
use libfuzzer_sys::fuzz_target;

const EXTENSIONS: [&str; 4] = ["exr", "png", "pfm", "tga"];

fuzz_target!(|data: &[u8]| {
    let Some((&pick, body)) = data.split_first() else {
        return;
    };
    let ext = EXTENSIONS[pick as usize % EXTENSIONS.len()];
    let dir = std::env::temp_dir().join(format!("penumbra-cargo-fuzz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join(format!("input.{ext}"));
    if std::fs::write(&path, body).is_ok() {
        let _ = render::image_io::read_image(&path);
    }
});
