//! Runtime shapes: a file per kind of shape, each with its interaction (position with its
//! floating-point error bound, normals, shading frame, uv) and what light sampling needs of
//! it; [`ShapeGeom`] is the one runtime shape type and [`ShapeGeom::accel_shape`] its view for
//! the accelerator (`accel::AccelShape`: the data the BVH's leaf packets are built from —
//! ray–primitive intersection stays in `accel/prim.rs`, where the packets live).
//!
//! - `mesh.rs` — triangle meshes: interaction (smooth or flat), area, area sampling
//!   ([`MeshSampling`], [`Parallelogram`]).
//! - `sphere.rs`, `ellipsoid.rs`, `disk.rs`, `cylinder.rs`, `plane.rs` — the analytic shapes
//!   (rectangles and cubes are meshed at build time, as Mitsuba does); spheres and ellipsoids
//!   carry their solid-angle sampling, cylinders their (φ, z) area sampling.
//! - `instance.rs` — a prototype mesh seen through a placement, or a moving shape.
//! - `interaction.rs` — [`SurfaceInteraction`] and robust spawning (pbrt-v4 §6.8): every hit
//!   point carries a conservative bound `p_error` of its rounding error; rays leave along the
//!   geometric normal by exactly that bound (rounded away from the surface), so there is
//!   neither self-intersection nor a light leak, whatever the scene scale.

pub mod cylinder;
pub mod disk;
pub mod ellipsoid;
pub mod instance;
mod interaction;
pub mod mesh;
pub mod plane;
pub mod sphere;

use std::sync::Arc;

pub use cylinder::{Cylinder, cylinder_uv};
pub use disk::disk_uv;
pub use ellipsoid::Ellipsoid;
pub use instance::Instance;
pub use interaction::{SHADOW_EPSILON, SurfaceInteraction, offset_ray_origin};
pub use mesh::{MeshSampling, Parallelogram};
pub use sphere::sphere_uv;

use crate::accel::{AccelShape, Hit};
use crate::geometry::Ray;
use crate::math::{Frame, Mat4, PI, Vec2, Vec3, rsqrt};
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
    /// Mitsuba's open cylinder: the unit cylinder x² + y² = 1, 0 ≤ z ≤ 1 of its `to_world`.
    Cylinder(Box<Cylinder>),
    Plane {
        point: Vec3,
        normal: Vec3,
    },
    /// An instance of a shared prototype mesh, or a moving shape (see [`Instance`]).
    Instance(Box<Instance>),
}

impl ShapeGeom {
    /// ∂p/∂u and ∂p/∂v on primitive `prim` (world space), for texture footprints: meshes
    /// only (their uvs, or the barycentrics that stand for missing ones); `None` elsewhere.
    pub fn uv_derivatives(&self, prim: u32) -> Option<(Vec3, Vec3)> {
        let ShapeGeom::Mesh {
            positions,
            uvs,
            indices,
            ..
        } = self
        else {
            return None;
        };
        let idx = indices.get(prim as usize)?.map(|i| i as usize);
        let [p0, p1, p2] = idx.map(|i| positions[i]);
        let [t0, t1, t2] = match uvs {
            Some(t) => idx.map(|i| t[i]),
            None => [Vec2::ZERO, Vec2::X, Vec2::Y],
        };
        let (e1, e2) = (p1 - p0, p2 - p0);
        let (du1, du2) = (t1 - t0, t2 - t0);
        let det = du1.x * du2.y - du1.y * du2.x;
        if det.abs() < 1e-12 {
            return None;
        }
        let dpdu = (e1 * du2.y - e2 * du1.y) / det;
        let dpdv = (e2 * du1.x - e1 * du2.x) / det;
        Some((dpdu, dpdv))
    }

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
            ShapeGeom::Cylinder(c) => AccelShape::Cylinder {
                to_world: c.to_world,
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

    /// World-space bounds (`None` for planes; instances' prototypes are not at hand here,
    /// so `None` for them too).
    pub fn bounds(&self) -> Option<(Vec3, Vec3)> {
        match self {
            ShapeGeom::Mesh { positions, .. } => Some(
                positions
                    .iter()
                    .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
                        (lo.min(p), hi.max(p))
                    }),
            ),
            ShapeGeom::Sphere { center, radius } => Some((
                *center - Vec3::splat(*radius),
                *center + Vec3::splat(*radius),
            )),
            // The unit disk lies in the unit sphere: its image's bounds hold it.
            ShapeGeom::Disk { to_world, .. } => Some(crate::accel::ellipsoid_bounds(to_world)),
            ShapeGeom::Ellipsoid(e) => Some(crate::accel::ellipsoid_bounds(&e.to_world)),
            ShapeGeom::Cylinder(c) => Some(crate::accel::cylinder_bounds(&c.to_world)),
            ShapeGeom::Plane { .. } | ShapeGeom::Instance(_) => None,
        }
    }

    /// Surface area in world space (infinite for planes).
    pub fn area(&self) -> f32 {
        match self {
            ShapeGeom::Mesh {
                positions, indices, ..
            } => mesh::area(positions, indices, |p| p),
            ShapeGeom::Sphere { radius, .. } => 4.0 * PI * radius * radius,
            ShapeGeom::Disk { to_world, .. } => disk::area(to_world),
            ShapeGeom::Ellipsoid(e) => e.area,
            ShapeGeom::Cylinder(c) => c.area,
            ShapeGeom::Plane { .. } => f32::INFINITY,
            ShapeGeom::Instance(i) => match &i.base {
                ShapeGeom::Mesh {
                    positions, indices, ..
                } => mesh::area(positions, indices, |p| i.to_world.transform_point3a(p)),
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

/// What a shape's own interaction code finds before the common tail
/// ([`finish_interaction`]): position, its error bound, geometric and shading normals,
/// ∂p/∂u and uv.
pub(super) type Local = (Vec3, Vec3, Vec3, Vec3, Vec3, Vec2);

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
            return mesh::interaction(
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
            sphere::interaction(*center, *radius, hit, ray, reads)
        }
        ShapeGeom::Disk { to_world, normal } => disk::interaction(to_world, *normal, hit, reads),
        ShapeGeom::Ellipsoid(e) => e.interaction(hit, ray, reads),
        ShapeGeom::Cylinder(c) => c.interaction(hit, ray, reads),
        ShapeGeom::Plane { point, normal } => plane::interaction(*point, *normal, hit, ray),
        ShapeGeom::Instance(i) => return i.interaction(hit, ray, flip, reads),
    };
    finish_interaction(p, p_error, ng, ns, dpdu, uv, wo, hit, ray.time, flip)
}

/// The common tail of [`interaction`]: orientation and the shading frame.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn finish_interaction(
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
    /// The media inside (opposite the geometric normal) and outside (where it points): indices
    /// into the scene's media. A shape with either set is a medium transition.
    pub interior: Option<u32>,
    pub exterior: Option<u32>,
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
}
