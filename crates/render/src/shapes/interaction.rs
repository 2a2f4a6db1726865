//! The surface interaction and robust ray spawning.

use crate::geometry::Ray;
use crate::math::{Frame, Vec2, Vec3};

/// A ray–surface intersection in world space.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceInteraction {
    pub p: Vec3,
    /// Conservative absolute error bound of `p`, per component.
    pub p_error: Vec3,
    /// Geometric normal (unit), oriented by the shape (outward / winding / flip_normals).
    pub ng: Vec3,
    /// Shading frame (interpolated normals), `shading.n` on the same side as `ng`.
    pub shading: Frame,
    pub uv: Vec2,
    /// Direction towards where the ray came from (unit).
    pub wo: Vec3,
    pub t: f32,
    pub shape: u32,
    pub prim: u32,
    /// The time of the ray that found it (see [`Ray::time`]); rays spawned here keep it.
    pub time: f32,
}

impl SurfaceInteraction {
    /// Where textures are looked up at this point.
    #[inline]
    pub fn tex(&self) -> crate::textures::TexCoord {
        crate::textures::TexCoord::at(self.uv, self.p)
    }

    /// A ray leaving the surface in direction `d`, origin offset to the side `d` points to.
    #[inline]
    pub fn spawn_ray(&self, d: Vec3) -> Ray {
        Ray::at_time(
            offset_ray_origin(self.p, self.p_error, self.ng, d),
            d,
            self.time,
        )
    }

    /// A ray towards `target` and the parameter range (0, t_max) that stops just short of it
    /// (`d` is not normalised: t = 1 is the target).
    #[inline]
    pub fn spawn_ray_to(&self, target: Vec3) -> (Ray, f32) {
        let o = offset_ray_origin(self.p, self.p_error, self.ng, target - self.p);
        (Ray::at_time(o, target - o, self.time), 1.0 - SHADOW_EPSILON)
    }

    /// Like `spawn_ray_to`, but towards another surface point, offsetting both ends.
    #[inline]
    pub fn spawn_ray_to_surface(&self, p: Vec3, p_error: Vec3, n: Vec3) -> (Ray, f32) {
        let o = offset_ray_origin(self.p, self.p_error, self.ng, p - self.p);
        let t = offset_ray_origin(p, p_error, n, o - p);
        (Ray::at_time(o, t - o, self.time), 1.0 - SHADOW_EPSILON)
    }
}

/// Relative shortening of shadow rays towards a known point (pbrt-v4's ShadowEpsilon).
pub const SHADOW_EPSILON: f32 = 1e-4;

/// `x` moved by one ulp towards the sign of `step` (−1, 0 or +1): pbrt-v4's `NextFloatUp` /
/// `NextFloatDown` without branches. The bits are mapped to an integer that is monotonic in
/// the value (both zeros to 0), stepped and mapped back; infinities and NaN stay as they are,
/// and so does `x` when `step` is 0.
///
/// The reference for the SIMD [`next_float_away`] (and its portable form).
#[cfg(any(test, not(target_arch = "x86_64")))]
#[inline(always)]
fn next_float(x: f32, step: i32) -> f32 {
    let b = x.to_bits() as i32;
    let mag = b & 0x7fff_ffff;
    let m = if b < 0 { -mag } else { mag } + step;
    let stepped = if m < 0 {
        (m.unsigned_abs()) | 0x8000_0000
    } else {
        m as u32
    };
    f32::from_bits(if step == 0 || !x.is_finite() {
        x.to_bits()
    } else {
        stepped
    })
}

/// The direction [`next_float`] rounds `x + o` to for an offset `o`: +1, −1, or 0 (also NaN).
#[cfg(any(test, not(target_arch = "x86_64")))]
#[inline(always)]
fn step_sign(o: f32) -> i32 {
    (o > 0.0) as i32 - (o < 0.0) as i32
}

/// pbrt-v4's OffsetRayOrigin: move `p` off the surface along `n` by the error bound, to the
/// side of `w`, rounding away from the surface.
///
/// Branch-free: which way each coordinate is rounded depends on the sign of the offset, which
/// a branch predictor cannot guess.
#[inline]
pub fn offset_ray_origin(p: Vec3, p_error: Vec3, n: Vec3, w: Vec3) -> Vec3 {
    let d = n.abs().dot(p_error);
    let offset = if w.dot(n) < 0.0 { -(n * d) } else { n * d };
    next_float_away(p + offset, offset)
}

/// Each coordinate of `x` moved by one ulp towards the sign of that coordinate of `offset`
/// ([`next_float`] on all lanes at once, with SSE2 integer operations).
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn next_float_away(x: Vec3, offset: Vec3) -> Vec3 {
    use std::arch::x86_64::*;
    // SAFETY: SSE2 is part of the x86_64 baseline, so these intrinsics are always available;
    // none of them touches memory.
    unsafe {
        let zero = _mm_setzero_ps();
        let o: __m128 = offset.into();
        // All-ones (−1) masks: step = (o < 0) − (o > 0) as integers is `step_sign(o)`.
        let step = _mm_sub_epi32(
            _mm_castps_si128(_mm_cmplt_ps(o, zero)),
            _mm_castps_si128(_mm_cmpgt_ps(o, zero)),
        );
        let b = _mm_castps_si128(x.into());
        let mag = _mm_and_si128(b, _mm_set1_epi32(0x7fff_ffff));
        // Monotonic integer image (both zeros to 0): conditional negation by the sign mask.
        let sign = _mm_srai_epi32(b, 31);
        let m = _mm_add_epi32(_mm_sub_epi32(_mm_xor_si128(mag, sign), sign), step);
        // Back to float bits: magnitude and sign of `m`.
        let m_sign = _mm_srai_epi32(m, 31);
        let m_abs = _mm_sub_epi32(_mm_xor_si128(m, m_sign), m_sign);
        let stepped = _mm_or_si128(m_abs, _mm_and_si128(m_sign, _mm_set1_epi32(i32::MIN)));
        // Unchanged where the step is 0 or `x` is infinite or NaN.
        let keep = _mm_or_si128(
            _mm_cmpeq_epi32(step, _mm_setzero_si128()),
            _mm_cmpgt_epi32(mag, _mm_set1_epi32(0x7f7f_ffff)),
        );
        let r = _mm_or_si128(_mm_and_si128(keep, b), _mm_andnot_si128(keep, stepped));
        Vec3::from(_mm_castsi128_ps(r))
    }
}

/// Portable [`next_float_away`].
#[cfg(not(target_arch = "x86_64"))]
#[inline(always)]
fn next_float_away(x: Vec3, offset: Vec3) -> Vec3 {
    Vec3::new(
        next_float(x.x, step_sign(offset.x)),
        next_float(x.y, step_sign(offset.y)),
        next_float(x.z, step_sign(offset.z)),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn offset_origin_clears_the_error_box() {
        let p = Vec3::new(1000.0, -3.0, 0.5);
        let err = Vec3::splat(1e-3);
        let n = Vec3::new(0.0, 1.0, 0.0);
        let up = offset_ray_origin(p, err, n, n);
        assert!(up.y > p.y + 1e-3 * 0.999);
        let down = offset_ray_origin(p, err, n, -n);
        assert!(down.y < p.y - 1e-3 * 0.999);
    }

    #[test]
    fn next_float_steps_one_ulp() {
        assert!(next_float(1.0, 1) > 1.0 && next_float(1.0, -1) < 1.0);
        assert!(next_float(0.0, 1) > 0.0 && next_float(0.0, -1) < 0.0);
        assert!(next_float(-0.0, 1) > 0.0 && next_float(-0.0, -1) < 0.0);
        assert!(next_float(-1.0, 1) > -1.0 && next_float(-1.0, -1) < -1.0);
        // One ulp, as pbrt-v4's NextFloatUp/NextFloatDown.
        assert_eq!(next_float(1.0, 1), 1.0 + f32::EPSILON);
        assert_eq!(next_float(-1.0, -1), -1.0 - f32::EPSILON);
        assert_eq!(next_float(0.0, 1), f32::from_bits(1));
        assert_eq!(next_float(0.0, -1), -f32::from_bits(1));
        assert_eq!(next_float(-f32::from_bits(1), 1), 0.0);
        assert_eq!(next_float(f32::MAX, 1), f32::INFINITY);
        for x in [f32::INFINITY, f32::NEG_INFINITY] {
            assert_eq!(next_float(x, 1), x);
            assert_eq!(next_float(x, -1), x);
        }
        assert!(next_float(f32::NAN, 1).is_nan());
        assert_eq!(next_float(-0.0, 0).to_bits(), (-0.0f32).to_bits());
    }

    #[test]
    fn next_float_away_is_next_float_per_lane() {
        use crate::sampling::sampler::mix64;
        let special = [
            0.0,
            -0.0,
            1.0,
            -1.0,
            f32::from_bits(1),
            -f32::from_bits(1),
            f32::MIN_POSITIVE,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
        ];
        let offsets = [
            1e-3,
            -1e-3,
            0.0,
            -0.0,
            f32::from_bits(1),
            -f32::MAX,
            f32::NAN,
        ];
        let random = (0..100_000u64).map(|i| f32::from_bits(mix64(i) as u32));
        let xs: Vec<f32> = special.into_iter().chain(random).collect();
        for (i, &x) in xs.iter().enumerate() {
            for (j, &o) in offsets.iter().enumerate() {
                // Each lane gets a different (value, offset) pair.
                let (y, z) = (xs[(i + 7) % xs.len()], xs[(i + 13) % xs.len()]);
                let (oy, oz) = (
                    offsets[(j + 1) % offsets.len()],
                    offsets[(j + 3) % offsets.len()],
                );
                let got = next_float_away(Vec3::new(x, y, z), Vec3::new(o, oy, oz));
                for (g, (v, o)) in got.to_array().into_iter().zip([(x, o), (y, oy), (z, oz)]) {
                    let want = next_float(v, step_sign(o));
                    assert_eq!(
                        g.to_bits(),
                        want.to_bits(),
                        "x = {v:e} ({:#x}), offset {o:e}",
                        v.to_bits()
                    );
                }
            }
        }
    }
}
