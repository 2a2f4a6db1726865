//! The film: per-pixel weighted sums, accumulated in tiles and merged.
//!
//! **Splatting** (Mitsuba 3's `ImageBlock::put`). Pixel `(i, j)` covers `[i, i+1) × [j, j+1)`
//! of the raster and has its centre at `(i + ½, j + ½)`. A camera sample taken at raster
//! position `p` (uniformly inside the pixel being sampled) with radiance `L` is added to every
//! pixel with `i + ½ − p.x ∈ (−r, r]` and `j + ½ − p.y ∈ (−r, r]` with the weight
//!
//! `w = g(i + ½ − p.x) · g(j + ½ − p.y)`
//!
//! (`r` the filter radius, `g` its 1D profile, see [`super::Filter`]). The half-open interval
//! puts every sample of the default box filter (r = ½) in exactly the pixel containing it; the
//! other filters vanish at ±r, where it only saves zero-weight updates: at most ⌈2r⌉ pixels per
//! axis are touched (16 pixels and 4 + 4 filter evaluations for r = 2). A developed pixel is
//! `Σ w L / Σ w`, a consistent estimate of the filtered image `∫ f(c − p) L(p) dp / ∫ f(c − p) dp`
//! (`c` the pixel centre, `p` over the sampled region). Samples are only taken inside the film's
//! pixel bounds (the crop window, if any), as Mitsuba does by default (`sample_border` off):
//! pixels within the filter's reach of those bounds average over a truncated filter.
//!
//! Unlike filter importance sampling (pbrt-v4, one pixel per sample with weight f/pdf), which
//! this film used before, splatting averages each sample over the filter footprint instead of
//! adding the footprint's variance to one pixel: with the default gaussian, the relMSE of the
//! `veach-plates` reference scene (small, very bright lights) at 256 spp fell from 3.9e-3 to
//! 4.4e-4 (Mitsuba: 4.9e-4). The price is that neighbouring pixels share samples.
//!
//! **Tiles and exact sums.** A [`FilmTile`] takes the samples of the pixels `[min, max)` (its
//! *sample bounds*) and stores those pixels plus the border of ⌈r − ½⌉ pixels its samples can
//! reach, clipped to the film. A tile sums in f64; the film sums in fixed point:
//! [`Film::merge`] rounds each of a tile's sums to a multiple of 2⁻⁴⁰ ([`FIXED_SCALE`]) and adds
//! it to a 128-bit integer ([`FixedSums`]). Integer addition is associative, so the film does
//! not depend on the order in which tiles are merged, nor on how the work was split into
//! tiles merged at once, passes, threads, processes (shards) or interrupted and resumed runs:
//! as long as each tile's f64 sums are the same, the film is the same bit for bit. The
//! drivers make them the same by fixing the unit of work (`drive/`: a tile of the fixed
//! tiling times a fixed chunk of sample indices). The rounding is far below anything the
//! image can show: 2⁻⁴¹ absolute per tile and sum (9e-13; a pixel of mean 1e-5 after 10⁴
//! samples is still within 1e-7 relative, the f32 of the developed image); a pixel's second
//! moments below that resolution (radiance under 1e-6) lose their precision, so its standard
//! error does. The range is ±2⁸⁷ (1.5e26) per sum, and sums wrap around beyond it (which
//! keeps them exact modulo 2¹²⁸, whatever the order): a sum of squares reaches it with
//! 1e4 samples of radiance 1e11 in one pixel. A single value beyond the range saturates.
//!
//! **Sums and standard error.** Each pixel keeps, in f64, `Σ wL, Σ w, Σ (wL)², Σ w², Σ w·(wL)`
//! and the number `n` of contributions it received. [`PixelSums::stderr`] is the per-pixel
//! standard error of `R = Σ wL / Σ w` by the delta method, treating the `n` contributions
//! `(wᵢ, wᵢLᵢ)` as independent:
//!
//! `Var(R) ≈ n / (n − 1) · Σ (wᵢLᵢ − R wᵢ)² / (Σ wᵢ)²`,
//! `Σ (wL − R w)² = Σ (wL)² − 2R Σ w·(wL) + R² Σ w²`,
//!
//! which for unit weights is the usual `s² / n` (slightly conservative otherwise: the
//! contributions are stratified by the pixel they were taken in). That is the error of each
//! pixel on its own, but neighbours share samples and their errors are positively correlated:
//! adding per-pixel variances as if independent, as block tests do (`compare --stderr`),
//! underestimates the variance of a block's mean by the footprint `F = (∫f)² / ∫f²`, the
//! effective number of pixels a sample is spread over (1 for the box filter, π for the default
//! gaussian σ = ½; a correct render then failed the `veach-plates` block test at p = 5e-7).
//! [`Film::develop_stderr`] therefore writes `√F ×` the per-pixel error: its square
//! approximates the sum of the pixel's covariances with all pixels (for a locally smooth
//! variance), so squares add up over any region to the variance of the region's sum,
//! conservatively at the region's edges. It overstates a lone pixel's error by `√F`, and
//! understates the error of pixels within the filter's reach of the film's edges, which see
//! samples from one side only (on a 48 × 48 film, the variance of the whole-image mean came
//! out 1.36× the prediction; on 144 × 144, 0.94×).
//!
//! Samples whose radiance or position is NaN or infinite are rejected and counted once
//! ([`Film::nonfinite_count`]); they touch no pixel.
//!
//! **Light-path splats** (light tracing, Mitsuba 3's particle tracer). A contribution that
//! a light path makes at a film position (through the camera's importance, not a camera
//! sample of a pixel) is added to a separate layer, [`Film::add_splat`], with the filter's
//! weights f(x − p) as they are, and pixel p develops its splats divided by c_p = ∫ f(x − p)
//! over the stored pixels' area (pbrt-v4 divides by the filter's integral). Camera samples
//! are drawn uniformly over that area, so `Σ w L / Σ w` tends to ∫ f(x − p) L(x) dx / c_p:
//! splats of the same radiance converge to the same image, also where L varies within a
//! pixel and at the film's edges. (Normalising each splat's weights to sum to 1, Mitsuba 3's
//! `put` for its particle tracer, does not: the gaussian's weights summed over the pixel
//! grid vary by ±5.6 % with the sub-pixel position, which shows on lights smaller than a
//! pixel.) Splats outside the stored area are dropped, as no camera sample comes from there.
//! A developed pixel is the camera samples' `Σ w L / Σ w` plus its splats times
//! [`Film::set_splat_scale`]'s scale (1 / the light paths per pixel) / c_p. The standard
//! error covers the camera samples only.
//!
//! Memory: 184 bytes per stored pixel of the film (96 per pixel of a tile), 48 more once
//! splats are added.

use super::{Filter, Image, filter};
use crate::math::{IVec2, UVec2, Vec2, Vec3};
use base::CropWindow;

/// The sums of one pixel (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PixelSums {
    /// Σ w L per channel.
    pub weighted: [f64; 3],
    /// Σ w.
    pub weight: f64,
    /// Σ (w L)² per channel.
    pub weighted_sq: [f64; 3],
    /// Σ w².
    pub weight_sq: f64,
    /// Σ w · (w L) per channel.
    pub cross: [f64; 3],
    /// Number of contributions (samples splatted onto this pixel).
    pub count: u64,
}

impl PixelSums {
    /// The sums in [`FixedSums::v`]'s order.
    #[inline]
    fn fields(&self) -> [f64; 11] {
        [
            self.weighted[0],
            self.weighted[1],
            self.weighted[2],
            self.weight,
            self.weighted_sq[0],
            self.weighted_sq[1],
            self.weighted_sq[2],
            self.weight_sq,
            self.cross[0],
            self.cross[1],
            self.cross[2],
        ]
    }

    #[inline]
    fn add(&mut self, l: [f64; 3], w: f64) {
        for (c, &lc) in l.iter().enumerate() {
            let v = w * lc;
            self.weighted[c] += v;
            self.weighted_sq[c] += v * v;
            self.cross[c] += w * v;
        }
        self.weight += w;
        self.weight_sq += w * w;
        self.count += 1;
    }

    /// `Σ w L / Σ w` (0 when `Σ w = 0`).
    #[inline]
    pub fn mean(&self) -> Vec3 {
        if self.weight == 0.0 {
            return Vec3::ZERO;
        }
        let inv = 1.0 / self.weight;
        Vec3::new(
            (self.weighted[0] * inv) as f32,
            (self.weighted[1] * inv) as f32,
            (self.weighted[2] * inv) as f32,
        )
    }

    /// Standard error of [`Self::mean`] (delta method, see the module docs; 0 with fewer than
    /// 2 contributions or `Σ w = 0`, where it is undefined).
    pub fn stderr(&self) -> Vec3 {
        if self.count < 2 || self.weight == 0.0 {
            return Vec3::ZERO;
        }
        let n = self.count as f64;
        let mut out = [0.0f32; 3];
        for (c, o) in out.iter_mut().enumerate() {
            let r = self.weighted[c] / self.weight;
            let ss =
                (self.weighted_sq[c] - 2.0 * r * self.cross[c] + r * r * self.weight_sq).max(0.0);
            let var = ss * n / ((n - 1.0) * self.weight * self.weight);
            *o = var.sqrt() as f32;
        }
        Vec3::from_array(out)
    }
}

/// The film's sums as 128-bit integers in units of 2⁻⁴⁰ (see the module docs: exact, so the
/// order of merging does not matter). Fields as in [`PixelSums`]: `v` holds Σ wL (3), Σ w,
/// Σ (wL)² (3), Σ w², Σ w·(wL) (3).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FixedSums {
    pub v: [i128; 11],
    pub count: u64,
}

/// One unit of [`FixedSums`]: values are rounded to multiples of `1 / FIXED_SCALE`.
pub const FIXED_SCALE: f64 = (1u64 << 40) as f64;

/// 1.5·2⁵²: `x + MAGIC` has the unit as its last place for |x| < [`MAGIC_RANGE`] = 2⁵¹.
const MAGIC: f64 = 6_755_399_441_055_744.0;
const MAGIC_RANGE: f64 = 2_251_799_813_685_248.0;

/// `v` in units of 2⁻⁴⁰, rounded to nearest (ties to even); saturating beyond ±2¹²⁷.
#[inline(always)]
pub fn to_fixed(v: f64) -> i128 {
    let s = v * FIXED_SCALE;
    if s.abs() < 9.0e18 {
        // The common case: one rounding and one conversion instruction (`as i128` from
        // f64 is a library call).
        s.round_ties_even() as i64 as i128
    } else {
        s.round_ties_even() as i128
    }
}

#[inline(always)]
fn from_fixed(x: i128) -> f64 {
    // `i128 as f64` is a library call; through i64, where the value fits, it is one
    // instruction with the same correctly rounded result.
    let f = match i64::try_from(x) {
        Ok(v) => v as f64,
        Err(_) => x as f64,
    };
    f * (1.0 / FIXED_SCALE)
}

impl FixedSums {
    /// Adds the f64 sums `p`, each rounded to the fixed-point grid.
    #[inline]
    fn add_rounded(&mut self, p: &PixelSums) {
        if p.count == 0 {
            return;
        }
        let f = p.fields();
        let scaled = f.map(|x| x * FIXED_SCALE);
        // `&` rather than a short-circuit or a NaN-aware `max`, so that the test is a few
        // vector compares; NaN fails it and takes the general path.
        let below = |limit: f64| scaled.iter().fold(true, |ok, x| ok & (x.abs() < limit));
        if below(MAGIC_RANGE) {
            // The common case: adding 1.5·2⁵² rounds |x| < 2⁵¹ to an integer (the FPU's
            // round-to-nearest-even, as `round_ties_even`), which the sum's bits then hold
            // above the constant's: an add and an integer subtract, no saturating
            // conversion.
            for (a, x) in self.v.iter_mut().zip(scaled) {
                let q = (x + MAGIC).to_bits() as i64 - MAGIC.to_bits() as i64;
                *a = a.wrapping_add(q as i128);
            }
        } else if below(9.0e18) {
            let q = scaled.map(|x| x.round_ties_even() as i64);
            for (a, x) in self.v.iter_mut().zip(q) {
                *a = a.wrapping_add(x as i128);
            }
        } else {
            for (a, x) in self.v.iter_mut().zip(f) {
                *a = a.wrapping_add(to_fixed(x));
            }
        }
        self.count += p.count;
    }

    /// Adds another film's sums (exact).
    #[inline]
    pub fn add(&mut self, o: &FixedSums) {
        for (a, b) in self.v.iter_mut().zip(&o.v) {
            *a = a.wrapping_add(*b);
        }
        self.count += o.count;
    }

    /// `Σ w L / Σ w` as [`PixelSums::mean`] of [`Self::to_f64`] gives it, from the four
    /// sums it needs.
    #[inline]
    fn mean(&self) -> Vec3 {
        PixelSums {
            weighted: [0, 1, 2].map(|c| from_fixed(self.v[c])),
            weight: from_fixed(self.v[3]),
            ..PixelSums::default()
        }
        .mean()
    }

    /// The sums as f64 (to develop).
    pub fn to_f64(&self) -> PixelSums {
        let f = self.v.map(from_fixed);
        PixelSums {
            weighted: [f[0], f[1], f[2]],
            weight: f[3],
            weighted_sq: [f[4], f[5], f[6]],
            weight_sq: f[7],
            cross: [f[8], f[9], f[10]],
            count: self.count,
        }
    }
}

/// Border, in pixels, that samples taken inside a rectangle reach with a filter of radius `r`:
/// the largest `k` with `k < r + ½` (see the module docs).
#[inline]
fn border(r: f32) -> u32 {
    (r - 0.5).ceil().max(0.0) as u32
}

/// Pixels filled by one worker: it takes the samples of `[sample_min, sample_max)` and stores
/// the sums of `[min, max)`, those pixels plus the filter's border (full-image coordinates).
#[derive(Clone, Debug)]
pub struct FilmTile {
    filter: Filter,
    sample_min: UVec2,
    sample_max: UVec2,
    min: UVec2,
    max: UVec2,
    pixels: Vec<PixelSums>,
    /// Units of work already rounded to the film's fixed point ([`Self::finish_unit`];
    /// empty until the first).
    fixed: Vec<FixedSums>,
    samples: u64,
    /// Of `samples`, those already in `fixed` (the rest are in `pixels`).
    rounded: u64,
    nonfinite: u64,
}

/// Splat taps processed per batch of precomputed x weights.
const TAPS: usize = 16;

impl FilmTile {
    /// `[min, max)` of the stored pixels, in full-image coordinates.
    #[inline]
    pub fn bounds(&self) -> (UVec2, UVec2) {
        (self.min, self.max)
    }

    /// `[min, max)` of the pixels whose samples this tile takes.
    #[inline]
    pub fn sample_bounds(&self) -> (UVec2, UVec2) {
        (self.sample_min, self.sample_max)
    }

    /// Row-major sums of the stored pixels.
    #[inline]
    pub fn sums(&self) -> &[PixelSums] {
        &self.pixels
    }

    /// Accepted samples.
    #[inline]
    pub fn sample_count(&self) -> u64 {
        self.samples
    }

    #[inline]
    pub fn nonfinite_count(&self) -> u64 {
        self.nonfinite
    }

    /// Splats radiance `l` taken at raster position `p_film` onto the pixels around it (see
    /// the module docs). `p_film` belongs in the sample bounds and is clamped into them (this
    /// absorbs `pixel + u` rounding up to the next pixel). Samples with a non-finite radiance
    /// or position are rejected and counted.
    pub fn add_sample(&mut self, p_film: Vec2, l: Vec3) {
        if !(l.is_finite() && p_film.is_finite()) {
            self.nonfinite += 1;
            return;
        }
        if self.sample_min.cmpge(self.sample_max).any() {
            debug_assert!(false, "sample added to the empty tile {:?}", self.bounds());
            return;
        }
        self.samples += 1;
        let hi = self.sample_max.as_vec2();
        let p = p_film.clamp(
            self.sample_min.as_vec2(),
            Vec2::new(hi.x.next_down(), hi.y.next_down()),
        );
        let l = [l.x as f64, l.y as f64, l.z as f64];
        // One loop per filter type: with a generic profile, every sample would pay for the
        // evaluation of every variant's constants.
        match self.filter {
            Filter::Box { radius } => self.splat(p, l, radius, |x| filter::box_1d(x, radius)),
            Filter::Tent { radius } => self.splat(p, l, radius, |x| filter::tent_1d(x, radius)),
            Filter::Gaussian { stddev, radius } => {
                self.splat(p, l, radius, |x| filter::gaussian_1d(x, stddev, radius))
            }
            Filter::Mitchell { b, c, radius } => {
                self.splat(p, l, radius, |x| filter::mitchell_1d(x, b, c, radius))
            }
            Filter::Lanczos { radius, tau } => {
                self.splat(p, l, radius, |x| filter::lanczos_1d(x, radius, tau))
            }
        }
    }

    /// Forgets every sample, keeping the bounds and the storage.
    pub fn clear(&mut self) {
        self.pixels.fill(PixelSums::default());
        self.fixed.clear();
        self.samples = 0;
        self.rounded = 0;
        self.nonfinite = 0;
    }

    /// Ends a unit of work: rounds the f64 sums into the tile's fixed-point sums (what
    /// [`Film::merge`] would do with them, exactly) and clears them. A driver that renders
    /// several units of one tile in a row merges the tile once, after the last, touching
    /// the film (larger than the caches) once instead of once per unit.
    pub fn finish_unit(&mut self) {
        if self.fixed.len() != self.pixels.len() {
            self.fixed.clear();
            self.fixed.resize(self.pixels.len(), FixedSums::default());
        }
        for (f, p) in self.fixed.iter_mut().zip(&mut self.pixels) {
            f.add_rounded(p);
            *p = PixelSums::default();
        }
        self.rounded = self.samples;
    }

    /// Adds `l` with weight `g(i + ½ − p.x) g(j + ½ − p.y)` to the stored pixels `(i, j)` with
    /// `i + ½ − p.x, j + ½ − p.y ∈ (−r, r]`.
    #[inline(always)]
    fn splat(&mut self, p: Vec2, l: [f64; 3], r: f32, g: impl Fn(f32) -> f32) {
        let c = p - 0.5;
        let first = (floor_to_int(c - r) + 1).max(self.min.as_ivec2());
        let last = floor_to_int(c + r).min(self.max.as_ivec2() - 1);
        if first.cmpgt(last).any() {
            return; // a filter narrower than a pixel may miss every centre
        }
        let (first, last) = (first.as_uvec2(), last.as_uvec2());
        let stride = (self.max.x - self.min.x) as usize;
        if first == last {
            // One pixel (every sample of the default box filter): the same weight as the
            // loops below compute, without their set-up.
            let w = g(first.x as f32 + 0.5 - p.x) as f64;
            let wy = g(first.y as f32 + 0.5 - p.y) as f64;
            let i = (first.y - self.min.y) as usize * stride + (first.x - self.min.x) as usize;
            self.pixels[i].add(l, w * wy);
            return;
        }
        let mut wx = [0.0f64; TAPS];
        let mut x0 = first.x;
        while x0 <= last.x {
            let n = ((last.x - x0) as usize + 1).min(TAPS);
            for (k, w) in wx[..n].iter_mut().enumerate() {
                *w = g((x0 + k as u32) as f32 + 0.5 - p.x) as f64;
            }
            for y in first.y..=last.y {
                let wy = g(y as f32 + 0.5 - p.y) as f64;
                let row = (y - self.min.y) as usize * stride + (x0 - self.min.x) as usize;
                for (px, &w) in self.pixels[row..row + n].iter_mut().zip(&wx[..n]) {
                    px.add(l, w * wy);
                }
            }
            x0 += n as u32;
        }
    }
}

impl Default for FilmTile {
    /// An empty tile of no pixels (to be given bounds by [`FilmLayout::reset_tile`]).
    fn default() -> Self {
        FilmTile {
            filter: Filter::Box { radius: 0.5 },
            sample_min: UVec2::ZERO,
            sample_max: UVec2::ZERO,
            min: UVec2::ZERO,
            max: UVec2::ZERO,
            pixels: Vec::new(),
            fixed: Vec::new(),
            samples: 0,
            rounded: 0,
            nonfinite: 0,
        }
    }
}

/// A film's pixel bounds and filter ([`Film::layout`]): enough to make its tiles while the
/// film itself is being merged into.
#[derive(Clone, Copy, Debug)]
pub struct FilmLayout {
    min: UVec2,
    max: UVec2,
    filter: Filter,
}

impl FilmLayout {
    /// Makes `tile` an empty tile taking the samples of `[min, max)` clipped to the pixel
    /// bounds, storing those pixels and the filter's border around them, reusing its
    /// storage (a worker keeps one tile from item to item).
    pub fn reset_tile(&self, tile: &mut FilmTile, min: UVec2, max: UVec2) {
        let sample_min = min.clamp(self.min, self.max);
        let sample_max = max.clamp(self.min, self.max).max(sample_min);
        let (tmin, tmax) = if sample_min.cmplt(sample_max).all() {
            let b = UVec2::splat(border(self.filter.radius()));
            (
                sample_min.saturating_sub(b).max(self.min),
                sample_max.saturating_add(b).min(self.max),
            )
        } else {
            (sample_min, sample_min)
        };
        let size = tmax - tmin;
        tile.filter = self.filter;
        tile.sample_min = sample_min;
        tile.sample_max = sample_max;
        tile.min = tmin;
        tile.max = tmax;
        tile.pixels.clear();
        tile.pixels
            .resize(size.x as usize * size.y as usize, PixelSums::default());
        tile.fixed.clear();
        tile.samples = 0;
        tile.rounded = 0;
        tile.nonfinite = 0;
    }
}

/// The image being rendered: sums for the pixels of the crop window (or the whole image).
#[derive(Clone, Debug)]
pub struct Film {
    full: UVec2,
    min: UVec2,
    max: UVec2,
    filter: Filter,
    pixels: Vec<FixedSums>,
    samples: u64,
    nonfinite: u64,
    /// Light-path splats per stored pixel, in units of 2⁻⁴⁰ (empty until the first).
    splats: Vec<[i128; 3]>,
    splat_scale: f64,
}

impl Film {
    /// A `width × height` film storing only `crop` (clipped to the image; an empty crop gives
    /// an empty film: validate crop windows where the scene is loaded), reconstructed with
    /// `filter`.
    pub fn new(width: u32, height: u32, crop: Option<CropWindow>, filter: Filter) -> Film {
        let full = UVec2::new(width, height);
        let (min, max) = pixel_bounds(width, height, crop);
        let size = max - min;
        Film {
            full,
            min,
            max,
            filter,
            pixels: vec![FixedSums::default(); size.x as usize * size.y as usize],
            samples: 0,
            nonfinite: 0,
            splats: Vec::new(),
            splat_scale: 1.0,
        }
    }

    /// Adds a light path's contribution `l` at film position `p` to the splat layer (see
    /// the module docs): nothing outside the stored pixels, and non-finite values are
    /// counted and dropped. Each pixel's share is rounded to the fixed-point grid on its own,
    /// so that the layer does not depend on the order of the splats.
    pub fn add_splat(&mut self, p: Vec2, l: Vec3) {
        if !(l.is_finite() && p.is_finite()) {
            self.nonfinite += 1;
            return;
        }
        if l == Vec3::ZERO || p.cmplt(self.min.as_vec2()).any() || p.cmpge(self.max.as_vec2()).any()
        {
            return;
        }
        if self.splats.is_empty() {
            self.splats = vec![[0; 3]; self.pixels.len()];
        }
        let r = self.filter.radius();
        let c = p - 0.5;
        let first = (floor_to_int(c - r) + 1).max(self.min.as_ivec2());
        let last = floor_to_int(c + r).min(self.max.as_ivec2() - 1);
        if first.cmpgt(last).any() {
            return;
        }
        let (first, last) = (first.as_uvec2(), last.as_uvec2());
        let g = |x: u32, pc: f32| self.filter.eval_1d(x as f32 + 0.5 - pc) as f64;
        let stride = (self.max.x - self.min.x) as usize;
        let l = [l.x as f64, l.y as f64, l.z as f64];
        for y in first.y..=last.y {
            let wy = g(y, p.y);
            for x in first.x..=last.x {
                let w = g(x, p.x) * wy;
                let i = (y - self.min.y) as usize * stride + (x - self.min.x) as usize;
                for (s, lc) in self.splats[i].iter_mut().zip(l) {
                    *s = s.wrapping_add(to_fixed(w * lc));
                }
            }
        }
    }

    /// 1 / c_p of the module docs for each stored column (`x`) or row (`y`): the filter's
    /// weight over the stored area, one axis at a time (the filter is separable).
    fn splat_norms(&self, axis: usize) -> Vec<f64> {
        let (lo, hi) = (self.min.to_array()[axis], self.max.to_array()[axis]);
        (lo..hi)
            .map(|i| {
                let c = i as f32 + 0.5;
                let w = self.filter.integral_1d(lo as f32 - c, hi as f32 - c);
                if w > 0.0 { 1.0 / w } else { 0.0 }
            })
            .collect()
    }

    /// Adds `other`'s splat layer (a film of the same size) times `scale` to this one's
    /// (rounded again to the grid: not exact unless `scale` is 1).
    pub fn add_splat_layer(&mut self, other: &Film, scale: f64) {
        if other.splats.is_empty() {
            return;
        }
        if self.splats.is_empty() {
            self.splats = vec![[0; 3]; self.pixels.len()];
        }
        for (a, b) in self.splats.iter_mut().zip(&other.splats) {
            for (x, y) in a.iter_mut().zip(b) {
                *x = x.wrapping_add(to_fixed(from_fixed(*y) * scale));
            }
        }
        self.nonfinite += other.nonfinite;
    }

    /// The factor the splat layer is developed with (1 / light paths per pixel).
    pub fn set_splat_scale(&mut self, scale: f64) {
        self.splat_scale = scale;
    }

    /// The factor the splat layer is developed with.
    pub fn splat_scale(&self) -> f64 {
        self.splat_scale
    }

    /// Multiplies the splat layer by its scale and sets the scale to 1 (the same image), so
    /// that layers with other scales can be added ([`Self::add_splat_layer`]).
    pub fn bake_splat_scale(&mut self) {
        let k = self.splat_scale;
        for s in &mut self.splats {
            for c in s.iter_mut() {
                *c = to_fixed(from_fixed(*c) * k);
            }
        }
        self.splat_scale = 1.0;
    }

    /// The full image resolution (the camera's raster).
    #[inline]
    pub fn full_resolution(&self) -> UVec2 {
        self.full
    }

    /// `[min, max)` of the stored pixels in full-image coordinates (where samples are taken).
    #[inline]
    pub fn pixel_bounds(&self) -> (UVec2, UVec2) {
        (self.min, self.max)
    }

    /// The number of stored pixels (where samples are taken).
    #[inline]
    pub fn pixel_count(&self) -> u64 {
        let size = self.max - self.min;
        size.x as u64 * size.y as u64
    }

    /// Size of the stored (crop) region = size of the developed images.
    #[inline]
    pub fn size(&self) -> UVec2 {
        self.max - self.min
    }

    #[inline]
    pub fn filter(&self) -> &Filter {
        &self.filter
    }

    /// An empty tile taking the samples of `[min, max)` clipped to the pixel bounds, storing
    /// those pixels and the filter's border around them.
    pub fn tile(&self, min: UVec2, max: UVec2) -> FilmTile {
        let mut tile = FilmTile::default();
        self.layout().reset_tile(&mut tile, min, max);
        tile
    }

    /// Where the film's pixels are and how samples spread: what making tiles needs.
    pub fn layout(&self) -> FilmLayout {
        FilmLayout {
            min: self.min,
            max: self.max,
            filter: self.filter,
        }
    }

    /// Bytes a render of a `width × height` film (`crop`, `filter`) in `tile_size²` tiles
    /// on `workers` threads holds at its peak, without allocating anything: the film's sums,
    /// one tile with the filter's border per worker, and the developed mean and
    /// standard-error images. What a caller checks against its memory budget before
    /// [`Film::new`].
    pub fn memory_needed(
        width: u32,
        height: u32,
        crop: Option<CropWindow>,
        filter: &Filter,
        tile_size: u32,
        workers: usize,
    ) -> u64 {
        let (w, h) = match crop {
            None => (width as u64, height as u64),
            Some(c) => (
                (c.width as u64).min(width as u64),
                (c.height as u64).min(height as u64),
            ),
        };
        let t = tile_size.max(1) as u64;
        let b = border(filter.radius()) as u64;
        let tile_pixels =
            (workers.max(1) as u64).saturating_mul((t.min(w) + 2 * b) * (t.min(h) + 2 * b));
        let sums = std::mem::size_of::<FixedSums>() as u64;
        let image = std::mem::size_of::<Vec3>() as u64;
        (w * h)
            .saturating_mul(sums + 2 * image)
            .saturating_add(tile_pixels.saturating_mul(std::mem::size_of::<PixelSums>() as u64))
    }

    /// Splits the pixel bounds into `tile_size²` tiles (row-major, edge tiles smaller).
    pub fn tile_bounds(&self, tile_size: u32) -> Vec<(UVec2, UVec2)> {
        tile_bounds(self.min, self.max, tile_size)
    }

    /// Adds a tile's sums (every stored pixel inside the pixel bounds, borders included):
    /// its finished units exactly, its f64 sums rounded to the fixed-point grid; and its
    /// sample counts.
    pub fn merge(&mut self, tile: &FilmTile) {
        self.samples += tile.samples;
        self.nonfinite += tile.nonfinite;
        let lo = tile.min.max(self.min);
        let hi = tile.max.min(self.max);
        if lo.cmpge(hi).any() {
            return;
        }
        let tw = (tile.max.x - tile.min.x) as usize;
        let fw = (self.max.x - self.min.x) as usize;
        let len = (hi.x - lo.x) as usize;
        for y in lo.y..hi.y {
            let t0 = (y - tile.min.y) as usize * tw + (lo.x - tile.min.x) as usize;
            let f0 = (y - self.min.y) as usize * fw + (lo.x - self.min.x) as usize;
            // After `finish_unit` the f64 sums are all zero: not read again.
            if tile.samples != tile.rounded {
                for (f, t) in self.pixels[f0..f0 + len]
                    .iter_mut()
                    .zip(&tile.pixels[t0..t0 + len])
                {
                    f.add_rounded(t);
                }
            }
            if !tile.fixed.is_empty() {
                for (f, t) in self.pixels[f0..f0 + len]
                    .iter_mut()
                    .zip(&tile.fixed[t0..t0 + len])
                {
                    f.add(t);
                }
            }
        }
    }

    /// Adds another film of the same size, crop and filter (a shard, a checkpoint): exact,
    /// splats included (`other`'s splat scale is not looked at: the layers are summed as
    /// they are).
    pub fn add_film(&mut self, other: &Film) {
        assert_eq!(
            (self.full, self.min, self.max),
            (other.full, other.min, other.max),
            "films of different sizes"
        );
        self.samples += other.samples;
        self.nonfinite += other.nonfinite;
        for (a, b) in self.pixels.iter_mut().zip(&other.pixels) {
            a.add(b);
        }
        if !other.splats.is_empty() {
            if self.splats.is_empty() {
                self.splats = vec![[0; 3]; self.pixels.len()];
            }
            for (a, b) in self.splats.iter_mut().zip(&other.splats) {
                for (x, y) in a.iter_mut().zip(b) {
                    *x = x.wrapping_add(*y);
                }
            }
        }
    }

    /// The sums of `pixel` (full-image coordinates), if stored, as f64.
    pub fn pixel(&self, pixel: UVec2) -> Option<PixelSums> {
        if pixel.cmpge(self.min).all() && pixel.cmplt(self.max).all() {
            let q = pixel - self.min;
            self.pixels
                .get(q.y as usize * (self.max.x - self.min.x) as usize + q.x as usize)
                .map(FixedSums::to_f64)
        } else {
            None
        }
    }

    /// The exact sums of every stored pixel (row-major) and of the splat layer (empty if
    /// there are no splats): what a film state file holds.
    pub fn fixed_sums(&self) -> (&[FixedSums], &[[i128; 3]]) {
        (&self.pixels, &self.splats)
    }

    /// The exact sums to add to (a state file decoded into the film), the splat layer
    /// empty until resized to the pixels' length.
    pub fn fixed_sums_mut(&mut self) -> (&mut [FixedSums], &mut Vec<[i128; 3]>) {
        (&mut self.pixels, &mut self.splats)
    }

    /// Adds to the sample counts (with [`Self::fixed_sums_mut`]).
    pub fn add_counts(&mut self, samples: u64, nonfinite: u64) {
        self.samples += samples;
        self.nonfinite += nonfinite;
    }

    /// An image of `f` of every stored pixel's sums, the pixels in parallel.
    fn develop_with(&self, f: impl Fn(&FixedSums) -> Vec3 + Sync + Send) -> Image {
        use rayon::prelude::*;
        let size = self.size();
        Image {
            width: size.x,
            height: size.y,
            pixels: self.pixels.par_iter().map(f).collect(),
        }
    }

    /// `Σ w L / Σ w` per pixel plus the scaled splats, a crop-sized image (pixels without
    /// weight or splats are black).
    pub fn develop(&self) -> Image {
        let mut img = self.develop_with(FixedSums::mean);
        if !self.splats.is_empty() {
            let (nx, ny) = (self.splat_norms(0), self.splat_norms(1));
            let stride = nx.len().max(1);
            for (i, (px, s)) in img.pixels.iter_mut().zip(&self.splats).enumerate() {
                let k = self.splat_scale * nx[i % stride] * ny[i / stride];
                let s = s.map(from_fixed);
                *px += Vec3::new((s[0] * k) as f32, (s[1] * k) as f32, (s[2] * k) as f32);
            }
        }
        img
    }

    /// Standard error of [`Self::develop`] for sums over pixels: [`PixelSums::stderr`] times
    /// the square root of the filter's [`Filter::footprint`] (see the module docs). Identical
    /// to the per-pixel error for the box filter.
    pub fn develop_stderr(&self) -> Image {
        let scale = self.filter.footprint().sqrt() as f32;
        self.develop_with(|p| p.to_f64().stderr() * scale)
    }

    /// Samples rejected because their radiance or position was NaN or infinite.
    #[inline]
    pub fn nonfinite_count(&self) -> u64 {
        self.nonfinite
    }

    /// Accepted camera samples (each counted once, however many pixels it touched).
    #[inline]
    pub fn sample_count(&self) -> u64 {
        self.samples
    }

    /// Accepted samples per stored pixel (progress reporting).
    pub fn spp_added(&self) -> f64 {
        if self.pixels.is_empty() {
            0.0
        } else {
            self.samples as f64 / self.pixels.len() as f64
        }
    }

    /// Forgets every sample and splat.
    pub fn clear(&mut self) {
        self.pixels.fill(FixedSums::default());
        self.samples = 0;
        self.nonfinite = 0;
        self.splats.clear();
    }
}

/// The pixels a `width × height` film with the crop window `crop` stores, `[min, max)`:
/// the crop clipped to the image (an empty crop gives an empty range).
pub fn pixel_bounds(width: u32, height: u32, crop: Option<CropWindow>) -> (UVec2, UVec2) {
    let full = UVec2::new(width, height);
    match crop {
        None => (UVec2::ZERO, full),
        Some(c) => {
            let min = UVec2::new(c.offset_x, c.offset_y).min(full);
            let max = UVec2::new(
                c.offset_x.saturating_add(c.width),
                c.offset_y.saturating_add(c.height),
            )
            .min(full)
            .max(min);
            (min, max)
        }
    }
}

/// Splits `[min, max)` into `tile_size²` tiles (row-major, edge tiles smaller).
pub fn tile_bounds(min: UVec2, max: UVec2, tile_size: u32) -> Vec<(UVec2, UVec2)> {
    let t = tile_size.max(1);
    let mut out = Vec::new();
    let mut y = min.y;
    while y < max.y {
        let y1 = y.saturating_add(t).min(max.y);
        let mut x = min.x;
        while x < max.x {
            let x1 = x.saturating_add(t).min(max.x);
            out.push((UVec2::new(x, y), UVec2::new(x1, y1)));
            x = x1;
        }
        y = y1;
    }
    out
}

/// `⌊v⌋` as integers, for film coordinates (finite, far inside the `i32` range): truncate,
/// then step down where that rounded up. On the SSE2 baseline `f32::floor` is a libm call,
/// four per sample here.
#[inline(always)]
fn floor_to_int(v: Vec2) -> IVec2 {
    let t = v.as_ivec2();
    t - IVec2::new((t.x as f32 > v.x) as i32, (t.y as f32 > v.y) as i32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use base::FilterDesc;

    /// Splats converge to the image camera samples of the same radiance give (module docs):
    /// a radiance field with a bright square a tenth of a pixel wide and a gradient, sampled
    /// on the same 64 × 64 stratified positions per pixel once as camera samples and once as
    /// splats (each worth 1/64² of a pixel's area), develops to the same image within the
    /// quadrature's error, at the film's edges and beside the square too (normalising each
    /// splat to sum to 1 was off by up to 5.6 % there with the gaussian). Off-film splats
    /// are dropped, non-finite ones counted; camera samples add beneath; `clear` forgets.
    /// A dense grid of samples developed with the one-pixel box filter and then given a
    /// filter by `Filter::apply_to_box_image` equals the same samples splatted with that
    /// filter (up to the variation of the radiance inside a pixel): what denoising relies on.
    #[test]
    fn box_image_refiltered_matches_the_filter() {
        let radiance = |p: Vec2| {
            // A step (an edge through pixels) and a gentle ramp.
            let step = if p.x + 0.3 * p.y > 6.4 { 1.0 } else { 0.05 };
            Vec3::new(step, 0.2 + 0.03 * p.y, step * 0.5)
        };
        for desc in [
            FilterDesc::Tent { radius: 1.0 },
            FilterDesc::Gaussian {
                stddev: 0.5,
                radius: 2.0,
            },
            FilterDesc::Mitchell {
                b: 1.0 / 3.0,
                c: 1.0 / 3.0,
                radius: 2.0,
            },
            FilterDesc::Lanczos {
                radius: 2.0,
                tau: 2.0,
            },
        ] {
            let (w, h, n) = (12u32, 10u32, 48u32);
            let filter = Filter::new(&desc);
            let mut direct = Film::new(w, h, None, filter);
            let mut boxed = Film::new(w, h, None, Filter::new(&FilterDesc::Box { radius: 0.5 }));
            let mut t1 = direct.tile(UVec2::ZERO, UVec2::new(w, h));
            let mut t2 = boxed.tile(UVec2::ZERO, UVec2::new(w, h));
            for py in 0..h * n {
                for px in 0..w * n {
                    let p = (Vec2::new(px as f32, py as f32) + 0.5) / n as f32;
                    t1.add_sample(p, radiance(p));
                    t2.add_sample(p, radiance(p));
                }
            }
            direct.merge(&t1);
            boxed.merge(&t2);
            let (a, b) = (
                direct.develop(),
                filter.apply_to_box_image(&boxed.develop()),
            );
            for (i, (x, y)) in a.pixels.iter().zip(&b.pixels).enumerate() {
                // Close where the radiance is linear over the support (up to the film border, where
                // the truncated support shifts the mean along the ramp); pixels that
                // the edge crosses within the support differ by part of the step (0.95).
                let c = Vec2::new((i as u32 % w) as f32, (i as u32 / w) as f32) + 0.5;
                let to_edge = (c.x + 0.3 * c.y - 6.4).abs() / 1.09f32.sqrt();
                let tol = if to_edge > filter.radius() + 0.8 {
                    3e-3
                } else {
                    0.1
                };
                assert!(
                    (*x - *y).abs().max_element() < tol,
                    "{desc:?} pixel {i}: filtered {x}, box then filter {y}"
                );
            }
        }
    }

    #[test]
    fn splats_develop_to_the_camera_samples_image() {
        let radiance = |p: Vec2| {
            let square = (5.3..5.4).contains(&p.x) && (4.6..4.7).contains(&p.y);
            Vec3::new(0.1 + 0.05 * p.x, 0.2, 0.3 + 0.02 * p.y)
                + Vec3::splat(if square { 1000.0 } else { 0.0 })
        };
        for desc in [
            FilterDesc::Box { radius: 0.5 },
            FilterDesc::Tent { radius: 1.0 },
            FilterDesc::Gaussian {
                stddev: 0.5,
                radius: 2.0,
            },
        ] {
            let (w, h, n) = (12u32, 10u32, 64u32);
            let mut cam = Film::new(w, h, None, Filter::new(&desc));
            let mut spl = Film::new(w, h, None, Filter::new(&desc));
            let mut tile = cam.tile(UVec2::ZERO, UVec2::new(w, h));
            for py in 0..h * n {
                for px in 0..w * n {
                    let p = (Vec2::new(px as f32, py as f32) + 0.5) / n as f32;
                    tile.add_sample(p, radiance(p));
                    spl.add_splat(p, radiance(p));
                }
            }
            cam.merge(&tile);
            spl.set_splat_scale(1.0 / (n * n) as f64);
            let (a, b) = (cam.develop(), spl.develop());
            for (i, (x, y)) in a.pixels.iter().zip(&b.pixels).enumerate() {
                let rel = ((*x - *y).abs() / x.abs().max(Vec3::splat(1e-3))).max_element();
                assert!(rel < 2e-3, "{desc:?} pixel {i}: camera {x}, splats {y}");
            }
            // A box-filtered splat lands on one pixel with exactly its value.
            let mut film = Film::new(16, 12, None, Filter::new(&desc));
            let l = Vec3::new(1.0, 2.0, 4.0);
            film.add_splat(Vec2::new(7.3, 5.6), l);
            film.add_splat(Vec2::new(100.0, 5.0), l); // off the film: dropped
            film.add_splat(Vec2::new(f32::NAN, 5.0), l); // counted, dropped
            assert_eq!(film.nonfinite_count(), 1);
            film.set_splat_scale(0.5);
            let img = film.develop();
            let touched = img.pixels.iter().filter(|p| p.x > 0.0).count();
            match desc {
                FilterDesc::Box { .. } => {
                    assert_eq!(touched, 1);
                    assert_eq!(img.pixels[5 * 16 + 7], 0.5 * l);
                }
                _ => assert!(touched >= 4),
            }
            // Camera samples add their mean beneath.
            let mut tile = film.tile(UVec2::ZERO, UVec2::new(16, 12));
            tile.add_sample(Vec2::new(0.5, 0.5), Vec3::ONE);
            film.merge(&tile);
            assert!((film.develop().pixels[0] - Vec3::ONE).abs().max_element() < 1e-6);
            film.clear();
            assert!(film.develop().pixels.iter().all(|p| *p == Vec3::ZERO));
        }
    }

    #[test]
    fn floor_to_int_is_floor() {
        for x in [
            -3.5f32, -3.0, -2.9, -0.5, -1e-7, -0.0, 0.0, 1e-7, 0.5, 1.0, 2.999, 511.5, 4095.0,
        ] {
            let v = Vec2::new(x, -x);
            assert_eq!(floor_to_int(v), v.floor().as_ivec2(), "{x}");
        }
    }

    /// The estimate bounds what a render really allocates (film, tiles, two images) and is
    /// not wildly above it.
    #[test]
    fn memory_needed_bounds_the_real_allocation() {
        for (w, h, desc) in [
            (37, 23, FilterDesc::Box { radius: 0.5 }),
            (
                64,
                48,
                FilterDesc::Gaussian {
                    stddev: 0.5,
                    radius: 2.0,
                },
            ),
            (100, 7, FilterDesc::Tent { radius: 1.5 }),
        ] {
            let filter = Filter::new(&desc);
            let film = Film::new(w, h, None, filter);
            let workers = 3;
            let tile = film
                .tile_bounds(16)
                .iter()
                .map(|&(lo, hi)| film.tile(lo, hi).pixels.len())
                .max()
                .unwrap();
            let real = (film.pixels.len() * (size_of::<FixedSums>() + 2 * size_of::<Vec3>())
                + workers * tile * size_of::<PixelSums>()) as u64;
            let est = Film::memory_needed(w, h, None, &filter, 16, workers);
            assert!(est >= real && est < 2 * real, "{w}x{h}: {est} vs {real}");
        }
    }

    /// The film's sums are exact: the same tiles merged in any order, or spread over two
    /// films that are then added (shards), give the same bits, splats included; and the
    /// rounding to 2⁻⁴⁰ is within half a unit of the f64 sums.
    #[test]
    fn merge_order_and_split_do_not_change_the_bits() {
        let filter = Filter::default_gaussian();
        let (w, h) = (23u32, 17u32);
        let reference = Film::new(w, h, None, filter);
        let mut rng = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            (rng >> 40) as f32 / (1u64 << 24) as f32
        };
        let mut tiles = Vec::new();
        let mut splats = Vec::new();
        for round in 0..3 {
            for (lo, hi) in reference.tile_bounds(5) {
                let mut t = reference.tile(lo, hi);
                for _ in 0..40 {
                    let p = lo.as_vec2() + Vec2::new(next(), next()) * (hi - lo).as_vec2();
                    // Radiances over many magnitudes, fireflies included.
                    let l = Vec3::new(next(), next(), next()) * 10f32.powf(6.0 * next() - 3.0);
                    t.add_sample(p, l);
                }
                tiles.push(t);
                splats.push((
                    Vec2::new(next() * w as f32, next() * h as f32),
                    Vec3::splat(round as f32 + next()),
                ));
            }
        }
        let mut forward = reference.clone();
        for t in &tiles {
            forward.merge(t);
        }
        for &(p, l) in &splats {
            forward.add_splat(p, l);
        }
        let mut odd = reference.clone();
        let mut even = reference.clone();
        for (k, t) in tiles.iter().enumerate().rev() {
            if k % 2 == 1 { &mut odd } else { &mut even }.merge(t);
        }
        for (k, &(p, l)) in splats.iter().enumerate().rev() {
            if k % 3 == 0 { &mut odd } else { &mut even }.add_splat(p, l);
        }
        even.add_film(&odd);
        assert_eq!(forward.fixed_sums(), even.fixed_sums());
        assert_eq!(forward.sample_count(), even.sample_count());
        // Within rounding of the f64 sums.
        let mut f64_film = vec![PixelSums::default(); (w * h) as usize];
        for t in &tiles {
            let (tmin, tmax) = t.bounds();
            for y in tmin.y..tmax.y {
                for x in tmin.x..tmax.x {
                    let s = &t.sums()[((y - tmin.y) * (tmax.x - tmin.x) + x - tmin.x) as usize];
                    let f = &mut f64_film[(y * w + x) as usize];
                    f.weight += s.weight;
                    f.weighted[0] += s.weighted[0];
                }
            }
        }
        for y in 0..h {
            for x in 0..w {
                let exact = forward.pixel(UVec2::new(x, y)).unwrap();
                let f = &f64_film[(y * w + x) as usize];
                let merges = tiles.len() as f64;
                let tol = merges * 0.5 / FIXED_SCALE + 1e-15 * f.weighted[0].abs();
                assert!((exact.weight - f.weight).abs() <= tol);
                assert!((exact.weighted[0] - f.weighted[0]).abs() <= tol);
            }
        }
        // Saturation rather than wrapping, and the fast and slow conversions agree.
        assert_eq!(to_fixed(f64::MAX), i128::MAX);
        assert_eq!(to_fixed(-1e300), i128::MIN);
        assert_eq!(to_fixed(1e7), (1e7 * FIXED_SCALE) as i128);
        assert_eq!(to_fixed(-2.5 / FIXED_SCALE), -2);
    }

    #[test]
    fn rounding_a_pixels_sums_is_to_fixed_of_each() {
        // Each of the three paths of `add_rounded` (the 1.5·2⁵² trick below 2⁵¹ units, the
        // i64 conversion below 9e18, the i128 one beyond) against `to_fixed` one value at a
        // time, at ties (odd multiples of half a unit), at the paths' limits and beyond (within
        // i128; `to_fixed` saturates outside it).
        assert_eq!(to_fixed(1e30), i128::MAX);
        assert_eq!(to_fixed(-1e30), i128::MIN);
        let u = 1.0 / FIXED_SCALE;
        let limit = MAGIC_RANGE * u;
        let values = [
            0.0,
            -0.0,
            0.5 * u,
            1.5 * u,
            -2.5 * u,
            3.25 * u,
            0.1,
            -7.3,
            1.0 / 3.0,
            limit.next_down(),
            -limit.next_down(),
            limit,
            -limit,
            1e5,
            -9.0e18 * u,
            1e12,
            -1e25,
        ];
        for (k, &x) in values.iter().enumerate() {
            // `x` alone in a slot, and `x` beside values of the other paths.
            for others in [0.0, 0.25, 1e6, 1e20] {
                let mut p = PixelSums {
                    weighted: [x, others, 0.75],
                    weight: x,
                    weighted_sq: [0.5, x, others],
                    weight_sq: 1.0,
                    cross: [x, -x, others],
                    count: 1 + k as u64,
                };
                p.weight_sq = -x;
                let fields = p.fields();
                let mut f = FixedSums {
                    v: [3; 11],
                    count: 0,
                };
                f.add_rounded(&p);
                for (got, want) in f.v.iter().zip(fields) {
                    assert_eq!(*got, 3 + to_fixed(want), "{want:e} beside {others:e}");
                }
                assert_eq!(f.count, p.count);
            }
        }
    }

    #[test]
    fn crop_is_clipped_and_tiles_cover_it() {
        let crop = CropWindow {
            offset_x: 5,
            offset_y: 2,
            width: 100,
            height: 3,
        };
        let film = Film::new(20, 10, Some(crop), Filter::default_gaussian());
        assert_eq!(film.pixel_bounds(), (UVec2::new(5, 2), UVec2::new(20, 5)));
        let tiles = film.tile_bounds(4);
        let area: u32 = tiles.iter().map(|(a, b)| (b.x - a.x) * (b.y - a.y)).sum();
        assert_eq!(area, 15 * 3);
        // Sample bounds clipped to the crop; the stored border (2 pixels for r = 2) too.
        let t = film.tile(UVec2::new(0, 0), UVec2::new(7, 7));
        assert_eq!(t.sample_bounds(), (UVec2::new(5, 2), UVec2::new(7, 5)));
        assert_eq!(t.bounds(), (UVec2::new(5, 2), UVec2::new(9, 5)));
        let t = film.tile(UVec2::new(10, 3), UVec2::new(12, 4));
        assert_eq!(t.bounds(), (UVec2::new(8, 2), UVec2::new(14, 5)));
        let box_film = Film::new(20, 10, None, Filter::new(&FilterDesc::Box { radius: 0.5 }));
        let t = box_film.tile(UVec2::new(10, 3), UVec2::new(12, 4));
        assert_eq!(t.bounds(), t.sample_bounds());
        let empty = Film::new(
            4,
            4,
            Some(CropWindow {
                offset_x: 10,
                offset_y: 0,
                width: 2,
                height: 2,
            }),
            Filter::default_gaussian(),
        );
        assert_eq!(empty.size(), UVec2::new(0, 2));
        assert_eq!(empty.develop().pixels.len(), 0);
        assert_eq!(empty.spp_added(), 0.0);
        assert_eq!(empty.tile(UVec2::ZERO, UVec2::splat(4)).sums().len(), 0);
    }

    #[test]
    fn border_is_the_reach_of_the_filter() {
        assert_eq!(border(0.5), 0);
        assert_eq!(border(0.3), 0);
        assert_eq!(border(0.6), 1);
        assert_eq!(border(1.0), 1);
        assert_eq!(border(1.5), 1);
        assert_eq!(border(2.0), 2);
    }

    #[test]
    fn splat_weights_are_mitsubas() {
        // One sample at p: pixel (i, j) gets g(i + ½ − p.x) g(j + ½ − p.y) for
        // i + ½ − p.x ∈ (−r, r] (ImageBlock::put's pixel range and weights).
        let filters = [
            Filter::default_gaussian(),
            Filter::new(&FilterDesc::Tent { radius: 1.0 }),
            Filter::new(&FilterDesc::Box { radius: 1.5 }),
            Filter::new(&FilterDesc::Mitchell {
                b: 1.0 / 3.0,
                c: 1.0 / 3.0,
                radius: 2.0,
            }),
        ];
        for filter in filters {
            let r = filter.radius();
            let film = Film::new(16, 12, None, filter);
            let mut tile = film.tile(UVec2::new(9, 7), UVec2::new(11, 9));
            let p = Vec2::new(10.3, 7.8);
            tile.add_sample(p, Vec3::new(1.0, 2.0, 3.0));
            let (lo, hi) = tile.bounds();
            let mut touched = 0;
            for y in lo.y..hi.y {
                for x in lo.x..hi.x {
                    let s = tile.sums()[((y - lo.y) * (hi.x - lo.x) + x - lo.x) as usize];
                    let d = Vec2::new(x as f32 + 0.5, y as f32 + 0.5) - p;
                    let inside = d.cmpgt(Vec2::splat(-r)).all() && d.cmple(Vec2::splat(r)).all();
                    assert_eq!(s.count, inside as u64, "{filter:?} ({x}, {y})");
                    let w = filter.eval_1d(d.x) as f64 * filter.eval_1d(d.y) as f64;
                    assert_eq!(s.weight, if inside { w } else { 0.0 });
                    assert_eq!(
                        s.weighted,
                        [w, 2.0 * w, 3.0 * w].map(|v| v * inside as u8 as f64)
                    );
                    touched += s.count;
                }
            }
            let side = (2.0 * r).ceil() as u64;
            assert!(touched <= side * side, "{filter:?}: {touched}");
            assert_eq!(tile.sample_count(), 1);
        }
        // The default box filter: exactly the pixel containing p, even at its corner.
        let film = Film::new(4, 4, None, Filter::new(&FilterDesc::Box { radius: 0.5 }));
        for p in [Vec2::new(2.0, 1.0), Vec2::new(2.999_999_8, 1.999_999_9)] {
            let mut tile = film.tile(UVec2::new(2, 1), UVec2::new(3, 2));
            tile.add_sample(p, Vec3::ONE);
            assert_eq!((tile.sums().len(), tile.sums()[0].weight), (1, 1.0));
        }
    }

    #[test]
    fn stderr_of_weighted_samples() {
        // Two samples, unit weights: mean 2, s² = 2, stderr = 1.
        let mut p = PixelSums::default();
        p.add([1.0; 3], 1.0);
        p.add([3.0; 3], 1.0);
        assert_eq!(p.mean(), Vec3::splat(2.0));
        assert!((p.stderr() - Vec3::ONE).abs().max_element() < 1e-6);
        // Scaling all weights changes nothing.
        let mut q = PixelSums::default();
        q.add([1.0; 3], 0.25);
        q.add([3.0; 3], 0.25);
        assert_eq!(q.mean(), p.mean());
        assert!((q.stderr() - p.stderr()).abs().max_element() < 1e-6);
        // A single sample or zero weight: no error estimate.
        let mut r = PixelSums::default();
        r.add([1.0; 3], 1.0);
        assert_eq!(r.stderr(), Vec3::ZERO);
        r.add([1.0; 3], -1.0);
        assert_eq!((r.mean(), r.stderr()), (Vec3::ZERO, Vec3::ZERO));
    }
}
