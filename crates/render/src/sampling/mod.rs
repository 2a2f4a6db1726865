//! Sampling: warps, discrete and piecewise-constant distributions, and the per-pixel samplers.

pub mod distrib;
pub mod sampler;
pub mod warp;

pub use distrib::{AliasTable, Distribution1D, Distribution2D, ONE_MINUS_EPSILON};
pub use sampler::Sampler;
