//! The film: per-pixel weighted sums, accumulated in tiles and merged.
//!
//! With filter importance sampling ([`super::Filter::sample`]) each camera sample contributes
//! to exactly one pixel, so a pixel's value is the ratio estimator `R = Σ wᵢLᵢ / Σ wᵢ` of
//! independent samples. Each pixel keeps, in f64,
//! `Σ wL, Σ w, Σ (wL)², Σ w², Σ w·(wL)` and the sample count `n`, which gives both `R` and its
//! standard error by the delta method:
//!
//! `Var(R) ≈ n / (n − 1) · Σ (wᵢLᵢ − R wᵢ)² / (Σ wᵢ)²`,
//! `Σ (wL − R w)² = Σ (wL)² − 2R Σ w·(wL) + R² Σ w²`,
//!
//! which for unit weights is the usual `s² / n`. Sums are plain additions, so splitting a render
//! into tiles, passes or machines and merging the pieces is exact: a pixel's sums only depend
//! on the order of its own samples, never on the tiling (merged tiles equal a single-tile
//! render bit for bit).
//!
//! Samples whose radiance or weight is NaN or infinite are rejected and counted
//! ([`Film::nonfinite_count`]); they do not count towards `n`.
//!
//! Memory: 96 bytes per pixel of the crop window.

use super::Image;
use crate::math::{UVec2, Vec3};
use scene::CropWindow;

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
    /// Number of accepted samples.
    pub count: u64,
}

impl PixelSums {
    #[inline]
    fn add(&mut self, l: Vec3, weight: f32) {
        let w = weight as f64;
        let wl = [w * l.x as f64, w * l.y as f64, w * l.z as f64];
        for (c, &v) in wl.iter().enumerate() {
            self.weighted[c] += v;
            self.weighted_sq[c] += v * v;
            self.cross[c] += w * v;
        }
        self.weight += w;
        self.weight_sq += w * w;
        self.count += 1;
    }

    #[inline]
    fn merge(&mut self, o: &PixelSums) {
        for c in 0..3 {
            self.weighted[c] += o.weighted[c];
            self.weighted_sq[c] += o.weighted_sq[c];
            self.cross[c] += o.cross[c];
        }
        self.weight += o.weight;
        self.weight_sq += o.weight_sq;
        self.count += o.count;
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

    /// Standard error of [`Self::mean`] (delta method; 0 with fewer than 2 samples or `Σ w = 0`,
    /// where it is undefined).
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

/// Sums for a rectangle of pixels `[min, max)` (full-image coordinates), filled by one worker
/// and merged into the [`Film`].
#[derive(Clone, Debug)]
pub struct FilmTile {
    min: UVec2,
    max: UVec2,
    pixels: Vec<PixelSums>,
    nonfinite: u64,
}

impl FilmTile {
    /// An empty tile covering `[min, max)` (an inverted rectangle becomes empty).
    pub fn new(min: UVec2, max: UVec2) -> FilmTile {
        let max = max.max(min);
        let size = max - min;
        FilmTile {
            min,
            max,
            pixels: vec![PixelSums::default(); size.x as usize * size.y as usize],
            nonfinite: 0,
        }
    }

    /// A tile from stored sums (e.g. a render resumed from disk); `None` if the sizes disagree.
    pub fn from_sums(min: UVec2, max: UVec2, pixels: Vec<PixelSums>) -> Option<FilmTile> {
        let size = max.saturating_sub(min);
        (max.cmpge(min).all() && pixels.len() == size.x as usize * size.y as usize).then_some(
            FilmTile {
                min,
                max,
                pixels,
                nonfinite: 0,
            },
        )
    }

    /// `[min, max)` in full-image pixels.
    #[inline]
    pub fn bounds(&self) -> (UVec2, UVec2) {
        (self.min, self.max)
    }

    /// Row-major sums of the tile's pixels.
    #[inline]
    pub fn sums(&self) -> &[PixelSums] {
        &self.pixels
    }

    #[inline]
    pub fn nonfinite_count(&self) -> u64 {
        self.nonfinite
    }

    #[inline]
    fn index(&self, p: UVec2) -> Option<usize> {
        if p.cmpge(self.min).all() && p.cmplt(self.max).all() {
            let q = p - self.min;
            Some(q.y as usize * (self.max.x - self.min.x) as usize + q.x as usize)
        } else {
            None
        }
    }

    /// Adds radiance `l` with filter weight `weight` to `pixel` (full-image coordinates).
    /// Non-finite samples are rejected and counted; pixels outside the tile are a caller bug
    /// (debug assertion) and are ignored in release builds.
    #[inline]
    pub fn add_sample(&mut self, pixel: UVec2, l: Vec3, weight: f32) {
        if !(l.is_finite() && weight.is_finite()) {
            self.nonfinite += 1;
            return;
        }
        match self.index(pixel) {
            Some(i) => self.pixels[i].add(l, weight),
            None => debug_assert!(false, "pixel {pixel} outside tile {:?}", self.bounds()),
        }
    }
}

/// The image being rendered: sums for the pixels of the crop window (or the whole image).
#[derive(Clone, Debug)]
pub struct Film {
    full: UVec2,
    min: UVec2,
    max: UVec2,
    pixels: Vec<PixelSums>,
    nonfinite: u64,
}

impl Film {
    /// A `width × height` film storing only `crop` (clipped to the image; an empty crop gives
    /// an empty film: validate crop windows where the scene is loaded).
    pub fn new(width: u32, height: u32, crop: Option<CropWindow>) -> Film {
        let full = UVec2::new(width, height);
        let (min, max) = match crop {
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
        };
        let size = max - min;
        Film {
            full,
            min,
            max,
            pixels: vec![PixelSums::default(); size.x as usize * size.y as usize],
            nonfinite: 0,
        }
    }

    /// The full image resolution (the camera's raster).
    #[inline]
    pub fn full_resolution(&self) -> UVec2 {
        self.full
    }

    /// `[min, max)` of the stored pixels in full-image coordinates.
    #[inline]
    pub fn pixel_bounds(&self) -> (UVec2, UVec2) {
        (self.min, self.max)
    }

    /// Size of the stored (crop) region = size of the developed images.
    #[inline]
    pub fn size(&self) -> UVec2 {
        self.max - self.min
    }

    /// An empty tile for `[min, max)` clipped to the pixel bounds.
    pub fn tile(&self, min: UVec2, max: UVec2) -> FilmTile {
        let tmin = min.clamp(self.min, self.max);
        let tmax = max.clamp(self.min, self.max).max(tmin);
        FilmTile::new(tmin, tmax)
    }

    /// Splits the pixel bounds into `tile_size²` tiles (row-major, edge tiles smaller).
    pub fn tile_bounds(&self, tile_size: u32) -> Vec<(UVec2, UVec2)> {
        let t = tile_size.max(1);
        let mut out = Vec::new();
        let mut y = self.min.y;
        while y < self.max.y {
            let y1 = y.saturating_add(t).min(self.max.y);
            let mut x = self.min.x;
            while x < self.max.x {
                let x1 = x.saturating_add(t).min(self.max.x);
                out.push((UVec2::new(x, y), UVec2::new(x1, y1)));
                x = x1;
            }
            y = y1;
        }
        out
    }

    /// Adds a tile's sums (the part inside the pixel bounds) and its non-finite count.
    pub fn merge(&mut self, tile: FilmTile) {
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
            for (f, t) in self.pixels[f0..f0 + len]
                .iter_mut()
                .zip(&tile.pixels[t0..t0 + len])
            {
                f.merge(t);
            }
        }
    }

    /// The sums of `pixel` (full-image coordinates), if stored.
    pub fn pixel(&self, pixel: UVec2) -> Option<&PixelSums> {
        if pixel.cmpge(self.min).all() && pixel.cmplt(self.max).all() {
            let q = pixel - self.min;
            self.pixels
                .get(q.y as usize * (self.max.x - self.min.x) as usize + q.x as usize)
        } else {
            None
        }
    }

    fn develop_with(&self, f: impl Fn(&PixelSums) -> Vec3) -> Image {
        let size = self.size();
        Image {
            width: size.x,
            height: size.y,
            pixels: self.pixels.iter().map(f).collect(),
        }
    }

    /// `Σ w L / Σ w` per pixel, a crop-sized image (pixels without weight are black).
    pub fn develop(&self) -> Image {
        self.develop_with(PixelSums::mean)
    }

    /// Per-pixel standard error of [`Self::develop`] (see the module docs).
    pub fn develop_stderr(&self) -> Image {
        self.develop_with(PixelSums::stderr)
    }

    /// Samples rejected because their radiance or weight was NaN or infinite.
    #[inline]
    pub fn nonfinite_count(&self) -> u64 {
        self.nonfinite
    }

    /// Accepted samples over all pixels.
    pub fn sample_count(&self) -> u64 {
        self.pixels.iter().map(|p| p.count).sum()
    }

    /// Mean accepted samples per stored pixel (progress reporting).
    pub fn spp_added(&self) -> f64 {
        if self.pixels.is_empty() {
            0.0
        } else {
            self.sample_count() as f64 / self.pixels.len() as f64
        }
    }

    /// Forgets every sample.
    pub fn clear(&mut self) {
        self.pixels.fill(PixelSums::default());
        self.nonfinite = 0;
    }

    /// The whole film as one tile (to merge films rendered separately, e.g. on several
    /// machines with disjoint sample ranges).
    pub fn into_tile(self) -> FilmTile {
        FilmTile {
            min: self.min,
            max: self.max,
            pixels: self.pixels,
            nonfinite: self.nonfinite,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crop_is_clipped_and_tiles_cover_it() {
        let crop = CropWindow {
            offset_x: 5,
            offset_y: 2,
            width: 100,
            height: 3,
        };
        let film = Film::new(20, 10, Some(crop));
        assert_eq!(film.pixel_bounds(), (UVec2::new(5, 2), UVec2::new(20, 5)));
        let tiles = film.tile_bounds(4);
        let area: u32 = tiles.iter().map(|(a, b)| (b.x - a.x) * (b.y - a.y)).sum();
        assert_eq!(area, 15 * 3);
        let t = film.tile(UVec2::new(0, 0), UVec2::new(7, 7));
        assert_eq!(t.bounds(), (UVec2::new(5, 2), UVec2::new(7, 5)));
        let empty = Film::new(
            4,
            4,
            Some(CropWindow {
                offset_x: 10,
                offset_y: 0,
                width: 2,
                height: 2,
            }),
        );
        assert_eq!(empty.size(), UVec2::new(0, 2));
        assert_eq!(empty.develop().pixels.len(), 0);
        assert_eq!(empty.spp_added(), 0.0);
    }

    #[test]
    fn stderr_of_weighted_samples() {
        // Two samples, unit weights: mean 2, s² = 2, stderr = 1.
        let mut p = PixelSums::default();
        p.add(Vec3::splat(1.0), 1.0);
        p.add(Vec3::splat(3.0), 1.0);
        assert_eq!(p.mean(), Vec3::splat(2.0));
        assert!((p.stderr() - Vec3::ONE).abs().max_element() < 1e-6);
        // Scaling all weights changes nothing.
        let mut q = PixelSums::default();
        q.add(Vec3::splat(1.0), 0.25);
        q.add(Vec3::splat(3.0), 0.25);
        assert_eq!(q.mean(), p.mean());
        assert!((q.stderr() - p.stderr()).abs().max_element() < 1e-6);
        // A single sample or zero weight: no error estimate.
        let mut r = PixelSums::default();
        r.add(Vec3::ONE, 1.0);
        assert_eq!(r.stderr(), Vec3::ZERO);
        r.add(Vec3::ONE, -1.0);
        assert_eq!((r.mean(), r.stderr()), (Vec3::ZERO, Vec3::ZERO));
    }

    #[test]
    fn from_sums_checks_sizes() {
        assert!(
            FilmTile::from_sums(UVec2::ZERO, UVec2::new(2, 2), vec![PixelSums::default(); 3])
                .is_none()
        );
        assert!(FilmTile::from_sums(UVec2::new(3, 0), UVec2::new(2, 2), vec![]).is_none());
        assert!(
            FilmTile::from_sums(UVec2::ZERO, UVec2::new(2, 2), vec![PixelSums::default(); 4])
                .is_some()
        );
    }
}
