//! A linear-RGB floating-point image: the developed film, the input/output of `image_io`.
//!
//! Pixels are stored row-major with `y` pointing down (row 0 is the top of the image), one
//! `Vec3` (linear Rec.709 RGB, no transfer curve) per pixel.

use crate::math::Vec3;

#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    /// `width * height` pixels, row-major, y down.
    pub pixels: Vec<Vec3>,
}

impl Image {
    /// A black image of the given size.
    pub fn new(width: u32, height: u32) -> Image {
        Image {
            width,
            height,
            pixels: vec![Vec3::ZERO; width as usize * height as usize],
        }
    }

    /// An image filled with `value`.
    pub fn filled(width: u32, height: u32, value: Vec3) -> Image {
        Image {
            width,
            height,
            pixels: vec![value; width as usize * height as usize],
        }
    }

    /// Wraps existing row-major pixels; `None` when `pixels.len() != width * height`.
    pub fn from_pixels(width: u32, height: u32, pixels: Vec<Vec3>) -> Option<Image> {
        (pixels.len() == width as usize * height as usize).then_some(Image {
            width,
            height,
            pixels,
        })
    }

    /// Row-major index of pixel (x, y). Panics (in debug) when out of bounds.
    #[inline]
    pub fn index(&self, x: u32, y: u32) -> usize {
        debug_assert!(x < self.width && y < self.height);
        y as usize * self.width as usize + x as usize
    }

    #[inline]
    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[self.index(x, y)]
    }

    #[inline]
    pub fn set(&mut self, x: u32, y: u32, v: Vec3) {
        let i = self.index(x, y);
        self.pixels[i] = v;
    }

    /// Number of pixels.
    #[inline]
    pub fn len(&self) -> usize {
        self.pixels.len()
    }

    #[inline]
    pub fn is_empty(&self) -> bool {
        self.pixels.is_empty()
    }

    /// Mean of all pixels (f64 accumulation); zero for an empty image.
    pub fn mean(&self) -> Vec3 {
        if self.pixels.is_empty() {
            return Vec3::ZERO;
        }
        let mut s = [0.0f64; 3];
        for p in &self.pixels {
            s[0] += p.x as f64;
            s[1] += p.y as f64;
            s[2] += p.z as f64;
        }
        let n = self.pixels.len() as f64;
        Vec3::new((s[0] / n) as f32, (s[1] / n) as f32, (s[2] / n) as f32)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn get_set_row_major() {
        let mut img = Image::new(3, 2);
        img.set(2, 1, Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(img.pixels[5], Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(img.get(2, 1), Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(img.get(0, 0), Vec3::ZERO);
        assert!(Image::from_pixels(2, 2, vec![Vec3::ZERO; 3]).is_none());
        assert_eq!(Image::filled(2, 2, Vec3::ONE).mean(), Vec3::ONE);
    }
}
