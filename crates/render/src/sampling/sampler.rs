//! Per-pixel sample generators.
//!
//! A [`Sampler`] produces, for sample `index` of pixel `pixel`, a stream of uniform numbers in
//! `[0, 1)` indexed by a *dimension* counter that [`Sampler::next_1d`] advances by 1 and
//! [`Sampler::next_2d`] by 2 (a 2D draw at dimension d is not the same as two 1D draws: use the
//! same call pattern for the same purpose). Every value is a pure function of
//! `(seed, pixel, index, dimension)` (and, for the stratified sampler, `spp`): there is no
//! hidden state carried from one pixel sample to the next, so the image does not depend on the
//! thread count or the tile order, progressive passes can resume, and a render split across
//! machines by sample index merges exactly.
//!
//! Kinds (`base::SamplerKind`):
//! - **Independent**: a counter-based generator: dimension `d` of a sample is SplitMix64's
//!   output for the state `key + (d + 1)·γ`, `key = hash(seed, pixel, index)`.
//! - **Stratified**: 1D draws are jittered strata `(π(index) + ξ)/spp` with a per-(pixel,
//!   dimension) hashed permutation `π` (Kensler 2013's cycle-walking hash permutation); 2D draws
//!   are multi-jittered points (Chiu, Shirley, Wang 1994) on an `m × n = spp` grid with `m, n`
//!   the divisor pair of `spp` closest to square (a Latin hypercube in both axes and stratified
//!   on the grid), again with a per-(pixel, dimension) permutation of the sample index so the
//!   dimensions are decorrelated. The sub-strata are shuffled independently per row/column:
//!   Kensler's *correlated* variant (one shuffle shared by all rows) measured an O(N^-1.5)
//!   variance on a smooth non-separable integrand instead of jittering's O(N^-2) (see
//!   `tests/it/sampling_stats.rs`). Sample indices `≥ spp` continue with independent samples.
//! - **Halton**: the per-pixel Halton sequence (dimension `d` uses the `d`-th prime as base)
//!   randomised by nested (Owen) scrambling: every digit goes through a hashed permutation
//!   chosen by the seed, the dimension, the digit position and the digits already produced
//!   (one permutation per node of the base-b digit tree), and the seed is
//!   hashed with the pixel so every pixel gets an independent scramble. Base 2 uses an exact
//!   Owen scramble via bit operations. Beyond the first 256 dimensions (base 1619) samples are
//!   independent.
//! - **Sobol** (Burley 2020, "Practical Hash-based Owen Scrambling", JCGT 9(4)): padded
//!   Sobol: each 1D / 2D draw takes the first one / two Sobol dimensions, whose sample index is
//!   shuffled by a nested uniform scramble seeded by (seed, pixel, dimension), and whose
//!   coordinates are then Owen-scrambled with their own seeds. Only the first two Sobol
//!   dimensions are used (van der Corput and the Pascal matrix, built at compile time), so no
//!   imported direction-number tables are needed. The per-bit scramble is a Laine–Karras-style hash (constants
//!   from Vegdahl 2021's improved variant): every step only lets lower bits affect higher
//!   ones, which on bit-reversed values is exactly a nested (Owen) scramble.
//!
//! With a power-of-two `spp` the first `spp` Sobol samples of every 2D draw form a (0, m, 2)-net.

use crate::math::{UVec2, Vec2};
use crate::sampling::distrib::ONE_MINUS_EPSILON;
use base::SamplerKind;

// ---------------------------------------------------------------------------------------------
// Hashing

const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

/// SplitMix64's output function (a bijective 64-bit mixer).
#[inline]
pub fn mix64(mut x: u64) -> u64 {
    x ^= x >> 30;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x ^= x >> 27;
    x = x.wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^ (x >> 31)
}

/// Hash of two 64-bit values (order matters).
#[inline]
pub fn hash2(a: u64, b: u64) -> u64 {
    mix64(a ^ mix64(b.wrapping_add(GOLDEN)).rotate_left(23))
}

/// Uniform `f32` in `[0, 1)` from the top 24 bits of a 64-bit hash.
#[inline]
pub fn u64_to_unit(x: u64) -> f32 {
    (x >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

/// Uniform `f32` in `[0, 1)` from the top 24 bits of a 32-bit value.
#[inline]
fn u32_to_unit(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

/// Kensler 2013 ("Correlated Multi-Jittered Sampling"): a hashed permutation of `[0, l)`,
/// `i < l`, by cycle walking a bijection on the enclosing power of two.
#[inline]
pub fn permute(mut i: u32, l: u32, p: u32) -> u32 {
    if l <= 1 {
        return 0;
    }
    let mut w = l - 1;
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    // Every step below is a bijection on the low bits selected by `w`.
    loop {
        i ^= p;
        i = i.wrapping_mul(0xE170_893D);
        i ^= p >> 16;
        i ^= (i & w) >> 4;
        i ^= p >> 8;
        i = i.wrapping_mul(0x0929_EB3F);
        i ^= p >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | (p >> 27));
        i = i.wrapping_mul(0x6935_FA69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74DC_B303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9E50_1CC3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xC860_A3DF);
        i &= w;
        i ^= i >> 5;
        if i < l {
            break;
        }
    }
    ((i as u64 + p as u64) % l as u64) as u32
}

// ---------------------------------------------------------------------------------------------
// Owen scrambling and Sobol (Burley 2020)

/// Laine–Karras-style hash: bit k of the result is bit k of `x` flipped by a function of the
/// lower bits and the seed, i.e. a nested scramble of the bit-reversed value.
#[inline]
fn lk_hash(mut x: u32, seed: u32) -> u32 {
    x ^= x.wrapping_mul(0x3D20_ADEA);
    x = x.wrapping_add(seed);
    x = x.wrapping_mul((seed >> 16) | 1);
    x ^= x.wrapping_mul(0x0552_6C56);
    x ^= x.wrapping_mul(0x53A2_2864);
    x
}

/// Owen (nested uniform) scramble of a 32-bit binary fraction: the flip of each bit depends on
/// the seed and on all more significant bits.
#[inline]
pub fn nested_uniform_scramble(x: u32, seed: u32) -> u32 {
    lk_hash(x.reverse_bits(), seed).reverse_bits()
}

/// Direction numbers of Sobol dimension 1 (primitive polynomial x + 1), most significant bit
/// first: v₀ = 2³¹, vₖ = vₖ₋₁ ⊕ (vₖ₋₁ ≫ 1).
const SOBOL_DIM1: [u32; 32] = {
    let mut v = [0u32; 32];
    v[0] = 1 << 31;
    let mut k = 1;
    while k < 32 {
        v[k] = v[k - 1] ^ (v[k - 1] >> 1);
        k += 1;
    }
    v
};

/// Sobol dimension 1 by bytes: `SOBOL_DIM1_BYTES[b][v]` is the XOR of the direction numbers
/// selected by the bits of byte value `v` at byte position `b` of the index (4 KiB).
const SOBOL_DIM1_BYTES: [[u32; 256]; 4] = {
    let mut t = [[0u32; 256]; 4];
    let mut b = 0;
    while b < 4 {
        let mut v = 0;
        while v < 256 {
            let mut x = 0u32;
            let mut k = 0;
            while k < 8 {
                if v & (1 << k) != 0 {
                    x ^= SOBOL_DIM1[8 * b + k];
                }
                k += 1;
            }
            t[b][v] = x;
            v += 1;
        }
        b += 1;
    }
    t
};

/// The first two Sobol dimensions of index `i` as 32-bit fractions.
#[inline]
fn sobol_2d(i: u32) -> (u32, u32) {
    let [b0, b1, b2, b3] = i.to_le_bytes();
    let y = SOBOL_DIM1_BYTES[0][b0 as usize]
        ^ SOBOL_DIM1_BYTES[1][b1 as usize]
        ^ SOBOL_DIM1_BYTES[2][b2 as usize]
        ^ SOBOL_DIM1_BYTES[3][b3 as usize];
    (i.reverse_bits(), y)
}

// ---------------------------------------------------------------------------------------------
// Halton

const N_PRIMES: usize = 256;

const PRIMES: [u32; N_PRIMES] = {
    let mut out = [0u32; N_PRIMES];
    let mut n = 0;
    let mut c = 2u32;
    while n < N_PRIMES {
        let mut is_prime = true;
        let mut d = 2u32;
        while d * d <= c {
            if c.is_multiple_of(d) {
                is_prime = false;
                break;
            }
            d += 1;
        }
        if is_prime {
            out[n] = c;
            n += 1;
        }
        c += 1;
    }
    out
};

/// Number of base-`b` digits scrambled: the smallest `k` with `bᵏ ≥ 2²⁶`, two bits beyond the
/// resolution of an `f32` in [0.5, 1).
const HALTON_DIGITS: [u8; N_PRIMES] = {
    let mut out = [0u8; N_PRIMES];
    let mut i = 0;
    while i < N_PRIMES {
        let b = PRIMES[i] as u64;
        let mut k = 0u8;
        let mut p = 1u64;
        while p < (1u64 << 26) {
            p *= b;
            k += 1;
        }
        out[i] = k;
        i += 1;
    }
    out
};

/// Owen-scrambled radical inverse of `a` in base `PRIMES[dim]`: digit j (most significant first)
/// goes through a hashed permutation of `[0, base)` (Kensler's [`permute`]) chosen by
/// (seed, j, the scrambled digits before it), i.e. one random permutation per node of the
/// base-b tree. Full permutations rather than pbrt-v4's random cyclic shifts: a cyclic shift
/// of the leading digit keeps the diagonal structure of high-base Halton pairs at low sample
/// counts (χ²-detected in `tests/it/sampling_stats.rs`). The (zero) digits beyond the last digit
/// of `a` are scrambled too, so points fill their cells uniformly; since each of those nodes is
/// visited by this point alone, that tail is one uniform draw.
fn scrambled_radical_inverse(dim: usize, mut a: u32, seed: u64) -> f32 {
    let base = PRIMES[dim];
    if base == 2 {
        return u32_to_unit(nested_uniform_scramble(a.reverse_bits(), seed as u32));
    }
    let b = base as u64;
    let mut reversed = 0u64;
    let mut scale = 1.0f64;
    let inv_base = 1.0 / base as f64;
    let mut j = 0u64;
    while j < HALTON_DIGITS[dim] as u64 {
        // One hash per node of the digit tree: (level j, prefix `reversed`).
        let node = mix64(seed ^ reversed.wrapping_mul(GOLDEN) ^ (j << 58));
        if a == 0 {
            // Every remaining digit is 0 and each node below this one is visited by this point
            // only, so the scrambled tail is an independent uniform number: draw it at once.
            let tail = (node >> 11) as f64 * (1.0 / (1u64 << 53) as f64);
            return (((reversed as f64 + tail) * scale) as f32).min(ONE_MINUS_EPSILON);
        }
        let digit = a % base;
        a /= base;
        reversed = reversed * b + permute(digit, base, node as u32) as u64;
        scale *= inv_base;
        j += 1;
    }
    ((reversed as f64 * scale) as f32).min(ONE_MINUS_EPSILON)
}

// ---------------------------------------------------------------------------------------------
// Sampler

/// A deterministic per-pixel sample generator. Cheap to clone: clone one per worker thread.
#[derive(Clone, Debug)]
pub struct Sampler {
    kind: SamplerKind,
    spp: u32,
    seed: u64,
    /// Stratified 2D grid `m × n = spp` (m ≤ n).
    grid: (u32, u32),
    /// hash(seed): constant over the render.
    seed_key: u64,
    /// The pixel of the current sample.
    pixel: UVec2,
    /// hash(seed, pixel): constant over a pixel's samples (permutations, scrambles).
    pixel_key: u64,
    /// hash(pixel_key, index): the independent stream of the current sample.
    sample_key: u64,
    index: u32,
    dim: u32,
}

/// The point of cell (`col`, `row`) of an m × n grid at sub-column `sx` of m and sub-row `sy`
/// of n (multi-jittering's n × m sub-grid within the cells), offset by `j` ∈ [0, 1)² in its
/// sub-cell.
#[inline]
fn multi_jittered(
    (m, n): (u32, u32),
    (col, row): (u32, u32),
    (sx, sy): (u32, u32),
    j: Vec2,
) -> Vec2 {
    let x = (col as f32 + (sy as f32 + j.x) / n as f32) / m as f32;
    let y = (row as f32 + (sx as f32 + j.y) / m as f32) / n as f32;
    Vec2::new(x.min(ONE_MINUS_EPSILON), y.min(ONE_MINUS_EPSILON))
}

/// The divisor pair `m × n = spp` with `m ≤ n` closest to square.
fn stratified_grid(spp: u32) -> (u32, u32) {
    let mut m = (spp as f64).sqrt() as u32;
    while m > 1 && !spp.is_multiple_of(m) {
        m -= 1;
    }
    let m = m.max(1);
    (m, spp / m)
}

impl Sampler {
    /// A sampler of the given kind with `spp` samples per pixel (0 is treated as 1) and seed.
    pub fn new(kind: SamplerKind, spp: u32, seed: u64) -> Sampler {
        let spp = spp.max(1);
        let mut s = Sampler {
            kind,
            spp,
            seed,
            grid: stratified_grid(spp),
            seed_key: mix64(seed ^ GOLDEN),
            pixel: UVec2::ZERO,
            pixel_key: 0,
            sample_key: 0,
            index: 0,
            dim: 0,
        };
        s.pixel_key = s.key_of(UVec2::ZERO);
        s.start_pixel_sample(UVec2::ZERO, 0);
        s
    }

    fn key_of(&self, pixel: UVec2) -> u64 {
        hash2(self.seed_key, pixel.x as u64 | ((pixel.y as u64) << 32))
    }

    #[inline]
    pub fn kind(&self) -> SamplerKind {
        self.kind
    }

    #[inline]
    pub fn spp(&self) -> u32 {
        self.spp
    }

    #[inline]
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// The next dimension to be drawn.
    #[inline]
    pub fn dimension(&self) -> u32 {
        self.dim
    }

    /// Starts sample `index` of `pixel` at dimension 0.
    #[inline]
    pub fn start_pixel_sample(&mut self, pixel: UVec2, index: u32) {
        self.start_pixel_sample_at(pixel, index, 0);
    }

    /// Starts sample `index` of `pixel` at dimension `dim` (pbrt-v4's `StartPixelSample`), e.g.
    /// to give a sub-path a fixed dimension budget.
    pub fn start_pixel_sample_at(&mut self, pixel: UVec2, index: u32, dim: u32) {
        // Consecutive samples are usually of the same pixel: keep its key.
        if pixel != self.pixel {
            self.pixel = pixel;
            self.pixel_key = self.key_of(pixel);
        }
        self.sample_key = hash2(self.pixel_key, index as u64);
        self.index = index;
        self.dim = dim;
    }

    /// Jumps to dimension `dim` of the current sample.
    #[inline]
    pub fn set_dimension(&mut self, dim: u32) {
        self.dim = dim;
    }

    /// Independent uniform value of dimension `d` of the current sample.
    #[inline]
    fn independent(&self, d: u32) -> f32 {
        u64_to_unit(self.independent_bits(d))
    }

    /// Dimensions `d` and `d + 1` from one hash: its top and its low 32 bits give two
    /// disjoint 24-bit fields (one hash costs as much as the rest of a 2D draw).
    #[inline(always)]
    fn independent_2d(&self, d: u32) -> Vec2 {
        let x = self.independent_bits(d);
        Vec2::new(u64_to_unit(x), u32_to_unit(x as u32))
    }

    /// SplitMix64 (Steele et al. 2014) at position `d` of the stream of the current sample.
    #[inline(always)]
    fn independent_bits(&self, d: u32) -> u64 {
        let state = self
            .sample_key
            .wrapping_add((d as u64).wrapping_add(1).wrapping_mul(GOLDEN));
        mix64(state)
    }

    /// The offset of a sample within its stratum in dimension `d`: uniform, or ½ for a
    /// multi-jittered sampler without jitter.
    #[inline]
    fn jitter(&self, d: u32) -> f32 {
        match self.kind {
            SamplerKind::MultiJitter { jitter: false } => 0.5,
            _ => self.independent(d),
        }
    }

    /// Per-(pixel, dimension) key (constant over the pixel's samples).
    #[inline]
    fn dim_key(&self, d: u32) -> u64 {
        hash2(self.pixel_key, d as u64)
    }

    /// The next value in `[0, 1)`.
    #[inline(always)]
    pub fn next_1d(&mut self) -> f32 {
        let d = self.dim;
        self.dim = self.dim.wrapping_add(1);
        // The independent sampler inline; the others (bigger) behind a call.
        if self.kind == SamplerKind::Independent {
            self.independent(d)
        } else {
            self.next_1d_other(d)
        }
    }

    #[inline(never)]
    fn next_1d_other(&self, d: u32) -> f32 {
        match self.kind {
            SamplerKind::Independent => self.independent(d),
            SamplerKind::Stratified | SamplerKind::MultiJitter { .. } => {
                if self.index >= self.spp {
                    return self.independent(d);
                }
                let stratum = permute(self.index, self.spp, self.dim_key(d) as u32);
                let jitter = self.jitter(d);
                ((stratum as f32 + jitter) / self.spp as f32).min(ONE_MINUS_EPSILON)
            }
            SamplerKind::Halton => {
                if d as usize >= N_PRIMES {
                    return self.independent(d);
                }
                scrambled_radical_inverse(d as usize, self.index, self.dim_key(d))
            }
            SamplerKind::Sobol => {
                let k = self.dim_key(d);
                let i = nested_uniform_scramble(self.index, k as u32);
                u32_to_unit(nested_uniform_scramble(i.reverse_bits(), (k >> 32) as u32))
            }
        }
    }

    /// The next pair of values in `[0, 1)²` (advances the dimension by 2).
    #[inline(always)]
    pub fn next_2d(&mut self) -> Vec2 {
        let d = self.dim;
        self.dim = self.dim.wrapping_add(2);
        if self.kind == SamplerKind::Independent {
            self.independent_2d(d)
        } else {
            self.next_2d_other(d)
        }
    }

    #[inline(never)]
    fn next_2d_other(&self, d: u32) -> Vec2 {
        match self.kind {
            SamplerKind::Independent => self.independent_2d(d),
            SamplerKind::Stratified => {
                if self.index >= self.spp {
                    return self.independent_2d(d);
                }
                let k = self.dim_key(d);
                let (m, n) = self.grid;
                // Decorrelate dimensions: which grid cell this sample takes depends on (pixel, d).
                let s = permute(self.index, self.spp, k as u32);
                let (col, row) = (s % m, s / m);
                // Multi-jittered (Chiu et al. 1994): the sub-row of the sample in cell (col, row)
                // is a permutation over the columns of that row, drawn independently per row
                // (and vice versa), so x offsets of different rows are uncorrelated.
                let sx = permute(col, m, hash2(k, row as u64) as u32);
                let sy = permute(row, n, hash2(k, (col as u64) | (1 << 32)) as u32);
                let j = Vec2::new(self.independent(d), self.independent(d + 1));
                multi_jittered(self.grid, (col, row), (sx, sy), j)
            }
            SamplerKind::MultiJitter { .. } => {
                if self.index >= self.spp {
                    return self.independent_2d(d);
                }
                let k = self.dim_key(d);
                let (m, n) = self.grid;
                let s = permute(self.index, self.spp, k as u32);
                let (col, row) = (s % m, s / m);
                // Correlated (Kensler 2013): one permutation of the sub-columns for every
                // row and one of the sub-rows for every column, which keeps the n-rooks
                // property of multi-jittering with less clumping than a permutation per row.
                let sx = permute(col, m, (k >> 32) as u32);
                let sy = permute(row, n, mix64(k) as u32);
                let j = Vec2::new(self.jitter(d), self.jitter(d + 1));
                multi_jittered(self.grid, (col, row), (sx, sy), j)
            }
            SamplerKind::Halton => {
                if d as usize + 1 >= N_PRIMES {
                    return self.independent_2d(d);
                }
                Vec2::new(
                    scrambled_radical_inverse(d as usize, self.index, self.dim_key(d)),
                    scrambled_radical_inverse(d as usize + 1, self.index, self.dim_key(d + 1)),
                )
            }
            SamplerKind::Sobol => {
                let k = self.dim_key(d);
                let k2 = mix64(k);
                let i = nested_uniform_scramble(self.index, k as u32);
                let (x, y) = sobol_2d(i);
                Vec2::new(
                    u32_to_unit(nested_uniform_scramble(x, (k >> 32) as u32)),
                    u32_to_unit(nested_uniform_scramble(y, k2 as u32)),
                )
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn permute_is_a_permutation() {
        for l in [1u32, 2, 3, 7, 16, 33, 100] {
            for p in [0u32, 1, 0xDEAD_BEEF, 12345] {
                let mut seen = vec![false; l as usize];
                for i in 0..l {
                    let j = permute(i, l, p);
                    assert!(j < l && !seen[j as usize], "l={l} p={p}");
                    seen[j as usize] = true;
                }
            }
        }
    }

    #[test]
    fn nested_scramble_is_a_bijection_preserving_prefix_structure() {
        // Owen scrambling maps each dyadic interval of length 2^-k onto one of the same length:
        // two values sharing their top k bits still share their top k bits afterwards.
        let seed = 0x1234_5678;
        for a in [0u32, 0x8000_0000, 0xF0F0_F0F0, 0x1234_5678] {
            for k in 1..32 {
                let b = a ^ (1u32 << (31 - k)); // differs only below the top k bits
                let (sa, sb) = (
                    nested_uniform_scramble(a, seed),
                    nested_uniform_scramble(b, seed),
                );
                assert_eq!(sa >> (32 - k), sb >> (32 - k));
                assert_ne!(sa, sb);
            }
        }
    }

    #[test]
    fn sobol_first_points_form_nets() {
        // Unscrambled (0,2)-sequence in base 2: every block of 2^m points has one point in each
        // elementary interval of area 2^-m; check all shapes for m = 4.
        let pts: Vec<(u32, u32)> = (0..16).map(sobol_2d).collect();
        for kx in 0..=4 {
            let ky = 4 - kx;
            let mut seen = [false; 16];
            for &(x, y) in &pts {
                let cx = if kx == 0 {
                    0
                } else {
                    (x >> (32 - kx)) as usize
                };
                let cy = if ky == 0 {
                    0
                } else {
                    (y >> (32 - ky)) as usize
                };
                let c = (cy << kx) | cx;
                assert!(!seen[c], "kx={kx}");
                seen[c] = true;
            }
        }
    }

    #[test]
    fn sobol_byte_tables_match_direction_numbers() {
        for i in [0u32, 1, 2, 3, 255, 256, 0x1234_5678, u32::MAX] {
            let mut y = 0;
            for (k, v) in SOBOL_DIM1.iter().enumerate() {
                if i >> k & 1 != 0 {
                    y ^= v;
                }
            }
            assert_eq!(sobol_2d(i), (i.reverse_bits(), y));
        }
        // Dimension 1 starts 1/2, 1/4, 3/4, ... for indices 1, 2, 3 (bit-reversed Pascal).
        assert_eq!(sobol_2d(1).1, 1 << 31);
        assert_eq!(sobol_2d(2).1, 3 << 30);
        assert_eq!(sobol_2d(3).1, 1 << 30);
    }

    #[test]
    fn primes_and_digits() {
        assert_eq!(&PRIMES[..6], &[2, 3, 5, 7, 11, 13]);
        assert_eq!(PRIMES[255], 1619);
        assert_eq!(HALTON_DIGITS[0], 26);
        assert_eq!(HALTON_DIGITS[1], 17); // 3^17 ≥ 2^26 > 3^16
    }

    #[test]
    fn stratified_grid_is_closest_to_square() {
        assert_eq!(stratified_grid(16), (4, 4));
        assert_eq!(stratified_grid(12), (3, 4));
        assert_eq!(stratified_grid(13), (1, 13));
        assert_eq!(stratified_grid(1), (1, 1));
    }

    #[test]
    fn stratified_1d_has_one_sample_per_stratum() {
        for kind in [SamplerKind::Stratified, SamplerKind::Sobol] {
            let spp = 16;
            let mut s = Sampler::new(kind, spp, 7);
            for dim in 0..6 {
                let mut seen = [false; 16];
                for i in 0..spp {
                    s.start_pixel_sample_at(UVec2::new(3, 9), i, dim);
                    let v = s.next_1d();
                    let c = (v * spp as f32) as usize;
                    assert!(!seen[c], "{kind:?} dim {dim}");
                    seen[c] = true;
                }
            }
        }
    }

    #[test]
    fn stratified_2d_is_latin_and_grid_stratified() {
        for (kind, spp) in [
            (SamplerKind::Stratified, 12),
            (SamplerKind::Stratified, 16),
            (SamplerKind::Sobol, 16),
        ] {
            let mut s = Sampler::new(kind, spp, 3);
            let (m, n) = stratified_grid(spp);
            for dim in [0, 2, 5] {
                let (mut xs, mut ys, mut cells) = (
                    vec![0; spp as usize],
                    vec![0; spp as usize],
                    vec![0; spp as usize],
                );
                for i in 0..spp {
                    s.start_pixel_sample_at(UVec2::new(1, 2), i, dim);
                    let p = s.next_2d();
                    xs[(p.x * spp as f32) as usize] += 1;
                    ys[(p.y * spp as f32) as usize] += 1;
                    cells[(p.y * n as f32) as usize * m as usize + (p.x * m as f32) as usize] += 1;
                }
                assert!(
                    xs.iter().chain(&ys).chain(&cells).all(|&c| c == 1),
                    "{kind:?} dim {dim}"
                );
            }
        }
    }
}
