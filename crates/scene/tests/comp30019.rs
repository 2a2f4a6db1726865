//! The COMP30019 loader on the course's own scenes (skipped when ../shared is absent) and on
//! ours.

use std::path::Path;

use scene::{Document, LoadOptions, Shape};

fn load(path: &Path) -> scene::SceneDesc {
    match scene::load(path, &LoadOptions::default()) {
        Ok(Document::Scene(s)) => *s,
        Ok(_) => panic!("{}: not a scene", path.display()),
        Err(e) => panic!("{e}"),
    }
}

#[test]
fn course_scenes_load() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes/comp30019");
    if !dir.is_dir() {
        println!("skipped: {} is absent", dir.display());
        return;
    }
    // Model paths are relative to the course project root: the loader falls back to the scene
    // file's folder, which does not hold `tests/models`, so run from the root.
    std::env::set_current_dir(&dir).unwrap();
    let s = load(Path::new("tests/sample_scene_2.txt"));
    assert_eq!(s.materials.len(), 6);
    assert_eq!(s.emitters.len(), 2);
    assert_eq!(s.shapes.len(), 2 + 2 + 8);
    let s = load(Path::new("tests/sample_scene_obj.txt"));
    let meshes = s
        .shapes
        .iter()
        .filter(|sh| matches!(&sh.shape, Shape::Mesh(m) if m.triangle_count() > 1000))
        .count();
    assert_eq!(meshes, 1, "the bunny");
    for entry in std::fs::read_dir("tests").unwrap() {
        let p = entry.unwrap().path();
        if p.extension().is_some_and(|e| e == "txt") {
            let s = load(&p);
            assert!(!s.shapes.is_empty(), "{}", p.display());
        }
    }
}

#[test]
fn our_scenes_load() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/comp30019");
    for name in ["showcase.txt", "dof.txt", "equivalence.txt"] {
        let s = load(&dir.join(name));
        assert!(s.warnings.is_empty(), "{name}: {:?}", s.warnings);
    }
}
