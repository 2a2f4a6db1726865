//! Film: per-pixel weighted sums ([`Film`], [`FilmTile`]), reconstruction filters
//! ([`Filter`]) and the developed [`Image`].
//!
//! Per camera sample the driver does (splatting, as Mitsuba 3):
//! ```text
//! sampler.start_pixel_sample(pixel, index);
//! let p_film = pixel.as_vec2() + sampler.next_2d();
//! let ray = camera.generate_ray(p_film, sampler.next_2d());
//! tile.add_sample(p_film, radiance);
//! ```

pub mod accum;
pub mod filter;
pub mod image;
pub mod state;
pub mod tonemap;

pub use accum::{Film, FilmLayout, FilmTile, FixedSums, PixelSums};
pub use filter::Filter;
pub use image::Image;

/// The film a scene renders to: its size, optional crop window, reconstruction filter and
/// the tone mapping of its 8-bit outputs (`None`: clamp and the sRGB curve).
#[derive(Clone, Debug, PartialEq)]
pub struct FilmSettings {
    pub width: u32,
    pub height: u32,
    pub crop: Option<base::CropWindow>,
    pub filter: Filter,
    pub tonemap: Option<base::Tonemap>,
}

impl FilmSettings {
    /// An empty film of this size, crop window and filter.
    pub fn film(&self) -> Film {
        Film::new(self.width, self.height, self.crop, self.filter)
    }

    /// `[min, max)` of the pixels the film stores (where samples are taken), without
    /// allocating it.
    pub fn pixel_bounds(&self) -> (crate::math::UVec2, crate::math::UVec2) {
        accum::pixel_bounds(self.width, self.height, self.crop)
    }
}
