//! Film: per-pixel weighted sums ([`Film`], [`FilmTile`]), reconstruction filters
//! ([`Filter`]) and the developed [`Image`].
//!
//! Per camera sample the integrator does (filter importance sampling, pbrt-v4):
//! ```text
//! sampler.start_pixel_sample(pixel, index);
//! let fs = filter.sample(sampler.next_2d());
//! let ray = camera.ray(pixel.as_vec2() + 0.5 + fs.offset, ...);
//! tile.add_sample(pixel, radiance, fs.weight);
//! ```

pub mod accum;
pub mod filter;
pub mod image;

pub use accum::{Film, FilmTile, PixelSums};
pub use filter::{Filter, FilterSample};
pub use image::Image;
