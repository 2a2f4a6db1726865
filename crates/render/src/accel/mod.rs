//! Ray–primitive intersection and the acceleration structure.
//!
//! [`Accel`] answers closest-hit ([`Accel::intersect`]) and any-hit ([`Accel::occluded`]) queries
//! over a list of [`AccelShape`]s: world-space triangle meshes, spheres, disks and infinite
//! planes. Queries take `&self`, allocate nothing and may run from any number of threads.
//!
//! # Conventions
//! - Hits satisfy `0 < t < t_max`, both bounds **exclusive**, with `t` in ray-parameter units
//!   (`p = o + t d`; `d` need not be normalised). There is no `t_min`: callers offset ray origins
//!   themselves (robust offsets along the geometric normal, see ARCHITECTURE.md).
//! - Triangles and disks are two-sided. A ray starting inside a sphere hits its far side.
//! - Rays with non-finite origin/direction or a zero direction hit nothing.
//! - Invalid input geometry is skipped, never a panic: triangles with out-of-range indices or
//!   non-finite vertices, spheres with a non-positive or non-finite radius, disks whose
//!   `to_world` is singular or non-finite, planes with a zero or non-finite normal.
//!   Triangles whose edge cross product is zero (or overflows) in `f32` are dropped too: they
//!   have no normal. The primitive tests themselves never return NaN.
//!
//! # Algorithms
//! - Triangles: watertight test of Woop, Benthin and Wald (2013, JCGT 2(1)), with the
//!   double-precision fallback for zero edge functions, evaluated four or eight triangles at a time
//!   ([`prim::tri_closest`]); no cracks along shared edges or at shared vertices.
//! - Spheres: the discriminant from the centre-to-line distance (pbrt-v4 §6.8.1, Ray Tracing
//!   Gems ch. 7) and the `q = -(b ± √Δ)/2` root pair, robust for distant and grazing rays.
//! - Disks: the ray is mapped to object space by the inverse of `to_world` (any invertible
//!   affine map, non-uniform scale included); `t` is invariant under that map.
//! - Planes: unbounded, so kept out of the BVH and tested linearly after it (and after the
//!   instances).
//!
//! # Structure: why one flat BVH
//! Everything bounded (every triangle of every mesh, every sphere and disk) goes into a single
//! 8-wide BVH (module `bvh`), built by obvhs' PLOC builder and collapsed to 8-wide float nodes tested
//! with SIMD. A flat tree over all primitives is at least as good as a two-level tree for
//! both scene classes we care about: a single 1M-triangle mesh (the top level of a two-level tree
//! would be one useless node) and small scenes of a few shapes, whose meshes may overlap in
//! space — a top level over per-shape boxes cannot separate overlapping meshes, whereas the flat
//! tree splits them primitive by primitive. Scenes that reuse geometry would pay in build
//! time and memory, which is what the instance level below is for.
//!
//! Instancing (two levels): shapes reusing one prototype, and moving shapes, are
//! [`AccelShape::Instance`]s of bottom-level trees built by [`Accel::build_instanced`]; they
//! live in a second, top-level tree queried after the flat one (module `instance`), so the
//! flat tree's leaf dispatch and traversal are exactly as without instancing. The top level
//! and the infinite planes are tested out of line (`Beside`); scenes with neither skip both
//! with one test. A hit on an instance reports the
//! instance's shape index and the prototype's primitive index.
//!
//! # Choice of tree
//! obvhs' own CWBVH (8-wide, 8-bit quantised boxes, Ylitie et al. 2017) is a GPU-oriented
//! layout: one ray at a time on the CPU, its decoding cost outweighs the memory it saves, and its
//! stock triangle test is not watertight. We keep obvhs for what it is good at (fast, parallel
//! PLOC construction and reinsertion) and own the traversal layout. `benches/accel.rs` measures
//! ours, obvhs' stock CWBVH and (with `--features embree`) Embree 3 in the same run.
//!
//! Speed: `benches/accel.rs` against obvhs' CWBVH and Embree; figures and their history in
//! `bench/README.md` ("Accelerator").

mod bvh;
mod instance;
pub mod prim;

use std::sync::Arc;

use obvhs::aabb::Aabb;

use crate::geometry::Ray;
use crate::math::{Mat3, Mat4, Vec3, Vec3A};
use bvh::{Prim, WideBvh};
use glam::Affine3A;

/// A shape as the acceleration structure sees it.
#[derive(Clone, Debug)]
pub enum AccelShape {
    /// World-space triangle mesh.
    Triangles {
        positions: Arc<[Vec3]>,
        indices: Arc<[[u32; 3]]>,
    },
    Sphere {
        center: Vec3,
        radius: f32,
    },
    /// Unit disk in the z=0 plane of its object space, placed by `to_world` (may scale non-uniformly).
    Disk {
        to_world: Mat4,
    },
    /// Unit sphere at the origin of its object space, placed by an affine `to_world` (an
    /// ellipsoid when it scales non-uniformly).
    Ellipsoid {
        to_world: Mat4,
    },
    /// The open unit cylinder x² + y² = 1, 0 ≤ z ≤ 1 of its object space, placed by an affine
    /// `to_world`.
    Cylinder {
        to_world: Mat4,
    },
    /// Infinite plane (not bounded: kept out of the BVH, tested separately).
    Plane {
        point: Vec3,
        normal: Vec3,
    },
    /// Prototype `proto` of [`Accel::build_instanced`] placed by `to_world` at time 0 and
    /// moving by `motion` per unit of [`Ray::time`] (zero for a static instance).
    Instance {
        proto: u32,
        to_world: Mat4,
        motion: Vec3,
    },
}

/// A ray hit.
///
/// `u, v`: triangle barycentrics (`p = (1-u-v) p0 + u p1 + v p2`); disk: object-space `x, y` of
/// the hit; sphere and plane: 0.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f32,
    /// Index of the shape in the `Vec` given to [`Accel::build`].
    pub shape: u32,
    /// Triangle index within the mesh; 0 for other shapes.
    pub prim: u32,
    pub u: f32,
    pub v: f32,
}

/// The scene's acceleration structure. See the module documentation.
pub struct Accel {
    bvh: WideBvh,
    bounds: (Vec3, Vec3),
    /// What is tested beside the flat tree: infinite planes and the instance level. `None`
    /// when there is neither, so that such scenes pay one test of a pointer per query (as
    /// they paid one test of the plane list's length before instancing).
    beside: Option<Box<Beside>>,
}

/// Planes and instances (see [`Accel::beside`]), queried out of line.
struct Beside {
    planes: Vec<(Vec3, Vec3, u32)>,
    /// Instances and moving shapes.
    top: Option<instance::TopLevel>,
}

impl Beside {
    /// The closest of `best` and the hits on instances and planes.
    #[inline(never)]
    fn closest(&self, ray: &Ray, t_max: f32, mut best: Option<Hit>) -> Option<Hit> {
        let mut t_max = best.map_or(t_max, |h| h.t);
        if let Some(h) = self.top.as_ref().and_then(|t| t.intersect(ray, t_max)) {
            t_max = h.t;
            best = Some(Hit {
                t: h.t,
                shape: h.shape,
                prim: h.prim,
                u: h.u,
                v: h.v,
            });
        }
        for &(point, normal, shape) in &self.planes {
            if let Some(t) = prim::intersect_plane(ray, point, normal, t_max) {
                t_max = t;
                best = Some(Hit {
                    t,
                    shape,
                    prim: 0,
                    u: 0.0,
                    v: 0.0,
                });
            }
        }
        best
    }

    #[inline(never)]
    fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        self.planes
            .iter()
            .any(|&(p, n, _)| prim::intersect_plane(ray, p, n, t_max).is_some())
            || self.top.as_ref().is_some_and(|t| t.occluded(ray, t_max))
    }
}

impl Accel {
    /// Builds the structure; a shape's index is its position in `shapes`. Invalid geometry is
    /// skipped (see the module documentation). Runs on the current rayon pool.
    ///
    /// # Panics
    /// Beyond 2²⁷ leaf packets (≈ 500M triangles), which the node encoding cannot address.
    pub fn build(shapes: Vec<AccelShape>) -> Accel {
        Accel::build_instanced(shapes, Vec::new())
    }

    /// [`Accel::build`] with prototypes: `protos` are shapes in their own object space (no
    /// planes, no instances), each given one bottom-level tree, which the
    /// [`AccelShape::Instance`]s of `shapes` refer to by index. Instances of a missing
    /// prototype, or with a singular or non-finite placement, are skipped.
    pub fn build_instanced(shapes: Vec<AccelShape>, protos: Vec<AccelShape>) -> Accel {
        let mut prims = Vec::new();
        let mut ids = Vec::new();
        let mut aabbs = Vec::new();
        let mut planes = Vec::new();
        let mut insts = Vec::new();
        let mut inst_boxes = Vec::new();
        for (s, shape) in shapes.iter().enumerate() {
            if let &AccelShape::Instance {
                proto,
                to_world,
                motion,
            } = shape
            {
                let (Some(to_object), true) = (invertible(&to_world), motion.is_finite()) else {
                    continue;
                };
                if proto as usize >= protos.len() {
                    continue;
                }
                insts.push(instance::Inst {
                    to_object: Affine3A::from_mat4(to_object),
                    motion,
                    blas: proto,
                    shape: s as u32,
                });
                continue;
            }
            add_prims(
                shape,
                s as u32,
                &mut prims,
                &mut ids,
                &mut aabbs,
                &mut planes,
            );
        }
        let blas: Vec<instance::Blas> = protos
            .iter()
            .map(|p| {
                let (mut pp, mut pi, mut pa, mut pl) =
                    (Vec::new(), Vec::new(), Vec::new(), Vec::new());
                add_prims(p, 0, &mut pp, &mut pi, &mut pa, &mut pl);
                let bounds = pa.iter().fold(Aabb::INVALID, |a, b| a.union(b));
                instance::Blas {
                    bvh: WideBvh::build(&pp, &pi, &pa),
                    bounds,
                }
            })
            .collect();
        // Instances of empty prototypes (all geometry invalid) have nothing to hit.
        insts.retain(|i| {
            blas[i.blas as usize]
                .bounds
                .min
                .cmple(blas[i.blas as usize].bounds.max)
                .all()
        });
        for i in &insts {
            let to_world = i.to_object.inverse();
            inst_boxes.push(instance::instance_box(
                &blas[i.blas as usize].bounds,
                &to_world,
                i.motion,
            ));
        }
        let top = instance::TopLevel::build(blas, insts, inst_boxes);
        let mut bb = aabbs.iter().fold(Aabb::INVALID, |a, b| a.union(b));
        if let Some(t) = &top {
            bb = bb.union(&t.bounds());
        }
        let bounds = if bb.min.cmple(bb.max).all() {
            (bb.min, bb.max)
        } else {
            (Vec3::ZERO, Vec3::ZERO)
        };
        let bvh = WideBvh::build(&prims, &ids, &aabbs);
        let beside =
            (!planes.is_empty() || top.is_some()).then(|| Box::new(Beside { planes, top }));
        Accel {
            bvh,
            bounds,
            beside,
        }
    }

    /// Bottom-level trees (prototypes) and bytes they, the instances and the top level hold;
    /// `(0, 0)` without instances.
    pub fn instancing_stats(&self) -> (usize, usize) {
        self.beside
            .as_ref()
            .and_then(|b| b.top.as_ref())
            .map_or((0, 0), |t| (t.blas_count(), t.memory_bytes()))
    }

    /// The closest hit with `0 < t < t_max`.
    #[inline]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        if !ray_ok(ray, t_max) {
            return None;
        }
        let best = self.bvh.intersect(ray, t_max).map(|h| Hit {
            t: h.t,
            shape: h.shape,
            prim: h.prim,
            u: h.u,
            v: h.v,
        });
        match &self.beside {
            None => best,
            Some(b) => b.closest(ray, t_max, best),
        }
    }

    /// Whether anything is hit with `0 < t < t_max`.
    #[inline]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        if !ray_ok(ray, t_max) {
            return false;
        }
        self.bvh.occluded(ray, t_max)
            || self.beside.as_ref().is_some_and(|b| b.occluded(ray, t_max))
    }

    /// Bounds `(min, max)` of the bounded shapes (planes excluded); `(0, 0)` if there are none.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }
}

#[inline]
#[allow(clippy::eq_op)] // `x - x` is deliberate: it is NaN exactly when `x` is not finite.
fn ray_ok(ray: &Ray, t_max: f32) -> bool {
    // `x - x` is 0 for finite `x` and NaN otherwise: one comparison covers all six
    // components, without a branch per component.
    let z = (ray.o - ray.o) + (ray.d - ray.d);
    // `cmpne(..).any()`: one mask test, where `!=` would branch on each component.
    t_max > 0.0 && z.x + z.y + z.z == 0.0 && ray.d.cmpne(Vec3::ZERO).any()
}

/// Appends the bounded primitives of `shape` (as shape `s`) or its plane.
fn add_prims(
    shape: &AccelShape,
    s: u32,
    prims: &mut Vec<Prim>,
    ids: &mut Vec<[u32; 2]>,
    aabbs: &mut Vec<Aabb>,
    planes: &mut Vec<(Vec3, Vec3, u32)>,
) {
    match shape {
        AccelShape::Triangles { positions, indices } => {
            prims.reserve(indices.len());
            ids.reserve(indices.len());
            aabbs.reserve(indices.len());
            for (t, tri) in indices.iter().enumerate() {
                let get = |i: u32| positions.get(i as usize).copied();
                let (Some(p0), Some(p1), Some(p2)) = (get(tri[0]), get(tri[1]), get(tri[2])) else {
                    continue;
                };
                // Zero-area triangles have no normal: a sliver hit after the ray's shear
                // would give shading a NaN frame, so they are dropped here.
                let n = (p1 - p0).cross(p2 - p0);
                if !(p0.is_finite() && p1.is_finite() && p2.is_finite())
                    || n == Vec3::ZERO
                    || !n.is_finite()
                {
                    continue;
                }
                prims.push(Prim::Tri([p0, p1, p2]));
                ids.push([s, t as u32]);
                aabbs.push(Aabb::new(p0.min(p1).min(p2), p0.max(p1).max(p2)));
            }
        }
        &AccelShape::Sphere { center, radius } => {
            if !(radius > 0.0 && radius.is_finite() && center.is_finite()) {
                return;
            }
            prims.push(Prim::Sphere { center, radius });
            ids.push([s, 0]);
            aabbs.push(Aabb::new(center - radius, center + radius));
        }
        &AccelShape::Disk { to_world } => {
            let Some(to_object) = invertible(&to_world) else {
                return;
            };
            let mut bb = Aabb::INVALID;
            for (x, y) in [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)] {
                bb.extend(to_world.transform_point3a(Vec3A::new(x, y, 0.0)));
            }
            prims.push(Prim::Disk { to_object });
            ids.push([s, 0]);
            aabbs.push(bb);
        }
        &AccelShape::Ellipsoid { to_world } => {
            let Some(to_object) = invertible(&to_world) else {
                return;
            };
            prims.push(Prim::Ellipsoid { to_object });
            ids.push([s, 0]);
            let (lo, hi) = ellipsoid_bounds(&to_world);
            aabbs.push(Aabb::new(lo, hi));
        }
        &AccelShape::Cylinder { to_world } => {
            let Some(to_object) = invertible(&to_world) else {
                return;
            };
            prims.push(Prim::Cylinder { to_object });
            ids.push([s, 0]);
            let (lo, hi) = cylinder_bounds(&to_world);
            aabbs.push(Aabb::new(lo, hi));
        }
        &AccelShape::Plane { point, normal } => {
            if normal.is_finite() && point.is_finite() && normal != Vec3::ZERO {
                planes.push((point, normal, s));
            }
        }
        // Instances are placed by `Accel::build_instanced`; one inside a prototype is ignored.
        AccelShape::Instance { .. } => {}
    }
}

/// The inverse of a finite, non-singular placement (`None`: the shape is skipped).
fn invertible(to_world: &Mat4) -> Option<Mat4> {
    let to_object = to_world.inverse();
    let det = to_world.determinant();
    (det != 0.0 && det.is_finite() && to_object.is_finite() && to_world.is_finite())
        .then_some(to_object)
}

/// The exact world bounds of the unit sphere under `to_world`: along axis i the extent is
/// the length of the i-th row of the linear part (max of e_i · M x over |x| = 1), rounded
/// outwards so the box contains every hit the robust test can report.
pub fn ellipsoid_bounds(to_world: &Mat4) -> (Vec3, Vec3) {
    let m = Mat3::from_mat4(*to_world).transpose();
    let half = Vec3::new(m.x_axis.length(), m.y_axis.length(), m.z_axis.length())
        * (1.0 + 4.0 * f32::EPSILON);
    let c = Vec3::from_vec4(to_world.w_axis);
    let pad = c.abs() * (2.0 * f32::EPSILON);
    (c - half - pad, c + half + pad)
}

/// Conservative world bounds of the unit cylinder's box [-1, 1]² × [0, 1] under an affine
/// `to_world`.
pub fn cylinder_bounds(to_world: &Mat4) -> (Vec3, Vec3) {
    let c0 = Vec3::from_vec4(to_world.w_axis);
    let c1 = to_world.transform_point3a(Vec3::Z);
    let (lo, hi) = (c0.min(c1), c0.max(c1));
    // The circle's half-extent along each world axis is the length of that row of the xy
    // columns; the padding covers the rounding of the transform.
    let (x, y) = (
        Vec3::from_vec4(to_world.x_axis),
        Vec3::from_vec4(to_world.y_axis),
    );
    let r = (x * x + y * y).powf(0.5);
    let pad = (lo.abs().max(hi.abs()) + r) * (4.0 * f32::EPSILON);
    (lo - r - pad, hi + r + pad)
}

/// Traversal counters for the accelerator benchmark (`--features stats`): rays, inner nodes
/// visited, leaves visited, per query kind. Without the feature the counting compiles away.
pub mod stats {
    use std::sync::atomic::{AtomicU64, Ordering};

    /// Closest hit: inner nodes, leaves, (unused), rays; occlusion: inner nodes, leaves,
    /// (unused), rays.
    static COUNTS: [AtomicU64; 8] = [const { AtomicU64::new(0) }; 8];

    #[inline(always)]
    pub(crate) fn bump(i: usize) {
        if cfg!(feature = "stats") {
            COUNTS[i].fetch_add(1, Ordering::Relaxed);
        }
    }

    /// The counters since the last call: `[closest nodes, leaves, _, rays, occlusion nodes,
    /// leaves, _, rays]`.
    pub fn take() -> [u64; 8] {
        std::array::from_fn(|i| COUNTS[i].swap(0, Ordering::Relaxed))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accel_is_shareable_between_threads() {
        fn assert_send_sync<T: Send + Sync>() {}
        assert_send_sync::<Accel>();
    }

    #[test]
    fn single_triangle_root_leaf() {
        // Fewer primitives than a leaf holds: the root is a leaf, no inner node.
        let accel = Accel::build(vec![AccelShape::Triangles {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y].into(),
            indices: vec![[0, 1, 2]].into(),
        }]);
        let h = accel
            .intersect(&Ray::new(Vec3::new(0.2, 0.3, 1.0), -Vec3::Z), f32::INFINITY)
            .expect("hit");
        assert_eq!((h.shape, h.prim, h.t), (0, 0, 1.0));
        assert!((h.u - 0.2).abs() < 1e-6 && (h.v - 0.3).abs() < 1e-6);
        assert_eq!(accel.bounds(), (Vec3::ZERO, Vec3::new(1.0, 1.0, 0.0)));
    }
}
