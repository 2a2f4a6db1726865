//! `docs/architecture.md` names every top-level module of the three crates and every format
//! module (as `name.rs` or `name/`), so that a module added without a word in the document
//! fails the tests. Inside a folder (`bsdf/`, `lights/`, `sampling/`...) the folder's own
//! docs list its files.

use std::path::Path;

#[test]
fn architecture_doc_names_every_module() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let doc = std::fs::read_to_string(root.join("docs/architecture.md")).unwrap();
    let mut missing = Vec::new();
    let mut dirs = vec![
        root.join("crates/render/src"),
        root.join("crates/scene/src"),
        root.join("crates/cli/src"),
    ];
    let mut seen = 0;
    while let Some(dir) = dirs.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            let name = p.file_name().unwrap().to_string_lossy().into_owned();
            let mention = if p.is_dir() {
                if name == "formats" {
                    dirs.push(p.clone());
                }
                format!("{name}/")
            } else if name.ends_with(".rs") && name != "lib.rs" && name != "mod.rs" {
                name
            } else {
                continue;
            };
            seen += 1;
            if !doc.contains(&mention) {
                missing.push(p.strip_prefix(&root).unwrap().display().to_string());
            }
        }
    }
    assert!(seen > 30, "only {seen} modules found");
    assert!(
        missing.is_empty(),
        "docs/architecture.md does not name: {missing:?}"
    );
}
