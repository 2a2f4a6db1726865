//! COMP30019 (University of Melbourne) text scenes: FORMATS.md §1. Issue 4.

use std::path::Path;

use crate::{Document, LoadError, LoadOptions, Loc, Result};

pub fn load(path: &Path, _opts: &LoadOptions) -> Result<Document> {
    Err(LoadError::new(
        Loc::file(path),
        "this format is not implemented yet",
    ))
}
