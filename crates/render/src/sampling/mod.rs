//! Sampling: warps, discrete and piecewise-constant distributions, and the per-pixel samplers.

pub mod distrib;
pub mod sampler;
pub mod warp;
