//! Image comparison: relMSE and the block t-test of `../shared/references/README.md`.
//! TO BE WRITTEN (helper: compare).
