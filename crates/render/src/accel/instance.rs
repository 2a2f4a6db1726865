//! The two-level part of [`super::Accel`]: instances of shared prototypes, and moving shapes.
//!
//! Each prototype (a mesh shared by several shapes, or the one shape of a moving object) has
//! its own bottom-level [`WideBvh`] in its object space, built once however many instances use
//! it. An instance is a prototype, an affine `to_object` map and a translation per unit of
//! time (`motion`, zero for static instances): a ray at time τ reaches the prototype as
//! `to_object(o − τ·motion) + s·to_object.linear(d)`. The affine map leaves the ray parameter
//! unchanged (the object-space direction is not normalised), so a bottom-level `t` is a
//! world `t` and the closest hit is found with one shared `t_max` across instances.
//!
//! The top level is a binary tree (obvhs PLOC, as the wide tree's input) over the instances'
//! world boxes; a moving instance's box is swept over the shutter (the union of its boxes at
//! τ = 0 and τ = 1, exact for a translation). It is traversed front to back; instance counts
//! are small next to triangle counts, so the simpler binary layout is not where time goes.
//!
//! Scenes without instances have no top level at all: their queries test one `Option` and go
//! on exactly as before (see [`super::Accel::intersect`]).

use obvhs::aabb::Aabb;
use obvhs::ploc::{PlocBuilder, PlocSearchDistance, SortPrecision};

use super::bvh::{RawHit, Tree2, WideBvh};
use crate::geometry::Ray;
use crate::math::{Vec3, Vec3A};
use glam::Affine3A;

/// `1 + 2γ₃` (pbrt-v4's robust slab test): the exit distances are scaled by it.
const ROBUST: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);
/// Deepest top-level tree traversed with the fixed stack; deeper PLOC trees are rebuilt
/// balanced (depth ≤ log₂ n + 1).
const MAX_DEPTH: u32 = 60;

/// One bottom-level tree.
pub(crate) struct Blas {
    pub bvh: WideBvh,
    /// Object-space bounds of the prototype's primitives.
    pub bounds: Aabb,
}

/// One placed instance.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Inst {
    /// World → prototype space (at τ = 0).
    pub to_object: Affine3A,
    /// World translation per unit of time.
    pub motion: Vec3,
    pub blas: u32,
    /// The scene shape this instance is (reported as `Hit::shape`).
    pub shape: u32,
}

impl Inst {
    /// `ray` in the prototype's space at the ray's time.
    #[inline(always)]
    fn local(&self, ray: &Ray) -> Ray {
        let o = ray.o - self.motion * ray.time;
        Ray {
            o: self.to_object.transform_point3a(o),
            d: self.to_object.transform_vector3a(ray.d),
            time: ray.time,
        }
    }
}

pub(crate) struct TopLevel {
    blas: Vec<Blas>,
    insts: Vec<Inst>,
    /// Binary tree over `insts` (leaves index `order`).
    tree: Tree2,
    bounds: Aabb,
}

impl TopLevel {
    /// `boxes[i]` is the world box of `insts[i]` (swept over the shutter when moving). `None`
    /// when there are no instances.
    pub(crate) fn build(blas: Vec<Blas>, insts: Vec<Inst>, boxes: Vec<Aabb>) -> Option<TopLevel> {
        if insts.is_empty() {
            return None;
        }
        let n = insts.len();
        let bounds = boxes.iter().fold(Aabb::INVALID, |a, b| a.union(b));
        let tree = if n == 1 {
            Tree2::single_leaf(&boxes)
        } else {
            let bvh2 = PlocBuilder::with_capacity(n).build(
                PlocSearchDistance::Medium,
                &boxes,
                (0..n as u32).collect(),
                SortPrecision::U64,
                1,
            );
            let t = Tree2::from_bvh2(bvh2);
            if t.depth() > MAX_DEPTH {
                Tree2::median(&boxes)
            } else {
                t
            }
        };
        Some(TopLevel {
            blas,
            insts,
            tree,
            bounds,
        })
    }

    pub(crate) fn bounds(&self) -> Aabb {
        self.bounds
    }

    /// Bytes held by the bottom-level trees and the instances (for reports and tests).
    pub(crate) fn memory_bytes(&self) -> usize {
        self.blas
            .iter()
            .map(|b| b.bvh.memory_bytes())
            .sum::<usize>()
            + self.insts.len() * size_of::<Inst>()
            + self.tree.memory_bytes()
    }

    pub(crate) fn blas_count(&self) -> usize {
        self.blas.len()
    }

    /// The closest instance hit with `0 < t < t_max`.
    pub(crate) fn intersect(&self, ray: &Ray, mut t_max: f32) -> Option<RawHit> {
        let slab = Slab::new(ray);
        let mut best = None;
        let mut stack = [(0u32, 0f32); MAX_DEPTH as usize + 2];
        let mut sp = 0;
        let nodes = &self.tree.nodes;
        let mut cur = 0u32;
        slab.hit(nodes[0].aabb(), t_max)?;
        loop {
            let node = &nodes[cur as usize];
            if node.is_leaf() {
                for k in 0..node.prim_count {
                    let i = self.tree.prim_indices[(node.first_index + k) as usize];
                    let inst = &self.insts[i as usize];
                    let local = inst.local(ray);
                    if let Some(h) = self.blas[inst.blas as usize].bvh.intersect(&local, t_max) {
                        t_max = h.t;
                        best = Some(RawHit {
                            shape: inst.shape,
                            ..h
                        });
                    }
                }
            } else {
                let (a, b) = (node.first_index, node.first_index + 1);
                let ta = slab.hit(nodes[a as usize].aabb(), t_max);
                let tb = slab.hit(nodes[b as usize].aabb(), t_max);
                match (ta, tb) {
                    (Some(ta), Some(tb)) => {
                        let (near, far, tf) = if tb < ta { (b, a, ta) } else { (a, b, tb) };
                        stack[sp] = (far, tf);
                        sp += 1;
                        cur = near;
                        continue;
                    }
                    (Some(_), None) => {
                        cur = a;
                        continue;
                    }
                    (None, Some(_)) => {
                        cur = b;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            loop {
                if sp == 0 {
                    return best;
                }
                sp -= 1;
                if stack[sp].1 <= t_max {
                    cur = stack[sp].0;
                    break;
                }
            }
        }
    }

    /// Whether any instance is hit with `0 < t < t_max`.
    pub(crate) fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let slab = Slab::new(ray);
        let mut stack = [0u32; MAX_DEPTH as usize + 2];
        let mut sp = 0;
        let nodes = &self.tree.nodes;
        if slab.hit(nodes[0].aabb(), t_max).is_none() {
            return false;
        }
        let mut cur = 0u32;
        loop {
            let node = &nodes[cur as usize];
            if node.is_leaf() {
                for k in 0..node.prim_count {
                    let i = self.tree.prim_indices[(node.first_index + k) as usize];
                    let inst = &self.insts[i as usize];
                    if self.blas[inst.blas as usize]
                        .bvh
                        .occluded(&inst.local(ray), t_max)
                    {
                        return true;
                    }
                }
            } else {
                let (a, b) = (node.first_index, node.first_index + 1);
                let ha = slab.hit(nodes[a as usize].aabb(), t_max).is_some();
                let hb = slab.hit(nodes[b as usize].aabb(), t_max).is_some();
                if ha {
                    if hb {
                        stack[sp] = b;
                        sp += 1;
                    }
                    cur = a;
                    continue;
                }
                if hb {
                    cur = b;
                    continue;
                }
            }
            if sp == 0 {
                return false;
            }
            sp -= 1;
            cur = stack[sp];
        }
    }
}

/// Per-ray constants of the (robust) slab test.
struct Slab {
    o: Vec3A,
    inv: Vec3A,
}

impl Slab {
    #[inline(always)]
    fn new(ray: &Ray) -> Slab {
        let r = Vec3A::ONE / ray.d;
        // ±∞ components (zero direction components) become ±MAX: no 0·∞ = NaN in the slabs.
        let inv = Vec3A::select(
            r.abs().cmplt(Vec3A::INFINITY),
            r,
            Vec3A::splat(f32::MAX).copysign(r),
        );
        Slab { o: ray.o, inv }
    }

    /// Entry distance into `b` if the ray overlaps it within `(0, t_max)`.
    #[inline(always)]
    fn hit(&self, b: &Aabb, t_max: f32) -> Option<f32> {
        let t0 = (b.min - self.o) * self.inv;
        let t1 = (b.max - self.o) * self.inv;
        let tn = t0.min(t1).max_element().max(0.0);
        let tf = (t0.max(t1).min_element() * ROBUST).min(t_max);
        (tn <= tf).then_some(tn)
    }
}

/// The world box of `local` (a box in an instance's space) under `to_world`, swept by
/// `motion` over the shutter, padded outwards for the rounding of the ray's transformation.
pub(crate) fn instance_box(local: &Aabb, to_world: &Affine3A, motion: Vec3) -> Aabb {
    let mut bb = Aabb::INVALID;
    for k in 0..8 {
        let c = Vec3A::new(
            if k & 1 == 0 { local.min.x } else { local.max.x },
            if k & 2 == 0 { local.min.y } else { local.max.y },
            if k & 4 == 0 { local.min.z } else { local.max.z },
        );
        let w = to_world.transform_point3a(c);
        bb.extend(w);
        bb.extend(w + motion);
    }
    // Relative padding: the box is only a culling test, a little slack costs nothing.
    let pad = (bb.max - bb.min).max(bb.min.abs().max(bb.max.abs())) * (16.0 * f32::EPSILON);
    Aabb::new(bb.min - pad, bb.max + pad)
}
