//! The crate's integration tests as one binary (linked once instead of once per file:
//! issue 36, the test suite's build time); each file is a module.

mod accel;
mod architecture_doc;
mod chi2_bsdf;
mod chi2_guiding;
mod chi2_media;
mod chi2_warps;
mod compare;
mod dispersion;
mod film_stats;
mod furnace_bsdf;
mod image_io;
mod layered_bsdf;
mod sampling_common;
mod sampling_stats;
mod spectral;
mod transmittance;
