//! RGB → spectrum upsampling (Jakob & Hanika 2019, "A Low-Dimensional Function Space for
//! Efficient Spectral Upsampling"), in pbrt-v4's arrangement.
//!
//! An RGB colour becomes the smooth spectrum s(λ) = S(c₀λ² + c₁λ + c₂) (λ in nm), with the
//! sigmoid S(x) = ½ + x / (2√(1 + x²)), whose values lie in (0, 1). The coefficients come from a
//! precomputed [`RgbToSpectrumTable`]: for each colour of a grid, the coefficients whose
//! reflectance, lit by the colour space's illuminant (D65 for sRGB) and seen by the CIE 1931
//! observer, has that colour. The table is computed by our own optimiser,
//! `crates/tools` (`cargo run -p penumbra-tools --release -- rgb2spec`), and checked in
//! (`srgb_to_spectrum.bin`; its size, resolution and generation time are in `mod.rs`).
//!
//! Table layout (pbrt-v4's): an RGB colour is indexed by the index `m` of its largest channel,
//! that channel's value z = rgb[m] and the two ratios x = rgb[(m+1) % 3]/z, y = rgb[(m+2) % 3]/z,
//! both in [0, 1]. x and y are on a uniform grid of `res` nodes; z on the nodes
//! [`z_node`]`(k) = smoothstep(smoothstep(k/(res − 1)))`, denser near 0 and 1 where the
//! coefficients change fastest. A lookup interpolates the coefficients trilinearly in
//! (x, y, z) within the table of `m`. Greys (r = g = b) bypass the table: the constant spectrum
//! S(c₂) = v has c₂ = (v − ½)/√(v(1 − v)).
//!
//! The three spectra, as pbrt-v4's:
//! - [`RgbAlbedoSpectrum`]: a reflectance, rgb ∈ [0, 1]³; values in [0, 1].
//! - [`RgbUnboundedSpectrum`]: any non-negative rgb, as scale·s(λ) with scale = 2·max(rgb) and
//!   s looked up for rgb/scale (largest channel ½, well inside the table).
//! - [`RgbIlluminantSpectrum`]: an emission, the unbounded spectrum times the colour space's
//!   illuminant (D65 of unit luminance), so that its XYZ (`SampledSpectrum::to_xyz`) is the
//!   colour's.
//!
//! Binary format of a table (little-endian): the 8 bytes `RGB2SPEC`, u32 version (1), u32 `res`,
//! `res` f32 z nodes, then 3·res³ coefficient triples (c₀, c₁, c₂) as f32, indexed
//! [m][z][y][x].

use super::cie;
use super::sampled::{SampledSpectrum, SampledWavelengths, Spectrum};
use crate::math::{Vec3, Vec4};
use std::cell::Cell;
use std::sync::OnceLock;

/// S(x) = ½ + x / (2√(1 + x²)): the sigmoid of Jakob & Hanika, 0 and 1 at ∓∞.
#[inline]
pub fn sigmoid(x: f32) -> f32 {
    if x.abs() > 1e15 {
        // ±∞ (and values whose square overflows): the limits.
        return if x > 0.0 { 1.0 } else { 0.0 };
    }
    0.5 + x / (2.0 * (1.0 + x * x).sqrt())
}

/// s(λ) = S(c₀λ² + c₁λ + c₂), λ in nm.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RgbSigmoidPolynomial {
    pub c0: f32,
    pub c1: f32,
    pub c2: f32,
}

impl RgbSigmoidPolynomial {
    #[inline]
    pub fn eval(&self, lambda: f32) -> f32 {
        sigmoid((self.c0 * lambda + self.c1) * lambda + self.c2)
    }

    /// [`Self::eval`] at four wavelengths at once (the same operations per lane, so the same
    /// values bit for bit; one vector square root and division instead of four dependent
    /// scalar ones, which were most of the time spectral mode spends on parameters).
    #[inline]
    pub fn eval4(&self, lambda: Vec4) -> Vec4 {
        let x = (self.c0 * lambda + Vec4::splat(self.c1)) * lambda + Vec4::splat(self.c2);
        let s = Vec4::splat(0.5) + x / (2.0 * (Vec4::ONE + x * x).sqrt());
        let step = Vec4::select(x.cmpgt(Vec4::ZERO), Vec4::ONE, Vec4::ZERO);
        Vec4::select(x.abs().cmpgt(Vec4::splat(1e15)), step, s)
    }

    /// The largest value over [360, 830] nm: at an end or at the parabola's vertex.
    pub fn max_value(&self) -> f32 {
        let mut m = self.eval(cie::LAMBDA_MIN).max(self.eval(cie::LAMBDA_MAX));
        if self.c0 != 0.0 {
            let vertex = -self.c1 / (2.0 * self.c0);
            if (cie::LAMBDA_MIN..=cie::LAMBDA_MAX).contains(&vertex) {
                m = m.max(self.eval(vertex));
            }
        }
        m
    }
}

/// Version of the binary table format.
pub const TABLE_FORMAT_VERSION: u32 = 1;
const MAGIC: &[u8; 8] = b"RGB2SPEC";

/// smoothstep(t) = t²(3 − 2t).
fn smoothstep(t: f64) -> f64 {
    t * t * (3.0 - 2.0 * t)
}

/// The `k`-th of `res` z nodes of the table layout: smoothstep(smoothstep(k/(res − 1))).
pub fn z_node(k: usize, res: usize) -> f64 {
    smoothstep(smoothstep(k as f64 / (res - 1) as f64))
}

/// Why a table could not be read.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum TableError {
    #[error("not an RGB-to-spectrum table (bad magic)")]
    Magic,
    #[error("table format version {0}, expected {TABLE_FORMAT_VERSION}")]
    Version(u32),
    #[error("table resolution {0} is out of range (2..=256)")]
    Resolution(u32),
    #[error("table is {got} bytes, expected {expected}")]
    Size { got: usize, expected: usize },
    #[error("table z nodes are not increasing from 0 to 1")]
    Nodes,
}

const MEMO_BITS: u32 = 6;

/// An entry of [`RgbToSpectrumTable::lookup_memo`]'s memo (`table` 0: empty; a table is
/// never at address 0).
#[derive(Clone, Copy)]
struct MemoEntry {
    table: usize,
    key: [u32; 3],
    poly: RgbSigmoidPolynomial,
}

const EMPTY: MemoEntry = MemoEntry {
    table: 0,
    key: [0; 3],
    poly: RgbSigmoidPolynomial {
        c0: 0.0,
        c1: 0.0,
        c2: 0.0,
    },
};

thread_local! {
    static MEMO: [Cell<MemoEntry>; 1 << MEMO_BITS] = const { [const { Cell::new(EMPTY) }; 1 << MEMO_BITS] };
}

/// Coefficients of s(λ) for every colour of a grid, in pbrt-v4's layout (see the module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct RgbToSpectrumTable {
    res: usize,
    z_nodes: Vec<f32>,
    /// [m][z][y][x] → (c₀, c₁, c₂).
    coeffs: Vec<[f32; 3]>,
}

impl RgbToSpectrumTable {
    /// A table of resolution `res` from its z nodes and 3·res³ coefficient triples ([m][z][y][x]).
    pub fn new(
        res: usize,
        z_nodes: Vec<f32>,
        coeffs: Vec<[f32; 3]>,
    ) -> Result<RgbToSpectrumTable, TableError> {
        if !(2..=256).contains(&res) {
            return Err(TableError::Resolution(res as u32));
        }
        if z_nodes.len() != res
            || z_nodes[0] != 0.0
            || z_nodes[res - 1] != 1.0
            || z_nodes.windows(2).any(|w| w[0] >= w[1])
        {
            return Err(TableError::Nodes);
        }
        if coeffs.len() != 3 * res * res * res {
            return Err(TableError::Size {
                got: coeffs.len(),
                expected: 3 * res * res * res,
            });
        }
        Ok(RgbToSpectrumTable {
            res,
            z_nodes,
            coeffs,
        })
    }

    /// Reads the binary format of the module docs.
    pub fn from_bytes(bytes: &[u8]) -> Result<RgbToSpectrumTable, TableError> {
        if bytes.len() < 16 || &bytes[..8] != MAGIC {
            return Err(TableError::Magic);
        }
        let u32_at = |o: usize| u32::from_le_bytes(bytes[o..o + 4].try_into().unwrap());
        let version = u32_at(8);
        if version != TABLE_FORMAT_VERSION {
            return Err(TableError::Version(version));
        }
        let res32 = u32_at(12);
        if !(2..=256).contains(&res32) {
            return Err(TableError::Resolution(res32));
        }
        let res = res32 as usize;
        let expected = 16 + 4 * res + 36 * res * res * res;
        if bytes.len() != expected {
            return Err(TableError::Size {
                got: bytes.len(),
                expected,
            });
        }
        let floats: Vec<f32> = bytes[16..]
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        let z_nodes = floats[..res].to_vec();
        let coeffs = floats[res..]
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        RgbToSpectrumTable::new(res, z_nodes, coeffs)
    }

    /// The binary format of the module docs.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(16 + 4 * self.res + 12 * self.coeffs.len());
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&TABLE_FORMAT_VERSION.to_le_bytes());
        out.extend_from_slice(&(self.res as u32).to_le_bytes());
        for z in &self.z_nodes {
            out.extend_from_slice(&z.to_le_bytes());
        }
        for c in self.coeffs.iter().flatten() {
            out.extend_from_slice(&c.to_le_bytes());
        }
        out
    }

    /// The checked-in table for linear sRGB under D65.
    pub fn srgb() -> &'static RgbToSpectrumTable {
        static TABLE: OnceLock<RgbToSpectrumTable> = OnceLock::new();
        TABLE.get_or_init(|| {
            RgbToSpectrumTable::from_bytes(include_bytes!("srgb_to_spectrum.bin"))
                .expect("the checked-in sRGB table is valid")
        })
    }

    pub fn res(&self) -> usize {
        self.res
    }

    pub fn z_nodes(&self) -> &[f32] {
        &self.z_nodes
    }

    /// Index of the coefficients of node (m, z, y, x).
    #[inline]
    pub fn index(res: usize, m: usize, zi: usize, yi: usize, xi: usize) -> usize {
        ((m * res + zi) * res + yi) * res + xi
    }

    /// The coefficients at node (m, z, y, x).
    #[inline]
    pub fn node(&self, m: usize, zi: usize, yi: usize, xi: usize) -> [f32; 3] {
        self.coeffs[Self::index(self.res, m, zi, yi, xi)]
    }

    /// [`Self::lookup`] through a small per-thread memo (direct-mapped, 64 entries, keyed by
    /// the table and the colour's bits). A path upsamples the same few constant colours at
    /// every vertex; the lookup (a search over the z nodes and a trilinear interpolation of
    /// 24 coefficients) cost a quarter of the spectral render time of bench-cbox, the memo
    /// hit a few nanoseconds. Same result bit for bit.
    #[inline]
    pub fn lookup_memo(&self, rgb: Vec3) -> RgbSigmoidPolynomial {
        let key = [rgb.x.to_bits(), rgb.y.to_bits(), rgb.z.to_bits()];
        let table = self as *const RgbToSpectrumTable as usize;
        let h = (key[0].wrapping_mul(0x9E37_79B1) ^ key[1].wrapping_mul(0x85EB_CA77))
            .wrapping_add(key[2].wrapping_mul(0xC2B2_AE3D));
        let slot = (h >> (32 - MEMO_BITS)) as usize;
        MEMO.with(|memo| {
            let e = memo[slot].get();
            if e.table == table && e.key == key {
                return e.poly;
            }
            let poly = self.lookup(rgb);
            memo[slot].set(MemoEntry { table, key, poly });
            poly
        })
    }

    /// The sigmoid polynomial of `rgb` (each channel in [0, 1]).
    pub fn lookup(&self, rgb: Vec3) -> RgbSigmoidPolynomial {
        let rgb = rgb.clamp(Vec3::ZERO, Vec3::ONE);
        if rgb.x == rgb.y && rgb.y == rgb.z {
            let v = rgb.x;
            return RgbSigmoidPolynomial {
                c0: 0.0,
                c1: 0.0,
                c2: (v - 0.5) / (v * (1.0 - v)).sqrt(),
            };
        }
        let m = if rgb.x > rgb.y {
            if rgb.x > rgb.z { 0 } else { 2 }
        } else if rgb.y > rgb.z {
            1
        } else {
            2
        };
        let z = rgb[m];
        let res = self.res;
        // Ratios first: (res − 1)/z would overflow for a subnormal z.
        let x = rgb[(m + 1) % 3] / z * (res - 1) as f32;
        let y = rgb[(m + 2) % 3] / z * (res - 1) as f32;
        let xi = (x as usize).min(res - 2);
        let yi = (y as usize).min(res - 2);
        // The last node at or below z, kept in 0..=res − 2.
        let zi = (self.z_nodes.partition_point(|&n| n <= z).max(1) - 1).min(res - 2);
        let dx = x - xi as f32;
        let dy = y - yi as f32;
        let dz = (z - self.z_nodes[zi]) / (self.z_nodes[zi + 1] - self.z_nodes[zi]);
        let mut c = [0.0f32; 3];
        for (k, ck) in c.iter_mut().enumerate() {
            let at = |zo: usize, yo: usize, xo: usize| self.node(m, zi + zo, yi + yo, xi + xo)[k];
            let lerp = |t: f32, a: f32, b: f32| a + (b - a) * t;
            *ck = lerp(
                dz,
                lerp(
                    dy,
                    lerp(dx, at(0, 0, 0), at(0, 0, 1)),
                    lerp(dx, at(0, 1, 0), at(0, 1, 1)),
                ),
                lerp(
                    dy,
                    lerp(dx, at(1, 0, 0), at(1, 0, 1)),
                    lerp(dx, at(1, 1, 0), at(1, 1, 1)),
                ),
            );
        }
        RgbSigmoidPolynomial {
            c0: c[0],
            c1: c[1],
            c2: c[2],
        }
    }
}

/// A reflectance (or transmittance) given as linear sRGB in [0, 1]³: values in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RgbAlbedoSpectrum {
    rsp: RgbSigmoidPolynomial,
}

impl RgbAlbedoSpectrum {
    /// `rgb` is clamped to [0, 1]³.
    pub fn new(table: &RgbToSpectrumTable, rgb: Vec3) -> RgbAlbedoSpectrum {
        RgbAlbedoSpectrum {
            rsp: table.lookup_memo(rgb),
        }
    }

    pub fn polynomial(&self) -> RgbSigmoidPolynomial {
        self.rsp
    }

    pub fn max_value(&self) -> f32 {
        self.rsp.max_value()
    }
}

impl Spectrum for RgbAlbedoSpectrum {
    #[inline]
    fn eval(&self, lambda: f32) -> f32 {
        self.rsp.eval(lambda)
    }
    #[inline]
    fn sample(&self, wavelengths: &SampledWavelengths) -> SampledSpectrum {
        SampledSpectrum::from_vec4(self.rsp.eval4(wavelengths.lambda4()))
    }
}

/// scale·s(λ) for `rgb` ≥ 0 of any size (σ of media, unbounded parameters).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RgbUnboundedSpectrum {
    scale: f32,
    rsp: RgbSigmoidPolynomial,
}

impl RgbUnboundedSpectrum {
    /// scale = 2·max(rgb), s looked up for rgb/scale; negative channels count as 0.
    pub fn new(table: &RgbToSpectrumTable, rgb: Vec3) -> RgbUnboundedSpectrum {
        let rgb = rgb.max(Vec3::ZERO);
        let m = rgb.max_element();
        let scale = 2.0 * m;
        let rsp = table.lookup_memo(if scale > 0.0 { rgb / scale } else { Vec3::ZERO });
        RgbUnboundedSpectrum { scale, rsp }
    }

    pub fn scale(&self) -> f32 {
        self.scale
    }

    pub fn polynomial(&self) -> RgbSigmoidPolynomial {
        self.rsp
    }

    pub fn max_value(&self) -> f32 {
        self.scale * self.rsp.max_value()
    }
}

impl Spectrum for RgbUnboundedSpectrum {
    #[inline]
    fn eval(&self, lambda: f32) -> f32 {
        self.scale * self.rsp.eval(lambda)
    }
    #[inline]
    fn sample(&self, wavelengths: &SampledWavelengths) -> SampledSpectrum {
        SampledSpectrum::from_vec4(self.scale * self.rsp.eval4(wavelengths.lambda4()))
    }
}

/// An emission given as linear sRGB ≥ 0: [`RgbUnboundedSpectrum`] times D65 of unit luminance,
/// so that its XYZ is the colour's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RgbIlluminantSpectrum {
    unbounded: RgbUnboundedSpectrum,
}

impl RgbIlluminantSpectrum {
    pub fn new(table: &RgbToSpectrumTable, rgb: Vec3) -> RgbIlluminantSpectrum {
        RgbIlluminantSpectrum {
            unbounded: RgbUnboundedSpectrum::new(table, rgb),
        }
    }

    pub fn scale(&self) -> f32 {
        self.unbounded.scale
    }

    pub fn polynomial(&self) -> RgbSigmoidPolynomial {
        self.unbounded.rsp
    }
}

impl Spectrum for RgbIlluminantSpectrum {
    #[inline]
    fn eval(&self, lambda: f32) -> f32 {
        self.unbounded.eval(lambda) * cie::d65_unit_y(lambda)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn memo_returns_the_lookup() {
        // More colours than memo slots, twice over, from two tables: every answer is the
        // table's own lookup, bit for bit (evictions and collisions included).
        let srgb = RgbToSpectrumTable::srgb();
        let tiny = tiny_table();
        for pass in 0..2 {
            for k in 0..300u32 {
                let c = Vec3::new(
                    (k % 7) as f32 / 6.0,
                    (k % 11) as f32 / 10.0,
                    ((k * 13 + pass) % 17) as f32 / 16.0,
                );
                assert_eq!(srgb.lookup_memo(c), srgb.lookup(c));
                assert_eq!(tiny.lookup_memo(c), tiny.lookup(c));
            }
        }
    }

    #[test]
    fn sigmoid_limits_and_inverse() {
        assert_eq!(sigmoid(0.0), 0.5);
        assert_eq!(sigmoid(f32::INFINITY), 1.0);
        assert_eq!(sigmoid(f32::NEG_INFINITY), 0.0);
        assert_eq!(sigmoid(1e30), 1.0);
        for v in [0.01f32, 0.2, 0.5, 0.77, 0.99] {
            let c2 = (v - 0.5) / (v * (1.0 - v)).sqrt();
            assert!((sigmoid(c2) - v).abs() < 1e-6);
        }
        let p = RgbSigmoidPolynomial {
            c0: -1e-4,
            c1: 0.11,
            c2: -30.0,
        };
        // Vertex at 550 nm.
        assert_eq!(p.max_value(), p.eval(550.0));
    }

    /// The 4-wide evaluation is the scalar one bit for bit, the limits included.
    #[test]
    fn eval4_is_eval_per_lane() {
        let table = RgbToSpectrumTable::srgb();
        let lambdas = Vec4::new(361.5, 471.25, 559.0, 829.9);
        let mut polys = vec![
            RgbSigmoidPolynomial {
                c0: 1e30,
                c1: 0.0,
                c2: 0.0,
            },
            RgbSigmoidPolynomial {
                c0: -1e30,
                c1: 0.0,
                c2: 0.0,
            },
            RgbSigmoidPolynomial {
                c0: 0.0,
                c1: 0.0,
                c2: f32::INFINITY,
            },
            RgbSigmoidPolynomial {
                c0: 0.0,
                c1: 0.0,
                c2: f32::NEG_INFINITY,
            },
        ];
        for k in 0..512u32 {
            let c = Vec3::new(
                (k % 8) as f32 / 7.0,
                (k / 8 % 8) as f32 / 7.0,
                (k / 64) as f32 / 7.0,
            );
            polys.push(table.lookup(c));
        }
        for p in polys {
            let v = p.eval4(lambdas);
            for i in 0..4 {
                assert_eq!(
                    v[i].to_bits(),
                    p.eval(lambdas[i]).to_bits(),
                    "{p:?} at {}",
                    lambdas[i]
                );
            }
        }
    }

    fn tiny_table() -> RgbToSpectrumTable {
        let res = 3;
        let z_nodes = (0..res).map(|k| z_node(k, res) as f32).collect();
        let coeffs = (0..3 * res * res * res)
            .map(|i| [i as f32, -(i as f32), 0.5 * i as f32])
            .collect();
        RgbToSpectrumTable::new(res, z_nodes, coeffs).unwrap()
    }

    #[test]
    fn binary_format_round_trips_and_rejects_bad_input() {
        let t = tiny_table();
        let bytes = t.to_bytes();
        assert_eq!(bytes.len(), 16 + 4 * 3 + 36 * 27);
        assert_eq!(RgbToSpectrumTable::from_bytes(&bytes).unwrap(), t);
        assert_eq!(
            RgbToSpectrumTable::from_bytes(b"nonsense........"),
            Err(TableError::Magic)
        );
        let mut v = bytes.clone();
        v[8] = 9;
        assert_eq!(
            RgbToSpectrumTable::from_bytes(&v),
            Err(TableError::Version(9))
        );
        assert!(matches!(
            RgbToSpectrumTable::from_bytes(&bytes[..bytes.len() - 4]),
            Err(TableError::Size { .. })
        ));
        let mut v = bytes.clone();
        v[12..16].copy_from_slice(&100_000u32.to_le_bytes());
        assert_eq!(
            RgbToSpectrumTable::from_bytes(&v),
            Err(TableError::Resolution(100_000))
        );
    }

    #[test]
    fn lookup_interpolates_in_the_layout() {
        let t = tiny_table();
        // (0.2, 1.0, 0.5): m = 1 (green), z = 1 → the last z interval, x = b/g·2 = 1.0,
        // y = r/g·2 = 0.4.
        let p = t.lookup(Vec3::new(0.2, 1.0, 0.5));
        let at = |zi, yi, xi| t.node(1, zi, yi, xi)[0];
        let expect = at(2, 0, 1) + (at(2, 1, 1) - at(2, 0, 1)) * 0.4;
        assert!((p.c0 - expect).abs() < 1e-4, "{} vs {expect}", p.c0);
        // At a node exactly.
        let p = t.lookup(Vec3::new(1.0, 0.5, 0.0));
        assert_eq!(p.c0, t.node(0, 2, 0, 1)[0]);
        // Greys bypass the table.
        let g = t.lookup(Vec3::splat(0.25));
        assert_eq!((g.c0, g.c1), (0.0, 0.0));
        assert!((sigmoid(g.c2) - 0.25).abs() < 1e-6);
        assert_eq!(t.lookup(Vec3::ZERO).eval(500.0), 0.0);
        let tiny = t.lookup(Vec3::new(1e-45, 0.0, 0.0));
        assert!(tiny.c0.is_finite() && tiny.c1.is_finite() && tiny.c2.is_finite());
        assert_eq!(t.lookup(Vec3::ONE).eval(500.0), 1.0);
    }

    #[test]
    fn srgb_spectra_are_in_range_and_white_is_d65() {
        let t = RgbToSpectrumTable::srgb();
        for rgb in [
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(0.9, 0.8, 0.1),
            Vec3::new(0.02, 0.5, 0.3),
        ] {
            let a = RgbAlbedoSpectrum::new(t, rgb);
            for l in (360..=830).step_by(10) {
                let v = a.eval(l as f32);
                assert!((0.0..=1.0).contains(&v), "{rgb:?} at {l} nm: {v}");
                assert!(v <= a.max_value() + 1e-6);
            }
            let u = RgbUnboundedSpectrum::new(t, rgb * 7.0);
            assert_eq!(u.scale(), 2.0 * 7.0 * rgb.max_element());
        }
        let w = RgbIlluminantSpectrum::new(t, Vec3::ONE);
        for l in [380.0, 555.0, 700.0] {
            assert!((w.eval(l) - cie::d65_unit_y(l)).abs() < 1e-6);
        }
        assert_eq!(RgbUnboundedSpectrum::new(t, Vec3::ZERO).eval(500.0), 0.0);
    }

    #[test]
    fn checked_in_srgb_table_loads() {
        let t = RgbToSpectrumTable::srgb();
        assert!(t.res() >= 16);
        assert_eq!(t.z_nodes()[0], 0.0);
        assert_eq!(*t.z_nodes().last().unwrap(), 1.0);
        for (k, &z) in t.z_nodes().iter().enumerate() {
            assert_eq!(z, z_node(k, t.res()) as f32);
        }
    }
}
