//! Choosing one light for next-event estimation: uniformly (Mitsuba), in proportion to
//! emitted power (an alias table, pbrt-v4's `PowerLightSampler`) or with the light BVH
//! ([`super::bvh`]), and the power and bounds of each light these need.
//!
//! Power follows pbrt-v4's `Phi` with the channel mean of RGB: π·A·L̄ for area lights (twice
//! for two-sided ones), 4π·I for point lights, 2π·I·((1 − cos θbeam) + (cos θbeam −
//! cos θcutoff)/2) for spots, and for infinite lights the power through a disk of the scene's
//! bounding radius r: π r²·E (directional), 4π·π r²·L̄ (constant and environment maps, L̄ the
//! solid-angle mean). Textured emitters use the mean of an 8×8 grid of texture lookups.

use scene::{ColorParam, EnvMapping, LightSelection};

use crate::build::Scene;
use crate::math::{PI, Vec2, Vec3};
use crate::sampling::distrib::AliasTable;
use crate::shapes::ShapeGeom;

use super::bvh::{LightBounds, LightBvh};
use super::{Light, Receiver};

/// The light selection strategy of a scene, built once.
#[derive(Clone, Debug)]
pub enum LightSampler {
    Uniform,
    Power(AliasTable),
    Bvh(LightBvh),
}

#[inline]
fn mean(c: Vec3) -> f32 {
    ((c.x + c.y + c.z) / 3.0).max(0.0)
}

/// Mean radiance of an emitter's colour over its texture space.
fn mean_radiance(scene: &Scene, c: &ColorParam) -> f32 {
    match c {
        ColorParam::Const(c) => mean((*c).into()),
        ColorParam::Texture(_) => {
            const N: usize = 8;
            let mut sum = 0.0;
            for i in 0..N * N {
                let uv = Vec2::new(
                    ((i % N) as f32 + 0.5) / N as f32,
                    ((i / N) as f32 + 0.5) / N as f32,
                );
                sum += mean(scene.color(c, uv));
            }
            sum / (N * N) as f32
        }
    }
}

/// Radius of the bounding sphere of the scene's bounded geometry (1 if it has none).
fn scene_radius(scene: &Scene) -> f32 {
    let (lo, hi) = scene.bounds;
    let r = 0.5 * (hi - lo).length();
    if r.is_finite() && r > 0.0 { r } else { 1.0 }
}

/// Emitted power of `light` (see the module docs); 0 for a light that emits nothing.
pub fn phi(scene: &Scene, light: &Light) -> f32 {
    let p = match light {
        Light::Area {
            radiance,
            two_sided,
            area,
            ..
        } => {
            let sides = if *two_sided { 2.0 } else { 1.0 };
            PI * sides * *area * mean_radiance(scene, radiance)
        }
        Light::Point { intensity, .. } => 4.0 * PI * mean(*intensity),
        Light::Spot {
            intensity,
            cos_cutoff,
            cos_beam,
            ..
        } => 2.0 * PI * mean(*intensity) * ((1.0 - cos_beam) + 0.5 * (cos_beam - cos_cutoff)),
        Light::Directional { irradiance, .. } => {
            let r = scene_radius(scene);
            PI * r * r * mean(*irradiance)
        }
        Light::Constant { radiance } => {
            let r = scene_radius(scene);
            4.0 * PI * PI * r * r * mean(*radiance)
        }
        Light::EnvMap(env) => {
            let (w, h) = (env.image.width, env.image.height);
            let (mut sum, mut weight) = (0f64, 0f64);
            for y in 0..h {
                // Lat-long rows are spaced by θ: weight by sin θ for the solid-angle mean.
                let s = match env.mapping {
                    EnvMapping::LatLong => ((y as f32 + 0.5) / h as f32 * PI).sin() as f64,
                    EnvMapping::Probe => 1.0,
                };
                for x in 0..w {
                    let v = mean(env.image.get(x, y));
                    if v.is_finite() {
                        sum += s * v as f64;
                    }
                    weight += s;
                }
            }
            let avg = if weight > 0.0 { sum / weight } else { 0.0 } as f32 * env.scale.max(0.0);
            let r = scene_radius(scene);
            4.0 * PI * PI * r * r * avg
        }
    };
    if p.is_finite() { p.max(0.0) } else { 0.0 }
}

/// Bounds of a bounded light for the light BVH (`None` for infinite lights and lights
/// without power).
pub fn light_bounds(scene: &Scene, light: &Light) -> Option<LightBounds> {
    let phi = phi(scene, light);
    if phi <= 0.0 {
        return None;
    }
    let any = |lo: Vec3, hi: Vec3| LightBounds {
        lo,
        hi,
        w: Vec3::Z,
        phi,
        cos_o: -1.0,
        cos_e: 0.0,
        two_sided: false,
    };
    match light {
        Light::Point { position, .. } => Some(any(*position, *position)),
        Light::Spot {
            position,
            to_local,
            cos_cutoff,
            cos_beam,
            ..
        } => {
            let w = (to_local.inverse() * Vec3::Z).normalize_or_zero();
            if w == Vec3::ZERO {
                return Some(any(*position, *position));
            }
            let theta_e =
                (cos_cutoff.clamp(-1.0, 1.0).acos() - cos_beam.clamp(-1.0, 1.0).acos()).max(0.0);
            Some(LightBounds {
                w,
                cos_o: *cos_beam,
                cos_e: theta_e.cos(),
                ..any(*position, *position)
            })
        }
        Light::Area {
            shape,
            two_sided,
            prim,
            ..
        } => {
            let info = &scene.shapes[*shape as usize];
            let flip = if info.flip_normals { -1.0 } else { 1.0 };
            match &info.geom {
                ShapeGeom::Sphere { center, radius } => {
                    let r = Vec3::splat(*radius);
                    Some(LightBounds {
                        two_sided: *two_sided,
                        ..any(*center - r, *center + r)
                    })
                }
                ShapeGeom::Ellipsoid(e) => {
                    let (lo, hi) = crate::accel::ellipsoid_bounds(&e.to_world);
                    Some(LightBounds {
                        two_sided: *two_sided,
                        ..any(lo, hi)
                    })
                }
                ShapeGeom::Disk { to_world, normal } => {
                    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
                        .map(|(x, y)| to_world.transform_point3a(Vec3::new(x, y, 0.0)));
                    let lo = corners.iter().fold(corners[0], |a, c| a.min(*c));
                    let hi = corners.iter().fold(corners[0], |a, c| a.max(*c));
                    Some(LightBounds {
                        w: *normal * flip,
                        cos_o: 1.0,
                        two_sided: *two_sided,
                        ..any(lo, hi)
                    })
                }
                ShapeGeom::Mesh {
                    positions,
                    normals,
                    indices,
                    ..
                } => match prim {
                    Some(t) => {
                        let tri = indices.get(*t as usize)?;
                        let [i0, i1, i2] = tri.map(|i| i as usize);
                        let (p0, p1, p2) = (positions[i0], positions[i1], positions[i2]);
                        let w = (p1 - p0).cross(p2 - p0).normalize_or_zero() * flip;
                        let mut b = LightBounds {
                            w,
                            cos_o: 1.0,
                            two_sided: *two_sided,
                            ..any(p0.min(p1).min(p2), p0.max(p1).max(p2))
                        };
                        if let Some(ns) = normals {
                            // Shading normals tilt the emitting hemisphere: widen the cone
                            // to hold them (on the side of w; one against w is either side).
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
                        Some(LightBounds {
                            two_sided: *two_sided,
                            ..any(lo, hi)
                        })
                    }
                },
                // Emitters are never instanced nor moving (`build` flattens them).
                ShapeGeom::Plane { .. } | ShapeGeom::Instance(_) => None,
            }
        }
        Light::Directional { .. } | Light::Constant { .. } | Light::EnvMap(_) => None,
    }
}

/// One of `n > 0` lights, uniformly. In u32: conversions between f32 and 64-bit unsigned
/// integers take several instructions on x86-64, 32-bit ones one or two.
#[inline(always)]
fn uniform_choice(u: f32, n: usize) -> Option<(u32, f32)> {
    let n = n as u32;
    let i = ((u * n as f32) as u32).min(n - 1);
    Some((i, 1.0 / n as f32))
}

impl LightSampler {
    /// Builds the strategy `kind` over the lights of `scene`.
    pub fn new(kind: LightSelection, scene: &Scene) -> LightSampler {
        match kind {
            LightSelection::Uniform => LightSampler::Uniform,
            LightSelection::Power => {
                let w: Vec<f32> = scene.lights.iter().map(|l| phi(scene, l)).collect();
                LightSampler::Power(AliasTable::new(&w))
            }
            LightSelection::Bvh => {
                let bounds: Vec<Option<LightBounds>> = scene
                    .lights
                    .iter()
                    .map(|l| {
                        if l.is_infinite() {
                            None
                        } else {
                            light_bounds(scene, l)
                        }
                    })
                    .collect();
                LightSampler::Bvh(LightBvh::new(&bounds, &scene.infinite_lights))
            }
        }
    }

    /// A light index for `r` among `n` lights and its probability.
    #[inline]
    pub fn sample(&self, u: f32, r: &Receiver, n: usize) -> Option<(u32, f32)> {
        if n == 0 {
            return None;
        }
        match self {
            LightSampler::Uniform => uniform_choice(u, n),
            _ => self.sample_other(u, r, n),
        }
    }

    /// [`Self::sample`] by power or with the light BVH: out of line (one call site keeps the
    /// uniform choice inlined into the path loop at a few instructions).
    #[inline(never)]
    fn sample_other(&self, u: f32, r: &Receiver, n: usize) -> Option<(u32, f32)> {
        match self {
            LightSampler::Uniform => uniform_choice(u, n),
            LightSampler::Power(table) => {
                let (i, pmf) = table.sample(u);
                (pmf > 0.0).then_some((i as u32, pmf))
            }
            LightSampler::Bvh(bvh) => bvh.sample(u, r),
        }
    }

    /// Probability that [`Self::sample`] returns `light`.
    #[inline]
    pub fn pmf(&self, r: &Receiver, light: u32, n: usize) -> f32 {
        match self {
            LightSampler::Uniform => 1.0 / n.max(1) as u32 as f32,
            LightSampler::Power(table) => table.pmf(light as usize),
            LightSampler::Bvh(bvh) => bvh.pmf(r, light),
        }
    }
}
