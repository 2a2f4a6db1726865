//! Math helpers on top of glam: orthonormal frames and spherical coordinates.

pub use glam::{IVec2, Mat3, Mat4, UVec2, Vec2, Vec3, Vec3A, Vec4};

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
        let s = s / len2.sqrt();
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

#[cfg(test)]
mod tests {
    use super::*;

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
