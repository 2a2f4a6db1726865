//! Penumbra's scene description and loaders.
//!
//! `load` picks a loader by extension (and by content where the extension is ambiguous) and
//! returns a [`Document`]: a scene, or a Nori-style test file. See `docs/architecture.md`.

pub mod error;
pub mod formats;
pub mod model;
pub mod spectra;
pub mod testing;
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

/// Read a whole file, refusing anything but a regular file first: a device such as
/// `/dev/zero` or a FIFO named as a mesh or texture would otherwise be read until memory runs
/// out, or block for ever.
pub fn read_file(path: &Path) -> std::io::Result<Vec<u8>> {
    let meta = std::fs::metadata(path)?;
    if !meta.is_file() {
        return Err(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "not a regular file",
        ));
    }
    std::fs::read(path)
}

/// Load any supported scene file.
pub fn load(path: &Path, opts: &LoadOptions) -> Result<Document> {
    formats::load(path, opts)
}
