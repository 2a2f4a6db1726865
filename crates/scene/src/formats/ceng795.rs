//! CENG795 (METU) scenes, JSON and XML encodings: FORMATS.md §2. Issue 5.

use std::path::Path;

use crate::{Document, LoadError, LoadOptions, Loc, Result};

/// Whether an `.xml` file is a CENG795 scene (root element `<Scene>`), not Mitsuba/Nori.
pub fn is_ceng795_xml(path: &Path) -> bool {
    let Ok(text) = std::fs::read(path) else {
        return false;
    };
    let head = String::from_utf8_lossy(&text[..text.len().min(4096)]);
    // The first element that is not a declaration or comment.
    let mut rest: &str = &head;
    while let Some(i) = rest.find('<') {
        rest = &rest[i + 1..];
        if rest.starts_with('?') || rest.starts_with('!') {
            continue;
        }
        return rest.starts_with("Scene") && !rest.starts_with("Scene_");
    }
    false
}

pub fn load(path: &Path, _opts: &LoadOptions) -> Result<Document> {
    Err(LoadError::new(
        Loc::file(path),
        "this format is not implemented yet",
    ))
}
