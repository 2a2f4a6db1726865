//! Runtime shapes: the world-space geometry behind each `Accel` shape, and the surface
//! interaction computed from a hit (position with its floating-point error bound, normals,
//! shading frame, uv).
//!
//! Rectangles and cubes are meshed at build time (2 and 12 triangles, as Mitsuba does), so at
//! run time there are four kinds: triangle meshes, spheres, disks and infinite planes.
//!
//! Robust spawning (pbrt-v4 §6.8): every hit point carries a conservative bound `p_error` of
//! its rounding error; rays leave along the geometric normal by exactly that bound (rounded
//! away from the surface), so there is neither self-intersection nor a light leak, whatever
//! the scene scale.

use std::sync::Arc;

use crate::accel::{AccelShape, Hit};
use crate::geometry::Ray;
use glam::Mat3A;

use crate::math::{Frame, Mat3, Mat4, PI, Vec2, Vec3, normalize_or_zero_fast, rsqrt};
use crate::textures::{ColorRef, FloatRef};

/// γ(n) of Higham / pbrt: a bound on the relative error of n floating-point operations.
#[inline]
pub fn gamma(n: i32) -> f32 {
    let e = f32::EPSILON * 0.5 * n as f32;
    e / (1.0 - e)
}

#[derive(Clone, Debug)]
pub enum ShapeGeom {
    Mesh {
        positions: Arc<[Vec3]>,
        normals: Option<Arc<[Vec3]>>,
        uvs: Option<Arc<[Vec2]>>,
        indices: Arc<[[u32; 3]]>,
    },
    Sphere {
        center: Vec3,
        radius: f32,
    },
    /// Unit disk in the z = 0 plane of `to_world`.
    Disk {
        to_world: Mat4,
        normal: Vec3,
    },
    /// The unit sphere at the origin of `to_world`'s object space: an ellipsoid under a
    /// non-uniform scale or a shear (CENG795 spheres with transformations). Hits are found in
    /// object space; normals go to world space by the inverse transpose.
    Ellipsoid(Box<Ellipsoid>),
    Plane {
        point: Vec3,
        normal: Vec3,
    },
    /// An instance of a shared prototype mesh, or a moving shape (see [`Instance`]).
    Instance(Box<Instance>),
}

impl ShapeGeom {
    pub fn accel_shape(&self) -> AccelShape {
        match self {
            ShapeGeom::Mesh {
                positions, indices, ..
            } => AccelShape::Triangles {
                positions: positions.clone(),
                indices: indices.clone(),
            },
            ShapeGeom::Sphere { center, radius } => AccelShape::Sphere {
                center: *center,
                radius: *radius,
            },
            ShapeGeom::Disk { to_world, .. } => AccelShape::Disk {
                to_world: *to_world,
            },
            ShapeGeom::Ellipsoid(e) => AccelShape::Ellipsoid {
                to_world: e.to_world,
            },
            ShapeGeom::Plane { point, normal } => AccelShape::Plane {
                point: *point,
                normal: *normal,
            },
            ShapeGeom::Instance(i) => AccelShape::Instance {
                proto: i.proto,
                to_world: i.to_world,
                motion: i.motion,
            },
        }
    }

    /// Surface area in world space (infinite for planes).
    pub fn area(&self) -> f32 {
        match self {
            ShapeGeom::Mesh {
                positions, indices, ..
            } => indices
                .iter()
                .map(|t| {
                    let [a, b, c] = t.map(|i| positions[i as usize]);
                    0.5 * (b - a).cross(c - a).length()
                })
                .sum(),
            ShapeGeom::Sphere { radius, .. } => 4.0 * PI * radius * radius,
            ShapeGeom::Disk { to_world, .. } => {
                let ex = to_world.x_axis.truncate();
                let ey = to_world.y_axis.truncate();
                PI * ex.cross(ey).length()
            }
            ShapeGeom::Ellipsoid(e) => e.area,
            ShapeGeom::Plane { .. } => f32::INFINITY,
            ShapeGeom::Instance(i) => match &i.base {
                ShapeGeom::Mesh {
                    positions, indices, ..
                } => indices
                    .iter()
                    .map(|t| {
                        let [a, b, c] =
                            t.map(|k| i.to_world.transform_point3a(positions[k as usize]));
                        0.5 * (b - a).cross(c - a).length()
                    })
                    .sum(),
                // Moving shapes: a translation keeps the area.
                base => base.area(),
            },
        }
    }

    /// Triangles of the shape (an instance counts its prototype's).
    pub fn triangle_count(&self) -> usize {
        match self {
            ShapeGeom::Mesh { indices, .. } => indices.len(),
            ShapeGeom::Instance(i) => i.base.triangle_count(),
            _ => 0,
        }
    }
}

/// A shape seen through a placement (an instance of a prototype mesh) and moving by a
/// translation over the shutter: at time τ its world geometry is `to_world(x) + τ·motion`.
///
/// Hits are found in the prototype's space (`accel`'s two-level part); the interaction is
/// computed from the hit triangle's vertices mapped to world space with the same arithmetic
/// the flattened copy of the mesh uses, so shading is the same as for a copy (up to the
/// rounding of the barycentrics, which the object-space test finds). The error bound adds the
/// rounding of mapping the spawned ray back into the prototype's space.
#[derive(Clone, Debug)]
pub struct Instance {
    /// A prototype mesh in its object space (its arrays shared by every instance of it), or
    /// for a moving shape that is not instanced, the shape itself at time 0 (`to_world` the
    /// identity).
    pub base: ShapeGeom,
    /// Index of the accelerator's bottom-level tree for `base`.
    pub proto: u32,
    pub to_world: Mat4,
    /// Inverse transpose of `to_world`'s linear part (object normal → world normal).
    pub normal_matrix: Mat3,
    /// `to_world` mirrors: the winding is reversed, as `build`'s flattened meshes do.
    pub mirror: bool,
    /// World translation over the shutter interval [0, 1].
    pub motion: Vec3,
    /// |linear part| of `to_world` and of its inverse, and |translation of the inverse|, for
    /// the error bound.
    abs_m: Mat3A,
    abs_inv: Mat3A,
    abs_inv_t: Vec3,
}

impl Instance {
    /// `None` for a singular or non-finite placement.
    pub fn new(base: ShapeGeom, proto: u32, to_world: Mat4, motion: Vec3) -> Option<Instance> {
        let inv = to_world.inverse();
        let det = Mat3::from_mat4(to_world).determinant();
        if det == 0.0 || !det.is_finite() || !inv.is_finite() || !to_world.is_finite() {
            return None;
        }
        let abs = |m: Mat3A| Mat3A::from_cols(m.x_axis.abs(), m.y_axis.abs(), m.z_axis.abs());
        Some(Instance {
            base,
            proto,
            to_world,
            normal_matrix: Mat3::from_mat4(to_world).inverse().transpose(),
            mirror: det < 0.0,
            motion: if motion.is_finite() {
                motion
            } else {
                Vec3::ZERO
            },
            abs_m: abs(Mat3A::from_mat4(to_world)),
            abs_inv: abs(Mat3A::from_mat4(inv)),
            abs_inv_t: Vec3::from_vec4(inv.w_axis).abs(),
        })
    }

    /// Added to a world point's error bound: the rounding of the shift by `τ·motion` and of
    /// the map into the prototype's space that the next query applies (generously, γ₈).
    #[inline]
    fn extra_error(&self, p: Vec3, shift: Vec3) -> Vec3 {
        let a = p.abs() + shift.abs();
        gamma(8) * (self.abs_m * (self.abs_inv * a + self.abs_inv_t) + a)
    }
}

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
        crate::textures::TexCoord {
            uv: self.uv,
            p: self.p,
        }
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

/// What shading at a shape reads of its interactions beyond position and normals, fixed at
/// build time (see [`ShapeInfo`]); [`interaction`] skips computing the rest.
/// Mitsuba's ray flags serve the same purpose.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Reads {
    /// How the tangent turns about the normal (normal maps, anisotropic roughness). Without
    /// it a triangle's tangent is its first edge rather than `∂p/∂u` of its uv
    /// parameterisation: no solve for `∂p/∂u` and no Gram–Schmidt step. Isotropic BSDFs only
    /// map random numbers to directions differently; no distribution changes.
    pub tangent: bool,
    /// The uv coordinates (textures). Without them `uv` holds a triangle's barycentrics, or
    /// zero on spheres and disks (no trigonometry).
    pub uv: bool,
}

/// Mitsuba's sphere parameterisation of the unit direction `dir` from the centre:
/// u = φ / 2π, v = θ / π (θ from +z).
pub fn sphere_uv(dir: Vec3) -> Vec2 {
    let phi = dir.y.atan2(dir.x);
    let phi = if phi < 0.0 { phi + 2.0 * PI } else { phi };
    let theta = dir.z.clamp(-1.0, 1.0).acos();
    Vec2::new(phi / (2.0 * PI), theta / PI)
}

/// Mitsuba's disk parameterisation of the point `d` of the unit disk: u = r, v = φ / 2π.
pub fn disk_uv(d: Vec2) -> Vec2 {
    let phi = d.y.atan2(d.x);
    let phi = if phi < 0.0 { phi + 2.0 * PI } else { phi };
    Vec2::new(d.length(), phi / (2.0 * PI))
}

/// Compute the surface interaction of `hit` on `geom`. `flip` flips both normals; `reads`
/// says what the caller's shading reads (the rest is skipped).
pub fn interaction(
    geom: &ShapeGeom,
    hit: &Hit,
    ray: &Ray,
    flip: bool,
    reads: Reads,
) -> SurfaceInteraction {
    let wo = -ray.d * rsqrt(ray.d.length_squared());
    let (p, p_error, ng, ns, dpdu, uv) = match geom {
        ShapeGeom::Mesh {
            positions,
            normals,
            uvs,
            indices,
        } => {
            let idx = indices[hit.prim as usize].map(|i| i as usize);
            let p = idx.map(|i| positions[i]);
            return mesh_interaction(
                p,
                idx,
                normals.as_deref(),
                |n| n,
                uvs.as_deref(),
                hit,
                wo,
                ray.time,
                flip,
                reads,
            );
        }
        ShapeGeom::Sphere { center, radius } => {
            let raw = ray.at(hit.t);
            let dir = (raw - *center).normalize_or(Vec3::Z);
            let p = *center + dir * *radius;
            let p_error = gamma(5) * (p.abs() + center.abs());
            let uv = if reads.uv { sphere_uv(dir) } else { Vec2::ZERO };
            let dpdu = Vec3::new(-dir.y, dir.x, 0.0);
            (p, p_error, dir, dir, dpdu, uv)
        }
        ShapeGeom::Disk { to_world, normal } => {
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
        ShapeGeom::Ellipsoid(e) => {
            // Re-project the object-space hit onto the unit sphere, as for spheres.
            let local = e.to_object.transform_point3a(ray.at(hit.t));
            let dir = local.normalize_or(Vec3::Z);
            let (p, p_error) = e.point(dir);
            let n = e.normal(dir);
            let uv = if reads.uv { sphere_uv(dir) } else { Vec2::ZERO };
            let dpdu = e.to_world.transform_vector3a(Vec3::new(-dir.y, dir.x, 0.0));
            (p, p_error, n, n, dpdu, uv)
        }
        ShapeGeom::Plane { point, normal } => {
            let raw = ray.at(hit.t);
            // Project onto the plane to remove the error along the normal.
            let p = raw - *normal * (raw - *point).dot(*normal);
            let p_error = gamma(6) * (p.abs() + point.abs());
            let frame = Frame::from_normal(*normal);
            let uv = Vec2::new((p - *point).dot(frame.s), (p - *point).dot(frame.t));
            (p, p_error, *normal, *normal, frame.s, uv)
        }
        ShapeGeom::Instance(i) => return instance_interaction(i, hit, ray, flip, reads),
    };
    finish_interaction(p, p_error, ng, ns, dpdu, uv, wo, hit, ray.time, flip)
}

/// The common tail of [`interaction`]: orientation and the shading frame.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn finish_interaction(
    p: Vec3,
    p_error: Vec3,
    mut ng: Vec3,
    mut ns: Vec3,
    dpdu: Vec3,
    uv: Vec2,
    wo: Vec3,
    hit: &Hit,
    time: f32,
    flip: bool,
) -> SurfaceInteraction {
    if flip {
        ng = -ng;
        ns = -ns;
    }
    if ns.dot(ng) < 0.0 {
        // Interpolated normals on the other side of the geometric one: trust the shading one
        // for orientation, as Mitsuba does for its shading frame.
        ng = -ng;
    }
    SurfaceInteraction {
        p,
        p_error,
        ng,
        shading: Frame::from_normal_tangent(ns, dpdu),
        uv,
        wo,
        t: hit.t,
        shape: hit.shape,
        prim: hit.prim,
        time,
    }
}

/// The interaction on the world-space triangle `p` (vertices `idx` of the mesh, for the
/// normals, mapped by `normal_to_world`, and uvs).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn mesh_interaction(
    [p0, p1, p2]: [Vec3; 3],
    [i0, i1, i2]: [usize; 3],
    normals: Option<&[Vec3]>,
    normal_to_world: impl Fn(Vec3) -> Vec3,
    uvs: Option<&[Vec2]>,
    hit: &Hit,
    wo: Vec3,
    time: f32,
    flip: bool,
    reads: Reads,
) -> SurfaceInteraction {
    let (b1, b2) = (hit.u, hit.v);
    let b0 = 1.0 - b1 - b2;
    let p = b0 * p0 + b1 * p1 + b2 * p2;
    let p_error = gamma(7) * ((b0 * p0).abs() + (b1 * p1).abs() + (b2 * p2).abs());
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let ng = normalize_or_zero_fast(e1.cross(e2));
    let uv = match uvs {
        Some(t) if reads.uv => b0 * t[i0] + b1 * t[i1] + b2 * t[i2],
        _ => Vec2::new(b1, b2),
    };
    if normals.is_none() && (uvs.is_none() || !reads.tangent) {
        // Flat mesh without uvs (the common case for OBJ/PLY without `vt`/`vn`), or
        // one whose tangent does not matter: the shading frame is the geometric one,
        // with `s` along the first edge, which is already orthogonal to `ng`, so no
        // Gram–Schmidt step is needed.
        return flat_interaction(p, p_error, ng, e1, uv, wo, hit, time, flip);
    }
    let dpdu = match uvs {
        Some(t) if reads.tangent => {
            let (t0, t1, t2) = (t[i0], t[i1], t[i2]);
            let du1 = t1 - t0;
            let du2 = t2 - t0;
            let det = du1.x * du2.y - du1.y * du2.x;
            if det.abs() > 1e-12 {
                (e1 * du2.y - e2 * du1.y) / det
            } else {
                e1
            }
        }
        _ => e1,
    };
    let ns = match normals {
        Some(n) => {
            // `normalize_or`: comparing with zero component by component is a branch on
            // the normal's direction, which the predictor cannot learn.
            (b0 * normal_to_world(n[i0])
                + b1 * normal_to_world(n[i1])
                + b2 * normal_to_world(n[i2]))
            .normalize_or(ng)
        }
        None => ng,
    };
    finish_interaction(p, p_error, ng, ns, dpdu, uv, wo, hit, time, flip)
}

/// [`interaction`] on an [`Instance`]: out of line, so that ordinary shapes' code is as
/// before.
#[inline(never)]
fn instance_interaction(
    inst: &Instance,
    hit: &Hit,
    ray: &Ray,
    flip: bool,
    reads: Reads,
) -> SurfaceInteraction {
    let shift = inst.motion * ray.time;
    let mut si = match &inst.base {
        ShapeGeom::Mesh {
            positions,
            normals,
            uvs,
            indices,
        } => {
            // The world triangle as the flattened copy stores it (with its winding reversed
            // under a mirroring placement, the barycentrics following).
            let [a, b, c] = indices[hit.prim as usize].map(|i| i as usize);
            let (idx, h) = if inst.mirror {
                (
                    [a, c, b],
                    Hit {
                        u: hit.v,
                        v: hit.u,
                        ..*hit
                    },
                )
            } else {
                ([a, b, c], *hit)
            };
            let p = idx.map(|i| inst.to_world.transform_point3a(positions[i]) + shift);
            let wo = -ray.d * rsqrt(ray.d.length_squared());
            mesh_interaction(
                p,
                idx,
                normals.as_deref(),
                |n| (inst.normal_matrix * n).normalize_or_zero(),
                uvs.as_deref(),
                &h,
                wo,
                ray.time,
                flip,
                reads,
            )
        }
        // A moving shape that is not a mesh instance (`to_world` is the identity): hit at its
        // time-0 place by the ray shifted back.
        base => {
            let local = Ray::at_time(ray.o - shift, ray.d, ray.time);
            let mut si = interaction(base, hit, &local, flip, reads);
            si.p += shift;
            si
        }
    };
    si.p_error += inst.extra_error(si.p, shift);
    si
}

/// [`interaction`] for a triangle without shading normals or uvs: shading frame = geometric
/// frame, tangent along the edge `e1` (orthogonal to `ng` by construction).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn flat_interaction(
    p: Vec3,
    p_error: Vec3,
    ng: Vec3,
    e1: Vec3,
    uv: Vec2,
    wo: Vec3,
    hit: &Hit,
    time: f32,
    flip: bool,
) -> SurfaceInteraction {
    let n = if flip { -ng } else { ng };
    let len2 = e1.length_squared();
    // Accel drops zero-area triangles, so `e1` is non-zero; keep the generic fallback anyway.
    // `n` is unit or zero: its squared length is the one test (`!= Vec3::ZERO` compares
    // component by component, a branch on which way the surface faces).
    let shading = if len2 > 1e-12 && len2.is_finite() && n.length_squared() > 0.0 {
        let s = e1 * rsqrt(len2);
        Frame {
            s,
            t: n.cross(s),
            n,
        }
    } else {
        Frame::from_normal_tangent(n, e1)
    };
    SurfaceInteraction {
        p,
        p_error,
        ng: n,
        shading,
        uv,
        wo,
        t: hit.t,
        shape: hit.shape,
        prim: hit.prim,
        time,
    }
}

/// A shape of the runtime scene: its geometry and what the renderer needs to shade it.
#[derive(Clone, Debug)]
pub struct ShapeInfo {
    pub geom: ShapeGeom,
    /// Index into the scene's materials; `None` on an emitter without a material (it does not
    /// scatter).
    pub material: Option<u32>,
    pub emission: Option<ColorRef>,
    pub flip_normals: bool,
    /// Alpha cut-out (the shape's material is a `mask`): the probability that a ray hitting
    /// the surface stops there. See `Scene::intersect`.
    pub opacity: Option<FloatRef>,
    /// What shading reads of this shape's interactions beyond position and normals.
    pub reads: Reads,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What `Reads` leaves out is skipped, and nothing else changes: the frame stays
    /// orthonormal around the same normal, position and error bound are identical.
    #[test]
    fn interaction_skips_what_is_not_read() {
        // A sheared uv parameterisation, so that ∂p/∂u is not along the first edge.
        let geom = ShapeGeom::Mesh {
            positions: vec![
                Vec3::ZERO,
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(0.5, 1.0, 0.0),
            ]
            .into(),
            normals: None,
            uvs: Some(vec![Vec2::ZERO, Vec2::new(1.0, 0.5), Vec2::new(0.0, 1.0)].into()),
            indices: vec![[0, 1, 2]].into(),
        };
        let hit = Hit {
            t: 1.0,
            shape: 0,
            prim: 0,
            u: 0.25,
            v: 0.5,
        };
        let ray = Ray::new(Vec3::new(0.75, 0.5, 1.0), Vec3::new(0.0, 0.0, -1.0));
        let read = |tangent, uv| interaction(&geom, &hit, &ray, false, Reads { tangent, uv });
        let all = read(true, true);
        let none = read(false, false);
        assert!(
            (all.uv - Vec2::new(0.25, 0.625)).length() < 1e-6,
            "{:?}",
            all.uv
        );
        assert_eq!(
            none.uv,
            Vec2::new(0.25, 0.5),
            "barycentrics when uv is not read"
        );
        assert_eq!(read(false, true).uv, all.uv);
        // ∂p/∂u = e₁ - e₂/2 = (1.75, -0.5, 0) here: not along the first edge (x).
        let dpdu = Vec3::new(1.75, -0.5, 0.0).normalize();
        assert!(
            (all.shading.s - dpdu).length() < 1e-6,
            "{:?}",
            all.shading.s
        );
        assert!(
            (none.shading.s - Vec3::X).length() < 1e-6,
            "{:?}",
            none.shading.s
        );
        assert_eq!(read(true, false).shading.s, all.shading.s);
        for si in [all, none] {
            let f = si.shading;
            assert_eq!(
                (si.p, si.p_error, si.ng, f.n),
                (all.p, all.p_error, all.ng, all.shading.n)
            );
            assert!((f.s.length() - 1.0).abs() < 1e-6 && (f.t.length() - 1.0).abs() < 1e-6);
            assert!(f.s.dot(f.n).abs() < 1e-6 && f.t.dot(f.n).abs() < 1e-6);
            assert!((f.s.cross(f.t) - f.n).length() < 1e-6, "right-handed");
        }
        // Spheres skip their trigonometric uv.
        let sphere = ShapeGeom::Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        };
        let ray = Ray::new(Vec3::new(0.0, 0.0, 3.0), Vec3::new(0.0, 0.0, -1.0));
        let hit = Hit { t: 2.0, ..hit };
        let uv = |uv| interaction(&sphere, &hit, &ray, false, Reads { tangent: true, uv }).uv;
        assert_eq!(uv(false), Vec2::ZERO);
        assert!(
            (uv(true) - Vec2::new(0.0, 0.0)).length() < 1e-6,
            "{:?}",
            uv(true)
        );
    }

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
