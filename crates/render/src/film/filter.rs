//! Pixel reconstruction filters (Mitsuba 3's `rfilter` plugins), used by the film to splat
//! every camera sample onto the pixels around it ([`super::FilmTile::add_sample`]).
//!
//! Every filter is separable, `f(x, y) = g(x) g(y)`, with Mitsuba 3's 1D profiles `g`
//! (`x` in pixels):
//!
//! | filter   | `g(x)` on `|x| ≤ r`                                          | defaults          |
//! |----------|---------------------------------------------------------------|-------------------|
//! | box      | 1                                                             | r = 0.5           |
//! | tent     | 1 − |x|/r                                                     | r = 1             |
//! | gaussian | max(0, exp(−x²/2σ²) − exp(−r²/2σ²)) (truncation value removed) | σ = 0.5, r = 4σ   |
//! | mitchell | Mitchell–Netravali cubic of `t = 2|x|/r ∈ [0, 2]`             | B = C = 1/3, r = 2 |
//! | lanczos  | sinc(x) sinc(x/τ), sinc(x) = sin(πx)/(πx) (negative lobes kept) | r = τ = 3         |
//!
//! The values are unnormalised, as in Mitsuba: the film divides by the sum of the weights.
//! Mitsuba's gaussian evaluates a Remez fit of the same truncated profile (its LLVM variants)
//! or a 32-per-pixel table (scalar variants); we evaluate it exactly. Its Mitchell filter
//! always has radius 2, where our `t = 2|x|/r` is `|x|`.
//!
//! Invalid parameters (non-finite, ≤ 0) fall back to the defaults above. A gaussian radius is
//! capped at 8σ (beyond it the truncated profile is < 10⁻¹³ and would only cost pixel updates),
//! and every radius at [`MAX_RADIUS`], which bounds the border of a film tile.

use super::Image;
use crate::math::{Vec2, Vec3};
use base::FilterDesc;

/// Largest filter radius, in pixels (a film tile stores a border this wide around its pixels).
pub const MAX_RADIUS: f32 = 16.0;

/// A reconstruction filter (closed set, see the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Filter {
    Box { radius: f32 },
    Tent { radius: f32 },
    Gaussian { stddev: f32, radius: f32 },
    Mitchell { b: f32, c: f32, radius: f32 },
    Lanczos { radius: f32, tau: f32 },
}

#[inline]
fn radius_or(v: f32, default: f32) -> f32 {
    if v.is_finite() && v > 0.0 {
        v.min(MAX_RADIUS)
    } else {
        default
    }
}

#[inline]
pub(crate) fn box_1d(x: f32, radius: f32) -> f32 {
    if x.abs() <= radius { 1.0 } else { 0.0 }
}

#[inline]
pub(crate) fn tent_1d(x: f32, radius: f32) -> f32 {
    (1.0 - x.abs() / radius).max(0.0)
}

#[inline]
pub(crate) fn gaussian_1d(x: f32, stddev: f32, radius: f32) -> f32 {
    if x.abs() > radius {
        return 0.0;
    }
    let alpha = -1.0 / (2.0 * stddev * stddev);
    ((alpha * x * x).exp() - (alpha * radius * radius).exp()).max(0.0)
}

#[inline]
pub(crate) fn mitchell_1d(x: f32, b: f32, c: f32, radius: f32) -> f32 {
    let t = (2.0 * x / radius).abs();
    let (t2, t3) = (t * t, t * t * t);
    let v = if t < 1.0 {
        (12.0 - 9.0 * b - 6.0 * c) * t3 + (-18.0 + 12.0 * b + 6.0 * c) * t2 + (6.0 - 2.0 * b)
    } else if t < 2.0 {
        (-b - 6.0 * c) * t3
            + (6.0 * b + 30.0 * c) * t2
            + (-12.0 * b - 48.0 * c) * t
            + (8.0 * b + 24.0 * c)
    } else {
        0.0
    };
    v * (1.0 / 6.0)
}

/// Mitsuba 3's windowed sinc (its `lanczos`, evaluated as `sin(πx) sin(πx/τ) / (π² x² / τ)`,
/// 1 below 10⁻⁵ pixels).
#[inline]
pub(crate) fn lanczos_1d(x: f32, radius: f32, tau: f32) -> f32 {
    let x = x.abs();
    if x > radius {
        return 0.0;
    }
    if x < 1e-5 {
        return 1.0;
    }
    let x1 = std::f32::consts::PI * x;
    let x2 = x1 / tau;
    (x1.sin() * x2.sin()) / (x1 * x2)
}

impl Filter {
    /// The filter described by `desc` (invalid parameters replaced by defaults).
    pub fn new(desc: &FilterDesc) -> Filter {
        match *desc {
            FilterDesc::Box { radius } => Filter::Box {
                radius: radius_or(radius, 0.5),
            },
            FilterDesc::Tent { radius } => Filter::Tent {
                radius: radius_or(radius, 1.0),
            },
            FilterDesc::Gaussian { stddev, radius } => {
                let stddev = radius_or(stddev, 0.5);
                Filter::Gaussian {
                    stddev,
                    radius: radius_or(radius, 4.0 * stddev)
                        .min(8.0 * stddev)
                        .min(MAX_RADIUS),
                }
            }
            FilterDesc::Mitchell { b, c, radius } => Filter::Mitchell {
                b: if b.is_finite() { b } else { 1.0 / 3.0 },
                c: if c.is_finite() { c } else { 1.0 / 3.0 },
                radius: radius_or(radius, 2.0),
            },
            FilterDesc::Lanczos { radius, tau } => Filter::Lanczos {
                radius: radius_or(radius, 3.0),
                tau: radius_or(tau, 3.0),
            },
        }
    }

    /// Mitsuba's default: gaussian, σ = 0.5, radius 2.
    pub fn default_gaussian() -> Filter {
        Filter::new(&FilterDesc::Gaussian {
            stddev: 0.5,
            radius: 2.0,
        })
    }

    /// Support radius in pixels (the filter is 0 for |x| or |y| > radius).
    #[inline]
    pub fn radius(&self) -> f32 {
        match *self {
            Filter::Box { radius }
            | Filter::Tent { radius }
            | Filter::Gaussian { radius, .. }
            | Filter::Mitchell { radius, .. }
            | Filter::Lanczos { radius, .. } => radius,
        }
    }

    /// The 1D profile g(x).
    #[inline]
    pub fn eval_1d(&self, x: f32) -> f32 {
        match *self {
            Filter::Box { radius } => box_1d(x, radius),
            Filter::Tent { radius } => tent_1d(x, radius),
            Filter::Gaussian { stddev, radius } => gaussian_1d(x, stddev, radius),
            Filter::Mitchell { b, c, radius } => mitchell_1d(x, b, c, radius),
            Filter::Lanczos { radius, tau } => lanczos_1d(x, radius, tau),
        }
    }

    /// f(p) = g(p.x) g(p.y), unnormalised (Mitsuba's values).
    #[inline]
    pub fn eval(&self, p: Vec2) -> f32 {
        self.eval_1d(p.x) * self.eval_1d(p.y)
    }

    /// ∫ g(x) dx over `[a, b]` (clipped to the support): the 1D profile's weight over an
    /// interval. Midpoint rule on 2048 steps, exact for the box filter.
    pub fn integral_1d(&self, a: f32, b: f32) -> f64 {
        let r = self.radius() as f64;
        let (a, b) = ((a as f64).max(-r), (b as f64).min(r));
        if b <= a {
            return 0.0;
        }
        let n = 2048;
        let dx = (b - a) / n as f64;
        (0..n)
            .map(|k| self.eval_1d((a + (k as f64 + 0.5) * dx) as f32) as f64)
            .sum::<f64>()
            * dx
    }

    /// `(∫f)² / ∫f²` in pixels, at least 1: the effective number of pixels a splatted sample
    /// is spread over (1 for the box filter, π for the default gaussian). Midpoint rule.
    pub fn footprint(&self) -> f64 {
        let n = 4096;
        let r = self.radius() as f64;
        let dx = 2.0 * r / n as f64;
        let (mut s1, mut s2) = (0.0f64, 0.0f64);
        for k in 0..n {
            let g = self.eval_1d((-r + (k as f64 + 0.5) * dx) as f32) as f64;
            s1 += g * dx;
            s2 += g * g * dx;
        }
        if s2 > 0.0 {
            (s1 * s1 / s2).powi(2).max(1.0)
        } else {
            1.0
        }
    }
}

impl Filter {
    /// Whether this is the box filter of one pixel (a sample counts in its own pixel only).
    pub fn is_pixel_box(&self) -> bool {
        matches!(*self, Filter::Box { radius } if radius <= 0.5)
    }

    /// `img`, an image made with the one-pixel box filter (each pixel the mean over its own
    /// area), reconstructed with this filter instead: each pixel the filter-weighted mean of
    /// its neighbours, the weight of a neighbour `k` pixels away `∫ g` over that pixel
    /// (separable, two passes), normalised over the neighbours inside the image as the film
    /// normalises by the weights of the samples it received. Denoising renders with the box
    /// filter (its noise independent from pixel to pixel, as denoisers are trained on) and
    /// applies the scene's filter to the denoised image this way.
    pub fn apply_to_box_image(&self, img: &Image) -> Image {
        if self.is_pixel_box() {
            return img.clone();
        }
        let k = (self.radius() + 0.5).ceil() as i64;
        let w: Vec<f32> = (-k..=k)
            .map(|o| self.integral_1d(o as f32 - 0.5, o as f32 + 0.5) as f32)
            .collect();
        let (width, height) = (img.width as i64, img.height as i64);
        let pass = |src: &Image, horizontal: bool| -> Image {
            let mut out = src.clone();
            for y in 0..height {
                for x in 0..width {
                    let (mut sum, mut wsum) = (Vec3::ZERO, 0.0f32);
                    for (i, &wk) in w.iter().enumerate() {
                        let o = i as i64 - k;
                        let (sx, sy) = if horizontal { (x + o, y) } else { (x, y + o) };
                        if sx < 0 || sy < 0 || sx >= width || sy >= height {
                            continue;
                        }
                        sum += src.get(sx as u32, sy as u32) * wk;
                        wsum += wk;
                    }
                    if wsum.abs() > 1e-6 {
                        out.set(x as u32, y as u32, sum / wsum);
                    }
                }
            }
            out
        };
        pass(&pass(img, true), false)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lanczos_is_a_windowed_sinc() {
        let f = Filter::new(&FilterDesc::Lanczos {
            radius: 3.0,
            tau: 3.0,
        });
        assert_eq!(f.eval_1d(0.0), 1.0);
        // Zeros at the integers, a negative lobe between 1 and 2, nothing beyond the radius.
        for x in [1.0f32, 2.0, -2.0] {
            assert!(f.eval_1d(x).abs() < 1e-6, "g({x}) = {}", f.eval_1d(x));
        }
        let pi = std::f32::consts::PI;
        let want = (1.5 * pi).sin() * (0.5 * pi).sin() / (1.5 * pi * 0.5 * pi);
        assert!((f.eval_1d(1.5) - want).abs() < 1e-6 && want < 0.0);
        assert_eq!(f.eval_1d(3.01), 0.0);
    }

    #[test]
    fn profiles_match_mitsuba_values() {
        let bx = Filter::new(&FilterDesc::Box { radius: 0.5 });
        assert_eq!(bx.eval_1d(0.5), 1.0);
        assert_eq!(bx.eval_1d(0.51), 0.0);
        let tent = Filter::new(&FilterDesc::Tent { radius: 1.0 });
        assert!((tent.eval_1d(-0.25) - 0.75).abs() < 1e-6);
        let g = Filter::default_gaussian();
        let bias = (-8.0f32).exp();
        assert!((g.eval_1d(0.5) - ((-0.5f32).exp() - bias)).abs() < 1e-6);
        assert_eq!(g.eval_1d(2.0), 0.0);
        assert_eq!(g.eval(Vec2::new(0.5, 3.0)), 0.0);
        // Mitchell (B = C = 1/3): g(0) = (6 − 2B)/6 = 8/9, g(1) = B/6 = 1/18, g(2) = 0.
        let m = Filter::new(&FilterDesc::Mitchell {
            b: 1.0 / 3.0,
            c: 1.0 / 3.0,
            radius: 2.0,
        });
        assert!((m.eval_1d(0.0) - 8.0 / 9.0).abs() < 1e-6);
        assert!((m.eval_1d(1.0) - 1.0 / 18.0).abs() < 1e-6);
        assert!(m.eval_1d(1.5) < 0.0, "negative lobe");
        assert_eq!(m.eval_1d(2.0), 0.0);
    }

    #[test]
    fn footprints() {
        let bx = Filter::new(&FilterDesc::Box { radius: 0.5 });
        assert!((bx.footprint() - 1.0).abs() < 1e-9);
        let narrow = Filter::new(&FilterDesc::Box { radius: 0.3 });
        assert_eq!(narrow.footprint(), 1.0);
        let wide = Filter::new(&FilterDesc::Box { radius: 1.5 });
        assert!((wide.footprint() - 9.0).abs() < 1e-5);
        // Tent: ∫g = r, ∫g² = 2r/3.
        let tent = Filter::new(&FilterDesc::Tent { radius: 1.0 });
        assert!((tent.footprint() - 2.25).abs() < 1e-4);
        // Gaussian σ = ½ (truncation at 4σ changes little): (2σ√π)² = π.
        let g = Filter::default_gaussian().footprint();
        assert!((g - std::f64::consts::PI).abs() < 0.05, "{g}");
    }

    #[test]
    fn invalid_parameters_fall_back_to_defaults() {
        let f = Filter::new(&FilterDesc::Box { radius: f32::NAN });
        assert_eq!(f.radius(), 0.5);
        let f = Filter::new(&FilterDesc::Gaussian {
            stddev: -1.0,
            radius: f32::INFINITY,
        });
        assert_eq!(f, Filter::default_gaussian());
        let f = Filter::new(&FilterDesc::Gaussian {
            stddev: 0.5,
            radius: 100.0,
        });
        assert_eq!(f.radius(), 4.0, "capped at 8σ");
        let f = Filter::new(&FilterDesc::Mitchell {
            b: f32::NAN,
            c: 0.5,
            radius: 0.0,
        });
        assert_eq!(f.radius(), 2.0);
        assert!(f.eval_1d(0.3).is_finite());
        let f = Filter::new(&FilterDesc::Tent { radius: 1e9 });
        assert_eq!(f.radius(), MAX_RADIUS);
    }
}
