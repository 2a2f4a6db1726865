//! Textures evaluated at a surface uv (Mitsuba 3 semantics).
//!
//! - `Bitmap`: uv is transformed by `to_uv`, then wrapped; (0,0) is the *top-left* corner of
//!   the image file (Mitsuba 3 does not flip bitmaps; its OBJ reader flips v instead).
//!   Bilinear filtering between pixel centres, or nearest.
//! - `Checkerboard`: `color0` where the fractional parts of u and v are both below or both
//!   above ½, `color1` elsewhere.

use std::sync::Arc;

use scene::{TextureFilter, WrapMode};

use crate::film::Image;
use crate::math::{Mat3, Vec2, Vec3};

#[derive(Clone, Debug)]
pub enum Texture {
    Constant(Vec3),
    Bitmap {
        image: Arc<Image>,
        filter: TextureFilter,
        wrap: WrapMode,
        to_uv: Mat3,
    },
    Checkerboard {
        color0: Vec3,
        color1: Vec3,
        to_uv: Mat3,
    },
}

#[inline]
fn wrap_index(i: i64, n: u32, mode: WrapMode) -> u32 {
    let n = n as i64;
    let v = match mode {
        WrapMode::Repeat => i.rem_euclid(n),
        WrapMode::Clamp => i.clamp(0, n - 1),
        WrapMode::Mirror => {
            let m = i.rem_euclid(2 * n);
            if m < n { m } else { 2 * n - 1 - m }
        }
    };
    v as u32
}

impl Texture {
    pub fn eval(&self, uv: Vec2) -> Vec3 {
        match self {
            Texture::Constant(c) => *c,
            Texture::Checkerboard {
                color0,
                color1,
                to_uv,
            } => {
                let p = to_uv.transform_point2(uv);
                let f = p - p.floor();
                if (f.x > 0.5) == (f.y > 0.5) {
                    *color0
                } else {
                    *color1
                }
            }
            Texture::Bitmap {
                image,
                filter,
                wrap,
                to_uv,
            } => {
                let p = to_uv.transform_point2(uv);
                if !p.is_finite() {
                    return Vec3::ZERO;
                }
                let (w, h) = (image.width, image.height);
                let x = p.x * w as f32;
                let y = p.y * h as f32;
                match filter {
                    TextureFilter::Nearest => {
                        let xi = wrap_index(x.floor() as i64, w, *wrap);
                        let yi = wrap_index(y.floor() as i64, h, *wrap);
                        image.get(xi, yi)
                    }
                    TextureFilter::Bilinear => {
                        let (xs, ys) = (x - 0.5, y - 0.5);
                        let (x0, y0) = (xs.floor(), ys.floor());
                        let (fx, fy) = (xs - x0, ys - y0);
                        let (x0, y0) = (x0 as i64, y0 as i64);
                        let px = |dx: i64, dy: i64| {
                            image.get(wrap_index(x0 + dx, w, *wrap), wrap_index(y0 + dy, h, *wrap))
                        };
                        (px(0, 0) * (1.0 - fx) + px(1, 0) * fx) * (1.0 - fy)
                            + (px(0, 1) * (1.0 - fx) + px(1, 1) * fx) * fy
                    }
                }
            }
        }
    }

    /// Mean value over the unit uv square (for light power estimates and albedo hints).
    pub fn mean(&self) -> Vec3 {
        match self {
            Texture::Constant(c) => *c,
            Texture::Checkerboard { color0, color1, .. } => 0.5 * (*color0 + *color1),
            Texture::Bitmap { image, .. } => {
                let n = image.pixels.len().max(1) as f32;
                image.pixels.iter().copied().sum::<Vec3>() / n
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_modes() {
        assert_eq!(wrap_index(-1, 4, WrapMode::Repeat), 3);
        assert_eq!(wrap_index(5, 4, WrapMode::Repeat), 1);
        assert_eq!(wrap_index(-1, 4, WrapMode::Clamp), 0);
        assert_eq!(wrap_index(9, 4, WrapMode::Clamp), 3);
        assert_eq!(wrap_index(4, 4, WrapMode::Mirror), 3);
        assert_eq!(wrap_index(-1, 4, WrapMode::Mirror), 0);
    }

    #[test]
    fn checkerboard_quadrants() {
        let t = Texture::Checkerboard {
            color0: Vec3::ZERO,
            color1: Vec3::ONE,
            to_uv: Mat3::IDENTITY,
        };
        assert_eq!(t.eval(Vec2::new(0.25, 0.25)), Vec3::ZERO);
        assert_eq!(t.eval(Vec2::new(0.75, 0.75)), Vec3::ZERO);
        assert_eq!(t.eval(Vec2::new(0.75, 0.25)), Vec3::ONE);
        assert_eq!(t.eval(Vec2::new(1.25, 0.75)), Vec3::ONE);
    }

    #[test]
    fn bilinear_hits_pixel_centres_exactly() {
        let mut img = Image::new(2, 2);
        img.set(0, 0, Vec3::new(1.0, 0.0, 0.0));
        img.set(1, 0, Vec3::new(0.0, 1.0, 0.0));
        img.set(0, 1, Vec3::new(0.0, 0.0, 1.0));
        img.set(1, 1, Vec3::ONE);
        let t = Texture::Bitmap {
            image: Arc::new(img),
            filter: TextureFilter::Bilinear,
            wrap: WrapMode::Clamp,
            to_uv: Mat3::IDENTITY,
        };
        assert!((t.eval(Vec2::new(0.25, 0.25)) - Vec3::new(1.0, 0.0, 0.0)).length() < 1e-6);
        assert!((t.eval(Vec2::new(0.75, 0.75)) - Vec3::ONE).length() < 1e-6);
        let mid = t.eval(Vec2::new(0.5, 0.5));
        assert!((mid - Vec3::splat(0.5)).length() < 1e-6);
    }
}
