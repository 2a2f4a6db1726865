//! Infinite planes (tested beside the BVH; never emitters).

use super::{Local, gamma};
use crate::accel::Hit;
use crate::geometry::Ray;
use crate::math::{Frame, Vec2, Vec3};

/// The interaction at `hit` on the plane through `point` with normal `normal`, before the
/// common tail.
#[inline(always)]
pub(super) fn interaction(point: Vec3, normal: Vec3, hit: &Hit, ray: &Ray) -> Local {
    let point = &point;
    let normal = &normal;
    let raw = ray.at(hit.t);
    // Project onto the plane to remove the error along the normal.
    let p = raw - *normal * (raw - *point).dot(*normal);
    let p_error = gamma(6) * (p.abs() + point.abs());
    let frame = Frame::from_normal(*normal);
    let uv = Vec2::new((p - *point).dot(frame.s), (p - *point).dot(frame.t));
    (p, p_error, *normal, *normal, frame.s, uv)
}
