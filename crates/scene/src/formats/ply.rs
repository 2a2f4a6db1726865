//! Stanford PLY mesh reader: ascii, binary little- and big-endian.

use std::path::Path;

use crate::{LoadError, Loc, Result, TriMesh};

/// Read a PLY file into a triangle mesh.
pub fn read_ply(path: &Path) -> Result<TriMesh> {
    Err(LoadError::new(
        Loc::file(path),
        "PLY reader not implemented yet",
    ))
}
