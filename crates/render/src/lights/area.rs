//! Area lights: an emitting shape. Radiance leaves the front side (the side the shading
//! normal points to) unless two-sided. Spheres seen from outside are sampled uniformly in the
//! cone they subtend (solid angle), ellipsoids in the cone of their object sphere carried by
//! the Jacobian of the map; meshes by area (triangle chosen in proportion to its area, then a
//! uniform point; a two-triangle parallelogram, the usual quad light, in one step), disks by
//! area; area densities are converted to solid angle. Under light selection by power or BVH
//! an emitting mesh becomes one light per triangle (`prim`), so that each triangle is chosen
//! on its own.

use std::sync::Arc;

use glam::Mat3A;

use super::LightScene;
use super::bvh::LightBounds;
use super::select::{mean_radiance, omni};
use super::{LightModel, LightSample, Receiver, ShadowTarget};
use crate::math::{Frame, PI, Vec2, Vec3, rsqrt};
use crate::sampling::distrib::Distribution1D;
use crate::sampling::warp;
use crate::shapes::{Ellipsoid, ShapeGeom, SurfaceInteraction, disk_uv, gamma, sphere_uv};
use crate::textures::{ColorRef, TexCoord, TexRef};

#[derive(Clone, Debug)]
pub struct AreaLight {
    pub shape: u32,
    pub radiance: ColorRef,
    pub two_sided: bool,
    /// How a point is placed on a mesh lit as a whole (meshes only).
    pub triangles: Option<MeshSampling>,
    /// For a light that is one triangle of a mesh (light selection by power or by the
    /// light BVH splits emitting meshes): that triangle; `triangles` is then `None`.
    pub prim: Option<u32>,
    /// Area of the emitting surface (of the one triangle when `prim` is set).
    pub area: f32,
}

impl LightModel for AreaLight {
    fn is_delta(&self) -> bool {
        false
    }

    fn sample_li(&self, scene: &impl LightScene, r: &Receiver, u: Vec2) -> Option<LightSample> {
        let info = scene.shape(self.shape);
        let flip = if info.flip_normals { -1.0 } else { 1.0 };
        // The sampled point's uv only feeds a radiance texture.
        let textured = matches!(self.radiance, TexRef::Texture(_));
        let (p, p_error, n, uv, pdf) = match &info.geom {
            ShapeGeom::Sphere { center, radius } => {
                return sample_sphere(
                    scene,
                    *center,
                    *radius,
                    flip,
                    self.two_sided,
                    &self.radiance,
                    r,
                    u,
                );
            }
            ShapeGeom::Mesh {
                positions,
                normals,
                uvs,
                indices,
            } => {
                if self.area.is_nan() || self.area <= 0.0 {
                    return None;
                }
                let (tri, b) = match (self.prim, &self.triangles) {
                    (Some(t), _) => (t as usize, warp::square_to_uniform_triangle(u)),
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
                let err = gamma(6) * ((b0 * p0).abs() + (b.x * p1).abs() + (b.y * p2).abs());
                let face = match &self.triangles {
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
                (p, err, n, uv, 1.0 / self.area)
            }
            ShapeGeom::Disk { to_world, normal } => {
                let d = warp::square_to_uniform_disk_concentric(u);
                let p = to_world.transform_point3a(Vec3::new(d.x, d.y, 0.0));
                let err = gamma(6) * (p.abs() + Vec3::from_vec4(to_world.w_axis).abs());
                let uv = if textured { disk_uv(d) } else { Vec2::ZERO };
                (p, err, *normal * flip, uv, 1.0 / self.area)
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
                if n.dot(-wi) <= 0.0 && !self.two_sided {
                    return None;
                }
                let uv = if textured { sphere_uv(dir) } else { Vec2::ZERO };
                return Some(LightSample {
                    wi,
                    li: scene.color(&self.radiance, TexCoord { uv, p }),
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
        if cos_l == 0.0 || (!self.two_sided && cos_l < 0.0) {
            return None;
        }
        Some(LightSample {
            wi,
            li: scene.color(&self.radiance, TexCoord { uv, p }),
            pdf: pdf * d2 / cos_l.abs(),
            delta: false,
            target: ShadowTarget::Surface { p, p_error, n },
        })
    }

    fn pdf_li(
        &self,
        scene: &impl LightScene,
        r: &Receiver,
        wi: Vec3,
        si: Option<&SurfaceInteraction>,
    ) -> f32 {
        let Some(si) = si else { return 0.0 };
        let info = scene.shape(self.shape);
        if let ShapeGeom::Sphere { center, radius } = &info.geom {
            // Zero where `sample_li` yields nothing: the back of a one-sided light.
            if !self.two_sided && si.shading.n.dot(-wi) <= 0.0 {
                return 0.0;
            }
            return sphere_pdf(*center, *radius, r.p, si.p);
        }
        let d2 = (si.p - r.p).length_squared();
        let cos_l = si.ng.dot(-wi);
        if cos_l == 0.0 || (!self.two_sided && si.shading.n.dot(-wi) < 0.0) {
            return 0.0;
        }
        match &info.geom {
            ShapeGeom::Ellipsoid(e) => ellipsoid_pdf(e, r.p, wi, si.p, cos_l.abs()),
            _ => d2 / (cos_l.abs() * self.area),
        }
    }

    fn le(&self, scene: &impl LightScene, si: &SurfaceInteraction) -> Vec3 {
        if self.two_sided || si.shading.n.dot(si.wo) > 0.0 {
            scene.color(&self.radiance, si.tex())
        } else {
            Vec3::ZERO
        }
    }

    /// π·A·L̄, twice for a two-sided light.
    fn power(&self, scene: &impl LightScene) -> f32 {
        let sides = if self.two_sided { 2.0 } else { 1.0 };
        PI * sides * self.area * mean_radiance(scene, &self.radiance)
    }

    fn bounds(&self, scene: &impl LightScene, phi: f32) -> Option<LightBounds> {
        let info = scene.shape(self.shape);
        let flip = if info.flip_normals { -1.0 } else { 1.0 };
        let any = |lo, hi| LightBounds {
            two_sided: self.two_sided,
            ..omni(lo, hi, phi)
        };
        match &info.geom {
            ShapeGeom::Sphere { center, radius } => {
                let r = Vec3::splat(*radius);
                Some(any(*center - r, *center + r))
            }
            ShapeGeom::Ellipsoid(e) => {
                let (lo, hi) = crate::accel::ellipsoid_bounds(&e.to_world);
                Some(any(lo, hi))
            }
            ShapeGeom::Disk { to_world, normal } => {
                let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                    .map(|(x, y)| to_world.transform_point3a(Vec3::new(x, y, 0.0)));
                let lo = corners.iter().fold(corners[0], |a, c| a.min(*c));
                let hi = corners.iter().fold(corners[0], |a, c| a.max(*c));
                Some(LightBounds {
                    w: *normal * flip,
                    cos_o: 1.0,
                    ..any(lo, hi)
                })
            }
            ShapeGeom::Mesh {
                positions,
                normals,
                indices,
                ..
            } => match self.prim {
                Some(t) => {
                    let tri = indices.get(t as usize)?;
                    let [i0, i1, i2] = tri.map(|i| i as usize);
                    let (p0, p1, p2) = (positions[i0], positions[i1], positions[i2]);
                    let w = (p1 - p0).cross(p2 - p0).normalize_or_zero() * flip;
                    let mut b = LightBounds {
                        w,
                        cos_o: 1.0,
                        ..any(p0.min(p1).min(p2), p0.max(p1).max(p2))
                    };
                    if let Some(ns) = normals {
                        // Shading normals tilt the emitting hemisphere: widen the cone to hold
                        // them (on the side of w; one against w is either side).
                        for i in [i0, i1, i2] {
                            let c = ns[i].normalize_or_zero().dot(w);
                            if c < 0.0 {
                                b.two_sided = true;
                            }
                            b.cos_o = b.cos_o.min(c.abs());
                        }
                    }
                    Some(b)
                }
                None => {
                    let lo = positions.iter().fold(Vec3::INFINITY, |a, p| a.min(*p));
                    let hi = positions.iter().fold(Vec3::NEG_INFINITY, |a, p| a.max(*p));
                    Some(any(lo, hi))
                }
            },
            // Emitters are never instanced nor moving (`build` flattens them).
            ShapeGeom::Plane { .. } | ShapeGeom::Instance(_) => None,
        }
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
    /// reading it back.
    #[inline(always)]
    pub fn sample(&self, u: Vec2) -> (usize, Vec2) {
        let tri = (u.x + u.y > 1.0) as usize;
        let [c1, c2] = self.coef[tri];
        let x = Vec3::new(1.0, u.x, u.y);
        (tri, Vec2::new(c1.dot(x), c2.dot(x)))
    }
}

/// Mitsuba's sphere emitter sampling: uniform cone from outside, uniform area from inside.
#[allow(clippy::too_many_arguments)]
fn sample_sphere(
    scene: &impl LightScene,
    center: Vec3,
    radius: f32,
    flip: f32,
    two_sided: bool,
    radiance: &ColorRef,
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
    let uv = if matches!(radiance, TexRef::Texture(_)) {
        sphere_uv(n_out)
    } else {
        Vec2::ZERO
    };
    Some(LightSample {
        wi,
        li: scene.color(radiance, TexCoord { uv, p }),
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
    use crate::math::Mat3;

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
