//! Sampling: warps, discrete and piecewise-constant distributions, equiangular distances
//! towards a point, and the per-pixel samplers.

pub mod distrib;
pub mod equiangular;
pub mod sampler;
pub mod warp;

pub use distrib::{AliasTable, Distribution1D, Distribution2D, ONE_MINUS_EPSILON};
pub use equiangular::Equiangular;
pub use sampler::Sampler;
