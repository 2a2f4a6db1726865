//! Ellipsoids: an affinely transformed unit sphere (CENG795 spheres under a non-uniform scale
//! or a shear), its interaction and its solid-angle sampling.

use glam::Mat3A;

use super::{Local, gamma, sphere_uv};
use crate::accel::Hit;
use crate::geometry::Ray;
use crate::math::{Frame, Mat4, PI, Vec2, Vec3};
use crate::sampling::warp;

/// An affinely transformed unit sphere (see [`ShapeGeom::Ellipsoid`]).
#[derive(Clone, Debug)]
pub struct Ellipsoid {
    pub to_world: Mat4,
    pub to_object: Mat4,
    /// The inverse transpose of the linear part, as columns (object normal → world normal).
    pub normal_matrix: Mat3A,
    /// |det| of the linear part.
    pub det: f32,
    /// World surface area (numerical: ellipsoids have no closed form).
    pub area: f32,
}

impl Ellipsoid {
    /// `None` for a singular or non-finite transform.
    pub fn new(to_world: Mat4) -> Option<Ellipsoid> {
        let to_object = to_world.inverse();
        let det = to_world.determinant().abs();
        if det == 0.0 || !det.is_finite() || !to_object.is_finite() || !to_world.is_finite() {
            return None;
        }
        let normal_matrix = Mat3A::from_mat4(to_object).transpose();
        let mut e = Ellipsoid {
            to_world,
            to_object,
            normal_matrix,
            det,
            area: 0.0,
        };
        // ∫ over the unit sphere of the area element ratio, midpoint rule in (cos θ, φ) — an
        // equal-area grid, so each cell is 4π/(N·M) of the sphere.
        let (n, m) = (256, 512);
        let mut sum = 0.0f64;
        for i in 0..n {
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - z * z).max(0.0).sqrt();
            for j in 0..m {
                let phi = 2.0 * PI * (j as f32 + 0.5) / m as f32;
                let dir = Vec3::new(r * phi.cos(), r * phi.sin(), z);
                sum += e.area_scale(dir) as f64;
            }
        }
        e.area = (sum * 4.0 * std::f64::consts::PI / (n * m) as f64) as f32;
        Some(e)
    }

    /// World area per object area at the unit-sphere point `dir`: |det M| · |M⁻ᵀ n| (the
    /// object normal is `dir`).
    #[inline]
    pub fn area_scale(&self, dir: Vec3) -> f32 {
        self.det * (self.normal_matrix * dir).length()
    }

    /// World normal at the unit-sphere point `dir`.
    #[inline]
    pub fn normal(&self, dir: Vec3) -> Vec3 {
        (self.normal_matrix * dir).normalize_or(Vec3::Z)
    }

    /// World point and conservative error bound for the unit-sphere point `dir`: the object
    /// point's own error (γ₅ per unit coordinate, pbrt-v4's sphere bound) carried through the
    /// affine map with its rounding (pbrt-v4's `Transform` of an interval point).
    #[inline]
    pub fn point(&self, dir: Vec3) -> (Vec3, Vec3) {
        let p = self.to_world.transform_point3a(dir);
        let m = Mat3A::from_mat4(self.to_world);
        let abs_m = Mat3A::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs());
        let obj_err = dir.abs() * gamma(5);
        let t = Vec3::from_vec4(self.to_world.w_axis).abs();
        let err = abs_m * obj_err + gamma(3) * (abs_m * dir.abs() + t);
        (p, err)
    }
}

impl Ellipsoid {
    /// The interaction at `hit`, before the common tail.
    #[inline(always)]
    pub(super) fn interaction(&self, hit: &Hit, ray: &Ray, reads: super::Reads) -> Local {
        let e = self;
        // Re-project the object-space hit onto the unit sphere, as for spheres.
        let local = e.to_object.transform_point3a(ray.at(hit.t));
        let dir = local.normalize_or(Vec3::Z);
        let (p, p_error) = e.point(dir);
        let n = e.normal(dir);
        let uv = if reads.uv { sphere_uv(dir) } else { Vec2::ZERO };
        let dpdu = e.to_world.transform_vector3a(Vec3::new(-dir.y, dir.x, 0.0));
        (p, p_error, n, n, dpdu, uv)
    }
}

/// An ellipsoid light seen from `from`: the unit-sphere point (object space) and the
/// solid-angle density of the world direction towards it. Outside, the cone of directions
/// the object sphere subtends from the object-space receiver is sampled uniformly (as for
/// spheres) and carried to world directions by the Jacobian of the linear map A = M⁻¹ on
/// directions, dω_obj/dω = |det A| / |A w|³; inside, uniformly on the object sphere by area.
pub fn sample(e: &Ellipsoid, from: Vec3, u: Vec2) -> Option<(Vec3, f32)> {
    let o = e.to_object.transform_point3a(from);
    let dc2 = o.length_squared();
    if dc2 > 1.0 + 1e-4 {
        let dc = dc2.sqrt();
        let cos_max = (1.0 - 1.0 / dc2).max(0.0).sqrt();
        let axis = -o / dc;
        let w = Frame::from_normal(axis).to_world(warp::square_to_uniform_cone(u, cos_max));
        // Nearest intersection with the unit sphere (clamped for grazing directions).
        let b = w.dot(-o);
        let disc = (1.0 - (-o - b * w).length_squared()).max(0.0);
        let q = (o + w * (b - disc.sqrt())).normalize_or(axis);
        let (p, _) = e.point(q);
        let wi = (p - from).normalize_or_zero();
        let a = Mat3A::from_mat4(e.to_object);
        let aw = (a * wi).length();
        Some((q, warp::uniform_cone_pdf(cos_max) / (e.det * aw * aw * aw)))
    } else {
        let q = warp::square_to_uniform_sphere(u);
        let (p, _) = e.point(q);
        let to = p - from;
        let cos_l = e.normal(q).dot(to.normalize_or_zero()).abs();
        if cos_l == 0.0 {
            return None;
        }
        Some((
            q,
            to.length_squared() / (cos_l * 4.0 * PI * e.area_scale(q)),
        ))
    }
}

/// The density [`sample`] gives the direction `wi` from `from` towards the point
/// `on` of the ellipsoid (`cos_l`: |cosine| at `on`).
pub fn pdf(e: &Ellipsoid, from: Vec3, wi: Vec3, on: Vec3, cos_l: f32) -> f32 {
    let o = e.to_object.transform_point3a(from);
    let dc2 = o.length_squared();
    if dc2 > 1.0 + 1e-4 {
        let cos_max = (1.0 - 1.0 / dc2).max(0.0).sqrt();
        let a = Mat3A::from_mat4(e.to_object);
        let aw = (a * wi).length();
        warp::uniform_cone_pdf(cos_max) / (e.det * aw * aw * aw)
    } else {
        if cos_l == 0.0 {
            return 0.0;
        }
        let q = e.to_object.transform_point3a(on).normalize_or(Vec3::Z);
        (on - from).length_squared() / (cos_l * 4.0 * PI * e.area_scale(q))
    }
}
