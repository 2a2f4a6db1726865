//! Disks: the unit disk in the z = 0 plane of a transform.

use super::{Local, gamma};
use crate::accel::Hit;
use crate::math::{Mat4, PI, Vec2, Vec3};

/// Mitsuba's disk parameterisation of the point `d` of the unit disk: u = r, v = φ / 2π.
pub fn disk_uv(d: Vec2) -> Vec2 {
    let phi = d.y.atan2(d.x);
    let phi = if phi < 0.0 { phi + 2.0 * PI } else { phi };
    Vec2::new(d.length(), phi / (2.0 * PI))
}

/// Area of the unit disk under `to_world`.
pub fn area(to_world: &Mat4) -> f32 {
    let ex = to_world.x_axis.truncate();
    let ey = to_world.y_axis.truncate();
    PI * ex.cross(ey).length()
}

/// The interaction at `hit` (object-space `u`, `v` on the disk), before the common tail.
#[inline(always)]
pub(super) fn interaction(to_world: &Mat4, normal: Vec3, hit: &Hit, reads: super::Reads) -> Local {
    let normal = &normal;
    let local = Vec3::new(hit.u, hit.v, 0.0);
    let p = to_world.transform_point3a(local);
    let p_error = gamma(6) * (p.abs() + Vec3::from_vec4(to_world.w_axis).abs());
    let uv = if reads.uv {
        disk_uv(Vec2::new(hit.u, hit.v))
    } else {
        Vec2::ZERO
    };
    let dpdu = Vec3::from_vec4(to_world.x_axis);
    (p, p_error, *normal, *normal, dpdu, uv)
}
