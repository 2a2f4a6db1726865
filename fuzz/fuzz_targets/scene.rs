//! Every scene loader: the first byte picks the format (its extension), the rest is the file.
#![no_main]
use libfuzzer_sys::fuzz_target;

const EXTENSIONS: [&str; 6] = ["xml", "json", "txt", "obj", "dae", "pbrt"];

fuzz_target!(|data: &[u8]| {
    let Some((&pick, body)) = data.split_first() else {
        return;
    };
    let ext = EXTENSIONS[pick as usize % EXTENSIONS.len()];
    let dir = std::env::temp_dir().join(format!("penumbra-cargo-fuzz-{}", std::process::id()));
    let _ = std::fs::create_dir_all(&dir);
    let path = dir.join(format!("input.{ext}"));
    if std::fs::write(&path, body).is_ok() {
        let _ = scene::load(&path, &scene::LoadOptions::default());
    }
});
