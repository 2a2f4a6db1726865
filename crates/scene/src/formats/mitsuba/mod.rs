//! Mitsuba 3 XML scenes, also accepting the Mitsuba 0.6 / Nori dialect.

use std::path::Path;

use crate::{Document, LoadError, LoadOptions, Loc, Result};

pub fn load(path: &Path, _opts: &LoadOptions) -> Result<Document> {
    Err(LoadError::new(
        Loc::file(path),
        "Mitsuba loader not implemented yet",
    ))
}
