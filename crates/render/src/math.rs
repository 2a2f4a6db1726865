//! Math helpers on top of glam: orthonormal frames and spherical coordinates.

/// Packed three-float vector (12 bytes), for storage and the scene model.
pub use glam::Vec3 as PVec3;
pub use glam::{IVec2, Mat3, Mat4, UVec2, Vec2, Vec3A, Vec3A as Vec3, Vec4};

pub const PI: f32 = std::f32::consts::PI;
pub const INV_PI: f32 = std::f32::consts::FRAC_1_PI;
pub const INV_2PI: f32 = 0.5 * std::f32::consts::FRAC_1_PI;
pub const INV_4PI: f32 = 0.25 * std::f32::consts::FRAC_1_PI;

/// An orthonormal frame; local coordinates have the normal along +z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    pub s: Vec3,
    pub t: Vec3,
    pub n: Vec3,
}

impl Frame {
    /// A frame around the unit vector `n` (Duff et al. 2017, branchless ONB).
    pub fn from_normal(n: Vec3) -> Frame {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Frame { s, t, n }
    }

    /// A frame with normal `n` whose `s` axis follows `dpdu` as closely as possible.
    pub fn from_normal_tangent(n: Vec3, dpdu: Vec3) -> Frame {
        let s = dpdu - n * n.dot(dpdu);
        let len2 = s.length_squared();
        if !len2.is_finite() || len2 <= 1e-12 {
            return Frame::from_normal(n);
        }
        let s = s * rsqrt(len2);
        Frame {
            s,
            t: n.cross(s),
            n,
        }
    }

    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }

    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }
}

/// Local-frame trigonometry (normal = +z).
#[inline]
pub fn cos_theta(w: Vec3) -> f32 {
    w.z
}
#[inline]
pub fn abs_cos_theta(w: Vec3) -> f32 {
    w.z.abs()
}
#[inline]
pub fn cos2_theta(w: Vec3) -> f32 {
    w.z * w.z
}
#[inline]
pub fn sin2_theta(w: Vec3) -> f32 {
    (1.0 - cos2_theta(w)).max(0.0)
}
#[inline]
pub fn tan2_theta(w: Vec3) -> f32 {
    sin2_theta(w) / cos2_theta(w)
}

/// Direction from spherical angles (θ from +z, φ from +x).
#[inline]
pub fn spherical_direction(sin_theta: f32, cos_theta: f32, phi: f32) -> Vec3 {
    let (sp, cp) = phi.sin_cos();
    Vec3::new(
        sin_theta.clamp(-1.0, 1.0) * cp,
        sin_theta.clamp(-1.0, 1.0) * sp,
        cos_theta.clamp(-1.0, 1.0),
    )
}

/// Reflect `wo` about `n` (both pointing away from the surface).
#[inline]
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    -wo + 2.0 * wo.dot(n) * n
}

#[inline]
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

#[inline]
pub fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// `v / |v|` by [`rsqrt`]; zero when `v` is zero, tiny or not finite (as `normalize_or_zero`).
#[inline(always)]
pub fn normalize_or_zero_fast(v: Vec3) -> Vec3 {
    let l2 = v.length_squared();
    if l2 >= f32::MIN_POSITIVE && l2.is_finite() {
        v * rsqrt(l2)
    } else {
        v.normalize_or_zero()
    }
}

/// `1/√x` for `x > 0` (finite): the SSE reciprocal square-root estimate refined by one
/// Newton–Raphson step (relative error below 2⁻²², a few ulp), instead of a square root and a
/// division (together ~25 cycles of latency on the hit-to-shading critical path).
#[inline(always)]
pub fn rsqrt(x: f32) -> f32 {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_mm_cvtss_f32, _mm_rsqrt_ss, _mm_set_ss};
        // SAFETY: SSE is part of the x86_64 baseline, so these intrinsics are always available.
        let r = unsafe { _mm_cvtss_f32(_mm_rsqrt_ss(_mm_set_ss(x))) };
        r * (1.5 - 0.5 * x * r * r)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        1.0 / x.sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rsqrt_is_within_a_few_ulp() {
        let mut worst = 0f64;
        let mut x = 1e-30f32;
        while x < 1e30 {
            let exact = 1.0 / (x as f64).sqrt();
            worst = worst.max((rsqrt(x) as f64 / exact - 1.0).abs());
            x *= 1.001_7;
        }
        assert!(worst < 4.0 * f32::EPSILON as f64, "relative error {worst}");
        for v in [
            Vec3::ZERO,
            Vec3::splat(1e-30),
            Vec3::new(f32::MAX, 0.0, 0.0),
            Vec3::NAN,
        ] {
            assert!(normalize_or_zero_fast(v).is_finite(), "{v:?}");
        }
        let v = Vec3::new(3.0, -4.0, 12.0);
        assert!((normalize_or_zero_fast(v) - v / 13.0).length() < 1e-6);
    }

    #[test]
    fn frame_is_orthonormal() {
        for n in [
            Vec3::Z,
            -Vec3::Z,
            Vec3::X,
            Vec3::new(0.3, -0.4, 0.866).normalize(),
            Vec3::new(0.0, 0.0, -0.99999).normalize(),
        ] {
            let f = Frame::from_normal(n);
            assert!((f.s.length() - 1.0).abs() < 1e-5);
            assert!((f.t.length() - 1.0).abs() < 1e-5);
            assert!(
                f.s.dot(f.t).abs() < 1e-5 && f.s.dot(n).abs() < 1e-5 && f.t.dot(n).abs() < 1e-5
            );
            assert!((f.s.cross(f.t) - n).length() < 1e-5, "right-handed");
            let v = Vec3::new(0.2, -0.5, 0.7);
            assert!((f.to_world(f.to_local(v)) - v).length() < 1e-5);
        }
    }
}
