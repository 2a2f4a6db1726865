//! CS-E5520 (Aalto) OBJ+MTL files as whole scenes: FORMATS.md §3. Issue 7.

use std::path::Path;

use crate::{Document, LoadError, LoadOptions, Loc, Result};

pub fn load(path: &Path, _opts: &LoadOptions) -> Result<Document> {
    Err(LoadError::new(
        Loc::file(path),
        "this format is not implemented yet",
    ))
}
