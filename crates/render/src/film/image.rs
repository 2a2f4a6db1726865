//! PLACEHOLDER (helper: compare) until the film helper's `Image` lands; keep theirs on merge.

use crate::math::Vec3;

/// A linear-RGB f32 image, row-major, y down.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec3>,
}

impl Image {
    pub fn new(width: u32, height: u32) -> Image {
        Image {
            width,
            height,
            pixels: vec![Vec3::ZERO; width as usize * height as usize],
        }
    }

    pub fn get(&self, x: u32, y: u32) -> Vec3 {
        self.pixels[y as usize * self.width as usize + x as usize]
    }

    pub fn set(&mut self, x: u32, y: u32, v: Vec3) {
        self.pixels[y as usize * self.width as usize + x as usize] = v;
    }
}
