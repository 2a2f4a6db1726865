//! Image-space post-processing of developed (linear) images.
//!
//! [`bloom`]: the glow around bright pixels that a real lens and eye add (COMP30019's extended
//! `--post`). The part of every pixel above a luminance `threshold` is blurred with a Gaussian
//! whose standard deviation is a fraction of the image size and added back with weight
//! `strength`. Energy is moved, not created, when `strength` = 1 and the bright part is removed
//! from the source (`conserve`): the blur kernel is normalised, so the image's total stays the
//! same up to what spreads past the borders.

use crate::film::Image;
use crate::math::{Vec3, luminance};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bloom {
    /// Luminance above which a pixel glows.
    pub threshold: f32,
    /// Standard deviation of the blur as a fraction of max(width, height).
    pub radius: f32,
    /// Weight of the blurred highlights added back.
    pub strength: f32,
    /// Remove the bright part from its pixel before adding the blur (energy-conserving glow).
    pub conserve: bool,
}

impl Default for Bloom {
    fn default() -> Self {
        Bloom {
            threshold: 1.0,
            radius: 0.01,
            strength: 1.0,
            conserve: true,
        }
    }
}

/// Separable Gaussian blur with clamp-free borders (weights renormalised over the image).
fn blur(img: &[Vec3], w: usize, h: usize, sigma: f32) -> Vec<Vec3> {
    let r = (3.0 * sigma).ceil().max(1.0) as isize;
    let kernel: Vec<f32> = (-r..=r)
        .map(|i| (-(i * i) as f32 / (2.0 * sigma * sigma)).exp())
        .collect();
    let pass = |src: &[Vec3], horizontal: bool| -> Vec<Vec3> {
        let mut out = vec![Vec3::ZERO; w * h];
        for y in 0..h {
            for x in 0..w {
                let (mut sum, mut wsum) = (Vec3::ZERO, 0.0f32);
                for (k, &kw) in kernel.iter().enumerate() {
                    let o = k as isize - r;
                    let (sx, sy) = if horizontal {
                        (x as isize + o, y as isize)
                    } else {
                        (x as isize, y as isize + o)
                    };
                    if sx < 0 || sy < 0 || sx >= w as isize || sy >= h as isize {
                        continue;
                    }
                    sum += src[sy as usize * w + sx as usize] * kw;
                    wsum += kw;
                }
                out[y * w + x] = if wsum > 0.0 { sum / wsum } else { Vec3::ZERO };
            }
        }
        out
    };
    let tmp = pass(img, true);
    pass(&tmp, false)
}

/// Add a bloom to `img` in place.
pub fn bloom(img: &mut Image, b: &Bloom) {
    let (w, h) = (img.width as usize, img.height as usize);
    if w == 0 || h == 0 || b.strength.is_nan() || b.strength <= 0.0 {
        return;
    }
    let bright: Vec<Vec3> = img
        .pixels
        .iter()
        .map(|&c| {
            let y = luminance(c);
            if y > b.threshold && y.is_finite() {
                c * ((y - b.threshold) / y)
            } else {
                Vec3::ZERO
            }
        })
        .collect();
    let sigma = (b.radius * w.max(h) as f32).max(0.5);
    let glow = blur(&bright, w, h, sigma);
    for ((p, g), s) in img.pixels.iter_mut().zip(glow).zip(bright) {
        if b.conserve {
            *p -= s;
        }
        *p += g * b.strength;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dark_images_are_unchanged() {
        let mut img = Image::filled(8, 8, Vec3::splat(0.5));
        let before = img.clone();
        bloom(&mut img, &Bloom::default());
        assert_eq!(img, before);
    }

    #[test]
    fn highlight_spreads_and_total_is_kept_in_the_interior() {
        let mut img = Image::new(41, 41);
        img.pixels[20 * 41 + 20] = Vec3::splat(101.0);
        let total = |i: &Image| i.pixels.iter().map(|p| p.x as f64).sum::<f64>();
        let before = total(&img);
        bloom(
            &mut img,
            &Bloom {
                radius: 2.0 / 41.0,
                ..Bloom::default()
            },
        );
        assert!(img.pixels[20 * 41 + 22].x > 0.1);
        assert!(img.pixels[20 * 41 + 20].x < 101.0);
        assert!(
            (total(&img) - before).abs() < 1e-3 * before,
            "{}",
            total(&img)
        );
    }
}
