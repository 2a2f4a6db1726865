//! The architecture as written, checked:
//! - `docs/architecture.md` names every top-level module of every crate and every format
//!   module (as `name.rs` or `name/`), so that a module added without a word in the document
//!   fails the tests. Inside a folder (`bsdf/`, `lights/`, `sampling/`...) the folder's own
//!   docs list its files.
//! - The renderer does not depend on the scene model (only `penumbra-build` reads both).
//! - The renderer's modules import each other without a circle, and so do the modules inside
//!   each of its folders (a folder's `mod.rs` aside: it is the folder's face, which its
//!   files may use).

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

#[test]
fn architecture_doc_names_every_module() {
    let root = root();
    let doc = std::fs::read_to_string(root.join("docs/architecture.md")).unwrap();
    let mut missing = Vec::new();
    let mut dirs: Vec<PathBuf> = ["base", "scene", "build", "render", "cli", "tools"]
        .iter()
        .map(|c| root.join("crates").join(c).join("src"))
        .collect();
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

#[test]
fn the_renderer_does_not_depend_on_the_scene_model() {
    let manifest = std::fs::read_to_string(root().join("crates/render/Cargo.toml")).unwrap();
    assert!(
        !manifest.contains("penumbra-scene"),
        "crates/render must not depend on penumbra-scene: scene-model types are turned into \
         runtime objects in crates/build"
    );
}

/// The source of `path` (a file, or every file under a folder) without its test module.
fn sources(path: &Path, out: &mut String) {
    if path.is_dir() {
        for e in std::fs::read_dir(path).unwrap() {
            sources(&e.unwrap().path(), out);
        }
    } else if path.extension().is_some_and(|e| e == "rs") {
        let text = std::fs::read_to_string(path).unwrap();
        let end = text.find("#[cfg(test)]\nmod tests").unwrap_or(text.len());
        out.push_str(&text[..end]);
        out.push('\n');
    }
}

/// The modules of folder `dir` (its files but `face` — `lib` or `mod`, the folder's face —
/// and its subfolders) → the siblings each names after `prefix`: `crate::name` at the top,
/// `super::name` inside a folder (also inside `prefix{…}`).
fn graph(dir: &Path, face: &str, prefix: &str) -> BTreeMap<String, BTreeSet<String>> {
    let mut modules = BTreeMap::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_stem().unwrap().to_string_lossy().into_owned();
        if p.is_dir() || (p.extension().is_some_and(|e| e == "rs") && name != face) {
            modules.insert(name, p);
        }
    }
    let ident = |c: char| c.is_alphanumeric() || c == '_';
    let mut graph = BTreeMap::new();
    for (name, path) in &modules {
        let mut text = String::new();
        sources(path, &mut text);
        let mut uses = BTreeSet::new();
        for (i, _) in text.match_indices(prefix) {
            let rest = &text[i + prefix.len()..];
            let names: Vec<&str> = match rest.strip_prefix('{') {
                Some(list) => list[..list.find('}').unwrap_or(list.len())]
                    .split(|c: char| !ident(c))
                    .collect(),
                None => vec![&rest[..rest.find(|c: char| !ident(c)).unwrap_or(rest.len())]],
            };
            for target in names {
                if target != name && modules.contains_key(target) {
                    uses.insert(target.to_string());
                }
            }
        }
        graph.insert(name.clone(), uses);
    }
    graph
}

/// The renderer's module graph: top-level module → modules it names as `crate::name`.
fn module_graph() -> BTreeMap<String, BTreeSet<String>> {
    graph(&root().join("crates/render/src"), "lib", "crate::")
}

/// A circle in `graph`, if there is one (depth-first search; a grey node reached again
/// closes a circle).
fn find_circle(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        n: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        match state.get(n) {
            Some(2) => return None,
            Some(1) => {
                let at = stack.iter().position(|s| s == n).unwrap();
                let mut circle = stack[at..].to_vec();
                circle.push(n.to_string());
                return Some(circle);
            }
            _ => {}
        }
        state.insert(n.to_string(), 1);
        stack.push(n.to_string());
        for m in &graph[n] {
            if let Some(c) = visit(m, graph, state, stack) {
                return Some(c);
            }
        }
        stack.pop();
        state.insert(n.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for n in graph.keys() {
        let mut stack = Vec::new();
        if let Some(circle) = visit(n, graph, &mut state, &mut stack) {
            return Some(circle);
        }
    }
    None
}

#[test]
fn renderer_modules_import_each_other_without_a_circle() {
    let graph = module_graph();
    assert!(graph.len() > 15, "only {} modules found", graph.len());
    if let Some(circle) = find_circle(&graph) {
        panic!("import circle: {}", circle.join(" → "));
    } // The layering, printed for the record (`cargo test -- --nocapture`).
    for (n, uses) in &graph {
        println!(
            "{n} → {}",
            uses.iter().cloned().collect::<Vec<_>>().join(", ")
        );
    }
}

#[test]
fn modules_inside_each_folder_import_each_other_without_a_circle() {
    let mut dirs = vec![root().join("crates/render/src")];
    let mut checked = 0;
    while let Some(dir) = dirs.pop() {
        for e in std::fs::read_dir(&dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                let graph = graph(&p, "mod", "super::");
                if let Some(circle) = find_circle(&graph) {
                    panic!(
                        "import circle in {}: {}",
                        p.strip_prefix(root()).unwrap().display(),
                        circle.join(" → ")
                    );
                }
                checked += 1;
                dirs.push(p);
            }
        }
    }
    assert!(checked > 10, "only {checked} folders checked");
}
