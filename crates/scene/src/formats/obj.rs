//! Wavefront OBJ mesh reader (geometry only; materials are the CS-E5520 loader's business).

use std::path::Path;

use crate::{LoadError, Loc, Result, TriMesh};

/// Read an OBJ file into one triangle mesh (all groups merged).
pub fn read_obj(path: &Path) -> Result<TriMesh> {
    Err(LoadError::new(
        Loc::file(path),
        "OBJ reader not implemented yet",
    ))
}
