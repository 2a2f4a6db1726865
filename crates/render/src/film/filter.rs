//! Pixel reconstruction filters, used by filter importance sampling (pbrt-v4 §5.4.3, 8.8).
//!
//! Every filter is separable, `f(x, y) = g(x) g(y)`, with Mitsuba 3's 1D profiles `g`:
//!
//! | filter   | `g(x)` on `|x| ≤ r`                                          | defaults          |
//! |----------|---------------------------------------------------------------|-------------------|
//! | box      | 1                                                             | r = 0.5           |
//! | tent     | 1 − |x|/r                                                     | r = 1             |
//! | gaussian | max(0, exp(−x²/2σ²) − exp(−r²/2σ²)) (truncation value removed) | σ = 0.5, r = 4σ   |
//! | mitchell | Mitchell–Netravali cubic of `t = 2|x|/r ∈ [0, 2]`             | B = C = 1/3, r = 2 |
//!
//! Instead of splatting a sample onto every pixel under the filter, the camera ray of pixel
//! `p` goes through `p + ½ + offset` with `offset` drawn ∝ |f| ([`Filter::sample`]) and the
//! sample is added to pixel `p` only, with weight `f(offset) / (pdf(offset) ∫f)`. The
//! developed pixel `Σ w L / Σ w` is then a consistent estimate of the filtered image, pixels
//! are statistically independent, and their variance can be estimated per pixel.
//!
//! Box and tent are sampled analytically (weight exactly 1). Gaussian and Mitchell invert a
//! tabulated |g| (1024 cells over [−r, r], each the average of |g| over the cell), separately
//! per axis: for a separable filter this is the same distribution as pbrt-v4's tabulated 2D
//! `FilterSampler`, at a far finer resolution for the same memory. The weight `f/pdf` then
//! corrects the small table error exactly, so the estimate stays unbiased; for the gaussian it
//! is ≈ 1, for Mitchell it is ≈ ±∫|f|/∫f with the sign of the lobe.
//!
//! Invalid parameters (non-finite, ≤ 0) fall back to the defaults above; a gaussian radius is
//! capped at 8σ (beyond that the truncated profile is < 10⁻¹³ and the table would waste cells).

use crate::math::Vec2;
use crate::sampling::distrib::{Distribution1D, ONE_MINUS_EPSILON};
use scene::FilterDesc;

/// An offset from the pixel centre and its importance weight `f / (pdf ∫f)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterSample {
    pub offset: Vec2,
    pub weight: f32,
}

/// Cells of the tabulated 1D profiles.
const TABLE_CELLS: usize = 1024;
/// Quadrature points per cell when tabulating.
const TABLE_SUBSAMPLES: usize = 8;

/// A 1D profile tabulated for importance sampling on [−r, r].
#[derive(Clone, Debug)]
pub struct FilterTable {
    distrib: Distribution1D,
    radius: f32,
    /// Signed ∫ g over [−r, r] (midpoint quadrature at the table's sub-resolution).
    integral: f32,
}

impl FilterTable {
    fn new(radius: f32, g: impl Fn(f32) -> f32) -> FilterTable {
        let width = 2.0 * radius as f64 / TABLE_CELLS as f64;
        let mut cells = Vec::with_capacity(TABLE_CELLS);
        let mut signed = 0.0f64;
        for i in 0..TABLE_CELLS {
            let (mut abs_sum, mut sum) = (0.0f64, 0.0f64);
            for k in 0..TABLE_SUBSAMPLES {
                let t = (i as f64 + (k as f64 + 0.5) / TABLE_SUBSAMPLES as f64) * width;
                let v = g((t - radius as f64) as f32) as f64;
                abs_sum += v.abs();
                sum += v;
            }
            cells.push((abs_sum / TABLE_SUBSAMPLES as f64) as f32);
            signed += sum / TABLE_SUBSAMPLES as f64 * width;
        }
        FilterTable {
            distrib: Distribution1D::new(&cells),
            radius,
            integral: signed as f32,
        }
    }

    /// `(x, pdf(x))` with `x ∈ [−r, r)` drawn ∝ the tabulated |g|.
    #[inline]
    fn sample(&self, u: f32) -> (f32, f32) {
        let (t, pdf, _) = self.distrib.sample_continuous(u);
        let r = self.radius;
        ((2.0 * t - 1.0) * r, pdf / (2.0 * r))
    }
}

/// A reconstruction filter (closed set, see the module docs).
#[derive(Clone, Debug)]
pub enum Filter {
    Box {
        radius: f32,
    },
    Tent {
        radius: f32,
    },
    Gaussian {
        stddev: f32,
        radius: f32,
        table: FilterTable,
    },
    Mitchell {
        b: f32,
        c: f32,
        radius: f32,
        table: FilterTable,
    },
}

#[inline]
fn positive_or(v: f32, default: f32) -> f32 {
    if v.is_finite() && v > 0.0 { v } else { default }
}

#[inline]
fn gaussian_1d(x: f32, stddev: f32, radius: f32) -> f32 {
    if x.abs() > radius {
        return 0.0;
    }
    let alpha = -1.0 / (2.0 * stddev * stddev);
    ((alpha * x * x).exp() - (alpha * radius * radius).exp()).max(0.0)
}

#[inline]
fn mitchell_1d(x: f32, b: f32, c: f32, radius: f32) -> f32 {
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

/// Samples the normalised tent `(1 − |x|/r)/r` on [−r, r] by inverting its CDF.
#[inline]
fn sample_tent(u: f32, r: f32) -> f32 {
    if u < 0.5 {
        r * ((2.0 * u).sqrt() - 1.0)
    } else {
        r * (1.0 - (2.0 - 2.0 * u).max(0.0).sqrt())
    }
}

impl Filter {
    /// The filter described by `desc` (invalid parameters replaced by defaults).
    pub fn new(desc: &FilterDesc) -> Filter {
        match *desc {
            FilterDesc::Box { radius } => Filter::Box {
                radius: positive_or(radius, 0.5),
            },
            FilterDesc::Tent { radius } => Filter::Tent {
                radius: positive_or(radius, 1.0),
            },
            FilterDesc::Gaussian { stddev, radius } => {
                let stddev = positive_or(stddev, 0.5);
                let radius = positive_or(radius, 4.0 * stddev).min(8.0 * stddev);
                Filter::Gaussian {
                    stddev,
                    radius,
                    table: FilterTable::new(radius, |x| gaussian_1d(x, stddev, radius)),
                }
            }
            FilterDesc::Mitchell { b, c, radius } => {
                let b = if b.is_finite() { b } else { 1.0 / 3.0 };
                let c = if c.is_finite() { c } else { 1.0 / 3.0 };
                let radius = positive_or(radius, 2.0);
                Filter::Mitchell {
                    b,
                    c,
                    radius,
                    table: FilterTable::new(radius, |x| mitchell_1d(x, b, c, radius)),
                }
            }
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
            | Filter::Mitchell { radius, .. } => radius,
        }
    }

    /// The 1D profile g(x).
    #[inline]
    pub fn eval_1d(&self, x: f32) -> f32 {
        match *self {
            Filter::Box { radius } => {
                if x.abs() <= radius {
                    1.0
                } else {
                    0.0
                }
            }
            Filter::Tent { radius } => (1.0 - x.abs() / radius).max(0.0),
            Filter::Gaussian { stddev, radius, .. } => gaussian_1d(x, stddev, radius),
            Filter::Mitchell { b, c, radius, .. } => mitchell_1d(x, b, c, radius),
        }
    }

    /// f(p) = g(p.x) g(p.y), unnormalised (Mitsuba's values).
    #[inline]
    pub fn eval(&self, p: Vec2) -> f32 {
        self.eval_1d(p.x) * self.eval_1d(p.y)
    }

    /// ∫∫ f over the plane (box, tent: exact; gaussian, Mitchell: fine quadrature).
    pub fn integral(&self) -> f32 {
        let i1 = match self {
            Filter::Box { radius } => 2.0 * radius,
            Filter::Tent { radius } => *radius,
            Filter::Gaussian { table, .. } | Filter::Mitchell { table, .. } => table.integral,
        };
        i1 * i1
    }

    /// Filter importance sampling: an offset from the pixel centre drawn ∝ |f| and the weight
    /// `f / (pdf ∫f)` (1 for box and tent; ≈ 1 for the gaussian; negative in Mitchell's
    /// negative lobes).
    #[inline]
    pub fn sample(&self, u: Vec2) -> FilterSample {
        let u = u.clamp(Vec2::ZERO, Vec2::splat(ONE_MINUS_EPSILON));
        match self {
            Filter::Box { radius } => FilterSample {
                offset: (2.0 * u - Vec2::ONE) * *radius,
                weight: 1.0,
            },
            Filter::Tent { radius } => FilterSample {
                offset: Vec2::new(sample_tent(u.x, *radius), sample_tent(u.y, *radius)),
                weight: 1.0,
            },
            Filter::Gaussian { table, .. } | Filter::Mitchell { table, .. } => {
                let (x, pdf_x) = table.sample(u.x);
                let (y, pdf_y) = table.sample(u.y);
                let f = self.eval_1d(x) * self.eval_1d(y);
                let denom = pdf_x * pdf_y * table.integral * table.integral;
                let weight = if denom > 0.0 { f / denom } else { 0.0 };
                FilterSample {
                    offset: Vec2::new(x, y),
                    weight,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all() -> Vec<Filter> {
        vec![
            Filter::new(&FilterDesc::Box { radius: 0.5 }),
            Filter::new(&FilterDesc::Tent { radius: 1.0 }),
            Filter::new(&FilterDesc::Gaussian {
                stddev: 0.5,
                radius: 2.0,
            }),
            Filter::new(&FilterDesc::Mitchell {
                b: 1.0 / 3.0,
                c: 1.0 / 3.0,
                radius: 2.0,
            }),
        ]
    }

    #[test]
    fn profiles_match_mitsuba_values() {
        let f = all();
        assert_eq!(f[0].eval_1d(0.5), 1.0);
        assert_eq!(f[0].eval_1d(0.51), 0.0);
        assert!((f[1].eval_1d(-0.25) - 0.75).abs() < 1e-6);
        let bias = (-8.0f32).exp();
        assert!((f[2].eval_1d(0.5) - ((-0.5f32).exp() - bias)).abs() < 1e-6);
        assert_eq!(f[2].eval_1d(2.0), 0.0);
        // Mitchell (B = C = 1/3): g(0) = (6 − 2B)/6 = 8/9, g(1) = B/6 = 1/18, g(2) = 0.
        assert!((f[3].eval_1d(0.0) - 8.0 / 9.0).abs() < 1e-6);
        assert!((f[3].eval_1d(1.0) - 1.0 / 18.0).abs() < 1e-6);
        assert!(f[3].eval_1d(1.5) < 0.0, "negative lobe");
        assert_eq!(f[3].eval_1d(2.0), 0.0);
        // Mitchell–Netravali integrates to 1 in its native coordinate t: ∫g dx = r/2.
        assert!((f[3].integral() - 1.0).abs() < 1e-4);
    }

    #[test]
    fn samples_stay_in_support_with_consistent_weights() {
        for f in all() {
            let r = f.radius();
            let mut mean_w = 0.0f64;
            let n = 64;
            for i in 0..n {
                for j in 0..n {
                    let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                    let s = f.sample(u);
                    assert!(s.offset.abs().max_element() <= r, "{f:?}");
                    assert!(s.weight.is_finite());
                    if matches!(f, Filter::Box { .. } | Filter::Tent { .. }) {
                        assert_eq!(s.weight, 1.0);
                    }
                    mean_w += s.weight as f64;
                }
            }
            // E[weight] = ∫ f / ∫ f = 1 for every filter.
            mean_w /= (n * n) as f64;
            assert!((mean_w - 1.0).abs() < 0.02, "{f:?}: {mean_w}");
        }
        let s = Filter::new(&FilterDesc::Tent { radius: 1.0 }).sample(Vec2::new(0.5, 0.0));
        assert!(s.offset.x.abs() < 1e-6 && (s.offset.y + 1.0).abs() < 1e-6);
    }

    #[test]
    fn gaussian_weight_is_nearly_constant() {
        let f = Filter::default_gaussian();
        for k in 0..997 {
            let u = Vec2::new(
                ((k as f32 + 0.5) * 0.618_034).fract(),
                (k as f32 + 0.5) / 997.0,
            );
            let w = f.sample(u).weight;
            assert!((w - 1.0).abs() < 0.05, "{w}");
        }
    }

    #[test]
    fn invalid_parameters_fall_back_to_defaults() {
        let f = Filter::new(&FilterDesc::Box { radius: f32::NAN });
        assert_eq!(f.radius(), 0.5);
        let f = Filter::new(&FilterDesc::Gaussian {
            stddev: -1.0,
            radius: f32::INFINITY,
        });
        assert_eq!(f.radius(), 2.0);
        let f = Filter::new(&FilterDesc::Mitchell {
            b: f32::NAN,
            c: 0.5,
            radius: 0.0,
        });
        assert_eq!(f.radius(), 2.0);
        assert!(f.sample(Vec2::splat(0.3)).weight.is_finite());
    }
}
