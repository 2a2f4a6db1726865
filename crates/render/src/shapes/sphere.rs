//! Spheres: interaction, uv, and the solid-angle sampling of Mitsuba's sphere emitter.

use super::{Local, gamma};
use crate::accel::Hit;
use crate::geometry::Ray;
use crate::math::{Frame, PI, Vec2, Vec3};
use crate::sampling::warp;

/// Mitsuba's sphere parameterisation of the unit direction `dir` from the centre:
/// u = φ / 2π, v = θ / π (θ from +z).
pub fn sphere_uv(dir: Vec3) -> Vec2 {
    let phi = dir.y.atan2(dir.x);
    let phi = if phi < 0.0 { phi + 2.0 * PI } else { phi };
    let theta = dir.z.clamp(-1.0, 1.0).acos();
    Vec2::new(phi / (2.0 * PI), theta / PI)
}

/// The interaction at `hit` on the sphere (`center`, `radius`), before the common tail.
#[inline(always)]
pub(super) fn interaction(
    center: Vec3,
    radius: f32,
    hit: &Hit,
    ray: &Ray,
    reads: super::Reads,
) -> Local {
    let center = &center;
    let radius = &radius;
    let raw = ray.at(hit.t);
    let dir = (raw - *center).normalize_or(Vec3::Z);
    let p = *center + dir * *radius;
    let p_error = gamma(5) * (p.abs() + center.abs());
    let uv = if reads.uv { sphere_uv(dir) } else { Vec2::ZERO };
    let dpdu = Vec3::new(-dir.y, dir.x, 0.0);
    (p, p_error, dir, dir, dpdu, uv)
}

/// Mitsuba's sphere emitter sampling seen from `from`: a uniform direction in the cone the
/// sphere subtends from outside, a uniform point by area from inside. The point (before its
/// projection onto the surface) and the solid-angle density; `None` for a degenerate sample.
#[inline]
pub fn sample(center: Vec3, radius: f32, from: Vec3, u: Vec2) -> Option<(Vec3, f32)> {
    let to_c = center - from;
    let dc2 = to_c.length_squared();
    let r2 = radius * radius;
    let (p, pdf_solid) = if dc2 > r2 * (1.0 + 1e-4) {
        let dc = dc2.sqrt();
        let sin_max2 = r2 / dc2;
        let cos_max = (1.0 - sin_max2).max(0.0).sqrt();
        let frame = Frame::from_normal(to_c / dc);
        let local = warp::square_to_uniform_cone(u, cos_max);
        let wi = frame.to_world(local);
        // Nearest intersection of the ray from + t wi with the sphere (clamped for grazing).
        let b = wi.dot(to_c);
        let disc = (r2 - (to_c - b * wi).length_squared()).max(0.0);
        let t = b - disc.sqrt();
        (from + wi * t, warp::uniform_cone_pdf(cos_max))
    } else {
        let d = warp::square_to_uniform_sphere(u);
        let p = center + d * radius;
        let to = p - from;
        let d2 = to.length_squared();
        let cos_l = d.dot(-to.normalize_or_zero()).abs();
        if d2 <= 0.0 || cos_l == 0.0 {
            return None;
        }
        (p, d2 / (cos_l * 4.0 * PI * r2))
    };
    Some((p, pdf_solid))
}

/// The density [`sample`] gives the direction from `from` towards the point `on` of the
/// sphere.
pub fn pdf(center: Vec3, radius: f32, from: Vec3, on: Vec3) -> f32 {
    let to_c = center - from;
    let dc2 = to_c.length_squared();
    let r2 = radius * radius;
    if dc2 > r2 * (1.0 + 1e-4) {
        let cos_max = (1.0 - r2 / dc2).max(0.0).sqrt();
        warp::uniform_cone_pdf(cos_max)
    } else {
        let to = on - from;
        let d2 = to.length_squared();
        let n = (on - center).normalize_or_zero();
        let cos_l = n.dot(to.normalize_or_zero()).abs();
        if cos_l == 0.0 {
            return 0.0;
        }
        d2 / (cos_l * 4.0 * PI * r2)
    }
}
