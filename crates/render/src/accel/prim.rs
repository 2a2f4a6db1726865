//! Ray–primitive intersection: watertight triangles (scalar and 4-wide), spheres, disks, planes.
//!
//! All tests report hits with `0 < t < t_max` (both bounds exclusive) in ray-parameter units, so
//! directions need not be normalised. Every function rejects NaN results: a degenerate primitive
//! (zero-area triangle, zero-radius sphere, singular disk transform) never produces a hit.

use crate::geometry::Ray;
use crate::math::{Mat4, Vec3, Vec4};

/// Per-ray constants of the watertight ray–triangle test (Woop, Benthin, Wald 2013, "Watertight
/// Ray/Triangle Intersection", JCGT 2(1)): the ray is permuted so that its dominant axis is `z`
/// and sheared so that it becomes the `+z` axis; triangles are then tested in 2D with edge
/// functions whose signs are computed consistently for an edge shared by two triangles.
#[derive(Clone, Copy, Debug)]
pub struct WoopRay {
    /// Axis permutation `[kx, ky, kz]`, `kz` the dominant axis of the direction.
    pub k: [usize; 3],
    /// Shear constants `(Sx, Sy, Sz)`.
    pub s: Vec3,
    /// Ray origin permuted by `k`.
    pub o: Vec3,
}

impl WoopRay {
    #[inline(always)]
    pub fn new(ray: &Ray) -> WoopRay {
        let d = ray.d;
        let a = d.abs();
        let kz = if a.x > a.y {
            if a.x > a.z { 0 } else { 2 }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        // Array indexing: glam's `Index` for `Vec3` is a three-way match per access.
        let d = d.to_array();
        let o = ray.o.to_array();
        let dz = d[kz];
        // (kz + 1) % 3 and (kz + 2) % 3, swapped to preserve the winding of the triangle (so
        // det has a consistent sign).
        // By table rather than by branch: the sign of the direction is a coin toss.
        const NEXT: [[usize; 3]; 2] = [[1, 2, 0], [2, 0, 1]];
        let neg = (dz < 0.0) as usize;
        let (kx, ky) = (NEXT[neg][kz], NEXT[1 - neg][kz]);
        // One vector division: lane-wise IEEE division gives the same values as three scalar ones.
        let s = Vec4::new(d[kx], d[ky], 1.0, 1.0) / Vec4::splat(dz);
        WoopRay {
            k: [kx, ky, kz],
            s: Vec3::from_vec4(s),
            o: Vec3::new(o[kx], o[ky], o[kz]),
        }
    }
}

/// Watertight ray–triangle intersection for a single triangle. Returns `(t, u, v)` with
/// `p = (1-u-v) p0 + u p1 + v p2`. Both faces are hit.
#[inline]
pub fn intersect_triangle(
    ray: &Ray,
    p0: Vec3,
    p1: Vec3,
    p2: Vec3,
    t_max: f32,
) -> Option<(f32, f32, f32)> {
    triangle_woop(&WoopRay::new(ray), p0, p1, p2, t_max)
}

/// [`intersect_triangle`] with precomputed per-ray constants.
#[inline]
pub fn triangle_woop(
    w: &WoopRay,
    p0: Vec3,
    p1: Vec3,
    p2: Vec3,
    t_max: f32,
) -> Option<(f32, f32, f32)> {
    let [kx, ky, kz] = w.k;
    let (sx, sy, sz) = (w.s.x, w.s.y, w.s.z);
    // Vertices relative to the origin, permuted.
    let ax = p0[kx] - w.o.x;
    let ay = p0[ky] - w.o.y;
    let az = p0[kz] - w.o.z;
    let bx = p1[kx] - w.o.x;
    let by = p1[ky] - w.o.y;
    let bz = p1[kz] - w.o.z;
    let cx = p2[kx] - w.o.x;
    let cy = p2[ky] - w.o.y;
    let cz = p2[kz] - w.o.z;
    // Shear.
    let ax = ax - sx * az;
    let ay = ay - sy * az;
    let bx = bx - sx * bz;
    let by = by - sy * bz;
    let cx = cx - sx * cz;
    let cy = cy - sy * cz;
    // Scaled barycentrics (edge functions).
    let mut u = cx * by - cy * bx;
    let mut v = ax * cy - ay * cx;
    let mut wgt = bx * ay - by * ax;
    if u == 0.0 || v == 0.0 || wgt == 0.0 {
        (u, v, wgt) = edge_functions_f64([ax, ay, bx, by, cx, cy]);
    }
    let max_x = ax.abs().max(bx.abs()).max(cx.abs());
    let max_y = ay.abs().max(by.abs()).max(cy.abs());
    finish_triangle(u, v, wgt, [az, bz, cz], sz, (max_x, max_y), t_max)
}

/// γ(n) = nε/(1 − nε) for ε = 2⁻²⁴ (Higham; pbrt-v4 §6.8).
const fn gamma(n: i32) -> f32 {
    let e = f32::EPSILON * 0.5 * n as f32;
    e / (1.0 - e)
}

/// pbrt-v4's conservative lower bound on a computed triangle t, scaled by |det| (so it compares
/// with |t_scaled| without a division). A hit whose t is within the rounding error of the
/// test itself is rejected: without it, a ray leaving a surface whose coordinates are exact
/// (e.g. a wall in the plane x = 0, where the hit point carries no error to offset by) can
/// re-hit that surface at t ≈ 1e-9.
#[inline(always)]
fn delta_t_scaled(max_x: f32, max_y: f32, max_z: f32, max_e: f32) -> f32 {
    let delta_z = gamma(3) * max_z;
    let delta_x = gamma(5) * (max_x + max_z);
    let delta_y = gamma(5) * (max_y + max_z);
    let delta_e = 2.0 * (gamma(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    3.0 * (gamma(3) * max_e * max_z + delta_e * max_z + delta_z * max_e)
}

/// Edge functions recomputed in double precision: products of two `f32` are exact in `f64`, so
/// the sign of each difference is exact. Used when a single-precision edge function is zero.
#[inline(never)]
#[cold]
fn edge_functions_f64([ax, ay, bx, by, cx, cy]: [f32; 6]) -> (f32, f32, f32) {
    let (ax, ay, bx, by, cx, cy) = (
        f64::from(ax),
        f64::from(ay),
        f64::from(bx),
        f64::from(by),
        f64::from(cx),
        f64::from(cy),
    );
    (
        (cx * by - cy * bx) as f32,
        (ax * cy - ay * cx) as f32,
        (bx * ay - by * ax) as f32,
    )
}

/// Shared tail of the scalar and lane-fallback paths: sign test, depth test, normalisation.
#[inline]
fn finish_triangle(
    u: f32,
    v: f32,
    w: f32,
    z: [f32; 3],
    sz: f32,
    (max_x, max_y): (f32, f32),
    t_max: f32,
) -> Option<(f32, f32, f32)> {
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return None;
    }
    let det = u + v + w;
    if det == 0.0 {
        return None;
    }
    let az = sz * z[0];
    let bz = sz * z[1];
    let cz = sz * z[2];
    let t_scaled = u * az + v * bz + w * cz;
    let sign = if det < 0.0 { -1.0 } else { 1.0 };
    let ts = t_scaled * sign;
    let adet = det * sign;
    let max_z = az.abs().max(bz.abs()).max(cz.abs());
    let max_e = u.abs().max(v.abs()).max(w.abs());
    let floor = delta_t_scaled(max_x, max_y, max_z, max_e);
    if !(ts > floor && ts < t_max * adet) {
        return None;
    }
    // Same operations as the 4-wide path, so both give bit-identical results.
    let t = t_scaled / det;
    if !(t > 0.0 && t < t_max) {
        return None;
    }
    let rcp = 1.0 / det;
    Some((t, v * rcp, w * rcp))
}

/// Four triangles in structure-of-arrays layout for the 4-wide watertight test.
/// `p[vertex][axis]` holds that coordinate of the four triangles; lanes `>= count` are unused.
#[derive(Clone, Copy, Debug)]
pub struct Tri4 {
    pub p: [[Vec4; 3]; 3],
    pub count: u32,
}

impl Tri4 {
    pub fn new(tris: &[[Vec3; 3]]) -> Tri4 {
        assert!(!tris.is_empty() && tris.len() <= 4);
        let mut p = [[[0.0f32; 4]; 3]; 3];
        for lane in 0..4 {
            // Unused lanes repeat the first triangle; they are masked out by `count`.
            let tri = tris.get(lane).unwrap_or(&tris[0]);
            for (vtx, pv) in p.iter_mut().enumerate() {
                for axis in 0..3 {
                    pv[axis][lane] = tri[vtx][axis];
                }
            }
        }
        Tri4 {
            p: p.map(|v| v.map(Vec4::from_array)),
            count: tris.len() as u32,
        }
    }
}

/// Per-ray constants of the 4-wide test (splatted [`WoopRay`]).
#[derive(Clone, Copy, Debug)]
pub struct WoopRay4 {
    pub k: [usize; 3],
    pub sx: Vec4,
    pub sy: Vec4,
    pub sz: Vec4,
    pub ox: Vec4,
    pub oy: Vec4,
    pub oz: Vec4,
}

impl WoopRay4 {
    #[inline]
    pub fn new(w: &WoopRay) -> WoopRay4 {
        WoopRay4 {
            k: w.k,
            sx: Vec4::splat(w.s.x),
            sy: Vec4::splat(w.s.y),
            sz: Vec4::splat(w.s.z),
            ox: Vec4::splat(w.o.x),
            oy: Vec4::splat(w.o.y),
            oz: Vec4::splat(w.o.z),
        }
    }
}

/// Result of the 4-wide test before normalisation: a lane mask of hits and per-lane values.
struct Tri4Eval {
    mask: u32,
    v: Vec4,
    w: Vec4,
    t_scaled: Vec4,
    det: Vec4,
}

#[inline(always)]
fn tri4_eval(w: &WoopRay4, tri: &Tri4, t_max: f32) -> Tri4Eval {
    let [kx, ky, kz] = w.k;
    let [p0, p1, p2] = &tri.p;
    let az = p0[kz] - w.oz;
    let bz = p1[kz] - w.oz;
    let cz = p2[kz] - w.oz;
    let ax = (p0[kx] - w.ox) - w.sx * az;
    let ay = (p0[ky] - w.oy) - w.sy * az;
    let bx = (p1[kx] - w.ox) - w.sx * bz;
    let by = (p1[ky] - w.oy) - w.sy * bz;
    let cx = (p2[kx] - w.ox) - w.sx * cz;
    let cy = (p2[ky] - w.oy) - w.sy * cz;
    let mut u = cx * by - cy * bx;
    let mut v = ax * cy - ay * cx;
    let mut wg = bx * ay - by * ax;
    let lanes = (1u32 << tri.count) - 1;
    let zero = (u.cmpeq(Vec4::ZERO) | v.cmpeq(Vec4::ZERO) | wg.cmpeq(Vec4::ZERO)).bitmask() & lanes;
    if zero != 0 {
        // Rare: the ray passes exactly through an edge or vertex in the sheared frame.
        let (axa, aya, bxa, bya, cxa, cya) = (
            ax.to_array(),
            ay.to_array(),
            bx.to_array(),
            by.to_array(),
            cx.to_array(),
            cy.to_array(),
        );
        let (mut ua, mut va, mut wa) = (u.to_array(), v.to_array(), wg.to_array());
        let mut bits = zero;
        while bits != 0 {
            let i = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            (ua[i], va[i], wa[i]) =
                edge_functions_f64([axa[i], aya[i], bxa[i], bya[i], cxa[i], cya[i]]);
        }
        (u, v, wg) = (
            Vec4::from_array(ua),
            Vec4::from_array(va),
            Vec4::from_array(wa),
        );
    }
    let neg = u.cmplt(Vec4::ZERO) | v.cmplt(Vec4::ZERO) | wg.cmplt(Vec4::ZERO);
    let pos = u.cmpgt(Vec4::ZERO) | v.cmpgt(Vec4::ZERO) | wg.cmpgt(Vec4::ZERO);
    let inside = !(neg & pos).bitmask() & lanes;
    let det = u + v + wg;
    if inside == 0 {
        // Most packets miss on the edge test: skip the depth test and its error bound.
        return Tri4Eval {
            mask: 0,
            v,
            w: wg,
            t_scaled: Vec4::ZERO,
            det,
        };
    }
    let t_scaled = u * (w.sz * az) + v * (w.sz * bz) + wg * (w.sz * cz);
    // Multiplying by ±1 is exact: this is |det| and t_scaled·sign(det).
    let sign = Vec4::select(det.cmplt(Vec4::ZERO), Vec4::NEG_ONE, Vec4::ONE);
    let ts = t_scaled * sign;
    let adet = det * sign;
    let in_range = ts.cmpgt(Vec4::ZERO) & ts.cmplt(Vec4::splat(t_max) * adet);
    if in_range.bitmask() & inside == 0 {
        // Inside the edges but behind the origin or beyond t_max (typically a shadow ray
        // passing through the emitter it ends at): the error floor below is positive, so it
        // cannot accept these lanes; skip computing it.
        return Tri4Eval {
            mask: 0,
            v,
            w: wg,
            t_scaled,
            det,
        };
    }
    let (szs_a, szs_b, szs_c) = ((w.sz * az).abs(), (w.sz * bz).abs(), (w.sz * cz).abs());
    let max_z = szs_a.max(szs_b).max(szs_c);
    let max_x = ax.abs().max(bx.abs()).max(cx.abs());
    let max_y = ay.abs().max(by.abs()).max(cy.abs());
    let max_e = u.abs().max(v.abs()).max(wg.abs());
    let delta_z = gamma(3) * max_z;
    let delta_x = gamma(5) * (max_x + max_z);
    let delta_y = gamma(5) * (max_y + max_z);
    let delta_e = 2.0 * (gamma(2) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    let floor = 3.0 * (gamma(3) * max_e * max_z + delta_e * max_z + delta_z * max_e);
    let ok = ts.cmpgt(floor) & in_range & det.cmpne(Vec4::ZERO);
    let mask = ok.bitmask() & inside;
    Tri4Eval {
        mask,
        v,
        w: wg,
        t_scaled,
        det,
    }
}

/// Closest hit among the four triangles: `(lane, t, u, v)`.
#[inline(always)]
pub fn tri4_closest(w: &WoopRay4, tri: &Tri4, t_max: f32) -> Option<(usize, f32, f32, f32)> {
    let e = tri4_eval(w, tri, t_max);
    if e.mask == 0 {
        return None;
    }
    let t = e.t_scaled / e.det;
    let ta = t.to_array();
    let mut best: Option<usize> = None;
    let mut best_t = t_max;
    let mut bits = e.mask;
    while bits != 0 {
        let i = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        let ti = ta[i];
        if ti > 0.0 && ti < best_t && ti.is_finite() {
            best_t = ti;
            best = Some(i);
        }
    }
    let i = best?;
    let det = e.det.to_array()[i];
    let rcp = 1.0 / det;
    Some((i, best_t, e.v.to_array()[i] * rcp, e.w.to_array()[i] * rcp))
}

/// Whether any of the four triangles is hit.
#[inline(always)]
pub fn tri4_any(w: &WoopRay4, tri: &Tri4, t_max: f32) -> bool {
    let e = tri4_eval(w, tri, t_max);
    if e.mask == 0 {
        return false;
    }
    // The integer-free tests above guarantee 0 < t < t_max up to the final division's rounding;
    // confirm with the same strict test the closest-hit path uses.
    let t = (e.t_scaled / e.det).to_array();
    let mut bits = e.mask;
    while bits != 0 {
        let i = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        if t[i] > 0.0 && t[i] < t_max {
            return true;
        }
    }
    false
}

/// Robust ray–sphere intersection (pbrt-v4 §6.8.1 / Ray Tracing Gems ch. 7): the discriminant
/// is computed from the distance of the centre to the ray line, which avoids the catastrophic
/// cancellation of `b² - 4ac` for distant and grazing rays. Returns the nearest `t` in
/// `(0, t_max)`; from inside the sphere that is the exit point.
#[inline]
pub fn intersect_sphere(ray: &Ray, center: Vec3, radius: f32, t_max: f32) -> Option<f32> {
    let f = ray.o - center;
    let a = ray.d.length_squared();
    if a.is_nan() || a <= 0.0 {
        return None;
    }
    let b = 2.0 * f.dot(ray.d);
    let c = f.length_squared() - radius * radius;
    // Vector from the centre to the closest point of the ray line.
    let l = f - (b / (2.0 * a)) * ray.d;
    let len = l.length();
    let disc = 4.0 * a * (radius + len) * (radius - len);
    if disc.is_nan() || disc < 0.0 {
        return None;
    }
    let root = disc.sqrt();
    let q = if b < 0.0 {
        -0.5 * (b - root)
    } else {
        -0.5 * (b + root)
    };
    let mut t0 = q / a;
    let mut t1 = if q != 0.0 { c / q } else { t0 };
    if t0 > t1 {
        std::mem::swap(&mut t0, &mut t1);
    }
    if t0 > 0.0 && t0 < t_max {
        Some(t0)
    } else if t1 > 0.0 && t1 < t_max {
        Some(t1)
    } else {
        None
    }
}

/// Ray–ellipsoid intersection: the unit sphere at the origin of the object space that
/// `to_object` (the inverse of the ellipsoid's `to_world`) maps into. The ray goes to object
/// space unnormalised, so the affine map preserves `t` and the robust sphere test applies.
#[inline]
pub fn intersect_ellipsoid(ray: &Ray, to_object: &Mat4, t_max: f32) -> Option<f32> {
    let local = Ray::new(
        to_object.transform_point3a(ray.o),
        to_object.transform_vector3a(ray.d),
    );
    intersect_sphere(&local, Vec3::ZERO, 1.0, t_max)
}

/// Ray–disk intersection. `to_object` is the inverse of the disk's `to_world`; the disk is the
/// unit disk in the object-space `z = 0` plane. Returns `(t, x, y)` with object-space `x, y`.
/// `t` is preserved by the affine map, so it is in the caller's ray-parameter units.
#[inline]
pub fn intersect_disk(ray: &Ray, to_object: &Mat4, t_max: f32) -> Option<(f32, f32, f32)> {
    let o = to_object.transform_point3a(ray.o);
    let d = to_object.transform_vector3a(ray.d);
    if d.z == 0.0 {
        return None;
    }
    let t = -o.z / d.z;
    if !(t > 0.0 && t < t_max) {
        return None;
    }
    let x = o.x + t * d.x;
    let y = o.y + t * d.y;
    if x * x + y * y <= 1.0 {
        Some((t, x, y))
    } else {
        None
    }
}

/// Ray–plane intersection (both sides).
#[inline]
pub fn intersect_plane(ray: &Ray, point: Vec3, normal: Vec3, t_max: f32) -> Option<f32> {
    let denom = normal.dot(ray.d);
    if denom == 0.0 {
        return None;
    }
    let t = (point - ray.o).dot(normal) / denom;
    if t > 0.0 && t < t_max { Some(t) } else { None }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tri4_matches_scalar() {
        let mut s = 12345u32;
        let mut rnd = || {
            s ^= s << 13;
            s ^= s >> 17;
            s ^= s << 5;
            (s as f32 / u32::MAX as f32) * 2.0 - 1.0
        };
        for _ in 0..2000 {
            let tris: Vec<[Vec3; 3]> = (0..3)
                .map(|_| {
                    [
                        Vec3::new(rnd(), rnd(), rnd()),
                        Vec3::new(rnd(), rnd(), rnd()),
                        Vec3::new(rnd(), rnd(), rnd()),
                    ]
                })
                .collect();
            let ray = Ray::new(
                Vec3::new(rnd(), rnd(), rnd()) * 3.0,
                Vec3::new(rnd(), rnd(), rnd()),
            );
            let w = WoopRay::new(&ray);
            let w4 = WoopRay4::new(&w);
            let t4 = Tri4::new(&tris);
            let mut best: Option<(usize, f32, f32, f32)> = None;
            for (i, t) in tris.iter().enumerate() {
                if let Some((th, u, v)) = triangle_woop(&w, t[0], t[1], t[2], 10.0)
                    && best.is_none_or(|b| th < b.1)
                {
                    best = Some((i, th, u, v));
                }
            }
            let simd = tri4_closest(&w4, &t4, 10.0);
            match (best, simd) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    assert_eq!(a.0, b.0);
                    assert_eq!(a.1, b.1);
                    assert!((a.2 - b.2).abs() < 1e-6 && (a.3 - b.3).abs() < 1e-6);
                }
                _ => panic!("scalar {best:?} vs simd {simd:?}"),
            }
            assert_eq!(tri4_any(&w4, &t4, 10.0), best.is_some());
        }
    }
}
