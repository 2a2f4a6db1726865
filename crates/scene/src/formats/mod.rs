//! One module per input format, and the registry that picks one for a file.

pub mod ceng795;
pub mod collada;
pub mod common;
pub mod comp30019;
pub mod mitsuba;
pub mod obj;
pub mod objmtl;
pub mod pbrt;
pub mod ply;

use std::path::Path;

use crate::{Document, LoadError, LoadOptions, Loc, Result};

/// Pick the loader by extension, sniffing the content where the extension is ambiguous.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Document> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .unwrap_or_default();
    match std::fs::metadata(path) {
        Ok(m) if m.is_file() => {}
        Ok(_) => {
            return Err(LoadError::new(
                Loc::file(path),
                "not a regular file (expected a scene file)",
            ));
        }
        Err(e) => return Err(LoadError::new(Loc::file(path), format!("cannot read: {e}"))),
    }
    match ext.as_str() {
        "xml" if ceng795::is_ceng795_xml(path) => ceng795::load(path, opts),
        "xml" => mitsuba::load(path, opts),
        "json" => ceng795::load(path, opts),
        "txt" => comp30019::load(path, opts),
        "obj" => objmtl::load(path, opts),
        "dae" => collada::load(path, opts),
        "pbrt" => pbrt::load(path, opts),
        _ => Err(LoadError::new(
            Loc::file(path),
            format!(
                "unsupported scene file extension '.{ext}' (supported: .xml (Mitsuba, Nori, CENG795), .json (CENG795), .txt (COMP30019), .obj (OBJ+MTL), .dae (COLLADA), .pbrt (pbrt-v4, pbrt-v3))"
            ),
        )),
    }
}
