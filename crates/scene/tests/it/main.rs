//! The crate's integration tests as one binary (linked once instead of once per file:
//! issue 36, the test suite's build time); each file is a module.

mod ceng795;
mod collada;
mod meshes;
mod mitsuba;
mod objmtl;
mod pbrt;
