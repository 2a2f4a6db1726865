//! Ray–primitive intersection: watertight triangles (scalar and 4-wide), spheres, disks, planes.
//!
//! All tests report hits with `0 < t < t_max` (both bounds exclusive) in ray-parameter units, so
//! directions need not be normalised. Every function rejects NaN results: a degenerate primitive
//! (zero-area triangle, zero-radius sphere, singular disk transform) never produces a hit.

use crate::geometry::Ray;
use crate::math::{Mat4, Vec3, Vec4};
use wide::{f32x4, f32x8};

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

/// The lane operations of the N-wide triangle test, for `wide`'s `f32x4` (SSE) and `f32x8`
/// (AVX). Every operation is the plain IEEE one per lane, so all widths give the scalar
/// test's values bit for bit.
pub trait Lanes:
    Copy
    + std::ops::Add<Output = Self>
    + std::ops::Sub<Output = Self>
    + std::ops::Mul<Output = Self>
    + std::ops::Div<Output = Self>
    + std::ops::BitAnd<Output = Self>
    + std::ops::BitOr<Output = Self>
    + std::ops::BitXor<Output = Self>
    + std::ops::Not<Output = Self>
{
    /// Lanes.
    const N: usize;
    type Array: AsRef<[f32]> + AsMut<[f32]>;
    fn splat(x: f32) -> Self;
    fn from_array(a: Self::Array) -> Self;
    fn to_array(self) -> Self::Array;
    fn abs(self) -> Self;
    /// `maxps`: the second operand where either is NaN.
    fn max(self, o: Self) -> Self;
    /// `minps`: the second operand where either is NaN.
    fn min(self, o: Self) -> Self;
    /// Per lane, `t` where `self` (a comparison result) is set, else `f`.
    fn select(self, t: Self, f: Self) -> Self;
    fn lt(self, o: Self) -> Self;
    fn gt(self, o: Self) -> Self;
    fn eq(self, o: Self) -> Self;
    fn ne(self, o: Self) -> Self;
    /// Bit `i` set where lane `i` of a comparison result is true.
    fn bits(self) -> u32;
}

macro_rules! lanes {
    ($t:ty, $n:literal) => {
        impl Lanes for $t {
            const N: usize = $n;
            type Array = [f32; $n];
            #[inline(always)]
            fn splat(x: f32) -> Self {
                <$t>::splat(x)
            }
            #[inline(always)]
            fn from_array(a: [f32; $n]) -> Self {
                <$t>::new(a)
            }
            #[inline(always)]
            fn to_array(self) -> [f32; $n] {
                <$t>::to_array(self)
            }
            #[inline(always)]
            fn abs(self) -> Self {
                <$t>::abs(self)
            }
            #[inline(always)]
            fn max(self, o: Self) -> Self {
                <$t>::fast_max(self, o)
            }
            #[inline(always)]
            fn min(self, o: Self) -> Self {
                <$t>::fast_min(self, o)
            }
            #[inline(always)]
            fn select(self, t: Self, f: Self) -> Self {
                <$t>::bitselect(self, t, f)
            }
            #[inline(always)]
            fn lt(self, o: Self) -> Self {
                <$t>::simd_lt(self, o)
            }
            #[inline(always)]
            fn gt(self, o: Self) -> Self {
                <$t>::simd_gt(self, o)
            }
            #[inline(always)]
            fn eq(self, o: Self) -> Self {
                <$t>::simd_eq(self, o)
            }
            #[inline(always)]
            fn ne(self, o: Self) -> Self {
                <$t>::simd_ne(self, o)
            }
            #[inline(always)]
            fn bits(self) -> u32 {
                <$t>::to_bitmask(self)
            }
        }
    };
}
lanes!(f32x4, 4);
lanes!(f32x8, 8);

/// `N` triangles in structure-of-arrays layout for the N-wide watertight test:
/// `p[vertex][axis]` holds that coordinate of every lane's triangle. Packets with fewer
/// triangles repeat their first triangle in the unused lanes: a repeated lane finds exactly
/// the first lane's hit, which it never displaces (ties keep the lowest lane).
#[derive(Clone, Copy, Debug)]
pub struct TriPacket<L> {
    pub p: [[L; 3]; 3],
}

/// Four triangles (SSE).
pub type Tri4 = TriPacket<f32x4>;
/// Eight triangles (AVX; two SSE halves without it).
pub type Tri8 = TriPacket<f32x8>;

impl<L: Lanes> TriPacket<L> {
    /// A packet of 1 to `L::N` triangles.
    pub fn new(tris: &[[Vec3; 3]]) -> TriPacket<L> {
        assert!(!tris.is_empty() && tris.len() <= L::N);
        let mut p: [[L::Array; 3]; 3] =
            std::array::from_fn(|_| std::array::from_fn(|_| L::splat(0.0).to_array()));
        for lane in 0..L::N {
            let tri = tris.get(lane).unwrap_or(&tris[0]);
            for (vtx, pv) in p.iter_mut().enumerate() {
                for axis in 0..3 {
                    pv[axis].as_mut()[lane] = tri[vtx][axis];
                }
            }
        }
        TriPacket {
            p: p.map(|v| v.map(L::from_array)),
        }
    }
}

/// Per-ray constants of the N-wide test (splatted [`WoopRay`]).
#[derive(Clone, Copy, Debug)]
pub struct WoopRayN<L> {
    pub k: [usize; 3],
    pub sx: L,
    pub sy: L,
    pub sz: L,
    pub ox: L,
    pub oy: L,
    pub oz: L,
}

pub type WoopRay4 = WoopRayN<f32x4>;
pub type WoopRay8 = WoopRayN<f32x8>;

impl<L: Lanes> WoopRayN<L> {
    #[inline(always)]
    pub fn new(w: &WoopRay) -> WoopRayN<L> {
        WoopRayN {
            k: w.k,
            sx: L::splat(w.s.x),
            sy: L::splat(w.s.y),
            sz: L::splat(w.s.z),
            ox: L::splat(w.o.x),
            oy: L::splat(w.o.y),
            oz: L::splat(w.o.z),
        }
    }
}

/// Result of the N-wide test before normalisation: the lanes hit (as a bit mask and as a
/// comparison result) and per-lane values.
struct TriEval<L> {
    mask: u32,
    hit: L,
    v: L,
    w: L,
    t_scaled: L,
    det: L,
}

#[inline(always)]
fn tri_eval<L: Lanes>(w: &WoopRayN<L>, tri: &TriPacket<L>, t_max: f32) -> TriEval<L> {
    let [kx, ky, kz] = w.k;
    let [p0, p1, p2] = &tri.p;
    let zero = L::splat(0.0);
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
    let zeros = (u.eq(zero) | v.eq(zero) | wg.eq(zero)).bits();
    if zeros != 0 {
        // Rare: the ray passes exactly through an edge or vertex in the sheared frame.
        (u, v, wg) = edge_lanes_f64(zeros, [ax, ay, bx, by, cx, cy], [u, v, wg]);
    }
    let neg = u.lt(zero) | v.lt(zero) | wg.lt(zero);
    let pos = u.gt(zero) | v.gt(zero) | wg.gt(zero);
    let outside = neg & pos;
    let inside = !outside.bits() & ((1u32 << L::N) - 1);
    let det = u + v + wg;
    if inside == 0 {
        // Most packets miss on the edge test: skip the depth test and its error bound.
        return TriEval {
            mask: 0,
            hit: zero,
            v,
            w: wg,
            t_scaled: zero,
            det,
        };
    }
    let (sza, szb, szc) = (w.sz * az, w.sz * bz, w.sz * cz);
    let t_scaled = u * sza + v * szb + wg * szc;
    // |det| and t_scaled·sign(det): flipping the sign bit is the exact product by ±1.
    let sign = det & L::splat(-0.0);
    let ts = t_scaled ^ sign;
    let adet = det ^ sign;
    let in_range = ts.gt(zero) & ts.lt(L::splat(t_max) * adet);
    if in_range.bits() & inside == 0 {
        // Inside the edges but behind the origin or beyond t_max (typically a shadow ray
        // passing through the emitter it ends at): the error floor below is positive, so it
        // cannot accept these lanes; skip computing it.
        return TriEval {
            mask: 0,
            hit: zero,
            v,
            w: wg,
            t_scaled,
            det,
        };
    }
    let max_z = sza.abs().max(szb.abs()).max(szc.abs());
    let max_x = ax.abs().max(bx.abs()).max(cx.abs());
    let max_y = ay.abs().max(by.abs()).max(cy.abs());
    let max_e = u.abs().max(v.abs()).max(wg.abs());
    let delta_z = L::splat(gamma(3)) * max_z;
    let delta_x = L::splat(gamma(5)) * (max_x + max_z);
    let delta_y = L::splat(gamma(5)) * (max_y + max_z);
    let delta_e =
        L::splat(2.0) * (L::splat(gamma(2)) * max_x * max_y + delta_y * max_x + delta_x * max_y);
    let floor =
        L::splat(3.0) * (L::splat(gamma(3)) * max_e * max_z + delta_e * max_z + delta_z * max_e);
    let hit = ts.gt(floor) & in_range & det.ne(zero) & !outside;
    TriEval {
        mask: hit.bits(),
        hit,
        v,
        w: wg,
        t_scaled,
        det,
    }
}

/// The edge functions of the lanes in `lanes` recomputed in double precision (see
/// [`edge_functions_f64`]).
#[inline(never)]
#[cold]
fn edge_lanes_f64<L: Lanes>(lanes: u32, e: [L; 6], uvw: [L; 3]) -> (L, L, L) {
    let e = e.map(L::to_array);
    let [mut u, mut v, mut w] = uvw.map(L::to_array);
    let mut bits = lanes;
    while bits != 0 {
        let i = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        let c = |k: usize| e[k].as_ref()[i];
        (u.as_mut()[i], v.as_mut()[i], w.as_mut()[i]) =
            edge_functions_f64([c(0), c(1), c(2), c(3), c(4), c(5)]);
    }
    (L::from_array(u), L::from_array(v), L::from_array(w))
}

/// Closest hit among the packet's triangles: `(lane, t, u, v)`.
#[inline(always)]
pub fn tri_closest<L: Lanes>(
    w: &WoopRayN<L>,
    tri: &TriPacket<L>,
    t_max: f32,
) -> Option<(usize, f32, f32, f32)> {
    let e = tri_eval(w, tri, t_max);
    if e.mask == 0 {
        return None;
    }
    // The lanes whose rounded `t` lies in (0, t_max) (NaN and infinities fail); the nearest
    // of them without a loop over the lanes: leaves of fewer triangles repeat their first in
    // the unused lanes, so the number of hit lanes varied and a loop over them mispredicted
    // (7 % of bench-cbox's mispredicted branches). Ties keep the lowest lane, as the loop did.
    let t = e.t_scaled / e.det;
    let zero = L::splat(0.0);
    let ok = e.hit & t.gt(zero) & t.lt(L::splat(t_max));
    let bits = ok.bits();
    if bits == 0 {
        return None;
    }
    let tm = ok.select(t, L::splat(f32::INFINITY));
    let best_t = tm
        .to_array()
        .as_ref()
        .iter()
        .fold(f32::INFINITY, |a, &b| if b < a { b } else { a });
    let i = (tm.eq(L::splat(best_t)).bits() & bits).trailing_zeros() as usize;
    let det = e.det.to_array().as_ref()[i];
    let rcp = 1.0 / det;
    Some((
        i,
        best_t,
        e.v.to_array().as_ref()[i] * rcp,
        e.w.to_array().as_ref()[i] * rcp,
    ))
}

/// Whether any of the packet's triangles is hit.
#[inline(always)]
pub fn tri_any<L: Lanes>(w: &WoopRayN<L>, tri: &TriPacket<L>, t_max: f32) -> bool {
    let e = tri_eval(w, tri, t_max);
    if e.mask == 0 {
        return false;
    }
    // The integer-free tests above guarantee 0 < t < t_max up to the final division's rounding;
    // confirm with the same strict test the closest-hit path uses.
    let t = e.t_scaled / e.det;
    (e.hit & t.gt(L::splat(0.0)) & t.lt(L::splat(t_max))).bits() != 0
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
    let (t0, t1) = quadratic_roots(a, b, c, disc)?;
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

/// Ray–cylinder intersection: the open unit cylinder x² + y² = 1, 0 ≤ z ≤ 1 of the object
/// space `to_object` maps into (Mitsuba's `cylinder`, no caps). The nearest `t` in
/// `(0, t_max)` whose point lies between the ends. The discriminant is computed from the
/// distance of the axis to the ray line, as in [`intersect_sphere`], against cancellation.
#[inline]
pub fn intersect_cylinder(ray: &Ray, to_object: &Mat4, t_max: f32) -> Option<f32> {
    let o = to_object.transform_point3a(ray.o);
    let d = to_object.transform_vector3a(ray.d);
    let a = d.x * d.x + d.y * d.y;
    if a.is_nan() || a <= 0.0 {
        return None;
    }
    let b = 2.0 * (o.x * d.x + o.y * d.y);
    let c = o.x * o.x + o.y * o.y - 1.0;
    let h = b / (2.0 * a);
    let (lx, ly) = (o.x - h * d.x, o.y - h * d.y);
    let len = (lx * lx + ly * ly).sqrt();
    let disc = 4.0 * a * (1.0 + len) * (1.0 - len);
    let (t0, t1) = quadratic_roots(a, b, c, disc)?;
    [t0, t1].into_iter().find(|&t| {
        let z = o.z + t * d.z;
        t > 0.0 && t < t_max && (0.0..=1.0).contains(&z)
    })
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

/// The roots t0 ≤ t1 of a·t² + b·t + c = 0 (a > 0) from its discriminant `disc`, which the
/// caller computes in a cancellation-free form (pbrt-v4's); `None` when it is negative or
/// NaN. The larger-magnitude root first, the other as c/q (no cancellation).
#[inline]
fn quadratic_roots(a: f32, b: f32, c: f32, disc: f32) -> Option<(f32, f32)> {
    if disc.is_nan() || disc < 0.0 {
        return None;
    }
    let root = disc.sqrt();
    let q = if b < 0.0 {
        -0.5 * (b - root)
    } else {
        -0.5 * (b + root)
    };
    let t0 = q / a;
    let t1 = if q != 0.0 { c / q } else { t0 };
    Some(if t0 > t1 { (t1, t0) } else { (t0, t1) })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn packets_match_scalar() {
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
            let w8 = WoopRay8::new(&w);
            let t8 = Tri8::new(&tris);
            let mut best: Option<(usize, f32, f32, f32)> = None;
            for (i, t) in tris.iter().enumerate() {
                if let Some((th, u, v)) = triangle_woop(&w, t[0], t[1], t[2], 10.0)
                    && best.is_none_or(|b| th < b.1)
                {
                    best = Some((i, th, u, v));
                }
            }
            let simd = tri_closest(&w4, &t4, 10.0);
            assert_eq!(
                format!("{simd:?}"),
                format!("{:?}", tri_closest(&w8, &t8, 10.0))
            );
            match (best, simd) {
                (None, None) => {}
                (Some(a), Some(b)) => {
                    assert_eq!(a.0, b.0);
                    assert_eq!(a.1, b.1);
                    assert!((a.2 - b.2).abs() < 1e-6 && (a.3 - b.3).abs() < 1e-6);
                }
                _ => panic!("scalar {best:?} vs simd {simd:?}"),
            }
            assert_eq!(tri_any(&w4, &t4, 10.0), best.is_some());
            assert_eq!(tri_any(&w8, &t8, 10.0), best.is_some());
        }
    }
}
