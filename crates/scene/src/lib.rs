//! Penumbra's scene description and loaders.
//!
//! `load` picks a loader by extension (and by content where the extension is ambiguous) and
//! returns a [`Document`]: a scene, or a Nori-style test file. See `docs/architecture.md`.

pub mod error;
pub mod formats;
pub mod model;
pub mod spectra;
pub use base::testing;
pub(crate) mod textpos;

pub use error::{LoadError, Loc, Result, Warning};
pub use model::*;

use std::path::Path;

/// Options that apply to every loader.
#[derive(Clone, Debug, Default)]
pub struct LoadOptions {
    /// `-D name=value` overrides (Mitsuba `<default>` parameters).
    pub defines: Vec<(String, String)>,
}

/// Load any supported scene file.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Document> {
    formats::load(path, opts)
}

/// A scene given as Mitsuba/Nori XML text, as tests write them: the text is saved as
/// `<temp>/penumbra-scenes-<pid>/<name>-<n>.xml` (relative file references resolve there;
/// `n` counts the calls, so that tests running in parallel threads never write the file
/// another one is reading) and loaded. Errors (unwritable file, load error, a test file
/// instead of a scene) come back as messages.
pub fn load_xml_text(name: &str, xml: &str) -> std::result::Result<Box<SceneDesc>, String> {
    static CALLS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("penumbra-scenes-{}", std::process::id()));
    let path = dir.join(format!("{name}-{n}.xml"));
    std::fs::create_dir_all(&dir)
        .and_then(|()| std::fs::write(&path, xml))
        .map_err(|e| format!("{}: {e}", path.display()))?;
    match load(&path, &LoadOptions::default()).map_err(|e| e.to_string())? {
        Document::Scene(desc) => Ok(desc),
        Document::Test(_) => Err(format!("{}: a test file, not a scene", path.display())),
    }
}
