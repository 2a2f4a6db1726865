//! Textures evaluated at a surface point (Mitsuba 3 semantics, plus the CENG795 course's).
//!
//! - `Bitmap`: uv is transformed by `to_uv`, then wrapped; (0,0) is the *top-left* corner of
//!   the image file (Mitsuba 3 does not flip bitmaps; its OBJ reader flips v instead).
//!   Bilinear filtering between pixel centres, or nearest. With `corner_texels` (CENG795)
//!   texel (i, j) sits at (i/w, j/h): nearest is texel (round(u·w), round(v·h)) and bilinear
//!   weights the four texels around (u·w, v·h), as the course's lecture defines them.
//! - `Checkerboard`: `color0` where the fractional parts of u and v are both below or both
//!   above ½, `color1` elsewhere.
//! - `Perlin`, `SolidChecker`: solid textures of the world-space point (see [`perlin`]).
//! - `Affine`: another texture times a scale plus an offset.

use std::sync::Arc;

use base::spectrum::DeclaredSpectrum;
use base::{NoiseConversion, NoiseKind, TextureFilter, WrapMode};

use crate::film::Image;
use crate::math::{Mat3, Mat4, Vec2, Vec3};

/// Where a texture is looked up: the surface's uv and its world-space point, and the
/// lookup's footprint: the change of uv per pixel step in x and in y (zero when unknown:
/// MIP-mapped textures then read their finest level).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TexCoord {
    pub uv: Vec2,
    pub p: Vec3,
    pub duv: [Vec2; 2],
}

impl TexCoord {
    /// A lookup that only has a uv (surface textures ignore `p`).
    /// A lookup without a footprint.
    pub fn at(uv: Vec2, p: Vec3) -> TexCoord {
        TexCoord {
            uv,
            p,
            duv: [Vec2::ZERO; 2],
        }
    }

    pub fn uv(uv: Vec2) -> TexCoord {
        TexCoord {
            uv,
            ..TexCoord::default()
        }
    }
}

/// A parameter at run time: a constant, or the index of a texture evaluated at the hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TexRef<T> {
    Const(T),
    Texture(u32),
}

/// A colour parameter (reflectance, radiance, ...).
pub type ColorRef = TexRef<Vec3>;
/// A scalar parameter (roughness, opacity, ...); a texture's first channel.
pub type FloatRef = TexRef<f32>;

/// Evaluates parameters at a surface point.
pub trait Params {
    fn color(&self, p: &ColorRef, at: TexCoord) -> Vec3;
    fn float(&self, p: &FloatRef, at: TexCoord) -> f32;
    /// The spectrum `p` was declared as, if it was one ([`Texture::Spectrum`]): what spectral
    /// mode samples instead of upsampling [`Self::color`]. RGB mode never asks.
    #[inline(always)]
    fn spectrum(&self, _p: &ColorRef) -> Option<&DeclaredSpectrum> {
        None
    }
}

/// The scene's textures, indexed by [`TexRef::Texture`].
#[derive(Clone, Debug, Default)]
pub struct Textures(Vec<Texture>);

impl Textures {
    pub fn new(list: Vec<Texture>) -> Textures {
        Textures(list)
    }

    /// Texture `t` (an index a [`TexRef`] or a material names; the builder checks them).
    #[inline]
    pub fn get(&self, t: u32) -> &Texture {
        &self.0[t as usize]
    }

    /// Texture lookups stay behind a call, so that constants (most parameters) cost no call
    /// in the hot loops.
    #[inline(never)]
    fn eval(&self, t: u32, at: TexCoord) -> Vec3 {
        self.0[t as usize].eval(at)
    }
}

impl Params for Textures {
    #[inline(always)]
    fn color(&self, p: &ColorRef, at: TexCoord) -> Vec3 {
        match p {
            TexRef::Const(c) => *c,
            TexRef::Texture(t) => self.eval(*t, at),
        }
    }

    #[inline(always)]
    fn float(&self, p: &FloatRef, at: TexCoord) -> f32 {
        match p {
            TexRef::Const(c) => *c,
            TexRef::Texture(t) => self.eval(*t, at).x,
        }
    }

    #[inline]
    fn spectrum(&self, p: &ColorRef) -> Option<&DeclaredSpectrum> {
        match p {
            TexRef::Texture(t) => match &self.0[*t as usize] {
                Texture::Spectrum { spectrum, .. } => Some(spectrum),
                _ => None,
            },
            TexRef::Const(_) => None,
        }
    }
}

/// Parameters without textures (statistical tests of single BSDFs); a texture reads as 0.5.
pub struct ConstantParams;

impl Params for ConstantParams {
    fn color(&self, p: &ColorRef, _at: TexCoord) -> Vec3 {
        match p {
            TexRef::Const(c) => *c,
            TexRef::Texture(_) => Vec3::splat(0.5),
        }
    }
    fn float(&self, p: &FloatRef, _at: TexCoord) -> f32 {
        match p {
            TexRef::Const(c) => *c,
            TexRef::Texture(_) => 0.5,
        }
    }
}

#[derive(Clone, Debug)]
pub enum Texture {
    Constant(Vec3),
    Bitmap {
        image: Arc<Image>,
        filter: TextureFilter,
        wrap: WrapMode,
        to_uv: Mat3,
        corner_texels: bool,
        /// The MIP pyramid of trilinear and EWA filtering.
        mips: Option<Arc<MipMap>>,
    },
    Checkerboard {
        color0: Vec3,
        color1: Vec3,
        to_uv: Mat3,
    },
    Perlin {
        scale: f32,
        conversion: NoiseConversion,
    },
    SolidChecker {
        black: Vec3,
        white: Vec3,
        scale: f32,
        offset: f32,
    },
    Affine {
        texture: Box<Texture>,
        scale: f32,
        offset: Vec3,
    },
    Product(Box<[Texture; 2]>),
    /// `[a, b, amount]`: (1 − t)·a + t·b, t = amount's first channel.
    Mix(Box<[Texture; 3]>),
    /// Values at uv corners (0,0), (1,0), (0,1), (1,1) of `to_uv`·uv.
    Bilerp {
        corners: [Vec3; 4],
        to_uv: Mat3,
    },
    /// `[even, odd]` cells of ⌊x⌋ + ⌊y⌋ + ⌊z⌋ at `to_texture`·p.
    Checker3D {
        textures: Box<[Texture; 2]>,
        to_texture: Mat4,
    },
    Noise {
        kind: NoiseKind,
        to_texture: Mat4,
    },
    /// `[inside, outside]` of pbrt-v4's polka dots over `to_uv`·uv.
    Dots {
        textures: Box<[Texture; 2]>,
        to_uv: Mat3,
    },
    /// A constant the scene declared as a spectrum (made by `build` in spectral mode only):
    /// `rgb` wherever an RGB value is read (lobe-selection weights, light power), the
    /// spectrum where spectral mode converts the parameter ([`Params::spectrum`]).
    Spectrum {
        rgb: Vec3,
        spectrum: Arc<DeclaredSpectrum>,
    },
}

/// The course's gradient set: the 12 cube-edge directions, four of them repeated to make 16.
const GRADIENTS: [[f32; 3]; 16] = [
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [1.0, -1.0, 0.0],
    [-1.0, -1.0, 0.0],
    [1.0, 0.0, 1.0],
    [-1.0, 0.0, 1.0],
    [1.0, 0.0, -1.0],
    [-1.0, 0.0, -1.0],
    [0.0, 1.0, 1.0],
    [0.0, -1.0, 1.0],
    [0.0, 1.0, -1.0],
    [0.0, -1.0, -1.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [0.0, -1.0, 1.0],
    [0.0, -1.0, -1.0],
];

/// The permutation table P of 0..15. The course draws a random one when its program starts;
/// ours is one fixed draw, so that images repeat from run to run.
pub const PERMUTATION: [usize; 16] = [11, 4, 14, 1, 8, 6, 0, 13, 3, 15, 9, 2, 7, 12, 5, 10];

/// The course's weight f(x) = −6|x|⁵ + 15|x|⁴ − 10|x|³ + 1 (1 at 0, 0 at |x| = 1).
#[inline]
fn weight(x: f32) -> f32 {
    let a = x.abs();
    let a3 = a * a * a;
    a3 * (a * (-6.0 * a + 15.0) - 10.0) + 1.0
}

/// The gradient of lattice point (i, j, k): G[P[(i + P[(j + P[k mod 16]) mod 16]) mod 16]].
#[inline]
fn lattice_gradient(i: i64, j: i64, k: i64) -> Vec3 {
    let m = |x: i64| x.rem_euclid(16) as usize;
    let g = GRADIENTS[PERMUTATION[m(i + PERMUTATION[m(j + PERMUTATION[m(k)] as i64)] as i64)]];
    Vec3::new(g[0], g[1], g[2])
}

/// The CENG795 course's Perlin noise at `p` (already scaled), in [−1, 1]: the sum over the
/// eight lattice points (i, j, k) of the cell around p of G(i,j,k)·v · f(vx) f(vy) f(vz),
/// with v = p − (i, j, k).
pub fn perlin(p: Vec3) -> f32 {
    let base = p.floor();
    let (x0, y0, z0) = (base.x as i64, base.y as i64, base.z as i64);
    let mut sum = 0.0;
    for dz in 0..2 {
        for dy in 0..2 {
            for dx in 0..2 {
                let (i, j, k) = (x0 + dx, y0 + dy, z0 + dz);
                let v = p - Vec3::new(i as f32, j as f32, k as f32);
                sum += lattice_gradient(i, j, k).dot(v) * weight(v.x) * weight(v.y) * weight(v.z);
            }
        }
    }
    sum
}

/// Bilinear interpolation of `image` at continuous texel position (x, y) (texel i centred at
/// i + ½).
#[inline]
fn bilerp(image: &Image, x: f32, y: f32, wrap: WrapMode) -> Vec3 {
    let (w, h) = (image.width, image.height);
    let (xs, ys) = (x - 0.5, y - 0.5);
    let (x0, y0) = (xs.floor(), ys.floor());
    let (fx, fy) = (xs - x0, ys - y0);
    let (x0, y0) = (x0 as i64, y0 as i64);
    let px =
        |dx: i64, dy: i64| image.get(wrap_index(x0 + dx, w, wrap), wrap_index(y0 + dy, h, wrap));
    (px(0, 0) * (1.0 - fx) + px(1, 0) * fx) * (1.0 - fy)
        + (px(0, 1) * (1.0 - fx) + px(1, 1) * fx) * fy
}

/// An image pyramid for pbrt-v4's trilinear and EWA filtering: level 0 is the image
/// resampled (bilinearly) to power-of-two sides, each next level the 2×2 box average of the
/// one before, down to one texel.
#[derive(Debug)]
pub struct MipMap {
    levels: Vec<Image>,
}

impl MipMap {
    pub fn new(image: &Image, wrap: WrapMode) -> MipMap {
        let (w, h) = (
            image.width.next_power_of_two(),
            image.height.next_power_of_two(),
        );
        let mut base = Image::new(w, h);
        for y in 0..h {
            for x in 0..w {
                let fx = (x as f32 + 0.5) / w as f32 * image.width as f32;
                let fy = (y as f32 + 0.5) / h as f32 * image.height as f32;
                base.set(x, y, bilerp(image, fx, fy, wrap));
            }
        }
        let mut levels = vec![base];
        while let Some(last) = levels.last().filter(|l| l.width > 1 || l.height > 1) {
            let (w, h) = ((last.width / 2).max(1), (last.height / 2).max(1));
            let mut next = Image::new(w, h);
            for y in 0..h {
                for x in 0..w {
                    let (x2, y2) = (2 * x, 2 * y);
                    let at = |dx: u32, dy: u32| {
                        last.get(
                            (x2 + dx).min(last.width - 1),
                            (y2 + dy).min(last.height - 1),
                        )
                    };
                    next.set(x, y, (at(0, 0) + at(1, 0) + at(0, 1) + at(1, 1)) * 0.25);
                }
            }
            levels.push(next);
        }
        MipMap { levels }
    }

    pub fn levels(&self) -> usize {
        self.levels.len()
    }

    fn bilerp(&self, level: usize, st: Vec2, wrap: WrapMode) -> Vec3 {
        let l = &self.levels[level.min(self.levels.len() - 1)];
        bilerp(l, st.x * l.width as f32, st.y * l.height as f32, wrap)
    }

    fn texel(&self, level: usize, x: i64, y: i64, wrap: WrapMode) -> Vec3 {
        let l = &self.levels[level];
        l.get(wrap_index(x, l.width, wrap), wrap_index(y, l.height, wrap))
    }

    /// The filtered value at `st` for a footprint of `dst` (the change of st per pixel step
    /// in x and y), as pbrt-v4's `MIPMap::Filter` computes it.
    pub fn filter(&self, st: Vec2, dst: [Vec2; 2], filter: TextureFilter, wrap: WrapMode) -> Vec3 {
        let n = self.levels.len();
        if filter != TextureFilter::Ewa {
            let width = 2.0 * dst[0].abs().max(dst[1].abs()).max_element();
            let level = (n - 1) as f32 + width.max(1e-8).log2();
            if level >= (n - 1) as f32 {
                return self.texel(n - 1, 0, 0, wrap);
            }
            let il = level.floor().max(0.0) as usize;
            return match filter {
                TextureFilter::Nearest => {
                    let l = &self.levels[il];
                    let x = (st.x * l.width as f32).floor() as i64;
                    let y = (st.y * l.height as f32).floor() as i64;
                    self.texel(il, x, y, wrap)
                }
                TextureFilter::Bilinear => self.bilerp(il, st, wrap),
                _ if il == 0 => self.bilerp(0, st, wrap),
                _ => {
                    let t = level - il as f32;
                    self.bilerp(il, st, wrap) * (1.0 - t) + self.bilerp(il + 1, st, wrap) * t
                }
            };
        }
        let (mut major, mut minor) = (dst[0], dst[1]);
        if major.length_squared() < minor.length_squared() {
            std::mem::swap(&mut major, &mut minor);
        }
        let (long, mut short) = (major.length(), minor.length());
        const MAX_ANISOTROPY: f32 = 8.0;
        if short * MAX_ANISOTROPY < long && short > 0.0 {
            let scale = long / (short * MAX_ANISOTROPY);
            minor *= scale;
            short *= scale;
        }
        if short == 0.0 || !short.is_finite() {
            return self.bilerp(0, st, wrap);
        }
        let lod = ((n - 1) as f32 + short.log2()).max(0.0);
        let il = lod.floor() as usize;
        let t = lod - il as f32;
        self.ewa(il, st, major, minor, wrap) * (1.0 - t)
            + self.ewa(il + 1, st, major, minor, wrap) * t
    }

    /// Heckbert's elliptically weighted average at one level, Gaussian weights
    /// e^(−2r²) − e^(−2) over the ellipse spanned by the two footprint vectors.
    fn ewa(&self, level: usize, st: Vec2, d0: Vec2, d1: Vec2, wrap: WrapMode) -> Vec3 {
        if level >= self.levels.len() {
            return self.texel(self.levels.len() - 1, 0, 0, wrap);
        }
        let l = &self.levels[level];
        let res = Vec2::new(l.width as f32, l.height as f32);
        let c = st * res - Vec2::splat(0.5);
        let (d0, d1) = (d0 * res, d1 * res);
        let mut a = d0.y * d0.y + d1.y * d1.y + 1.0;
        let mut b = -2.0 * (d0.x * d0.y + d1.x * d1.y);
        let mut cc = d0.x * d0.x + d1.x * d1.x + 1.0;
        let inv_f = 1.0 / (a * cc - b * b * 0.25);
        a *= inv_f;
        b *= inv_f;
        cc *= inv_f;
        let det = 4.0 * a * cc - b * b;
        let inv_det = 1.0 / det;
        let (us, vs) = ((det * cc).max(0.0).sqrt(), (a * det).max(0.0).sqrt());
        let (s0, s1) = (
            (c.x - 2.0 * inv_det * us).ceil() as i64,
            (c.x + 2.0 * inv_det * us).floor() as i64,
        );
        let (t0, t1) = (
            (c.y - 2.0 * inv_det * vs).ceil() as i64,
            (c.y + 2.0 * inv_det * vs).floor() as i64,
        );
        let (mut sum, mut weights) = (Vec3::ZERO, 0f32);
        let edge = (-2f32).exp();
        for it in t0..=t1 {
            let tt = it as f32 - c.y;
            for is in s0..=s1 {
                let ss = is as f32 - c.x;
                let r2 = a * ss * ss + b * ss * tt + cc * tt * tt;
                if r2 < 1.0 {
                    let w = (-2.0 * r2).exp() - edge;
                    sum += self.texel(level, is, it, wrap) * w;
                    weights += w;
                }
            }
        }
        if weights > 0.0 {
            sum / weights
        } else {
            self.bilerp(level, st, wrap)
        }
    }
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
    pub fn eval(&self, at: TexCoord) -> Vec3 {
        match self {
            Texture::Constant(c) => *c,
            Texture::Checkerboard {
                color0,
                color1,
                to_uv,
            } => {
                let p = to_uv.transform_point2(at.uv);
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
                corner_texels,
                mips,
            } => {
                let p = to_uv.transform_point2(at.uv);
                if !p.is_finite() {
                    return Vec3::ZERO;
                }
                if let Some(m) = mips {
                    let d = at.duv.map(|d| to_uv.transform_vector2(d));
                    return m.filter(p, d, *filter, *wrap);
                }
                let (w, h) = (image.width, image.height);
                // Centred texels: texel i covers [i, i+1) of x; corner texels: [i-½, i+½).
                let shift = if *corner_texels { 0.5 } else { 0.0 };
                let x = p.x * w as f32 + shift;
                let y = p.y * h as f32 + shift;
                match filter {
                    TextureFilter::Nearest => {
                        let xi = wrap_index(x.floor() as i64, w, *wrap);
                        let yi = wrap_index(y.floor() as i64, h, *wrap);
                        image.get(xi, yi)
                    }
                    // Without a pyramid (not built for these filters) the finest level.
                    TextureFilter::Bilinear | TextureFilter::Trilinear | TextureFilter::Ewa => {
                        bilerp(image, x, y, *wrap)
                    }
                }
            }
            Texture::Perlin { scale, conversion } => {
                let n = perlin(at.p * *scale);
                Vec3::splat(match conversion {
                    NoiseConversion::Linear => 0.5 * (n + 1.0),
                    NoiseConversion::AbsVal => n.abs(),
                })
            }
            Texture::SolidChecker {
                black,
                white,
                scale,
                offset,
            } => {
                let c = ((at.p + Vec3::splat(*offset)) * *scale).floor();
                let odd = (c.x as i64 + c.y as i64 + c.z as i64).rem_euclid(2) == 1;
                if odd { *black } else { *white }
            }
            Texture::Affine {
                texture,
                scale,
                offset,
            } => texture.eval(at) * *scale + *offset,
            Texture::Product(t) => t[0].eval(at) * t[1].eval(at),
            Texture::Mix(t) => {
                let u = t[2].eval(at).x;
                t[0].eval(at) * (1.0 - u) + t[1].eval(at) * u
            }
            Texture::Bilerp { corners, to_uv } => {
                let q = to_uv.transform_point2(at.uv);
                let (u, v) = (q.x, q.y);
                corners[0] * ((1.0 - u) * (1.0 - v))
                    + corners[1] * (u * (1.0 - v))
                    + corners[2] * ((1.0 - u) * v)
                    + corners[3] * (u * v)
            }
            Texture::Checker3D {
                textures,
                to_texture,
            } => {
                let c = to_texture.transform_point3a(at.p).floor();
                let odd = (c.x as i64 + c.y as i64 + c.z as i64).rem_euclid(2) == 1;
                textures[usize::from(odd)].eval(at)
            }
            Texture::Noise { kind, to_texture } => {
                noise::texture(*kind, to_texture.transform_point3a(at.p))
            }
            Texture::Dots { textures, to_uv } => {
                let inside = noise::in_dot(to_uv.transform_point2(at.uv));
                textures[usize::from(!inside)].eval(at)
            }
            Texture::Spectrum { rgb, .. } => *rgb,
        }
    }

    /// The world-space gradient of the texture's height (its channel mean) at `at`, for bump
    /// mapping. Image textures differentiate between neighbouring texels along u and v, which
    /// run along `s` and `t` (the unit tangents of the shading frame); solid textures by
    /// central differences in space.
    pub fn height_gradient(&self, at: TexCoord, s: Vec3, t: Vec3) -> Vec3 {
        let height = |at: TexCoord| {
            let c = self.eval(at);
            (c.x + c.y + c.z) / 3.0
        };
        match self.texel_size() {
            Some(du) => {
                let h0 = height(at);
                let hu = height(TexCoord {
                    uv: at.uv + Vec2::new(du.x, 0.0),
                    ..at
                });
                let hv = height(TexCoord {
                    uv: at.uv + Vec2::new(0.0, du.y),
                    ..at
                });
                (hu - h0) * s + (hv - h0) * t
            }
            None => {
                let eps = self.solid_epsilon();
                let d = |e: Vec3| {
                    height(TexCoord { p: at.p + e, ..at }) - height(TexCoord { p: at.p - e, ..at })
                };
                Vec3::new(d(Vec3::X * eps), d(Vec3::Y * eps), d(Vec3::Z * eps)) / (2.0 * eps)
            }
        }
    }

    /// ∂/∂(u, v) of the first channel (Mitsuba's `eval_1_grad`, the height a bump map reads):
    /// exact for bilinear bitmaps (the derivative of the bilinear patch, chained through
    /// `to_uv`), 0 for nearest-neighbour bitmaps, checkerboards and constants, central
    /// differences elsewhere.
    pub fn uv_gradient(&self, at: TexCoord) -> Vec2 {
        match self {
            Texture::Constant(_) | Texture::Checkerboard { .. } => Vec2::ZERO,
            Texture::Bitmap {
                image,
                filter,
                wrap,
                to_uv,
                corner_texels,
                mips: None,
            } => {
                if *filter == TextureFilter::Nearest {
                    return Vec2::ZERO;
                }
                let p = to_uv.transform_point2(at.uv);
                if !p.is_finite() {
                    return Vec2::ZERO;
                }
                let (w, h) = (image.width, image.height);
                let shift = if *corner_texels { 0.5 } else { 0.0 };
                let xs = p.x * w as f32 + shift - 0.5;
                let ys = p.y * h as f32 + shift - 0.5;
                let (x0, y0) = (xs.floor(), ys.floor());
                let (fx, fy) = (xs - x0, ys - y0);
                let (x0, y0) = (x0 as i64, y0 as i64);
                let px = |dx: i64, dy: i64| {
                    image
                        .get(wrap_index(x0 + dx, w, *wrap), wrap_index(y0 + dy, h, *wrap))
                        .x
                };
                let (f00, f10, f01, f11) = (px(0, 0), px(1, 0), px(0, 1), px(1, 1));
                let dfdx = ((1.0 - fy) * (f10 - f00) + fy * (f11 - f01)) * w as f32;
                let dfdy = ((1.0 - fx) * (f01 - f00) + fx * (f11 - f10)) * h as f32;
                let (c0, c1) = (to_uv.x_axis, to_uv.y_axis);
                Vec2::new(dfdx * c0.x + dfdy * c0.y, dfdx * c1.x + dfdy * c1.y)
            }
            _ => {
                let e = 1e-3;
                let f = |d: Vec2| {
                    self.eval(TexCoord {
                        uv: at.uv + d,
                        ..at
                    })
                    .x
                };
                Vec2::new(
                    f(Vec2::new(e, 0.0)) - f(Vec2::new(-e, 0.0)),
                    f(Vec2::new(0.0, e)) - f(Vec2::new(0.0, -e)),
                ) / (2.0 * e)
            }
        }
    }

    /// Whether a lookup's footprint changes the value (a MIP-filtered bitmap inside).
    pub fn uses_footprint(&self) -> bool {
        match self {
            Texture::Bitmap { mips, .. } => mips.is_some(),
            Texture::Affine { texture, .. } => texture.uses_footprint(),
            Texture::Product(t) => t.iter().any(Texture::uses_footprint),
            Texture::Mix(t) => t.iter().any(Texture::uses_footprint),
            Texture::Checker3D { textures, .. } | Texture::Dots { textures, .. } => {
                textures.iter().any(Texture::uses_footprint)
            }
            _ => false,
        }
    }

    /// One texel in uv, for textures made of texels.
    fn texel_size(&self) -> Option<Vec2> {
        match self {
            Texture::Bitmap { image, .. } => Some(Vec2::new(
                1.0 / image.width as f32,
                1.0 / image.height as f32,
            )),
            Texture::Affine { texture, .. } => texture.texel_size(),
            Texture::Product(t) => t.iter().find_map(Texture::texel_size),
            Texture::Mix(t) => t.iter().find_map(Texture::texel_size),
            _ => None,
        }
    }

    /// A finite-difference step small against a solid texture's features.
    fn solid_epsilon(&self) -> f32 {
        match self {
            Texture::Perlin { scale, .. } | Texture::SolidChecker { scale, .. } => {
                1e-3 / scale.abs().max(1e-6)
            }
            Texture::Affine { texture, .. } => texture.solid_epsilon(),
            // Features of about a unit in texture space.
            Texture::Checker3D { to_texture, .. } | Texture::Noise { to_texture, .. } => {
                let stretch = Mat3::from_mat4(*to_texture);
                let s = [stretch.x_axis, stretch.y_axis, stretch.z_axis]
                    .map(|c| c.length())
                    .into_iter()
                    .fold(0f32, f32::max);
                1e-3 / s.max(1e-6)
            }
            _ => 1e-3,
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
            Texture::Perlin { conversion, .. } => Vec3::splat(match conversion {
                NoiseConversion::Linear => 0.5,
                NoiseConversion::AbsVal => 0.25,
            }),
            Texture::SolidChecker { black, white, .. } => 0.5 * (*black + *white),
            Texture::Affine {
                texture,
                scale,
                offset,
            } => texture.mean() * *scale + *offset,
            // Means of products and mixes as if the parts were independent.
            Texture::Product(t) => t[0].mean() * t[1].mean(),
            Texture::Mix(t) => {
                let u = t[2].mean().x;
                t[0].mean() * (1.0 - u) + t[1].mean() * u
            }
            Texture::Bilerp { corners, .. } => corners.iter().copied().sum::<Vec3>() * 0.25,
            Texture::Checker3D { textures, .. } => 0.5 * (textures[0].mean() + textures[1].mean()),
            Texture::Noise { kind, .. } => noise::mean(*kind),
            // About a fifth of the plane is inside a dot (half the cells, π·0.35² each).
            Texture::Dots { textures, .. } => {
                let f = 0.5 * std::f32::consts::PI * 0.35 * 0.35;
                textures[0].mean() * f + textures[1].mean() * (1.0 - f)
            }
            Texture::Spectrum { rgb, .. } => *rgb,
        }
    }
}

/// pbrt-v4's noise textures: Perlin's improved noise (2002), its fractional Brownian motion
/// and turbulence sums, and the textures made of them. Without ray differentials every octave
/// is summed (pbrt-v4's behaviour for a point seen at zero footprint).
mod noise {
    use super::{NoiseKind, Vec3};

    /// Perlin's reference permutation of 0..255.
    const PERM: [u8; 256] = [
        151, 160, 137, 91, 90, 15, 131, 13, 201, 95, 96, 53, 194, 233, 7, 225, 140, 36, 103, 30,
        69, 142, 8, 99, 37, 240, 21, 10, 23, 190, 6, 148, 247, 120, 234, 75, 0, 26, 197, 62, 94,
        252, 219, 203, 117, 35, 11, 32, 57, 177, 33, 88, 237, 149, 56, 87, 174, 20, 125, 136, 171,
        168, 68, 175, 74, 165, 71, 134, 139, 48, 27, 166, 77, 146, 158, 231, 83, 111, 229, 122, 60,
        211, 133, 230, 220, 105, 92, 41, 55, 46, 245, 40, 244, 102, 143, 54, 65, 25, 63, 161, 1,
        216, 80, 73, 209, 76, 132, 187, 208, 89, 18, 169, 200, 196, 135, 130, 116, 188, 159, 86,
        164, 100, 109, 198, 173, 186, 3, 64, 52, 217, 226, 250, 124, 123, 5, 202, 38, 147, 118,
        126, 255, 82, 85, 212, 207, 206, 59, 227, 47, 16, 58, 17, 182, 189, 28, 42, 223, 183, 170,
        213, 119, 248, 152, 2, 44, 154, 163, 70, 221, 153, 101, 155, 167, 43, 172, 9, 129, 22, 39,
        253, 19, 98, 108, 110, 79, 113, 224, 232, 178, 185, 112, 104, 218, 246, 97, 228, 251, 34,
        242, 193, 238, 210, 144, 12, 191, 179, 162, 241, 81, 51, 145, 235, 249, 14, 239, 107, 49,
        192, 214, 31, 181, 199, 106, 157, 184, 84, 204, 176, 115, 121, 50, 45, 127, 4, 150, 254,
        138, 236, 205, 93, 222, 114, 67, 29, 24, 72, 243, 141, 128, 195, 78, 66, 215, 61, 156, 180,
    ];

    fn perm(i: usize) -> usize {
        PERM[i & 255] as usize
    }

    fn grad(x: usize, y: usize, z: usize, d: Vec3) -> f32 {
        let h = perm(perm(perm(x) + y) + z) & 15;
        let u = if h < 8 || h == 12 || h == 13 {
            d.x
        } else {
            d.y
        };
        let v = if h < 4 || h == 12 || h == 13 {
            d.y
        } else {
            d.z
        };
        (if h & 1 != 0 { -u } else { u }) + (if h & 2 != 0 { -v } else { v })
    }

    fn fade(t: f32) -> f32 {
        let t3 = t * t * t;
        t3 * (t * (6.0 * t - 15.0) + 10.0)
    }

    fn lerp(t: f32, a: f32, b: f32) -> f32 {
        (1.0 - t) * a + t * b
    }

    /// Improved noise in about [−1, 1]; 0 on the integer lattice.
    pub fn perlin(p: Vec3) -> f32 {
        let c = p.floor();
        let d = p - c;
        let (x, y, z) = (
            (c.x as i64 & 255) as usize,
            (c.y as i64 & 255) as usize,
            (c.z as i64 & 255) as usize,
        );
        let g = |i: usize, j: usize, k: usize| {
            grad(
                x + i,
                y + j,
                z + k,
                d - Vec3::new(i as f32, j as f32, k as f32),
            )
        };
        let (wx, wy, wz) = (fade(d.x), fade(d.y), fade(d.z));
        let x00 = lerp(wx, g(0, 0, 0), g(1, 0, 0));
        let x10 = lerp(wx, g(0, 1, 0), g(1, 1, 0));
        let x01 = lerp(wx, g(0, 0, 1), g(1, 0, 1));
        let x11 = lerp(wx, g(0, 1, 1), g(1, 1, 1));
        lerp(wz, lerp(wy, x00, x10), lerp(wy, x01, x11))
    }

    /// Σ ωⁱ·noise(1.99ⁱ p) over `octaves` octaves.
    pub fn fbm(p: Vec3, omega: f32, octaves: u32) -> f32 {
        let (mut sum, mut lambda, mut o) = (0.0, 1.0, 1.0);
        for _ in 0..octaves {
            sum += o * perlin(lambda * p);
            lambda *= 1.99;
            o *= omega;
        }
        sum
    }

    /// Σ ωⁱ·|noise(1.99ⁱ p)|, plus pbrt-v4's allowance of 0.2·ω^octaves for the octaves
    /// beyond the last.
    pub fn turbulence(p: Vec3, omega: f32, octaves: u32) -> f32 {
        let (mut sum, mut lambda, mut o) = (0.0, 1.0, 1.0);
        for _ in 0..octaves {
            sum += o * perlin(lambda * p).abs();
            lambda *= 1.99;
            o *= omega;
        }
        sum + o * 0.2
    }

    /// Whether `st` lies in one of pbrt-v4's polka dots: cells centred on the integer
    /// lattice, the ones where noise at the cell centre is positive hold a disk of radius
    /// 0.35 whose centre noise shifts by up to 0.15.
    pub fn in_dot(st: super::Vec2) -> bool {
        let (sc, tc) = ((st.x + 0.5).floor(), (st.y + 0.5).floor());
        let n = |x: f32, y: f32| perlin(Vec3::new(x, y, 0.5));
        if n(sc + 0.5, tc + 0.5) <= 0.0 {
            return false;
        }
        const RADIUS: f32 = 0.35;
        let shift = 0.5 - RADIUS;
        let centre = super::Vec2::new(
            sc + shift * n(sc + 1.5, tc + 2.8),
            tc + shift * n(sc + 4.5, tc + 9.8),
        );
        (st - centre).length_squared() < RADIUS * RADIUS
    }

    pub fn texture(kind: NoiseKind, p: Vec3) -> Vec3 {
        match kind {
            NoiseKind::Fbm { octaves, omega } => Vec3::splat(fbm(p, omega, octaves)),
            NoiseKind::Wrinkled { octaves, omega } => Vec3::splat(turbulence(p, omega, octaves)),
            NoiseKind::Windy => {
                let strength = fbm(0.1 * p, 0.5, 3);
                Vec3::splat(strength.abs() * fbm(p, 0.5, 6))
            }
            NoiseKind::Marble {
                octaves,
                omega,
                scale,
                variation,
            } => {
                let p = p * scale;
                let m = p.y + variation * fbm(p, omega, octaves);
                marble(0.5 + 0.5 * m.sin())
            }
        }
    }

    /// pbrt-v4's marble colour spline at t ∈ [0, 1]: cubic Bézier segments through its
    /// nine colours, times 1.5.
    fn marble(t: f32) -> Vec3 {
        const C: [[f32; 3]; 9] = [
            [0.58, 0.58, 0.6],
            [0.58, 0.58, 0.6],
            [0.58, 0.58, 0.6],
            [0.5, 0.5, 0.5],
            [0.6, 0.59, 0.58],
            [0.58, 0.58, 0.6],
            [0.58, 0.58, 0.6],
            [0.2, 0.2, 0.33],
            [0.58, 0.58, 0.6],
        ];
        let segments = C.len() - 3;
        let first = ((t * segments as f32).floor().max(0.0) as usize).min(segments - 1);
        let t = t * segments as f32 - first as f32;
        let cp = |i: usize| Vec3::from_array(C[first + i]);
        let (a, b, c) = (
            cp(0).lerp(cp(1), t),
            cp(1).lerp(cp(2), t),
            cp(2).lerp(cp(3), t),
        );
        let (d, e) = (a.lerp(b, t), b.lerp(c, t));
        1.5 * d.lerp(e, t)
    }

    /// Noise has mean 0; turbulence's and marble's means are rough values for power
    /// estimates.
    pub fn mean(kind: NoiseKind) -> Vec3 {
        match kind {
            NoiseKind::Fbm { .. } | NoiseKind::Windy => Vec3::ZERO,
            NoiseKind::Wrinkled { omega, .. } => Vec3::splat(0.25 / (1.0 - omega).max(0.1)),
            NoiseKind::Marble { .. } => Vec3::splat(0.85),
        }
    }

    #[cfg(test)]
    mod tests {
        use super::*;

        #[test]
        fn perlin_noise_vanishes_on_the_lattice_and_stays_bounded() {
            for p in [
                Vec3::ZERO,
                Vec3::new(3.0, -2.0, 7.0),
                Vec3::new(255.0, 256.0, -1.0),
            ] {
                assert_eq!(perlin(p), 0.0);
            }
            let mut max = 0f32;
            let mut sum = 0f64;
            let n = 100_000;
            for i in 0..n {
                let t = i as f32 * 0.0137;
                let p = Vec3::new(t.sin() * 40.0 + t, t * 0.37, (t * 1.3).cos() * 17.0);
                let v = perlin(p);
                max = max.max(v.abs());
                sum += v as f64;
            }
            assert!(max <= 1.1 && max > 0.5, "max |noise| {max}");
            assert!((sum / n as f64).abs() < 0.02, "mean {}", sum / n as f64);
        }

        /// Dots sit inside their cells (centre shift 0.15 + radius 0.35 = ½), about half the
        /// cells hold one, and a dot is the disk it should be.
        #[test]
        fn polka_dots_stay_in_their_cells() {
            let (mut inside, mut cells_with) = (0usize, 0usize);
            for cy in 0..40 {
                for cx in 0..40 {
                    let mut any = false;
                    for j in 0..10 {
                        for i in 0..10 {
                            let st = super::super::Vec2::new(
                                cx as f32 - 0.5 + (i as f32 + 0.5) / 10.0,
                                cy as f32 - 0.5 + (j as f32 + 0.5) / 10.0,
                            );
                            if in_dot(st) {
                                inside += 1;
                                any = true;
                            }
                        }
                    }
                    cells_with += usize::from(any);
                }
            }
            let cells = 1600.0;
            let with = cells_with as f64 / cells;
            assert!((0.3..0.7).contains(&with), "{with} of the cells hold a dot");
            // Each dot covers π·0.35² ≈ 0.385 of its cell.
            let per_dot = inside as f64 / (100.0 * cells_with as f64);
            assert!((per_dot - 0.385).abs() < 0.03, "{per_dot}");
        }

        #[test]
        fn marble_spline_ends_at_its_first_and_last_colours() {
            assert!((marble(0.0) - 1.5 * Vec3::new(0.58, 0.58, 0.6)).length() < 1e-5);
            assert!((marble(1.0) - 1.5 * Vec3::new(0.58, 0.58, 0.6)).length() < 1e-5);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A checkerboard of single texels, 0 and 1.
    fn texel_checker(w: u32, h: u32) -> Image {
        let mut img = Image::new(w, h);
        for y in 0..h {
            for x in 0..w {
                img.set(x, y, Vec3::splat(((x + y) % 2) as f32));
            }
        }
        img
    }

    #[test]
    fn mip_pyramid_keeps_the_mean_and_filters_by_footprint() {
        let m = MipMap::new(&texel_checker(64, 32), WrapMode::Repeat);
        assert_eq!(m.levels(), 7, "64×32 → … → 1×1");
        assert_eq!(m.levels[1].width, 32);
        for l in &m.levels[1..] {
            let mean = l.pixels.iter().copied().sum::<Vec3>() / l.pixels.len() as f32;
            assert!((mean.x - 0.5).abs() < 1e-5, "level mean {mean}");
        }
        let st = Vec2::new(0.3, 0.6);
        for filter in [TextureFilter::Trilinear, TextureFilter::Ewa] {
            // No footprint: the finest level, bilinearly.
            let v = m.filter(st, [Vec2::ZERO; 2], filter, WrapMode::Repeat);
            assert!((v - m.bilerp(0, st, WrapMode::Repeat)).length() < 1e-6);
            // A footprint of many texels: the average.
            let wide = [Vec2::new(0.2, 0.0), Vec2::new(0.0, 0.2)];
            let v = m.filter(st, wide, filter, WrapMode::Repeat);
            assert!((v.x - 0.5).abs() < 0.02, "{filter:?}: {v}");
            // Wider than the image: the one top texel.
            let v = m.filter(
                st,
                [Vec2::splat(4.0), Vec2::splat(4.0)],
                filter,
                WrapMode::Repeat,
            );
            assert!((v.x - 0.5).abs() < 1e-5, "{filter:?}: {v}");
        }
        // EWA keeps detail along the short axis of a thin footprint: across the stripes of
        // an image constant along y, a footprint long in y and short in x still resolves x.
        let mut stripes = Image::new(64, 64);
        for y in 0..64 {
            for x in 0..64 {
                stripes.set(x, y, Vec3::splat(if (x / 8) % 2 == 0 { 1.0 } else { 0.0 }));
            }
        }
        let m = MipMap::new(&stripes, WrapMode::Repeat);
        let thin = [Vec2::new(0.0, 0.1), Vec2::new(0.002, 0.0)];
        let bright = m.filter(
            Vec2::new(4.0 / 64.0, 0.5),
            thin,
            TextureFilter::Ewa,
            WrapMode::Repeat,
        );
        let dark = m.filter(
            Vec2::new(12.0 / 64.0, 0.5),
            thin,
            TextureFilter::Ewa,
            WrapMode::Repeat,
        );
        assert!(bright.x > 0.9 && dark.x < 0.1, "EWA: {bright} / {dark}");
        let tri = m.filter(
            Vec2::new(4.0 / 64.0, 0.5),
            thin,
            TextureFilter::Trilinear,
            WrapMode::Repeat,
        );
        assert!(tri.x < 0.75, "trilinear blurs by the long axis: {tri}");
    }

    #[test]
    fn pbrt_texture_combinations() {
        let c = |v: f32| Texture::Constant(Vec3::splat(v));
        let at = TexCoord::at(Vec2::new(0.25, 0.75), Vec3::new(0.5, 1.5, -0.5));
        assert_eq!(
            Texture::Product(Box::new([c(0.5), c(0.4)])).eval(at),
            Vec3::splat(0.2)
        );
        let mix = Texture::Mix(Box::new([c(1.0), c(3.0), c(0.25)]));
        assert_eq!(mix.eval(at), Vec3::splat(1.5));
        let bilerp = Texture::Bilerp {
            corners: [Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE],
            to_uv: Mat3::IDENTITY,
        };
        // (1−u)(1−v)·X + u(1−v)·Y + (1−u)v·Z + uv·1 at u = ¼, v = ¾.
        let want = Vec3::new(0.1875 + 0.1875, 0.0625 + 0.1875, 0.5625 + 0.1875);
        assert!((bilerp.eval(at) - want).length() < 1e-6);
        let checker = Texture::Checker3D {
            textures: Box::new([c(0.0), c(1.0)]),
            to_texture: Mat4::IDENTITY,
        };
        // ⌊0.5⌋ + ⌊1.5⌋ + ⌊−0.5⌋ = 0 + 1 − 1 = 0: even.
        assert_eq!(checker.eval(at), Vec3::ZERO);
        let moved = TexCoord {
            p: at.p + Vec3::X,
            ..at
        };
        assert_eq!(checker.eval(moved), Vec3::ONE);
    }

    /// The noise is the course's formula: an independent, literal f64 evaluation of
    /// Σ G(i,j,k)·v f(vx) f(vy) f(vz) over the eight lattice points at a list of points, and
    /// one value worked by hand: at (0.5, 0, 0) only (0,0,0) and (1,0,0) weigh (f(±½) = ½,
    /// f(0) = 1, f(±1) = 0), with G(0,0,0) = G[P[P[P[0]]]] = G[14] = (0,−1,1) and G(1,0,0) =
    /// G[P[1 + P[P[0]]]] = G[P[3]] = G[1] = (−1,1,0): n = ½·(0·½) + ½·(−1·−½) = 0.25.
    #[test]
    fn perlin_is_the_course_formula() {
        assert!((perlin(Vec3::new(0.5, 0.0, 0.0)) - 0.25).abs() < 1e-6);
        let literal = |x: f64, y: f64, z: f64| -> f64 {
            let f = |t: f64| {
                let a = t.abs();
                -6.0 * a.powi(5) + 15.0 * a.powi(4) - 10.0 * a.powi(3) + 1.0
            };
            let m = |v: i64| v.rem_euclid(16) as usize;
            let mut sum = 0.0;
            for i in [x.floor() as i64, x.floor() as i64 + 1] {
                for j in [y.floor() as i64, y.floor() as i64 + 1] {
                    for k in [z.floor() as i64, z.floor() as i64 + 1] {
                        let idx =
                            PERMUTATION[m(i + PERMUTATION[m(j + PERMUTATION[m(k)] as i64)] as i64)];
                        let g = GRADIENTS[idx];
                        let v = [x - i as f64, y - j as f64, z - k as f64];
                        let dot = g[0] as f64 * v[0] + g[1] as f64 * v[1] + g[2] as f64 * v[2];
                        sum += dot * f(v[0]) * f(v[1]) * f(v[2]);
                    }
                }
            }
            sum
        };
        let mut rng = crate::stats::Pcg32::new(17, 3);
        let mut points = vec![(0.25, 0.5, 0.75), (-3.3, 7.1, -0.2), (15.9, -16.1, 31.5)];
        for _ in 0..200 {
            let mut c = || (rng.next_f32() as f64 - 0.5) * 40.0;
            points.push((c(), c(), c()));
        }
        for (x, y, z) in points {
            let ours = perlin(Vec3::new(x as f32, y as f32, z as f32)) as f64;
            let theirs = literal(x as f32 as f64, y as f32 as f64, z as f32 as f64);
            assert!(
                (ours - theirs).abs() < 1e-5,
                "({x}, {y}, {z}): {ours} vs {theirs}"
            );
            assert!(ours.abs() <= 1.0);
        }
        // Zero on the lattice; the conversions map into [0, 1].
        assert_eq!(perlin(Vec3::new(3.0, -2.0, 5.0)), 0.0);
        let patch = Texture::Perlin {
            scale: 1.0,
            conversion: NoiseConversion::Linear,
        };
        let vein = Texture::Perlin {
            scale: 1.0,
            conversion: NoiseConversion::AbsVal,
        };
        let at = TexCoord::at(Vec2::ZERO, Vec3::new(0.5, 0.0, 0.0));
        assert!((patch.eval(at).x - 0.625).abs() < 1e-6);
        assert!((vein.eval(at).x - 0.25).abs() < 1e-6);
    }

    /// The solid gradient used for bump mapping is the derivative of the height: compared
    /// with a wide central difference of the literal noise.
    #[test]
    fn perlin_height_gradient_is_its_derivative() {
        let t = Texture::Perlin {
            scale: 2.0,
            conversion: NoiseConversion::Linear,
        };
        let p = Vec3::new(0.37, -1.21, 2.03);
        let g = t.height_gradient(TexCoord::at(Vec2::ZERO, p), Vec3::X, Vec3::Y);
        let h = 1e-2;
        for axis in [Vec3::X, Vec3::Y, Vec3::Z] {
            let d =
                (0.5 * (perlin((p + axis * h) * 2.0) - perlin((p - axis * h) * 2.0))) / (2.0 * h);
            assert!(
                (g.dot(axis) - d).abs() < 0.02 * d.abs().max(0.1),
                "{g} vs {d}"
            );
        }
    }

    #[test]
    fn corner_texels_round_to_the_nearest() {
        let mut img = Image::new(4, 1);
        for i in 0..4 {
            img.set(i, 0, Vec3::splat(i as f32));
        }
        let t = Texture::Bitmap {
            image: Arc::new(img),
            filter: TextureFilter::Nearest,
            wrap: WrapMode::Repeat,
            to_uv: Mat3::IDENTITY,
            corner_texels: true,
            mips: None,
        };
        // u·w = 1.4 → texel 1; 1.6 → texel 2; 3.6 → 4 wraps to 0.
        let at = |u: f32| t.eval(TexCoord::uv(Vec2::new(u / 4.0, 0.0))).x;
        assert_eq!((at(1.4), at(1.6), at(3.6)), (1.0, 2.0, 0.0));
    }

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
        assert_eq!(t.eval(TexCoord::uv(Vec2::new(0.25, 0.25))), Vec3::ZERO);
        assert_eq!(t.eval(TexCoord::uv(Vec2::new(0.75, 0.75))), Vec3::ZERO);
        assert_eq!(t.eval(TexCoord::uv(Vec2::new(0.75, 0.25))), Vec3::ONE);
        assert_eq!(t.eval(TexCoord::uv(Vec2::new(1.25, 0.75))), Vec3::ONE);
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
            corner_texels: false,
            mips: None,
        };
        assert!(
            (t.eval(TexCoord::uv(Vec2::new(0.25, 0.25))) - Vec3::new(1.0, 0.0, 0.0)).length()
                < 1e-6
        );
        assert!((t.eval(TexCoord::uv(Vec2::new(0.75, 0.75))) - Vec3::ONE).length() < 1e-6);
        let mid = t.eval(TexCoord::uv(Vec2::new(0.5, 0.5)));
        assert!((mid - Vec3::splat(0.5)).length() < 1e-6);
    }
}
