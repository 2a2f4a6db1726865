//! Cylinders (Mitsuba 3's `cylinder`): the open unit cylinder x² + y² = 1, 0 ≤ z ≤ 1 of an
//! affine `to_world` (no caps), its interaction and its sampling by area.

use glam::Mat3A;

use super::{Local, gamma};
use crate::accel::Hit;
use crate::geometry::Ray;
use crate::math::{Mat4, PI, Vec2, Vec3};

/// An affinely transformed open unit cylinder (see [`super::ShapeGeom::Cylinder`]). Mitsuba
/// allows only a rotation, a translation and the scale (r, r, length); any other affine map
/// is rendered as the elliptic or slanted cylinder it describes.
#[derive(Clone, Debug)]
pub struct Cylinder {
    pub to_world: Mat4,
    pub to_object: Mat4,
    /// The inverse transpose of the linear part (object normal → world normal).
    pub normal_matrix: Mat3A,
    /// |det| of the linear part.
    pub det: f32,
    /// World surface area.
    pub area: f32,
}

impl Cylinder {
    /// `None` for a singular or non-finite transform.
    pub fn new(to_world: Mat4) -> Option<Cylinder> {
        let to_object = to_world.inverse();
        let det = to_world.determinant().abs();
        if det == 0.0 || !det.is_finite() || !to_object.is_finite() || !to_world.is_finite() {
            return None;
        }
        let normal_matrix = Mat3A::from_mat4(to_object).transpose();
        let mut c = Cylinder {
            to_world,
            to_object,
            normal_matrix,
            det,
            area: 0.0,
        };
        // ∫₀^2π of the area element ratio dφ (z does not change it): 2π r·length for
        // Mitsuba's transforms, numerically otherwise.
        let n = 1024;
        let sum: f64 = (0..n)
            .map(|j| c.area_scale((j as f32 + 0.5) / n as f32 * 2.0 * PI) as f64)
            .sum();
        c.area = (sum * 2.0 * std::f64::consts::PI / n as f64) as f32;
        Some(c)
    }

    /// World area per object area (dφ dz) at angle φ: |det M| · |M⁻ᵀ n| with the object
    /// normal n = (cos φ, sin φ, 0).
    #[inline]
    pub fn area_scale(&self, phi: f32) -> f32 {
        let (s, c) = phi.sin_cos();
        self.det * (self.normal_matrix * Vec3::new(c, s, 0.0)).length()
    }

    /// World normal at the object point `q` (on the unit cylinder).
    #[inline]
    pub fn normal(&self, q: Vec3) -> Vec3 {
        (self.normal_matrix * Vec3::new(q.x, q.y, 0.0)).normalize_or(Vec3::Z)
    }

    /// The object point at angle φ and height z.
    #[inline]
    pub fn object_point(phi: f32, z: f32) -> Vec3 {
        let (s, c) = phi.sin_cos();
        Vec3::new(c, s, z)
    }

    /// World point and conservative error bound for the object point `q` (its own error,
    /// γ₅ per coordinate as for spheres, carried through the affine map with its rounding).
    #[inline]
    pub fn point(&self, q: Vec3) -> (Vec3, Vec3) {
        let p = self.to_world.transform_point3a(q);
        let m = Mat3A::from_mat4(self.to_world);
        let abs_m = Mat3A::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs());
        let obj_err = q.abs() * gamma(5);
        let t = Vec3::from_vec4(self.to_world.w_axis).abs();
        let err = abs_m * obj_err + gamma(3) * (abs_m * q.abs() + t);
        (p, err)
    }

    /// The object point of the world point `p`, put back on the cylinder.
    #[inline]
    pub fn project(&self, p: Vec3) -> Vec3 {
        let l = self.to_object.transform_point3a(p);
        let r = (l.x * l.x + l.y * l.y).sqrt();
        let (x, y) = if r > 0.0 {
            (l.x / r, l.y / r)
        } else {
            (1.0, 0.0)
        };
        Vec3::new(x, y, l.z.clamp(0.0, 1.0))
    }

    /// The density by world area of [`Cylinder::sample`] at the object point `q`.
    #[inline]
    pub fn pdf_area(&self, q: Vec3) -> f32 {
        1.0 / (2.0 * PI * self.area_scale(q.y.atan2(q.x)))
    }

    /// A point uniform in (φ, z) of the object cylinder, as Mitsuba samples (z = u.x,
    /// φ = 2π u.y): uniform by area under Mitsuba's transforms. Returns the object point and
    /// its density by world area.
    #[inline]
    pub fn sample(&self, u: Vec2) -> (Vec3, f32) {
        let phi = 2.0 * PI * u.y;
        let q = Cylinder::object_point(phi, u.x);
        (q, 1.0 / (2.0 * PI * self.area_scale(phi)))
    }

    /// The interaction at `hit`, before the common tail.
    #[inline(always)]
    pub(super) fn interaction(&self, hit: &Hit, ray: &Ray, reads: super::Reads) -> Local {
        let q = self.project(ray.at(hit.t));
        let (p, p_error) = self.point(q);
        let n = self.normal(q);
        let uv = if reads.uv { cylinder_uv(q) } else { Vec2::ZERO };
        // ∂p/∂u = 2π (-y, x, 0) in object space: the shading tangent follows φ.
        let dpdu = self
            .to_world
            .transform_vector3a(Vec3::new(-q.y, q.x, 0.0) * (2.0 * PI));
        (p, p_error, n, n, dpdu, uv)
    }
}

/// Mitsuba's cylinder parameterisation of the object point `q`: u = φ / 2π with φ ∈ [0, 2π),
/// v = z.
pub fn cylinder_uv(q: Vec3) -> Vec2 {
    let phi = q.y.atan2(q.x);
    let phi = if phi < 0.0 { phi + 2.0 * PI } else { phi };
    Vec2::new(phi / (2.0 * PI), q.z)
}
