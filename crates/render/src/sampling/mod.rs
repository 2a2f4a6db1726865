//! Sampling: warps, discrete and piecewise-constant distributions, equiangular distances
//! towards a point, the per-pixel samplers, and path guiding's SD-tree (`sdtree.rs`).

pub mod distrib;
pub mod equiangular;
pub mod sampler;
pub mod sdtree;
pub mod warp;

pub use distrib::{AliasTable, Distribution1D, Distribution2D, ONE_MINUS_EPSILON};
pub use equiangular::Equiangular;
pub use sampler::Sampler;

use crate::math::Vec2;

/// A stream of uniform numbers in `[0, 1)`: a pixel sample's [`Sampler`], or a Markov
/// chain's primary sample vector (`integrators::mlt`). Code generic over it draws the same
/// numbers in the same order from either.
pub trait Samples {
    fn next_1d(&mut self) -> f32;
    fn next_2d(&mut self) -> Vec2;
    /// The numbers drawn from here on come from stream `stream` (0 until told otherwise).
    /// BDPT draws its camera subpath from stream 0, its light subpath from 1 and its
    /// connections from 2, so that a Markov chain's primary sample vector can keep them
    /// apart (a mutation that makes one part draw more or fewer numbers then does not shift
    /// another part's); a pixel sample's [`Sampler`] has one stream and ignores this.
    #[inline(always)]
    fn start_stream(&mut self, _stream: usize) {}
}

impl Samples for Sampler {
    #[inline(always)]
    fn next_1d(&mut self) -> f32 {
        Sampler::next_1d(self)
    }
    #[inline(always)]
    fn next_2d(&mut self) -> Vec2 {
        Sampler::next_2d(self)
    }
}
