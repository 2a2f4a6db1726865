//! The crate's integration tests as one binary (linked once instead of once per file:
//! issue 36, the test suite's build time); each file is a module.

mod ceng795;
mod ceng795_textures;
mod cli;
mod comp30019;
mod cs184;
mod debug_paths;
mod denoise;
mod flags;
mod fuzz;
mod hardening;
mod objmtl_cli;
mod readme;
mod shards;
