//! CS184 COLLADA 1.4.1 scenes with the CGL technique: FORMATS.md §5. Issue 6.

use std::path::Path;

use crate::{Document, LoadError, LoadOptions, Loc, Result};

pub fn load(path: &Path, _opts: &LoadOptions) -> Result<Document> {
    Err(LoadError::new(
        Loc::file(path),
        "this format is not implemented yet",
    ))
}
