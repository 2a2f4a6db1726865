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
