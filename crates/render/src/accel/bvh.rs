//! An 8-wide BVH with single-precision child boxes in SoA layout, traversed one ray at a time:
//! the eight box tests are one 8-wide operation per slab plane (AVX, via `wide::f32x8`; two
//! SSE halves on processors without AVX). A node is 256 bytes on 64-byte boundaries.
//!
//! Why 8-wide even on a 4-wide ISA: incoherent rays on large meshes are bound by the latency
//! of dependent node fetches; a wider node halves the depth, and its four cache lines load in
//! parallel (figures in `bench/README.md`, "Accelerator").
//!
//! Construction: obvhs builds a binary BVH (PLOC, Meister & Bittner 2018, followed by SAH
//! reinsertion optimisation, Meister & Bittner 2017); we collapse it into the wide tree by the
//! SAH-optimal dynamic programme of Ylitie et al. 2017 ([`Plan`]), which decides for every
//! binary node whether it becomes a wide node, a leaf (at most [`LEAF_MAX`] primitives,
//! [`SMALL_LEAF_MAX`] in small scenes) or is opened into its parent's slots. A node's children
//! are stored largest first.
//!
//! Leaves: a leaf of triangles only is one packet, tested in one go: up to four triangles in a
//! [`Tri4`] (SSE), five to eight in a [`Tri8`] (AVX), each kind in its own array, with the
//! `(shape, prim)` ids of its lanes in a parallel array read only for the final hit. A leaf
//! holding an analytic shape (sphere, disk, ellipsoid) is a list of [`Packet`]s: the shapes one
//! at a time, its triangles four at a time.
//!
//! Traversal: closest-hit orders the hit children front to back by entry distance and culls
//! popped entries that lie beyond the current hit; occlusion visits them in slot order
//! (largest first: the likeliest to hold an occluder) and returns on the first hit. Both prefetch every entered child (when the tree is larger than the caches).
//! The box test is made conservative by scaling the exit distances (Ize 2013, "Robust BVH Ray
//! Traversal"; here through the reciprocal direction, see [`ROBUST_FAR`]), so watertight
//! triangles are never lost to box misses.
//! The stack is a fixed-size array on the call stack (8 to 1024 entries, chosen at build
//! from the exact worst case of the tree's shape), so queries never allocate.

use std::mem::MaybeUninit;

use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::ploc::{PlocBuilder, PlocSearchDistance, SortPrecision};

use super::prim::{
    Tri4, Tri8, WoopRay, WoopRay4, WoopRay8, intersect_cylinder, intersect_disk,
    intersect_ellipsoid, intersect_sphere, tri_any, tri_closest,
};
use super::stats;
use crate::geometry::Ray;
use crate::math::{Mat4, Vec3, Vec4};
use wide::f32x8;

/// Most primitives in a leaf (the collapse chooses leaf sizes up to this by SAH): one 8-wide
/// packet, which saves dependent node fetches over smaller leaves (`bench/README.md`).
pub(crate) const LEAF_MAX: u32 = 8;

/// Scenes with at most this many primitives use [`SMALL_LEAF_MAX`] instead: their tree fits
/// in cache, so traversal is bound by arithmetic rather than by node fetches, and their
/// primitives are typically large (walls, boxes, area lights) with boxes that overlap much of
/// the scene: small leaves trade a few more node visits for far fewer triangle tests.
const SMALL_SCENE: usize = 4096;
const SMALL_LEAF_MAX: u32 = 2;

/// Scenes with at least this many primitives (or at most [`SMALL_SCENE`]) get the longer
/// reinsertion optimisation (see [`WideBvh::build`]).
const REINSERT_LARGE: usize = 500_000;

/// Child references: an inner node's index, or [`LEAF_BIT`] with a leaf kind in the two bits
/// above [`KIND_SHIFT`] and the index of its packet ([`TRI4`], [`TRI8`]) or of its first
/// packet ([`MIXED`], with the packet count above [`COUNT_SHIFT`]).
const LEAF_BIT: u32 = 1 << 31;
const KIND_SHIFT: u32 = 29;
const KIND_MASK: u32 = 3 << KIND_SHIFT;
const TRI4: u32 = LEAF_BIT;
const TRI8: u32 = LEAF_BIT | (1 << KIND_SHIFT);
const MIXED: u32 = LEAF_BIT | (2 << KIND_SHIFT);
/// An empty child slot (its box is inverted, so it is never entered).
const EMPTY: u32 = LEAF_BIT | KIND_MASK;
const INDEX_MASK: u32 = (1 << KIND_SHIFT) - 1;
const COUNT_SHIFT: u32 = 25;
const FIRST_MASK: u32 = (1 << COUNT_SHIFT) - 1;
/// Largest traversal stack (entries); deeper trees are rebuilt balanced.
const MAX_STACK: usize = 1024;

/// `1 + 2γ₄` with `γₙ = nε/(1-nε)`, ε = 2⁻²⁴: the factor on the reciprocal direction that
/// makes far-plane distances conservative. pbrt-v4's robust slab test scales the computed exit
/// distance by `1 + 2γ₃` (three roundings: the reciprocal, the difference, the product); here
/// the factor is applied to the reciprocal once per ray, which adds a fourth rounding.
const ROBUST_FAR: f32 = 1.0 + 2.0 * (4.0 * f32::EPSILON * 0.5) / (1.0 - 4.0 * f32::EPSILON * 0.5);

/// A bounded primitive handed to the builder.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Prim {
    Tri([Vec3; 3]),
    Sphere { center: Vec3, radius: f32 },
    Disk { to_object: Mat4 },
    Ellipsoid { to_object: Mat4 },
    Cylinder { to_object: Mat4 },
}

/// What a leaf holding an analytic shape stores: its triangles four at a time, the analytic
/// shapes one at a time.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Packet {
    Tri4(Tri4),
    Sphere {
        center: Vec3,
        radius: f32,
    },
    /// A disk or an ellipsoid: a unit shape seen through `to_object`. One variant for both
    /// keeps the leaf loop's dispatch small.
    Transformed {
        to_object: Mat4,
        kind: Unit,
    },
}

/// The unit shape of a [`Packet::Transformed`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Unit {
    Disk,
    Sphere,
    Cylinder,
}

/// Children per node.
const WIDTH: usize = 8;

/// Inner node: child boxes as `b[axis][0 = min, 1 = max]`, one child per lane (one AVX register
/// per plane; two SSE registers without AVX), and the child references.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct Node {
    b: [[f32x8; 2]; 3],
    child: [u32; WIDTH],
}

#[derive(Clone, Copy, Debug)]
enum StackClass {
    S8,
    S16,
    S32,
    S64,
    S128,
    S256,
    S1024,
}

/// `(shape, prim)` of a packet's lanes (`u32::MAX` in unused lanes).
type Ids<const N: usize> = [[u32; 2]; N];

pub(crate) struct WideBvh {
    nodes: Vec<Node>,
    tri4: Vec<Tri4>,
    ids4: Vec<Ids<4>>,
    tri8: Vec<Tri8>,
    ids8: Vec<Ids<8>>,
    /// Packets of the leaves that hold analytic shapes, and their lanes' ids.
    packets: Vec<Packet>,
    ids: Vec<Ids<4>>,
    root: u32,
    stack: StackClass,
    /// Traversal stack entries needed: the largest, over root-to-leaf paths, of the pushes a
    /// traversal may leave on the stack along the path (`children - 1` per inner node).
    stack_need: u32,
    /// Most primitives in a leaf.
    leaf_max: u32,
    /// Whether traversal prefetches the entered children: only worth its instructions when
    /// the tree does not fit in cache.
    prefetch: bool,
}

/// Trees smaller than this (bytes) are assumed cache resident: traversal skips prefetching.
const PREFETCH_MIN_BYTES: usize = 256 * 1024;

/// Per-ray traversal constants.
struct TravRay {
    o: [f32x8; 3],
    /// Reciprocal direction, for the near planes.
    inv: [f32x8; 3],
    /// Reciprocal direction scaled by [`ROBUST_FAR`], for the far planes.
    inv_far: [f32x8; 3],
    /// 1 where the direction component is negative (then the near plane is the max plane).
    neg: [usize; 3],
}

impl TravRay {
    #[inline(always)]
    fn new(ray: &Ray) -> TravRay {
        // Reciprocal direction in one vector division; an infinite component (zero direction
        // component) becomes ±MAX with its sign, so slabs never produce 0 · ∞ = NaN.
        let finite = |r: Vec4| {
            Vec4::select(
                r.abs().cmplt(Vec4::INFINITY),
                r,
                Vec4::splat(f32::MAX).copysign(r),
            )
        };
        let i = finite(Vec4::ONE / Vec4::new(ray.d.x, ray.d.y, ray.d.z, 1.0));
        let f = finite(i * ROBUST_FAR);
        let neg = i.is_negative_bitmask();
        TravRay {
            o: [
                f32x8::splat(ray.o.x),
                f32x8::splat(ray.o.y),
                f32x8::splat(ray.o.z),
            ],
            inv: [f32x8::splat(i.x), f32x8::splat(i.y), f32x8::splat(i.z)],
            inv_far: [f32x8::splat(f.x), f32x8::splat(f.y), f32x8::splat(f.z)],
            neg: [
                (neg & 1) as usize,
                ((neg >> 1) & 1) as usize,
                ((neg >> 2) & 1) as usize,
            ],
        }
    }

    /// Entry distances of the children and the mask of those entered within `(0, t_max)`.
    /// The reductions are balanced trees: the next node's address waits on this test.
    #[inline(always)]
    fn hit_node(&self, n: &Node, t_max: f32) -> (f32x8, u32) {
        let [nx, ny, nz] = self.neg;
        let b = &n.b;
        let tnx = (b[0][nx & 1] - self.o[0]) * self.inv[0];
        let tny = (b[1][ny & 1] - self.o[1]) * self.inv[1];
        let tnz = (b[2][nz & 1] - self.o[2]) * self.inv[2];
        let tfx = (b[0][(nx ^ 1) & 1] - self.o[0]) * self.inv_far[0];
        let tfy = (b[1][(ny ^ 1) & 1] - self.o[1]) * self.inv_far[1];
        let tfz = (b[2][(nz ^ 1) & 1] - self.o[2]) * self.inv_far[2];
        // `fast_max`/`fast_min` are the plain max/min instructions (no NaN can arise here).
        let tn = tnx.fast_max(tny).fast_max(tnz.fast_max(f32x8::ZERO));
        let tf = tfx
            .fast_min(tfy)
            .fast_min(tfz.fast_min(f32x8::splat(t_max)));
        (tn, tn.simd_le(tf).to_bitmask())
    }
}

/// A traversal stack of at most `N` entries, left uninitialised: clearing the 8 KiB of the
/// deepest trees' stacks cost more than a small tree's whole query.
struct Stack<T: Copy, const N: usize> {
    items: [MaybeUninit<T>; N],
    len: usize,
}

impl<T: Copy, const N: usize> Stack<T, N> {
    #[inline(always)]
    fn new() -> Self {
        Stack {
            items: [MaybeUninit::uninit(); N],
            len: 0,
        }
    }

    /// Panics beyond `N` entries (the build sizes `N` for the tree's deepest path).
    #[inline(always)]
    fn push(&mut self, x: T) {
        self.items[self.len] = MaybeUninit::new(x);
        self.len += 1;
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<T> {
        if self.len == 0 {
            return None;
        }
        self.len -= 1;
        // SAFETY: every entry below `len` was written by `push`.
        Some(unsafe { self.items[self.len].assume_init() })
    }
}

/// Closest-hit result of the BVH.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RawHit {
    pub t: f32,
    pub shape: u32,
    pub prim: u32,
    pub u: f32,
    pub v: f32,
}

/// Asks the processor to fetch the cache lines of `r` (a hint: it never faults and changes no
/// result).
#[inline(always)]
fn prefetch<T>(r: &T) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::x86_64::{_MM_HINT_T0, _mm_prefetch};
        let p = (r as *const T).cast::<i8>();
        let mut off = 0;
        while off < size_of::<T>() {
            // SAFETY: a prefetch reads nothing architecturally and cannot fault; the address
            // lies inside `*r` anyway.
            unsafe { _mm_prefetch::<_MM_HINT_T0>(p.wrapping_add(off)) };
            off += 64;
        }
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = r;
}

impl WideBvh {
    /// Builds over `prims`, whose ids are `ids[i] = (shape, prim)`.
    pub(crate) fn build(prims: &[Prim], ids: &[[u32; 2]], aabbs: &[Aabb]) -> WideBvh {
        let n = prims.len();
        let mut out = WideBvh {
            nodes: Vec::new(),
            tri4: Vec::new(),
            ids4: Vec::new(),
            tri8: Vec::new(),
            ids8: Vec::new(),
            packets: Vec::new(),
            ids: Vec::new(),
            root: EMPTY,
            stack: StackClass::S64,
            stack_need: 0,
            leaf_max: if prims.len() <= SMALL_SCENE {
                SMALL_LEAF_MAX
            } else {
                LEAF_MAX
            },
            prefetch: false,
        };
        if n == 0 {
            return out;
        }
        let tree = if n as u32 <= out.leaf_max {
            // A single leaf: no binary tree needed.
            Tree2::single_leaf(aabbs)
        } else {
            let mut bvh2 = PlocBuilder::with_capacity(n).build(
                PlocSearchDistance::Medium,
                aabbs,
                (0..n as u32).collect(),
                SortPrecision::U64,
                3,
            );
            // Batch ratio 0.4 (obvhs' "medium" is 0.05) in large scenes: a slower build for
            // faster traversal, the right trade for an offline renderer. Between
            // `SMALL_SCENE` and `REINSERT_LARGE` primitives 0.1: there the traversal gain of
            // more was within the noise, and reinsertion was most of the build. Small scenes
            // keep 0.4 (their build takes microseconds either way): a lighter reinsertion
            // leaves their trees with more mispredicted branches in traversal
            // (`bench/README.md`).
            let ratio = if n >= REINSERT_LARGE || n <= SMALL_SCENE {
                0.4
            } else {
                0.1
            };
            ReinsertionOptimizer::default().run(&mut bvh2, ratio, None);
            let t = Tree2::from_bvh2(bvh2);
            // PLOC trees are shallow in practice; a degenerate input (e.g. thousands of
            // coincident primitives) could make one deep. Bound the recursion here and the
            // traversal stack below.
            if t.depth() > 300 {
                Tree2::median(aabbs)
            } else {
                t
            }
        };
        out.collapse(&tree, prims, ids);
        out.prefetch = out.memory_bytes() >= PREFETCH_MIN_BYTES;
        if out.stack_need() > MAX_STACK {
            // A balanced tree has depth ≤ log2(n) + 1, far below the limit.
            out.clear();
            out.collapse(&Tree2::median(aabbs), prims, ids);
        }
        out.validate();
        out
    }

    fn clear(&mut self) {
        self.nodes.clear();
        self.tri4.clear();
        self.ids4.clear();
        self.tri8.clear();
        self.ids8.clear();
        self.packets.clear();
        self.ids.clear();
    }

    /// Bytes of nodes, packets and ids.
    pub(crate) fn memory_bytes(&self) -> usize {
        self.nodes.len() * size_of::<Node>()
            + self.tri4.len() * size_of::<(Tri4, Ids<4>)>()
            + self.tri8.len() * size_of::<(Tri8, Ids<8>)>()
            + self.packets.len() * size_of::<(Packet, Ids<4>)>()
    }

    /// Traversal stack entries needed (see the `stack_need` field).
    fn stack_need(&self) -> usize {
        self.stack_need as usize
    }

    fn collapse(&mut self, tree: &Tree2, prims: &[Prim], ids: &[[u32; 2]]) {
        let plan = Plan::new(tree, self.leaf_max);
        let mut need = 0;
        self.root = self.emit(tree, &plan, prims, ids, 0, 0, &mut need);
        self.stack_need = need;
        let need = self.stack_need();
        self.stack = if need <= 8 {
            StackClass::S8
        } else if need <= 16 {
            StackClass::S16
        } else if need <= 32 {
            StackClass::S32
        } else if need <= 64 {
            StackClass::S64
        } else if need <= 128 {
            StackClass::S128
        } else if need <= 256 {
            StackClass::S256
        } else {
            StackClass::S1024
        };
    }

    /// Emits binary node `node` as one child of a wide node: a leaf or a wide node, as `plan`
    /// decided; returns its child reference.
    #[allow(clippy::too_many_arguments)]
    fn emit(
        &mut self,
        tree: &Tree2,
        plan: &Plan,
        prims: &[Prim],
        ids: &[[u32; 2]],
        node: usize,
        pushed: u32,
        need: &mut u32,
    ) -> u32 {
        if plan.leaf[node] {
            return self.emit_leaf(tree, node, prims, ids);
        }
        let mut kids = [0usize; WIDTH];
        let mut k = 0;
        plan.open(tree, node, WIDTH, &mut kids, &mut k);
        // Largest first: occlusion queries visit the children in slot order, and a large
        // child is the likeliest to hold an occluder.
        kids[..k].sort_by(|&a, &b| {
            tree.nodes[b]
                .aabb()
                .half_area()
                .total_cmp(&tree.nodes[a].aabb().half_area())
        });
        // Visiting this node leaves at most `k - 1` of its children on the stack while the
        // traversal descends into one of them.
        let pushed = pushed + k as u32 - 1;
        *need = (*need).max(pushed);
        let index = self.nodes.len();
        self.nodes.push(Node {
            b: [[f32x8::splat(f32::INFINITY), f32x8::splat(f32::NEG_INFINITY)]; 3],
            child: [EMPTY; WIDTH],
        });
        let mut lo = [[f32::INFINITY; WIDTH]; 3];
        let mut hi = [[f32::NEG_INFINITY; WIDTH]; 3];
        let mut child = [EMPTY; WIDTH];
        for (slot, &c) in kids[..k].iter().enumerate() {
            let bb = tree.nodes[c].aabb();
            for axis in 0..3 {
                lo[axis][slot] = bb.min[axis];
                hi[axis][slot] = bb.max[axis];
            }
            child[slot] = self.emit(tree, plan, prims, ids, c, pushed, need);
        }
        let node = &mut self.nodes[index];
        for (b, (lo, hi)) in node.b.iter_mut().zip(lo.iter().zip(&hi)) {
            *b = [f32x8::new(*lo), f32x8::new(*hi)];
        }
        node.child = child;
        index as u32
    }

    fn emit_leaf(&mut self, tree: &Tree2, node: usize, prims: &[Prim], ids: &[[u32; 2]]) -> u32 {
        let mut items = [0u32; LEAF_MAX as usize];
        let mut n = 0;
        tree.gather(node, &mut items, &mut n);
        let mut tris = [[Vec3::ZERO; 3]; LEAF_MAX as usize];
        let mut tri_ids = [[u32::MAX; 2]; LEAF_MAX as usize];
        let mut nt = 0;
        for &i in &items[..n] {
            if let Prim::Tri(p) = prims[i as usize] {
                tris[nt] = p;
                tri_ids[nt] = ids[i as usize];
                nt += 1;
            }
        }
        let index = |len: usize| {
            assert!(
                len as u32 <= INDEX_MASK,
                "too many primitives for the BVH encoding"
            );
            len as u32
        };
        if nt == n && nt <= 4 {
            let r = TRI4 | index(self.tri4.len());
            self.tri4.push(Tri4::new(&tris[..nt]));
            let mut idv = [[u32::MAX; 2]; 4];
            idv[..nt].copy_from_slice(&tri_ids[..nt]);
            self.ids4.push(idv);
            return r;
        }
        if nt == n {
            let r = TRI8 | index(self.tri8.len());
            self.tri8.push(Tri8::new(&tris[..nt]));
            let mut idv = [[u32::MAX; 2]; 8];
            idv[..nt].copy_from_slice(&tri_ids[..nt]);
            self.ids8.push(idv);
            return r;
        }
        let first = self.packets.len() as u32;
        let one = |id: [u32; 2]| [id, [u32::MAX; 2], [u32::MAX; 2], [u32::MAX; 2]];
        for &i in &items[..n] {
            let i = i as usize;
            let packet = match prims[i] {
                Prim::Tri(_) => continue,
                Prim::Sphere { center, radius } => Packet::Sphere { center, radius },
                Prim::Disk { to_object } => Packet::Transformed {
                    to_object,
                    kind: Unit::Disk,
                },
                Prim::Ellipsoid { to_object } => Packet::Transformed {
                    to_object,
                    kind: Unit::Sphere,
                },
                Prim::Cylinder { to_object } => Packet::Transformed {
                    to_object,
                    kind: Unit::Cylinder,
                },
            };
            self.packets.push(packet);
            self.ids.push(one(ids[i]));
        }
        for (c, ci) in tris[..nt].chunks(4).zip(tri_ids[..nt].chunks(4)) {
            self.packets.push(Packet::Tri4(Tri4::new(c)));
            let mut idv = [[u32::MAX; 2]; 4];
            idv[..ci.len()].copy_from_slice(ci);
            self.ids.push(idv);
        }
        let count = self.packets.len() as u32 - first;
        assert!(
            first <= FIRST_MASK,
            "too many primitives for the BVH encoding"
        );
        MIXED | (count << COUNT_SHIFT) | first
    }

    /// Checks that the root and every child reference of every node name an existing node,
    /// packet or packet range: traversal follows them without bounds checks.
    fn validate(&self) {
        let ok = |c: u32| {
            let i = (c & INDEX_MASK) as usize;
            match c & (LEAF_BIT | KIND_MASK) {
                0 => i < self.nodes.len(),
                TRI4 => i < self.tri4.len() && i < self.ids4.len(),
                TRI8 => i < self.tri8.len() && i < self.ids8.len(),
                MIXED => {
                    let first = (c & FIRST_MASK) as usize;
                    let count = ((c & !(LEAF_BIT | KIND_MASK)) >> COUNT_SHIFT) as usize;
                    first + count <= self.packets.len() && first + count <= self.ids.len()
                }
                _ => c == EMPTY,
            }
        };
        assert!(ok(self.root), "BVH root out of range");
        for n in &self.nodes {
            assert!(n.child.iter().all(|&c| ok(c)), "BVH child out of range");
        }
    }

    /// The inner node `c` names (a reference met in traversal, see [`WideBvh::validate`]).
    #[inline(always)]
    fn node(&self, c: u32) -> &Node {
        debug_assert!((c as usize) < self.nodes.len());
        // SAFETY: `c` comes from the root or a node's child array, all of whose inner-node
        // references `validate` checked to be below `nodes.len()` at the end of the build;
        // the arrays are never modified afterwards.
        unsafe { self.nodes.get_unchecked(c as usize) }
    }

    /// The 4-wide leaf packet at index `i` of a leaf reference (see [`WideBvh::node`]).
    #[inline(always)]
    fn tri4(&self, i: usize) -> &Tri4 {
        debug_assert!(i < self.tri4.len());
        // SAFETY: as in `node`, for the `TRI4` references.
        unsafe { self.tri4.get_unchecked(i) }
    }

    /// The 8-wide leaf packet at index `i` of a leaf reference (see [`WideBvh::node`]).
    #[inline(always)]
    fn tri8(&self, i: usize) -> &Tri8 {
        debug_assert!(i < self.tri8.len());
        // SAFETY: as in `node`, for the `TRI8` references.
        unsafe { self.tri8.get_unchecked(i) }
    }

    /// Prefetches the node or leaf packet that child reference `c` names.
    #[inline(always)]
    fn prefetch_child(&self, c: u32) {
        let i = (c & INDEX_MASK) as usize;
        match c & (LEAF_BIT | KIND_MASK) {
            0 => prefetch(self.node(c)),
            TRI4 => prefetch(self.tri4(i)),
            TRI8 => prefetch(self.tri8(i)),
            _ => {}
        }
    }

    pub(crate) fn intersect(&self, ray: &Ray, t_max: f32) -> Option<RawHit> {
        if self.tri8.is_empty() {
            self.intersect_w::<false>(ray, t_max)
        } else {
            self.intersect_w::<true>(ray, t_max)
        }
    }

    /// [`WideBvh::intersect`] for trees with (`WIDE`) or without 8-wide leaves.
    #[inline(always)]
    fn intersect_w<const WIDE: bool>(&self, ray: &Ray, t_max: f32) -> Option<RawHit> {
        match self.stack {
            StackClass::S8 => self.intersect_n::<8, WIDE>(ray, t_max),
            StackClass::S16 => self.intersect_n::<16, WIDE>(ray, t_max),
            StackClass::S32 => self.intersect_n::<32, WIDE>(ray, t_max),
            StackClass::S64 => self.intersect_n::<64, WIDE>(ray, t_max),
            StackClass::S128 => self.intersect_n::<128, WIDE>(ray, t_max),
            StackClass::S256 => self.intersect_n::<256, WIDE>(ray, t_max),
            StackClass::S1024 => self.intersect_n::<1024, WIDE>(ray, t_max),
        }
    }

    pub(crate) fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        if self.tri8.is_empty() {
            self.occluded_w::<false>(ray, t_max)
        } else {
            self.occluded_w::<true>(ray, t_max)
        }
    }

    /// [`WideBvh::occluded`] for trees with (`WIDE`) or without 8-wide leaves.
    #[inline(always)]
    fn occluded_w<const WIDE: bool>(&self, ray: &Ray, t_max: f32) -> bool {
        match self.stack {
            StackClass::S8 => self.occluded_n::<8, WIDE>(ray, t_max),
            StackClass::S16 => self.occluded_n::<16, WIDE>(ray, t_max),
            StackClass::S32 => self.occluded_n::<32, WIDE>(ray, t_max),
            StackClass::S64 => self.occluded_n::<64, WIDE>(ray, t_max),
            StackClass::S128 => self.occluded_n::<128, WIDE>(ray, t_max),
            StackClass::S256 => self.occluded_n::<256, WIDE>(ray, t_max),
            StackClass::S1024 => self.occluded_n::<1024, WIDE>(ray, t_max),
        }
    }

    // Not inlined into the dispatch above: each stack size gets its own frame, so small trees
    // do not pay for the stack probes of the 1024-entry variant. Trees without 8-wide leaves
    // (small scenes) get a loop without their test: a smaller loop ran bench-cbox faster.
    #[inline(never)]
    fn intersect_n<const N: usize, const WIDE: bool>(
        &self,
        ray: &Ray,
        mut t_max: f32,
    ) -> Option<RawHit> {
        if self.root == EMPTY {
            return None;
        }
        stats::bump(3);
        let tr = TravRay::new(ray);
        // The triangle test's constants: 4-wide once per ray (splatted at each leaf instead,
        // they were 1 % of bench-cbox's instructions), 8-wide at each 8-wide leaf.
        let woop = WoopRay::new(ray);
        let w4 = WoopRay4::new(&woop);
        // Entries: a child reference and its entry distance.
        let mut stack = Stack::<(u32, f32), N>::new();
        let mut cur = self.root;
        // The leaf reference holding the closest hit so far, its lane and (t, u, v).
        let mut best: Option<(u32, usize, f32, f32, f32)> = None;
        'outer: loop {
            if cur & LEAF_BIT == 0 {
                stats::bump(0);
                let node = self.node(cur);
                let (tn, mask) = tr.hit_node(node, t_max);
                if mask != 0 {
                    if mask & (mask - 1) == 0 {
                        cur = node.child[mask.trailing_zeros() as usize];
                        continue;
                    }
                    if self.prefetch {
                        let mut m = mask;
                        while m != 0 {
                            self.prefetch_child(node.child[m.trailing_zeros() as usize]);
                            m &= m - 1;
                        }
                    }
                    let tb = tn.to_array();
                    let s0 = mask.trailing_zeros() as usize;
                    let rest = mask & (mask - 1);
                    if rest & (rest - 1) == 0 {
                        // Two children (the common case): push the farther, enter the nearer.
                        let s1 = rest.trailing_zeros() as usize;
                        let (near, far) = if tb[s1] < tb[s0] { (s1, s0) } else { (s0, s1) };
                        stack.push((node.child[far], tb[far]));
                        cur = node.child[near];
                        continue;
                    }
                    // Sort the entered children by entry distance; keys are the (non-negative)
                    // distances' bit patterns with the slot index in the three low bits.
                    let mut keys = [u32::MAX; WIDTH];
                    let mut k = 0;
                    let mut m = mask;
                    while m != 0 {
                        let s = m.trailing_zeros();
                        m &= m - 1;
                        let key = (tb[s as usize].to_bits() & !7) | s;
                        // Insertion sort, descending.
                        let mut j = k;
                        while j > 0 && keys[j - 1] < key {
                            keys[j] = keys[j - 1];
                            j -= 1;
                        }
                        keys[j] = key;
                        k += 1;
                    }
                    // Push all but the nearest (far ones first), continue with the nearest.
                    for &key in &keys[..k - 1] {
                        let s = (key & 7) as usize;
                        stack.push((node.child[s], tb[s]));
                    }
                    cur = node.child[(keys[k - 1] & 7) as usize];
                    continue;
                }
            } else {
                stats::bump(1);
                let i = (cur & INDEX_MASK) as usize;
                let hit = match cur & KIND_MASK {
                    0 => tri_closest(&w4, self.tri4(i), t_max),
                    k if k == TRI8 & KIND_MASK => {
                        assert!(WIDE, "an 8-wide leaf in a tree without them");
                        tri_closest(&WoopRay8::new(&woop), self.tri8(i), t_max)
                    }
                    _ => self.mixed_closest(cur, ray, &w4, t_max),
                };
                if let Some((lane, t, u, v)) = hit {
                    t_max = t;
                    best = Some((cur, lane, t, u, v));
                }
            }
            // Pop the next entry that may still hold a closer hit.
            loop {
                let Some((c, t)) = stack.pop() else {
                    break 'outer;
                };
                if t <= t_max {
                    cur = c;
                    break;
                }
            }
        }
        best.map(|(leaf, lane, t, u, v)| {
            let i = (leaf & INDEX_MASK) as usize;
            let [shape, prim] = match leaf & (LEAF_BIT | KIND_MASK) {
                TRI4 => self.ids4[i][lane],
                TRI8 => self.ids8[i][lane],
                // The mixed leaf's closest packet and lane, see `mixed_closest`.
                _ => self.ids[lane >> 2][lane & 3],
            };
            RawHit {
                t,
                shape,
                prim,
                u,
                v,
            }
        })
    }

    /// The closest hit in a leaf holding analytic shapes: `(packet · 4 + lane, t, u, v)`.
    #[inline(never)]
    fn mixed_closest(
        &self,
        leaf: u32,
        ray: &Ray,
        w4: &WoopRay4,
        mut t_max: f32,
    ) -> Option<(usize, f32, f32, f32)> {
        let first = (leaf & FIRST_MASK) as usize;
        let count = ((leaf & !(LEAF_BIT | KIND_MASK)) >> COUNT_SHIFT) as usize;
        let mut best = None;
        for (pi, p) in self.packets[first..first + count].iter().enumerate() {
            let slot = (first + pi) << 2;
            let hit = match p {
                Packet::Tri4(tri) => {
                    tri_closest(w4, tri, t_max).map(|(l, t, u, v)| (slot | l, t, u, v))
                }
                Packet::Sphere { center, radius } => {
                    intersect_sphere(ray, *center, *radius, t_max).map(|t| (slot, t, 0.0, 0.0))
                }
                Packet::Transformed { to_object, kind } => {
                    transformed_packet(ray, to_object, *kind, t_max)
                        .map(|(t, x, y)| (slot, t, x, y))
                }
            };
            if let Some(h) = hit {
                t_max = h.1;
                best = Some(h);
            }
        }
        best
    }

    #[inline(never)]
    fn occluded_n<const N: usize, const WIDE: bool>(&self, ray: &Ray, t_max: f32) -> bool {
        if self.root == EMPTY {
            return false;
        }
        stats::bump(7);
        let tr = TravRay::new(ray);
        // The triangle test's constants, made when the first leaf is reached: most shadow
        // rays in small scenes reach none.
        let mut woop: Option<WoopRay> = None;
        let mut w4: Option<WoopRay4> = None;
        let mut stack = Stack::<u32, N>::new();
        let mut cur = self.root;
        loop {
            if cur & LEAF_BIT == 0 {
                stats::bump(4);
                let node = self.node(cur);
                let (_, mut mask) = tr.hit_node(node, t_max);
                if mask != 0 {
                    cur = node.child[mask.trailing_zeros() as usize];
                    mask &= mask - 1;
                    if self.prefetch {
                        let mut m = mask;
                        while m != 0 {
                            self.prefetch_child(node.child[m.trailing_zeros() as usize]);
                            m &= m - 1;
                        }
                    }
                    // Pushed last slot first, so that they are popped in slot order.
                    while mask != 0 {
                        let s = 31 - mask.leading_zeros();
                        stack.push(node.child[s as usize]);
                        mask &= !(1 << s);
                    }
                    continue;
                }
            } else {
                stats::bump(5);
                let i = (cur & INDEX_MASK) as usize;
                let w = woop.get_or_insert_with(|| WoopRay::new(ray));
                let hit = match cur & KIND_MASK {
                    0 => {
                        let w4 = w4.get_or_insert_with(|| WoopRay4::new(w));
                        tri_any(w4, self.tri4(i), t_max)
                    }
                    k if k == TRI8 & KIND_MASK => {
                        assert!(WIDE, "an 8-wide leaf in a tree without them");
                        tri_any(&WoopRay8::new(w), self.tri8(i), t_max)
                    }
                    _ => self.mixed_any(cur, ray, w, t_max),
                };
                if hit {
                    return true;
                }
            }
            let Some(c) = stack.pop() else {
                return false;
            };
            cur = c;
        }
    }

    /// Whether a leaf holding analytic shapes blocks the ray.
    #[inline(never)]
    fn mixed_any(&self, leaf: u32, ray: &Ray, woop: &WoopRay, t_max: f32) -> bool {
        let first = (leaf & FIRST_MASK) as usize;
        let count = ((leaf & !(LEAF_BIT | KIND_MASK)) >> COUNT_SHIFT) as usize;
        self.packets[first..first + count].iter().any(|p| match p {
            Packet::Tri4(tri) => tri_any(&WoopRay4::new(woop), tri, t_max),
            Packet::Sphere { center, radius } => {
                intersect_sphere(ray, *center, *radius, t_max).is_some()
            }
            Packet::Transformed { to_object, kind } => {
                transformed_packet(ray, to_object, *kind, t_max).is_some()
            }
        })
    }
}

/// The disk or ellipsoid test: `(t, x, y)` with the disk's object-space hit `x, y` (0 for
/// ellipsoids).
#[inline]
fn transformed_packet(
    ray: &Ray,
    to_object: &Mat4,
    kind: Unit,
    t_max: f32,
) -> Option<(f32, f32, f32)> {
    match kind {
        Unit::Disk => intersect_disk(ray, to_object, t_max),
        Unit::Sphere => intersect_ellipsoid(ray, to_object, t_max).map(|t| (t, 0.0, 0.0)),
        Unit::Cylinder => intersect_cylinder(ray, to_object, t_max).map(|t| (t, 0.0, 0.0)),
    }
}

/// SAH cost of testing a wide node, relative to which the leaf costs below are given.
const COST_NODE: f32 = 1.0;
/// SAH cost of testing a leaf of up to four triangles (one 4-wide test).
const COST_LEAF4: f32 = 1.2;
/// SAH cost of testing a leaf of five to eight triangles (one 8-wide test).
const COST_LEAF8: f32 = 1.5;

/// How the binary tree collapses into the wide one: the SAH-optimal choice of which binary
/// nodes become wide nodes, which leaves, and which are opened into their parent's slots
/// (the dynamic programme of Ylitie, Karras & Laine 2017, "Efficient Incoherent Ray
/// Traversal on GPUs Through Compressed Wide BVHs", §3.1).
struct Plan {
    /// Whether a binary node, given one slot of a wide node, becomes a leaf (else a wide node).
    leaf: Vec<bool>,
    /// `cost[n][i - 1]`: the least SAH cost of representing subtree `n` in at most `i` slots.
    cost: Vec<[f32; WIDTH]>,
}

impl Plan {
    fn new(tree: &Tree2, leaf_max: u32) -> Plan {
        let n = tree.nodes.len();
        let mut plan = Plan {
            leaf: vec![false; n],
            cost: vec![[0.0; WIDTH]; n],
        };
        let mut count = vec![0u32; n];
        for &(i, _) in tree.preorder().iter().rev() {
            let i = i as usize;
            let nd = &tree.nodes[i];
            let area = nd.aabb().half_area();
            let leaf_cost = |c: u32| area * if c <= 4 { COST_LEAF4 } else { COST_LEAF8 };
            if nd.is_leaf() {
                count[i] = nd.prim_count;
                assert!(nd.prim_count <= leaf_max, "binary leaf larger than a leaf");
                plan.leaf[i] = true;
                plan.cost[i] = [leaf_cost(nd.prim_count); WIDTH];
                continue;
            }
            let (l, r) = (nd.first_index as usize, nd.first_index as usize + 1);
            count[i] = count[l] + count[r];
            // The least cost of spreading the subtree over its two children with `s` slots
            // between them.
            let (cl, cr) = (plan.cost[l], plan.cost[r]);
            let split = |s: usize| {
                (1..s)
                    .map(|j| cl[j - 1] + cr[s - j - 1])
                    .fold(f32::INFINITY, f32::min)
            };
            let inner = area * COST_NODE + split(WIDTH);
            let as_leaf = if count[i] <= leaf_max {
                leaf_cost(count[i])
            } else {
                f32::INFINITY
            };
            // (Compared only when a leaf may hold the subtree: infinite areas make both costs
            // infinite.) Small scenes make a leaf of every subtree that fits: their rays mostly
            // start inside the scene's box, which the SAH does not model.
            plan.leaf[i] = count[i] <= leaf_max && (leaf_max <= SMALL_LEAF_MAX || as_leaf <= inner);
            let one = if plan.leaf[i] { as_leaf } else { inner };
            let mut c = [one; WIDTH];
            for s in 2..=WIDTH {
                c[s - 1] = one.min(split(s)).min(c[s - 2]);
            }
            plan.cost[i] = c;
        }
        plan
    }

    /// Appends to `out` the binary nodes that fill at most `slots` slots for the inner node
    /// `node`, opened as the plan decided.
    fn open(
        &self,
        tree: &Tree2,
        node: usize,
        slots: usize,
        out: &mut [usize; WIDTH],
        k: &mut usize,
    ) {
        let first = tree.nodes[node].first_index as usize;
        let (l, r) = (first, first + 1);
        let (cl, cr) = (self.cost[l], self.cost[r]);
        let j = (1..slots)
            .min_by(|&a, &b| {
                (cl[a - 1] + cr[slots - a - 1]).total_cmp(&(cl[b - 1] + cr[slots - b - 1]))
            })
            .expect("at least two slots");
        self.fill(tree, l, j, out, k);
        self.fill(tree, r, slots - j, out, k);
    }

    /// Appends the binary nodes that represent subtree `node` in at most `slots` slots: the
    /// node itself when that is cheapest, else its opened children.
    fn fill(
        &self,
        tree: &Tree2,
        node: usize,
        slots: usize,
        out: &mut [usize; WIDTH],
        k: &mut usize,
    ) {
        let c = &self.cost[node];
        if slots == 1 || tree.nodes[node].is_leaf() || c[0] <= c[slots - 1] {
            out[*k] = node;
            *k += 1;
            return;
        }
        // The fewest slots that reach the least cost of `slots` slots.
        let s = (2..=slots)
            .find(|&s| c[s - 1] <= c[slots - 1])
            .unwrap_or(slots);
        self.open(tree, node, s, out, k);
    }
}

/// A binary tree in obvhs's layout (children of an inner node at `first_index` and
/// `first_index + 1`; leaves index `prim_indices`).
pub(crate) struct Tree2 {
    pub(crate) nodes: Vec<Bvh2Node>,
    pub(crate) prim_indices: Vec<u32>,
}

impl Tree2 {
    pub(crate) fn from_bvh2(b: Bvh2) -> Tree2 {
        Tree2 {
            nodes: b.nodes,
            prim_indices: b.primitive_indices,
        }
    }

    pub(crate) fn single_leaf(aabbs: &[Aabb]) -> Tree2 {
        let bb = aabbs.iter().fold(Aabb::INVALID, |a, b| a.union(b));
        Tree2 {
            nodes: vec![Bvh2Node::new(bb, aabbs.len() as u32, 0)],
            prim_indices: (0..aabbs.len() as u32).collect(),
        }
    }

    /// Fallback: a balanced tree by object-median splits on the largest centroid axis.
    pub(crate) fn median(aabbs: &[Aabb]) -> Tree2 {
        let mut t = Tree2 {
            nodes: vec![Bvh2Node::new(Aabb::INVALID, 0, 0)],
            prim_indices: (0..aabbs.len() as u32).collect(),
        };
        let n = aabbs.len();
        t.median_rec(aabbs, 0, 0, n);
        t
    }

    fn median_rec(&mut self, aabbs: &[Aabb], node: usize, lo: usize, hi: usize) {
        let bb = self.prim_indices[lo..hi]
            .iter()
            .fold(Aabb::INVALID, |a, &i| a.union(&aabbs[i as usize]));
        if hi - lo == 1 {
            self.nodes[node] = Bvh2Node::new(bb, 1, lo as u32);
            return;
        }
        let cb = self.prim_indices[lo..hi]
            .iter()
            .fold(Aabb::INVALID, |mut a, &i| {
                a.extend(aabbs[i as usize].center());
                a
            });
        let axis = cb.largest_axis();
        let mid = (hi - lo) / 2;
        self.prim_indices[lo..hi].select_nth_unstable_by(mid, |&a, &b| {
            let ca = aabbs[a as usize].center_axis(axis);
            let cb = aabbs[b as usize].center_axis(axis);
            ca.total_cmp(&cb)
        });
        let first = self.nodes.len();
        self.nodes.push(Bvh2Node::new(Aabb::INVALID, 0, 0));
        self.nodes.push(Bvh2Node::new(Aabb::INVALID, 0, 0));
        self.nodes[node] = Bvh2Node::new(bb, 0, first as u32);
        self.median_rec(aabbs, first, lo, lo + mid);
        self.median_rec(aabbs, first + 1, lo + mid, hi);
    }

    /// Nodes in depth-first pre-order (parents before children) with their depths.
    fn preorder(&self) -> Vec<(u32, u32)> {
        let mut order = Vec::with_capacity(self.nodes.len());
        let mut stack = vec![(0u32, 0u32)];
        while let Some((i, d)) = stack.pop() {
            order.push((i, d));
            let n = &self.nodes[i as usize];
            if !n.is_leaf() {
                stack.push((n.first_index, d + 1));
                stack.push((n.first_index + 1, d + 1));
            }
        }
        order
    }

    pub(crate) fn memory_bytes(&self) -> usize {
        self.nodes.len() * size_of::<Bvh2Node>() + self.prim_indices.len() * 4
    }

    pub(crate) fn depth(&self) -> u32 {
        self.preorder().iter().map(|&(_, d)| d).max().unwrap_or(0)
    }

    /// Collects the primitive indices below `node` (at most `LEAF_MAX` of them).
    fn gather(&self, node: usize, out: &mut [u32; LEAF_MAX as usize], n: &mut usize) {
        let nd = &self.nodes[node];
        if nd.is_leaf() {
            for k in 0..nd.prim_count {
                out[*n] = self.prim_indices[(nd.first_index + k) as usize];
                *n += 1;
            }
        } else {
            self.gather(nd.first_index as usize, out, n);
            self.gather(nd.first_index as usize + 1, out, n);
        }
    }
}
