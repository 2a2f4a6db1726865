//! Film: per-pixel weighted sums and reconstruction filters. TO BE WRITTEN (helper: sampling/film).

mod image;
pub use image::Image;
