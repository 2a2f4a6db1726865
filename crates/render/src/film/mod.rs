//! Film: per-pixel weighted sums and reconstruction filters.

pub mod image;

pub use image::Image;
