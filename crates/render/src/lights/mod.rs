//! Emitters and their sampling, following Mitsuba 3's definitions.
//!
//! - `Area`: an emitting shape; radiance leaves the front side (the side the shading normal
//!   points to) unless two-sided. Spheres seen from outside are sampled uniformly in the cone
//!   they subtend (solid angle); meshes by area (triangle chosen in proportion to its area,
//!   then a uniform point; a two-triangle parallelogram, the usual quad light, in one step),
//!   disks by area; area densities are converted to solid angle.
//!   Under light selection by power or BVH ([`select`], [`bvh`]) an emitting mesh becomes one
//!   `Area` light per triangle (`prim`), so that each triangle is chosen on its own.
//! - `Point` (intensity / d²), `Spot` (Mitsuba's linear falloff between `beam_width` and
//!   `cutoff_angle`), `Directional` (irradiance along `direction`): delta lights.
//! - `Constant` environment (sampled uniformly over the sphere) and `EnvMap`: an
//!   equirectangular image, bilinearly interpolated, importance-sampled with a piecewise-
//!   constant 2D distribution of its pixel luminance weighted by sin θ. Local directions map to
//!   uv = (atan2(x, −z) / 2π, acos(y) / π), y up, as in Mitsuba.

pub mod bvh;
pub mod select;

use std::sync::Arc;

use scene::{ColorParam, EnvMapping};

use crate::build::Scene;
use crate::film::Image;
use crate::geometry::Ray;
use crate::math::{Frame, INV_PI, Mat3, Mat4, PI, Vec2, Vec3, luminance, rsqrt};
use crate::sampling::distrib::{Distribution1D, Distribution2D};
use crate::sampling::warp;
use crate::shapes::{Ellipsoid, ShapeGeom, SurfaceInteraction, disk_uv, gamma, sphere_uv};
use glam::Mat3A;

/// A point on an emitter with what it sends towards the receiver.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction from the receiver towards the light.
    pub wi: Vec3,
    /// Emitted radiance arriving along `-wi` (for delta lights: intensity / d² or irradiance).
    pub li: Vec3,
    /// Solid-angle density of choosing `wi` (1 for delta lights), not including light selection.
    pub pdf: f32,
    pub delta: bool,
    /// Where the shadow ray must stop.
    pub target: ShadowTarget,
}

#[derive(Clone, Copy, Debug)]
pub enum ShadowTarget {
    /// A point on a surface (offset by its error bound along `n`).
    Surface { p: Vec3, p_error: Vec3, n: Vec3 },
    /// A point in space (point and spot lights).
    Point(Vec3),
    /// Infinitely far along `wi`.
    Infinite,
}

impl ShadowTarget {
    /// The shadow ray from `si` towards this light sample (direction `wi`) and its range
    /// `(0, t_max)`.
    #[inline]
    pub fn ray_from(&self, si: &SurfaceInteraction, wi: Vec3) -> (Ray, f32) {
        match *self {
            ShadowTarget::Infinite => (si.spawn_ray(wi), f32::INFINITY),
            ShadowTarget::Point(p) => si.spawn_ray_to(p),
            ShadowTarget::Surface { p, p_error, n } => si.spawn_ray_to_surface(p, p_error, n),
        }
    }
}

/// The receiving point of a light query.
#[derive(Clone, Copy, Debug)]
pub struct Receiver {
    pub p: Vec3,
    /// Shading normal at `p` (either orientation), or zero for a point without one; used
    /// only to guide light selection (the light BVH).
    pub n: Vec3,
}

impl Receiver {
    /// A receiver without a normal.
    pub fn at(p: Vec3) -> Receiver {
        Receiver { p, n: Vec3::ZERO }
    }
}

impl From<&SurfaceInteraction> for Receiver {
    fn from(si: &SurfaceInteraction) -> Self {
        Receiver {
            p: si.p,
            n: si.shading.n,
        }
    }
}

#[derive(Clone, Debug)]
pub enum Light {
    Area {
        shape: u32,
        radiance: ColorParam,
        two_sided: bool,
        /// How a point is placed on a mesh lit as a whole (meshes only).
        triangles: Option<MeshSampling>,
        /// For a light that is one triangle of a mesh (light selection by power or by the
        /// light BVH splits emitting meshes): that triangle; `triangles` is then `None`.
        prim: Option<u32>,
        /// Area of the emitting surface (of the one triangle when `prim` is set).
        area: f32,
    },
    Point {
        position: Vec3,
        intensity: Vec3,
    },
    Spot {
        position: Vec3,
        to_local: Mat3,
        intensity: Vec3,
        cos_cutoff: f32,
        cos_beam: f32,
        cutoff: f32,
        inv_transition: f32,
        /// The CENG795 course's profile instead of Mitsuba's.
        course: bool,
    },
    Directional {
        /// Direction the light travels in (unit).
        direction: Vec3,
        irradiance: Vec3,
    },
    Constant {
        radiance: Vec3,
    },
    EnvMap(Arc<EnvMap>),
}

#[derive(Debug)]
pub struct EnvMap {
    pub image: Image,
    pub scale: f32,
    pub to_world: Mat3,
    pub to_local: Mat3,
    pub mapping: EnvMapping,
    pub distribution: Distribution2D,
}

impl EnvMap {
    pub fn new(image: Image, scale: f32, to_world: &Mat4, mapping: EnvMapping) -> EnvMap {
        let (w, h) = (image.width as usize, image.height as usize);
        // Mitsuba's lat-long grid: columns are pixel centres (u = (x + ½)/w), rows are grid
        // *vertices* (v = y/(h − 1)), so cell (x, y) of the sampling grid spans the rows y and
        // y + 1 and, through the bilinear lookup, the columns x − 1 … x + 1. Each cell gets the
        // largest luminance of those pixels times sin θ at its centre: the pdf is then never
        // small where the interpolated radiance is large (a one-pixel sun would otherwise
        // bleed into cells the pdf barely samples).
        let lum = |x: usize, y: usize| {
            let v = luminance(image.get(x as u32, y as u32));
            if v.is_finite() { v.max(0.0) } else { 0.0 }
        };
        let rows = h.saturating_sub(1).max(1);
        let mut weights = vec![0f32; w * rows];
        for y in 0..rows {
            let sin_theta = ((y as f32 + 0.5) / rows as f32 * PI).sin();
            for x in 0..w {
                let mut m = 0f32;
                for yy in [y, (y + 1).min(h - 1)] {
                    for dx in [-1i64, 0, 1] {
                        let xx = (x as i64 + dx).rem_euclid(w as i64) as usize;
                        m = m.max(lum(xx, yy));
                    }
                }
                weights[y * w + x] = m * sin_theta;
            }
        }
        let rot = Mat3::from_mat4(*to_world);
        EnvMap {
            distribution: Distribution2D::new(&weights, w, rows),
            image,
            scale,
            to_world: rot,
            to_local: rot.inverse(),
            mapping,
        }
    }

    fn dir_to_uv(&self, d_world: Vec3) -> Vec2 {
        let d = (self.to_local * d_world).normalize_or_zero();
        match self.mapping {
            EnvMapping::LatLong => {
                let mut u = d.x.atan2(-d.z) * (0.5 * INV_PI);
                if u < 0.0 {
                    u += 1.0;
                }
                Vec2::new(u, d.y.clamp(-1.0, 1.0).acos() * INV_PI)
            }
            EnvMapping::Probe => {
                // Debevec's angular map: r = acos(-z) / (π √(x² + y²)).
                let xy = (d.x * d.x + d.y * d.y).sqrt();
                let r = if xy > 0.0 {
                    (-d.z).clamp(-1.0, 1.0).acos() * INV_PI / xy
                } else {
                    0.0
                };
                Vec2::new(0.5 + 0.5 * d.x * r, 0.5 - 0.5 * d.y * r)
            }
        }
    }

    fn uv_to_dir(&self, uv: Vec2) -> (Vec3, f32) {
        let phi = uv.x * 2.0 * PI;
        let theta = uv.y * PI;
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = phi.sin_cos();
        let local = Vec3::new(st * sp, ct, -st * cp);
        ((self.to_world * local).normalize(), st)
    }

    /// Bilinear lookup on Mitsuba's grid: x = u·w − ½ (pixel centres, wrapping in u),
    /// y = v·(h − 1) (rows at the grid vertices, v = 0 and 1 on the first and last rows).
    /// Probe maps use pixel centres in both axes.
    fn lookup(&self, uv: Vec2) -> Vec3 {
        let (w, h) = (self.image.width as i64, self.image.height as i64);
        let x = uv.x * w as f32 - 0.5;
        let y = match self.mapping {
            EnvMapping::LatLong => uv.y * (h - 1) as f32,
            EnvMapping::Probe => uv.y * h as f32 - 0.5,
        };
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let px = |dx: i64, dy: i64| {
            let xi = (x0 + dx).rem_euclid(w) as u32;
            let yi = (y0 + dy).clamp(0, h - 1) as u32;
            self.image.get(xi, yi)
        };
        ((px(0, 0) * (1.0 - fx) + px(1, 0) * fx) * (1.0 - fy)
            + (px(0, 1) * (1.0 - fx) + px(1, 1) * fx) * fy)
            * self.scale
    }

    pub fn eval(&self, d_world: Vec3) -> Vec3 {
        self.lookup(self.dir_to_uv(d_world))
    }

    fn sample(&self, u: Vec2) -> Option<(Vec3, Vec3, f32)> {
        if self.mapping == EnvMapping::Probe {
            // Probe maps are sampled uniformly over the sphere.
            let d = warp::square_to_uniform_sphere(u);
            return Some((d, self.eval(d), warp::uniform_sphere_pdf()));
        }
        let (uv, pdf_uv) = self.distribution.sample(u);
        let (d, sin_theta) = self.uv_to_dir(uv);
        if pdf_uv <= 0.0 || sin_theta <= 0.0 {
            return None;
        }
        Some((d, self.lookup(uv), pdf_uv / (2.0 * PI * PI * sin_theta)))
    }

    fn pdf(&self, d_world: Vec3) -> f32 {
        if self.mapping == EnvMapping::Probe {
            return warp::uniform_sphere_pdf();
        }
        let uv = self.dir_to_uv(d_world);
        let sin_theta = (uv.y * PI).sin();
        if sin_theta <= 0.0 {
            return 0.0;
        }
        self.distribution.pdf(uv) / (2.0 * PI * PI * sin_theta)
    }
}

/// Spot falloff of Mitsuba 3 for a local direction (cos θ = z).
fn spot_falloff(
    cos_t: f32,
    cos_cutoff: f32,
    cos_beam: f32,
    cutoff: f32,
    inv_trans: f32,
    course: bool,
) -> f32 {
    if cos_t <= cos_cutoff {
        0.0
    } else if cos_t >= cos_beam {
        1.0
    } else if course {
        // CENG795: ((cos α − cos cutoff) / (cos beam − cos cutoff))⁴.
        let s = ((cos_t - cos_cutoff) / (cos_beam - cos_cutoff)).clamp(0.0, 1.0);
        (s * s) * (s * s)
    } else {
        ((cutoff - cos_t.clamp(-1.0, 1.0).acos()) * inv_trans).clamp(0.0, 1.0)
    }
}

/// How an emitting mesh lit as a whole places a uniform point on its surface.
#[derive(Clone, Debug)]
pub enum MeshSampling {
    /// A triangle in proportion to its area, then a uniform point in it.
    ByArea(Arc<Distribution1D>),
    /// Two triangles forming a parallelogram (a meshed rectangle: the usual quad light).
    Parallelogram(Parallelogram),
}

impl MeshSampling {
    /// The sampling for a mesh with these triangles (whose areas are `areas`).
    pub fn new(positions: &[Vec3], indices: &[[u32; 3]], areas: &[f32]) -> MeshSampling {
        match Parallelogram::detect(positions, indices) {
            Some(q) => MeshSampling::Parallelogram(q),
            None => MeshSampling::ByArea(Arc::new(Distribution1D::new(areas))),
        }
    }
}

/// A mesh of two triangles that together form a parallelogram `a + s·e₁ + t·e₂`,
/// `(s, t) ∈ [0, 1]²`, split along the diagonal from `a + e₁` to `a + e₂`. One 2D sample gives
/// a uniform point with no discrete choice (an `f64` CDF search) and no triangle warp: the
/// same density as choosing a triangle by area, since the halves have equal areas.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Parallelogram {
    /// Per triangle (0 holds `a`, 1 the opposite corner), the barycentrics `b₁`, `b₂` of the
    /// point as affine functions of the sample: coefficients of `(1, s, t)`.
    coef: [[Vec3; 2]; 2],
    /// The unit normal of both triangles (by their winding), which they share.
    normal: Vec3,
}

impl Parallelogram {
    /// Relative tolerance on `a + (a + e₁ + e₂) = (a + e₁) + (a + e₂)`: corners placed by a
    /// float transform are off by a few ulp; the density error is of the same relative size.
    const TOLERANCE: f32 = 1e-5;

    /// The parallelogram formed by a two-triangle mesh, if it is one.
    pub fn detect(positions: &[Vec3], indices: &[[u32; 3]]) -> Option<Parallelogram> {
        let [t0, t1] = indices else { return None };
        let get = |i: u32| positions.get(i as usize).copied();
        let p0 = [get(t0[0])?, get(t0[1])?, get(t0[2])?];
        let p1 = [get(t1[0])?, get(t1[1])?, get(t1[2])?];
        // The diagonal: the two corners the triangles share (by position).
        let mut shared = Vec::with_capacity(3);
        for (i, a) in p0.iter().enumerate() {
            if let Some(j) = p1.iter().position(|b| b == a) {
                shared.push((i, j));
            }
        }
        let [(i0, i1), (j0, j1)] = shared[..] else {
            return None;
        };
        let k0 = 3 - i0 - j0;
        let l1 = 3 - i1 - j1;
        let (a, e1, e2) = (p0[k0], p0[i0] - p0[k0], p0[j0] - p0[k0]);
        let scale = e1.abs().max(e2.abs()).max_element();
        let face = |p: [Vec3; 3]| (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        let normal = face(p0);
        // Both windings alike (a mesh may flip one triangle: each then emits to its own side).
        let ok = (a + e1 + e2 - p1[l1]).abs().max_element() <= Self::TOLERANCE * scale
            && normal != Vec3::ZERO
            && normal.dot(face(p1)) > 0.0
            && scale.is_finite();
        if !ok {
            return None;
        }
        // Weights of the corners as coefficients of (1, s, t): in triangle 0, a, a + e₁, a + e₂
        // take 1 − s − t, s, t; in triangle 1, a + e₁, a + e₂, a + e₁ + e₂ take 1 − t, 1 − s,
        // s + t − 1. b₁, b₂ are the weights of the corners in vertex slots 1 and 2.
        let weights = [
            [Vec3::new(1.0, -1.0, -1.0), Vec3::Y, Vec3::Z],
            [
                Vec3::new(1.0, 0.0, -1.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::new(-1.0, 1.0, 1.0),
            ],
        ];
        let slots = [[k0, i0, j0], [i1, j1, l1]];
        let mut coef = [[Vec3::ZERO; 2]; 2];
        for (tri, (slots, weights)) in slots.iter().zip(weights).enumerate() {
            for (&slot, w) in slots.iter().zip(weights) {
                if slot > 0 {
                    coef[tri][slot - 1] = w;
                }
            }
        }
        Some(Parallelogram { coef, normal })
    }

    /// A uniform point: its triangle and its barycentrics `(b₁, b₂)` in that triangle's vertex
    /// order (`p = (1 − b₁ − b₂) p₀ + b₁ p₁ + b₂ p₂`).
    /// Always inlined: out of line, its result went through memory and the caller stalled
    /// reading it back (a time profile showed 7 % of `sample_li` on that load).
    #[inline(always)]
    pub fn sample(&self, u: Vec2) -> (usize, Vec2) {
        let tri = (u.x + u.y > 1.0) as usize;
        let [c1, c2] = self.coef[tri];
        let x = Vec3::new(1.0, u.x, u.y);
        (tri, Vec2::new(c1.dot(x), c2.dot(x)))
    }
}

impl Light {
    pub fn spot(
        to_world: &Mat4,
        intensity: Vec3,
        cutoff_deg: f32,
        beam_deg: f32,
        falloff: scene::SpotFalloff,
    ) -> Light {
        let cutoff = cutoff_deg.to_radians();
        let beam = beam_deg.to_radians().min(cutoff);
        let rot = Mat3::from_mat4(*to_world);
        Light::Spot {
            position: to_world.w_axis.truncate().into(),
            to_local: rot.inverse(),
            intensity,
            cos_cutoff: cutoff.cos(),
            cos_beam: beam.cos(),
            cutoff,
            inv_transition: if cutoff > beam {
                1.0 / (cutoff - beam)
            } else {
                0.0
            },
            course: falloff == scene::SpotFalloff::Cosine4,
        }
    }

    pub fn is_delta(&self) -> bool {
        matches!(
            self,
            Light::Point { .. } | Light::Spot { .. } | Light::Directional { .. }
        )
    }

    pub fn is_infinite(&self) -> bool {
        matches!(
            self,
            Light::Directional { .. } | Light::Constant { .. } | Light::EnvMap(_)
        )
    }

    /// Radiance of an environment light seen along `d` (escaping ray direction).
    pub fn environment(&self, d: Vec3) -> Vec3 {
        match self {
            Light::Constant { radiance } => *radiance,
            Light::EnvMap(env) => env.eval(d),
            _ => Vec3::ZERO,
        }
    }

    /// Sample a direction from `r` towards this light.
    pub fn sample_li(&self, scene: &Scene, r: &Receiver, u: Vec2) -> Option<LightSample> {
        match self {
            Light::Point {
                position,
                intensity,
            } => {
                let d = *position - r.p;
                let d2 = d.length_squared();
                (d2 > 0.0).then(|| LightSample {
                    wi: d / d2.sqrt(),
                    li: *intensity / d2,
                    pdf: 1.0,
                    delta: true,
                    target: ShadowTarget::Point(*position),
                })
            }
            Light::Spot {
                position,
                to_local,
                intensity,
                cos_cutoff,
                cos_beam,
                cutoff,
                inv_transition,
                course,
            } => {
                let d = *position - r.p;
                let d2 = d.length_squared();
                if d2 <= 0.0 {
                    return None;
                }
                let wi = d / d2.sqrt();
                let local = (*to_local * -wi).normalize_or_zero();
                let f = spot_falloff(
                    local.z,
                    *cos_cutoff,
                    *cos_beam,
                    *cutoff,
                    *inv_transition,
                    *course,
                );
                (f > 0.0).then(|| LightSample {
                    wi,
                    li: *intensity * f / d2,
                    pdf: 1.0,
                    delta: true,
                    target: ShadowTarget::Point(*position),
                })
            }
            Light::Directional {
                direction,
                irradiance,
            } => Some(LightSample {
                wi: -*direction,
                li: *irradiance,
                pdf: 1.0,
                delta: true,
                target: ShadowTarget::Infinite,
            }),
            Light::Constant { radiance } => {
                let wi = warp::square_to_uniform_sphere(u);
                Some(LightSample {
                    wi,
                    li: *radiance,
                    pdf: warp::uniform_sphere_pdf(),
                    delta: false,
                    target: ShadowTarget::Infinite,
                })
            }
            Light::EnvMap(env) => {
                let (wi, li, pdf) = env.sample(u)?;
                Some(LightSample {
                    wi,
                    li,
                    pdf,
                    delta: false,
                    target: ShadowTarget::Infinite,
                })
            }
            Light::Area {
                shape,
                radiance,
                two_sided,
                triangles,
                prim,
                area,
            } => {
                let info = &scene.shapes[*shape as usize];
                let flip = if info.flip_normals { -1.0 } else { 1.0 };
                // The sampled point's uv only feeds a radiance texture.
                let textured = matches!(radiance, ColorParam::Texture(_));
                let (p, p_error, n, uv, pdf) = match &info.geom {
                    ShapeGeom::Sphere { center, radius } => {
                        return sample_sphere(
                            scene, *center, *radius, flip, *two_sided, radiance, r, u,
                        );
                    }
                    ShapeGeom::Mesh {
                        positions,
                        normals,
                        uvs,
                        indices,
                    } => {
                        if area.is_nan() || *area <= 0.0 {
                            return None;
                        }
                        let (tri, b) = match (prim, triangles) {
                            (Some(t), _) => (*t as usize, warp::square_to_uniform_triangle(u)),
                            (None, Some(MeshSampling::ByArea(dist))) => {
                                let (tri, _, ux) = dist.sample_discrete(u.x);
                                let b = warp::square_to_uniform_triangle(Vec2::new(ux, u.y));
                                (tri, b)
                            }
                            (None, Some(MeshSampling::Parallelogram(q))) => q.sample(u),
                            (None, None) => return None,
                        };
                        let [i0, i1, i2] = indices.get(tri)?.map(|i| i as usize);
                        let b0 = 1.0 - b.x - b.y;
                        let (p0, p1, p2) = (positions[i0], positions[i1], positions[i2]);
                        let p = b0 * p0 + b.x * p1 + b.y * p2;
                        let err =
                            gamma(6) * ((b0 * p0).abs() + (b.x * p1).abs() + (b.y * p2).abs());
                        let face = match triangles {
                            Some(MeshSampling::Parallelogram(q)) => q.normal,
                            _ => (p1 - p0).cross(p2 - p0).normalize_or_zero(),
                        };
                        let mut n = face * flip;
                        if let Some(ns) = normals {
                            let s = b0 * ns[i0] + b.x * ns[i1] + b.y * ns[i2];
                            if s.dot(n) < 0.0 {
                                n = -n;
                            }
                        }
                        let uv = match uvs {
                            Some(t) if textured => b0 * t[i0] + b.x * t[i1] + b.y * t[i2],
                            _ => b,
                        };
                        (p, err, n, uv, 1.0 / *area)
                    }
                    ShapeGeom::Disk { to_world, normal } => {
                        let d = warp::square_to_uniform_disk_concentric(u);
                        let p = to_world.transform_point3a(Vec3::new(d.x, d.y, 0.0));
                        let err = gamma(6) * (p.abs() + Vec3::from_vec4(to_world.w_axis).abs());
                        let uv = if textured { disk_uv(d) } else { Vec2::ZERO };
                        (p, err, *normal * flip, uv, 1.0 / *area)
                    }
                    ShapeGeom::Ellipsoid(e) => {
                        let (dir, pdf_solid) = sample_ellipsoid(e, r.p, u)?;
                        let (p, p_error) = e.point(dir);
                        let n = e.normal(dir) * flip;
                        let to = p - r.p;
                        let d2 = to.length_squared();
                        if d2 <= 0.0 || !pdf_solid.is_finite() {
                            return None;
                        }
                        let wi = to / d2.sqrt();
                        if n.dot(-wi) <= 0.0 && !*two_sided {
                            return None;
                        }
                        let uv = if textured { sphere_uv(dir) } else { Vec2::ZERO };
                        return Some(LightSample {
                            wi,
                            li: scene.color(radiance, uv),
                            pdf: pdf_solid,
                            delta: false,
                            target: ShadowTarget::Surface { p, p_error, n },
                        });
                    }
                    // Emitters are never instanced nor moving (`build` flattens them).
                    ShapeGeom::Plane { .. } | ShapeGeom::Instance(_) => return None,
                };
                let to = p - r.p;
                let d2 = to.length_squared();
                if d2 <= 0.0 || d2.is_infinite() {
                    return None;
                }
                let wi = to * rsqrt(d2);
                let cos_l = n.dot(-wi);
                if cos_l == 0.0 || (!*two_sided && cos_l < 0.0) {
                    return None;
                }
                Some(LightSample {
                    wi,
                    li: scene.color(radiance, uv),
                    pdf: pdf * d2 / cos_l.abs(),
                    delta: false,
                    target: ShadowTarget::Surface { p, p_error, n },
                })
            }
        }
    }

    /// Solid-angle density with which `sample_li` from `r` produces the direction towards
    /// `si`, a point on this (area) light — or, for environment lights, the direction `wi`.
    pub fn pdf_li(
        &self,
        scene: &Scene,
        r: &Receiver,
        wi: Vec3,
        si: Option<&SurfaceInteraction>,
    ) -> f32 {
        match self {
            Light::Constant { .. } => warp::uniform_sphere_pdf(),
            Light::EnvMap(env) => env.pdf(wi),
            Light::Area {
                shape,
                area,
                two_sided,
                ..
            } => {
                let Some(si) = si else { return 0.0 };
                let info = &scene.shapes[*shape as usize];
                if let ShapeGeom::Sphere { center, radius } = &info.geom {
                    // Zero where `sample_li` yields nothing: the back of a one-sided light.
                    if !*two_sided && si.shading.n.dot(-wi) <= 0.0 {
                        return 0.0;
                    }
                    return sphere_pdf(*center, *radius, r.p, si.p);
                }
                let d2 = (si.p - r.p).length_squared();
                let cos_l = si.ng.dot(-wi);
                if cos_l == 0.0 || (!*two_sided && si.shading.n.dot(-wi) < 0.0) {
                    return 0.0;
                }
                match &info.geom {
                    ShapeGeom::Ellipsoid(e) => ellipsoid_pdf(e, r.p, wi, si.p, cos_l.abs()),
                    _ => d2 / (cos_l.abs() * *area),
                }
            }
            _ => 0.0,
        }
    }

    /// Radiance leaving an area light at `si` towards `si.wo`.
    pub fn le(&self, scene: &Scene, si: &SurfaceInteraction) -> Vec3 {
        match self {
            Light::Area {
                radiance,
                two_sided,
                ..
            } => {
                if *two_sided || si.shading.n.dot(si.wo) > 0.0 {
                    scene.color(radiance, si.uv)
                } else {
                    Vec3::ZERO
                }
            }
            _ => Vec3::ZERO,
        }
    }
}

/// Mitsuba's sphere emitter sampling: uniform cone from outside, uniform area from inside.
#[allow(clippy::too_many_arguments)]
fn sample_sphere(
    scene: &Scene,
    center: Vec3,
    radius: f32,
    flip: f32,
    two_sided: bool,
    radiance: &ColorParam,
    r: &Receiver,
    u: Vec2,
) -> Option<LightSample> {
    let to_c = center - r.p;
    let dc2 = to_c.length_squared();
    let r2 = radius * radius;
    let (p, pdf_solid) = if dc2 > r2 * (1.0 + 1e-4) {
        let dc = dc2.sqrt();
        let sin_max2 = r2 / dc2;
        let cos_max = (1.0 - sin_max2).max(0.0).sqrt();
        let frame = Frame::from_normal(to_c / dc);
        let local = warp::square_to_uniform_cone(u, cos_max);
        let wi = frame.to_world(local);
        // Nearest intersection of the ray r.p + t wi with the sphere (clamped for grazing).
        let b = wi.dot(to_c);
        let disc = (r2 - (to_c - b * wi).length_squared()).max(0.0);
        let t = b - disc.sqrt();
        (r.p + wi * t, warp::uniform_cone_pdf(cos_max))
    } else {
        let d = warp::square_to_uniform_sphere(u);
        let p = center + d * radius;
        let to = p - r.p;
        let d2 = to.length_squared();
        let cos_l = d.dot(-to.normalize_or_zero()).abs();
        if d2 <= 0.0 || cos_l == 0.0 {
            return None;
        }
        (p, d2 / (cos_l * 4.0 * PI * r2))
    };
    let n_out = (p - center).normalize_or_zero();
    let p = center + n_out * radius;
    let to = p - r.p;
    let d2 = to.length_squared();
    if d2 <= 0.0 || !pdf_solid.is_finite() {
        return None;
    }
    let wi = to / d2.sqrt();
    let n = n_out * flip;
    if n.dot(-wi) <= 0.0 && !two_sided {
        // Sampled the inside of the sphere from outside (or vice versa): no emission.
        return None;
    }
    let uv = if matches!(radiance, ColorParam::Texture(_)) {
        sphere_uv(n_out)
    } else {
        Vec2::ZERO
    };
    Some(LightSample {
        wi,
        li: scene.color(radiance, uv),
        pdf: pdf_solid,
        delta: false,
        target: ShadowTarget::Surface {
            p,
            p_error: gamma(5) * (p.abs() + center.abs()),
            n,
        },
    })
}

/// An ellipsoid light seen from `from`: the unit-sphere point (object space) and the
/// solid-angle density of the world direction towards it. Outside, the cone of directions
/// the object sphere subtends from the object-space receiver is sampled uniformly (as for
/// spheres) and carried to world directions by the Jacobian of the linear map A = M⁻¹ on
/// directions, dω_obj/dω = |det A| / |A w|³; inside, uniformly on the object sphere by area.
fn sample_ellipsoid(e: &Ellipsoid, from: Vec3, u: Vec2) -> Option<(Vec3, f32)> {
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

/// The density [`sample_ellipsoid`] gives the direction `wi` from `from` towards the point
/// `on` of the ellipsoid (`cos_l`: |cosine| at `on`).
fn ellipsoid_pdf(e: &Ellipsoid, from: Vec3, wi: Vec3, on: Vec3, cos_l: f32) -> f32 {
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

fn sphere_pdf(center: Vec3, radius: f32, from: Vec3, on: Vec3) -> f32 {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// The CENG795 spot profile: full intensity inside the falloff cone, nothing outside the
    /// coverage cone, ((cos α − cos c) / (cos f − cos c))⁴ between; Mitsuba's is linear in α.
    #[test]
    fn course_spot_profile() {
        let light = |falloff| Light::spot(&Mat4::IDENTITY, Vec3::ONE, 30.0, 10.0, falloff);
        let at = |l: &Light, deg: f32| {
            let Light::Spot {
                cos_cutoff,
                cos_beam,
                cutoff,
                inv_transition,
                course,
                ..
            } = *l
            else {
                panic!()
            };
            let c = deg.to_radians().cos();
            spot_falloff(c, cos_cutoff, cos_beam, cutoff, inv_transition, course)
        };
        let course = light(scene::SpotFalloff::Cosine4);
        let mitsuba = light(scene::SpotFalloff::Mitsuba);
        for deg in [0.0f32, 5.0, 9.9] {
            assert_eq!(at(&course, deg), 1.0);
        }
        for deg in [30.1f32, 45.0, 120.0] {
            assert_eq!(at(&course, deg), 0.0);
        }
        for deg in [12.0f32, 20.0, 28.0] {
            let (c, cc, cb) = (
                deg.to_radians().cos(),
                30f32.to_radians().cos(),
                10f32.to_radians().cos(),
            );
            let expected = ((c - cc) / (cb - cc)).powi(4);
            assert!((at(&course, deg) - expected).abs() < 1e-5, "{deg}°");
            let linear = (30.0 - deg) / 20.0;
            assert!((at(&mitsuba, deg) - linear).abs() < 1e-4, "{deg}°");
            assert!(
                (at(&course, deg) - at(&mitsuba, deg)).abs() > 0.02,
                "{deg}°"
            );
        }
    }

    /// The point a `Parallelogram` sample designates, from the mesh.
    fn point(pos: &[Vec3], idx: &[[u32; 3]], q: &Parallelogram, u: Vec2) -> Vec3 {
        let (tri, b) = q.sample(u);
        let [p0, p1, p2] = idx[tri].map(|i| pos[i as usize]);
        (1.0 - b.x - b.y) * p0 + b.x * p1 + b.y * p2
    }

    #[test]
    fn parallelogram_samples_are_the_bilinear_map_whatever_the_vertex_order() {
        let (a, e1, e2) = (
            Vec3::new(0.5, -1.0, 2.0),
            Vec3::new(2.0, 0.25, 0.0),
            Vec3::new(0.5, 0.0, 1.5),
        );
        let corners = [a, a + e1, a + e1 + e2, a + e2];
        // Split along either diagonal, with rotated and reversed (but matching) windings and unshared
        // vertices (the triangles share positions, not indices).
        let splits: [[[usize; 3]; 2]; 4] = [
            [[0, 1, 3], [1, 2, 3]],
            [[2, 3, 1], [3, 0, 1]],
            [[0, 2, 1], [0, 3, 2]],
            [[3, 0, 2], [2, 0, 1]],
        ];
        for split in splits {
            let pos: Vec<Vec3> = split.iter().flatten().map(|&c| corners[c]).collect();
            let idx = [[0, 1, 2], [3, 4, 5]];
            let q = Parallelogram::detect(&pos, &idx).expect("a parallelogram");
            for (s, t) in [(0.1, 0.2), (0.9, 0.8), (0.5, 0.5), (0.0, 0.99), (0.7, 0.31)] {
                let p = point(&pos, &idx, &q, Vec2::new(s, t));
                // Uniform in (s, t) over some parametrisation of the parallelogram: check the
                // point lies inside and that the map is affine within each half.
                let d = p - a;
                let m = Mat3::from_cols(e1.into(), e2.into(), e1.cross(e2).into());
                let st = m.inverse() * d;
                assert!(st.z.abs() < 1e-5, "{split:?} off the plane");
                assert!(
                    (-1e-5..=1.0 + 1e-5).contains(&st.x) && (-1e-5..=1.0 + 1e-5).contains(&st.y)
                );
            }
            // Area preserving: the Jacobian of u ↦ p is the same in both halves.
            let jac = |u: Vec2| {
                let h = 1e-3;
                let p = point(&pos, &idx, &q, u);
                let ds = point(&pos, &idx, &q, u + Vec2::new(h, 0.0)) - p;
                let dt = point(&pos, &idx, &q, u + Vec2::new(0.0, h)) - p;
                ds.cross(dt).length() / (h * h)
            };
            let area = e1.cross(e2).length();
            for u in [Vec2::new(0.2, 0.3), Vec2::new(0.7, 0.6)] {
                assert!((jac(u) / area - 1.0).abs() < 1e-2, "{split:?} {u:?}");
            }
        }
    }

    #[test]
    fn other_two_triangle_meshes_are_not_parallelograms() {
        let sq = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let quad = |p: [Vec3; 4]| Parallelogram::detect(&p, &[[0, 1, 3], [1, 2, 3]]);
        assert!(quad(sq).is_some());
        // A trapezoid, a folded quad, triangles sharing only a vertex, a degenerate one, and
        // a square whose second triangle is wound the other way.
        assert!(Parallelogram::detect(&sq, &[[0, 1, 3], [1, 3, 2]]).is_none());
        assert!(quad([sq[0], sq[1], Vec3::new(0.7, 1.0, 0.0), sq[3]]).is_none());
        assert!(quad([sq[0], sq[1], Vec3::new(1.0, 1.0, 0.5), sq[3]]).is_none());
        assert!(Parallelogram::detect(&sq, &[[0, 1, 2], [2, 3, 2]]).is_none());
        assert!(Parallelogram::detect(&sq, &[[0, 1, 2], [0, 2, 3], [0, 1, 3]]).is_none());
        assert!(Parallelogram::detect(&[Vec3::ZERO; 4], &[[0, 1, 3], [1, 2, 3]]).is_none());
        // Out-of-range indices are not a panic.
        assert!(Parallelogram::detect(&sq, &[[0, 1, 7], [1, 2, 3]]).is_none());
    }
}
