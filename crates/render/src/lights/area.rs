//! Area lights: an emitting shape. Radiance leaves the front side (the side the shading
//! normal points to) unless two-sided. Spheres seen from outside are sampled uniformly in the
//! cone they subtend (solid angle), ellipsoids in the cone of their object sphere carried by
//! the Jacobian of the map; meshes by area (triangle chosen in proportion to its area, then a
//! uniform point; a two-triangle parallelogram, the usual quad light, in one step), disks by
//! area, cylinders uniformly in (φ, z) as Mitsuba does (by area under Mitsuba's transforms);
//! area densities are converted to solid angle. Under light selection by power or BVH
//! an emitting mesh becomes one light per triangle (`prim`), so that each triangle is chosen
//! on its own.

use super::LightScene;
use super::bvh::LightBounds;
use super::select::{mean_radiance, omni};
use super::{EmissionSample, LightModel, LightSample, Receiver, ShadowTarget};
use crate::geometry::Ray;
use crate::math::{Frame, PI, Vec2, Vec3, rsqrt};
use crate::sampling::warp;
use crate::shapes::{
    MeshSampling, ShapeGeom, SurfaceInteraction, cylinder_uv, disk_uv, ellipsoid, gamma,
    offset_ray_origin, sphere, sphere_uv,
};
use crate::spectral::lanes::{Color, ColorMode};
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

impl AreaLight {
    /// A point on an emitting mesh, disk or cylinder, uniform by area (a cylinder's in (φ, z),
    /// see [`crate::shapes::Cylinder::sample`]): its position, error bound,
    /// emitting normal (`flip` applied, turned to the shading normal's side), uv (for a
    /// radiance texture, when `textured`) and area density. `None` for other shapes and
    /// degenerate meshes.
    #[inline(always)]
    pub(super) fn sample_point(
        &self,
        geom: &ShapeGeom,
        flip: f32,
        textured: bool,
        u: Vec2,
    ) -> Option<(Vec3, Vec3, Vec3, Vec2, f32)> {
        Some(match geom {
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
            ShapeGeom::Cylinder(c) => {
                let (q, pdf) = c.sample(u);
                let (p, err) = c.point(q);
                let uv = if textured { cylinder_uv(q) } else { Vec2::ZERO };
                (p, err, c.normal(q) * flip, uv, pdf)
            }
            _ => return None,
        })
    }

    /// A point of the emitting surface for an emitted ray (`sample_le`; the
    /// `directionalarea` light too): uniform by area (an ellipsoid's uniform on its object
    /// sphere, see `sample_le`): position, error bound, emitting normal, uv (when
    /// `textured`) and area density.
    #[inline]
    pub(super) fn sample_position(
        &self,
        scene: &impl LightScene,
        textured: bool,
        u_pos: Vec2,
    ) -> Option<(Vec3, Vec3, Vec3, Vec2, f32)> {
        let info = scene.shape(self.shape);
        let flip = if info.flip_normals { -1.0 } else { 1.0 };
        self.sample_position_on(&info.geom, flip, textured, u_pos)
    }

    /// [`Self::sample_position`] on a given geometry (world space, `flip` −1 for flipped
    /// normals): also Mitsuba's `irradiancemeter`, which places its rays' origins so
    /// (the camera module's `MeterShape`).
    #[inline]
    pub fn sample_position_on(
        &self,
        geom: &ShapeGeom,
        flip: f32,
        textured: bool,
        u_pos: Vec2,
    ) -> Option<(Vec3, Vec3, Vec3, Vec2, f32)> {
        Some(match geom {
            ShapeGeom::Sphere { center, radius } => {
                let d = warp::square_to_uniform_sphere(u_pos);
                let p = *center + d * *radius;
                let uv = if textured { sphere_uv(d) } else { Vec2::ZERO };
                let err = gamma(5) * (p.abs() + center.abs());
                (p, err, d * flip, uv, 1.0 / self.area)
            }
            ShapeGeom::Ellipsoid(e) => {
                let q = warp::square_to_uniform_sphere(u_pos);
                let (p, err) = e.point(q);
                let uv = if textured { sphere_uv(q) } else { Vec2::ZERO };
                (
                    p,
                    err,
                    e.normal(q) * flip,
                    uv,
                    1.0 / (4.0 * PI * e.area_scale(q)),
                )
            }
            geom => self.sample_point(geom, flip, textured, u_pos)?,
        })
    }
}

impl LightModel for AreaLight {
    fn is_delta(&self) -> bool {
        false
    }

    fn sample_li<M: ColorMode>(
        &self,
        scene: &impl LightScene,
        r: &Receiver,
        u: Vec2,
        m: &M,
    ) -> Option<LightSample<M::C>> {
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
                    m,
                );
            }
            ShapeGeom::Mesh { .. } | ShapeGeom::Disk { .. } | ShapeGeom::Cylinder(_) => {
                self.sample_point(&info.geom, flip, textured, u)?
            }
            ShapeGeom::Ellipsoid(e) => {
                let (dir, pdf_solid) = ellipsoid::sample(e, r.p, u)?;
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
                    li: m.illuminant_at(scene, &self.radiance, TexCoord::at(uv, p)),
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
            li: m.illuminant_at(scene, &self.radiance, TexCoord::at(uv, p)),
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
            return sphere::pdf(*center, *radius, r.p, si.p);
        }
        let d2 = (si.p - r.p).length_squared();
        let cos_l = si.ng.dot(-wi);
        if cos_l == 0.0 || (!self.two_sided && si.shading.n.dot(-wi) < 0.0) {
            return 0.0;
        }
        match &info.geom {
            ShapeGeom::Ellipsoid(e) => ellipsoid::pdf(e, r.p, wi, si.p, cos_l.abs()),
            ShapeGeom::Cylinder(c) => d2 * c.pdf_area(c.project(si.p)) / cos_l.abs(),
            _ => d2 / (cos_l.abs() * self.area),
        }
    }

    fn le<M: ColorMode>(&self, scene: &impl LightScene, si: &SurfaceInteraction, m: &M) -> M::C {
        if self.two_sided || si.shading.n.dot(si.wo) > 0.0 {
            m.illuminant_at(scene, &self.radiance, si.tex())
        } else {
            M::C::ZERO
        }
    }

    /// A point uniform by area (spheres too: photons leave every part of them), a direction
    /// cosine-weighted about its normal (a two-sided light picks a side with `u_dir.x`
    /// first). Ellipsoids: a point uniform on the object sphere carried to the world, of area
    /// density 1/(4π·s) with s the map's local area scale there (exact uniform-by-area
    /// sampling would need rejection, an unbounded number of random numbers); its photons
    /// carry power in proportion to s.
    fn sample_le<M: ColorMode>(
        &self,
        scene: &impl LightScene,
        u_pos: Vec2,
        u_dir: Vec2,
        m: &M,
    ) -> Option<EmissionSample<M::C>> {
        let textured = matches!(self.radiance, TexRef::Texture(_));
        let (p, p_error, n, uv, pdf_pos) = self.sample_position(scene, textured, u_pos)?;
        if !(pdf_pos > 0.0 && pdf_pos.is_finite()) {
            return None;
        }
        let (mut ud, mut n, mut sides) = (u_dir, n, 1.0);
        if self.two_sided {
            sides = 2.0;
            if ud.x < 0.5 {
                ud.x *= 2.0;
            } else {
                ud.x = (ud.x - 0.5) * 2.0;
                n = -n;
            }
        }
        let local = warp::square_to_cosine_hemisphere(ud);
        let cos = local.z;
        if cos <= 0.0 {
            return None;
        }
        let w = Frame::from_normal(n).to_world(local);
        let pdf_dir = cos / (PI * sides);
        let le = m.illuminant_at(scene, &self.radiance, TexCoord::at(uv, p));
        Some(EmissionSample {
            ray: Ray::new(offset_ray_origin(p, p_error, n, w), w),
            p,
            weight: le * (cos / (pdf_pos * pdf_dir)),
            pdf_pos,
            pdf_dir,
            n,
        })
    }

    /// `sample_le`'s densities: pdf_pos 1/A (meshes, disks, spheres; for an ellipsoid
    /// 1/(4π·s) with s the area scale at the object-sphere point of `p`), pdf_dir cos/π with
    /// cos = n·d (|n·d|/2π for a two-sided light); (0, 0) for d on or behind the emitting
    /// side and for shapes `sample_le` does not emit from.
    fn pdf_le(&self, scene: &impl LightScene, p: Vec3, n: Vec3, d: Vec3) -> (f32, f32) {
        let info = scene.shape(self.shape);
        let pdf_pos = match &info.geom {
            ShapeGeom::Sphere { .. } | ShapeGeom::Disk { .. } => 1.0 / self.area,
            ShapeGeom::Mesh { indices, .. } => {
                // What `sample_point` accepts: a positive area, a triangle to sample.
                let has_tri = match self.prim {
                    Some(t) => (t as usize) < indices.len(),
                    None => self.triangles.is_some(),
                };
                if self.area.is_nan() || self.area <= 0.0 || !has_tri {
                    return (0.0, 0.0);
                }
                1.0 / self.area
            }
            ShapeGeom::Ellipsoid(e) => {
                let q = e.to_object.transform_point3a(p).normalize_or(Vec3::Z);
                1.0 / (4.0 * PI * e.area_scale(q))
            }
            ShapeGeom::Cylinder(c) => c.pdf_area(c.project(p)),
            ShapeGeom::Plane { .. } | ShapeGeom::Instance(_) => return (0.0, 0.0),
        };
        if !(pdf_pos > 0.0 && pdf_pos.is_finite()) {
            return (0.0, 0.0);
        }
        let cos = n.dot(d);
        let (cos, sides) = if self.two_sided {
            (cos.abs(), 2.0)
        } else {
            (cos, 1.0)
        };
        if cos <= 0.0 {
            return (0.0, 0.0);
        }
        (pdf_pos, cos / (PI * sides))
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
            ShapeGeom::Cylinder(c) => {
                let (lo, hi) = crate::accel::cylinder_bounds(&c.to_world);
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

/// A sphere light's sample ([`sphere::sample`]) with its radiance and orientation.
#[allow(clippy::too_many_arguments)]
fn sample_sphere<M: ColorMode>(
    scene: &impl LightScene,
    center: Vec3,
    radius: f32,
    flip: f32,
    two_sided: bool,
    radiance: &ColorRef,
    r: &Receiver,
    u: Vec2,
    m: &M,
) -> Option<LightSample<M::C>> {
    let (p, pdf_solid) = sphere::sample(center, radius, r.p, u)?;
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
        li: m.illuminant_at(scene, radiance, TexCoord::at(uv, p)),
        pdf: pdf_solid,
        delta: false,
        target: ShadowTarget::Surface {
            p,
            p_error: gamma(5) * (p.abs() + center.abs()),
            n,
        },
    })
}
