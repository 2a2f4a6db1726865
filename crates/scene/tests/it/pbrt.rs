//! pbrt-v4 loader: directives, transforms and the camera frame, defaults, parameter types,
//! errors with their positions, the parse time of a large inline mesh, and the shared
//! Bitterli scenes.

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::{Mat4, Vec3};
use scene::*;

/// Write `files` (name, content) into a fresh temporary folder; returns the first file's path.
fn write_scene(files: &[(&str, &[u8])]) -> PathBuf {
    static N: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!(
        "penumbra-pbrt-test-{}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    dir.join(files[0].0)
}

fn load_text(text: &str) -> Result<SceneDesc> {
    let path = write_scene(&[("scene.pbrt", text.as_bytes())]);
    match load(&path, &LoadOptions::default())? {
        Document::Scene(s) => Ok(*s),
        Document::Test(_) => panic!("a scene expected"),
    }
}

fn scene(text: &str) -> SceneDesc {
    load_text(text).unwrap_or_else(|e| panic!("{e}"))
}

fn error(text: &str) -> LoadError {
    match load_text(text) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e,
    }
}

fn warnings(s: &SceneDesc) -> Vec<String> {
    s.warnings.iter().map(|w| w.message.clone()).collect()
}

#[test]
fn bitterli_scenes_load_without_warnings() {
    for name in [
        "bitterli-cornell-box",
        "bitterli-veach-mis",
        "bitterli-coffee",
        "bitterli-water-caustic",
    ] {
        let Some(dir) = testing::shared_dir(&format!("scenes/standard/{name}")) else {
            return;
        };
        let path = dir.join("pbrt/scene-v4.pbrt");
        let t = std::time::Instant::now();
        let Document::Scene(s) =
            load(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
        else {
            panic!("a scene expected")
        };
        let tris: usize = s
            .shapes
            .iter()
            .map(|x| match &x.shape {
                Shape::Mesh(m) => m.indices.len(),
                _ => 0,
            })
            .sum();
        println!(
            "{name}: {} shapes, {tris} triangles, {} materials, {} textures, {} emitters, {:?}",
            s.shapes.len(),
            s.materials.len(),
            s.textures.len(),
            s.emitters.len(),
            t.elapsed()
        );
        for w in &s.warnings {
            println!("  {w}");
        }
        assert!(s.warnings.is_empty(), "{name}: {:?}", warnings(&s));
        assert!(!s.shapes.is_empty());
    }
}
