//! An 8-wide BVH with single-precision child boxes in SoA layout, traversed one ray at a time:
//! the eight box tests are one 8-wide operation per slab plane (AVX, via `wide::f32x8`; two
//! SSE halves on processors without AVX), the triangle tests 4-wide (SSE, via glam `Vec4`). A
//! node is 256 bytes on 64-byte boundaries.
//!
//! Why 8-wide even on a 4-wide ISA: incoherent rays on large meshes are bound by the latency
//! of dependent node fetches; a wider node halves the depth, and its four cache lines load in
//! parallel (figures in `bench/README.md`, "Accelerator").
//!
//! Construction: obvhs builds a binary BVH (PLOC, Meister & Bittner 2018, followed by SAH
//! reinsertion optimisation, Meister & Bittner 2017); we collapse it into the wide tree by
//! repeatedly opening the largest-area child (as in Embree / Wald et al. 2008), and emit a leaf
//! for any subtree with at most [`LEAF_MAX`] primitives ([`SMALL_LEAF_MAX`] in small scenes). Triangles of a leaf are packed four at a
//! time into [`Tri4`]s; analytic shapes take one packet each.
//!
//! Traversal: closest-hit orders the hit children front to back by entry distance and culls
//! popped entries that lie beyond the current hit; occlusion skips ordering and returns on the
//! first hit. The box test is made conservative by scaling the exit distance by `1 + 2γ₃`
//! (Ize 2013, "Robust BVH Ray Traversal"), so watertight triangles are never lost to box misses.
//! The stack is a fixed-size array on the call stack (8 to 1024 entries, chosen at build
//! from the exact worst case of the tree's shape), so queries never allocate.

use obvhs::aabb::Aabb;
use obvhs::bvh2::Bvh2;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::ploc::{PlocBuilder, PlocSearchDistance, SortPrecision};

use super::prim::{
    Tri4, WoopRay, WoopRay4, intersect_disk, intersect_ellipsoid, intersect_sphere, tri4_any,
    tri4_closest,
};
use crate::geometry::Ray;
use crate::math::{Mat4, Vec3, Vec4};
use wide::f32x8;

/// Subtrees with at most this many primitives become leaves (triangles packed by four into
/// [`Tri4`]s). Measured on the 1M-triangle benchmark: 8 beats 2 and 4 (fewer dependent node
/// fetches; the packets of a leaf load in parallel) and equals 12.
pub(crate) const LEAF_MAX: u32 = 8;

/// Scenes with at most this many primitives use [`SMALL_LEAF_MAX`] instead: their tree fits
/// in cache, so traversal is bound by arithmetic rather than by node fetches, and their
/// primitives are typically large (walls, boxes, area lights) with boxes that overlap much of
/// the scene: small leaves trade a few more node visits for far fewer packet tests.
const SMALL_SCENE: usize = 4096;
const SMALL_LEAF_MAX: u32 = 2;

const LEAF_BIT: u32 = 1 << 31;
const COUNT_SHIFT: u32 = 27;
const FIRST_MASK: u32 = (1 << COUNT_SHIFT) - 1;
/// An empty child slot: a leaf with no packets (its box is inverted, so it is never entered).
const EMPTY: u32 = LEAF_BIT;
/// Largest traversal stack (entries); deeper trees are rebuilt balanced.
const MAX_STACK: usize = 1024;

/// `1 + 2γ₃` with `γₙ = nε/(1-nε)`, ε = 2⁻²⁴ (pbrt-v4's robust slab test).
const ROBUST: f32 = 1.0 + 2.0 * (3.0 * f32::EPSILON * 0.5) / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// A bounded primitive handed to the builder.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Prim {
    Tri([Vec3; 3]),
    Sphere { center: Vec3, radius: f32 },
    Disk { to_object: Mat4 },
    Ellipsoid { to_object: Mat4 },
}

/// What a leaf stores: triangles four at a time, analytic shapes one at a time.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Packet {
    Tri4(Tri4),
    Sphere {
        center: Vec3,
        radius: f32,
    },
    /// A disk or an ellipsoid: a unit shape seen through `to_object`. One variant for both
    /// keeps the leaf loop's dispatch as small as it was with disks alone.
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
}

/// Children per node.
const WIDTH: usize = 8;

/// Inner node: child boxes as `b[axis][0 = min, 1 = max]`, one child per lane (one AVX register
/// per plane; two SSE registers without AVX). A child reference with [`LEAF_BIT`] set encodes
/// `count` packets starting at `first`.
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

pub(crate) struct WideBvh {
    nodes: Vec<Node>,
    packets: Vec<Packet>,
    /// `(shape, prim)` per packet lane.
    ids: Vec<[[u32; 2]; 4]>,
    root: u32,
    stack: StackClass,
    /// Traversal stack entries needed: the largest, over root-to-leaf paths, of the pushes a
    /// traversal may leave on the stack along the path (`children - 1` per inner node).
    stack_need: u32,
    /// Subtrees with at most this many primitives become leaves.
    leaf_max: u32,
    /// Whether traversal touches the entered children ahead of time (see [`WideBvh::touch`]):
    /// only worth its loads when the tree does not fit in cache.
    prefetch: bool,
}

/// Trees smaller than this (nodes and packets, bytes) are assumed cache resident: traversal
/// skips the prefetching loads, which then only cost instructions.
const PREFETCH_MIN_BYTES: usize = 256 * 1024;

/// Per-ray traversal constants.
struct TravRay {
    o: [f32x8; 3],
    inv: [f32x8; 3],
    /// 1 where the direction component is negative (then the near plane is the max plane).
    neg: [usize; 3],
}

impl TravRay {
    #[inline(always)]
    fn new(ray: &Ray) -> TravRay {
        // Reciprocal direction in one vector division; an infinite component (zero direction
        // component) becomes ±MAX with its sign, so slabs never produce 0 · ∞ = NaN.
        let r = Vec4::ONE / Vec4::new(ray.d.x, ray.d.y, ray.d.z, 1.0);
        let i = Vec4::select(
            r.abs().cmplt(Vec4::INFINITY),
            r,
            Vec4::splat(f32::MAX).copysign(r),
        );
        let neg = i.is_negative_bitmask();
        TravRay {
            o: [
                f32x8::splat(ray.o.x),
                f32x8::splat(ray.o.y),
                f32x8::splat(ray.o.z),
            ],
            inv: [f32x8::splat(i.x), f32x8::splat(i.y), f32x8::splat(i.z)],
            neg: [
                (neg & 1) as usize,
                ((neg >> 1) & 1) as usize,
                ((neg >> 2) & 1) as usize,
            ],
        }
    }

    /// Entry distances of the children and the mask of those entered within `(0, t_max)`.
    #[inline(always)]
    fn hit_node(&self, n: &Node, t_max: f32) -> (f32x8, u32) {
        let [nx, ny, nz] = self.neg;
        let b = &n.b;
        let tnx = (b[0][nx & 1] - self.o[0]) * self.inv[0];
        let tny = (b[1][ny & 1] - self.o[1]) * self.inv[1];
        let tnz = (b[2][nz & 1] - self.o[2]) * self.inv[2];
        let tfx = (b[0][(nx ^ 1) & 1] - self.o[0]) * self.inv[0];
        let tfy = (b[1][(ny ^ 1) & 1] - self.o[1]) * self.inv[1];
        let tfz = (b[2][(nz ^ 1) & 1] - self.o[2]) * self.inv[2];
        // `fast_max`/`fast_min` are the plain max/min instructions (no NaN can arise here).
        let tn = tnx.fast_max(tny).fast_max(tnz).fast_max(f32x8::ZERO);
        let tf =
            (tfx.fast_min(tfy).fast_min(tfz) * f32x8::splat(ROBUST)).fast_min(f32x8::splat(t_max));
        (tn, tn.simd_le(tf).to_bitmask())
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

impl WideBvh {
    /// Builds over `prims`, whose ids are `ids[i] = (shape, prim)`.
    pub(crate) fn build(prims: &[Prim], ids: &[[u32; 2]], aabbs: &[Aabb]) -> WideBvh {
        let n = prims.len();
        let mut out = WideBvh {
            nodes: Vec::new(),
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
            // Batch ratio 0.4 rather than obvhs' "medium" 0.05: a slower build for faster
            // traversal, the right trade for an offline renderer.
            ReinsertionOptimizer::default().run(&mut bvh2, 0.4, None);
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
        out.prefetch = out.nodes.len() * size_of::<Node>()
            + out.packets.len() * size_of::<Packet>()
            + out.ids.len() * size_of::<[[u32; 2]; 4]>()
            >= PREFETCH_MIN_BYTES;
        if out.stack_need() > MAX_STACK {
            // A balanced tree has depth ≤ log2(n) + 1, far below the limit.
            out.nodes.clear();
            out.packets.clear();
            out.ids.clear();
            out.collapse(&Tree2::median(aabbs), prims, ids);
        }
        out
    }

    /// Bytes of nodes, packets and ids.
    pub(crate) fn memory_bytes(&self) -> usize {
        self.nodes.len() * size_of::<Node>()
            + self.packets.len() * size_of::<Packet>()
            + self.ids.len() * size_of::<[[u32; 2]; 4]>()
    }

    /// Traversal stack entries needed (see the `stack_need` field).
    fn stack_need(&self) -> usize {
        self.stack_need as usize
    }

    fn collapse(&mut self, tree: &Tree2, prims: &[Prim], ids: &[[u32; 2]]) {
        let counts = tree.subtree_counts();
        let mut need = 0;
        self.root = self.emit(tree, &counts, prims, ids, 0, 0, &mut need);
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

    #[allow(clippy::too_many_arguments)]
    fn emit(
        &mut self,
        tree: &Tree2,
        counts: &[u32],
        prims: &[Prim],
        ids: &[[u32; 2]],
        node: usize,
        pushed: u32,
        need: &mut u32,
    ) -> u32 {
        if counts[node] <= self.leaf_max {
            return self.emit_leaf(tree, node, prims, ids);
        }
        let first = tree.nodes[node].first_index as usize;
        let mut kids = [0usize; WIDTH];
        kids[0] = first;
        kids[1] = first + 1;
        let mut k = 2;
        while k < WIDTH {
            // Open the inner child with the largest surface area.
            let mut best = None;
            let mut best_area = -1.0;
            for (j, &c) in kids[..k].iter().enumerate() {
                if counts[c] > self.leaf_max {
                    let a = tree.nodes[c].aabb().half_area();
                    if a > best_area {
                        best_area = a;
                        best = Some(j);
                    }
                }
            }
            let Some(j) = best else { break };
            let c = tree.nodes[kids[j]].first_index as usize;
            kids[j] = c;
            kids[k] = c + 1;
            k += 1;
        }
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
            child[slot] = self.emit(tree, counts, prims, ids, c, pushed, need);
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
        let first = self.packets.len() as u32;
        let mut tris = [[Vec3::ZERO; 3]; LEAF_MAX as usize];
        let mut tri_ids = [[u32::MAX; 2]; LEAF_MAX as usize];
        let mut nt = 0;
        for &i in &items[..n] {
            let i = i as usize;
            match prims[i] {
                Prim::Tri(p) => {
                    tris[nt] = p;
                    tri_ids[nt] = ids[i];
                    nt += 1;
                }
                Prim::Sphere { center, radius } => {
                    self.packets.push(Packet::Sphere { center, radius });
                    self.ids
                        .push([ids[i], [u32::MAX; 2], [u32::MAX; 2], [u32::MAX; 2]]);
                }
                Prim::Disk { to_object } => {
                    self.packets.push(Packet::Transformed {
                        to_object,
                        kind: Unit::Disk,
                    });
                    self.ids
                        .push([ids[i], [u32::MAX; 2], [u32::MAX; 2], [u32::MAX; 2]]);
                }
                Prim::Ellipsoid { to_object } => {
                    self.packets.push(Packet::Transformed {
                        to_object,
                        kind: Unit::Sphere,
                    });
                    self.ids
                        .push([ids[i], [u32::MAX; 2], [u32::MAX; 2], [u32::MAX; 2]]);
                }
            }
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
        LEAF_BIT | (count << COUNT_SHIFT) | first
    }

    /// Loads a word from each cache line of the node or first packet `c` refers to. Used as a
    /// prefetch (without `unsafe` intrinsics): the loads of all entered children are issued
    /// together and overlap, instead of missing one after the other when they are popped.
    #[inline(always)]
    fn touch(&self, c: u32) -> u32 {
        if c & LEAF_BIT == 0 {
            let n = &self.nodes[c as usize];
            n.b[0][0].to_array()[0].to_bits()
                ^ n.b[1][0].to_array()[0].to_bits()
                ^ n.b[2][0].to_array()[0].to_bits()
                ^ n.child[0]
        } else if c != EMPTY {
            match &self.packets[(c & FIRST_MASK) as usize] {
                Packet::Tri4(t) => {
                    t.p[0][0].x.to_bits() ^ t.p[1][1].x.to_bits() ^ t.p[2][2].x.to_bits()
                }
                _ => 0,
            }
        } else {
            0
        }
    }

    pub(crate) fn intersect(&self, ray: &Ray, t_max: f32) -> Option<RawHit> {
        match self.stack {
            StackClass::S8 => self.intersect_n::<8>(ray, t_max),
            StackClass::S16 => self.intersect_n::<16>(ray, t_max),
            StackClass::S32 => self.intersect_n::<32>(ray, t_max),
            StackClass::S64 => self.intersect_n::<64>(ray, t_max),
            StackClass::S128 => self.intersect_n::<128>(ray, t_max),
            StackClass::S256 => self.intersect_n::<256>(ray, t_max),
            StackClass::S1024 => self.intersect_n::<1024>(ray, t_max),
        }
    }

    pub(crate) fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        match self.stack {
            StackClass::S8 => self.occluded_n::<8>(ray, t_max),
            StackClass::S16 => self.occluded_n::<16>(ray, t_max),
            StackClass::S32 => self.occluded_n::<32>(ray, t_max),
            StackClass::S64 => self.occluded_n::<64>(ray, t_max),
            StackClass::S128 => self.occluded_n::<128>(ray, t_max),
            StackClass::S256 => self.occluded_n::<256>(ray, t_max),
            StackClass::S1024 => self.occluded_n::<1024>(ray, t_max),
        }
    }

    // Not inlined into the dispatch above: each stack size gets its own frame, so small trees
    // do not pay for the stack probes of the 1024-entry variant.
    #[inline(never)]
    fn intersect_n<const N: usize>(&self, ray: &Ray, mut t_max: f32) -> Option<RawHit> {
        if self.root == EMPTY {
            return None;
        }
        let tr = TravRay::new(ray);
        let woop = WoopRay4::new(&WoopRay::new(ray));
        let mut stack_node = [0u32; N];
        let mut stack_t = [0f32; N];
        let mut sp = 0usize;
        let mut cur = self.root;
        // (packet, t, u, v) and the lane within the packet.
        let mut best: Option<(u32, f32, f32, f32)> = None;
        let mut best_lane = 0usize;
        let mut sink = 0u32;
        'outer: loop {
            if cur & LEAF_BIT == 0 {
                let node = &self.nodes[cur as usize];
                let (tn, mask) = tr.hit_node(node, t_max);
                if mask != 0 {
                    if mask & (mask - 1) == 0 {
                        cur = node.child[mask.trailing_zeros() as usize];
                        continue;
                    }
                    if self.prefetch {
                        let mut m = mask;
                        while m != 0 {
                            sink ^= self.touch(node.child[m.trailing_zeros() as usize]);
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
                        stack_node[sp] = node.child[far];
                        stack_t[sp] = tb[far];
                        sp += 1;
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
                        stack_node[sp] = node.child[s];
                        stack_t[sp] = tb[s];
                        sp += 1;
                    }
                    cur = node.child[(keys[k - 1] & 7) as usize];
                    continue;
                }
            } else {
                let first = (cur & FIRST_MASK) as usize;
                let count = ((cur & !LEAF_BIT) >> COUNT_SHIFT) as usize;
                for (pi, p) in self.packets[first..first + count].iter().enumerate() {
                    match p {
                        Packet::Tri4(tri) => {
                            if let Some((lane, t, u, v)) = tri4_closest(&woop, tri, t_max) {
                                t_max = t;
                                best = Some(((first + pi) as u32, t, u, v));
                                best_lane = lane;
                            }
                        }
                        Packet::Sphere { center, radius } => {
                            if let Some(t) = sphere_packet(ray, *center, *radius, t_max) {
                                t_max = t;
                                best = Some(((first + pi) as u32, t, 0.0, 0.0));
                                best_lane = 0;
                            }
                        }
                        Packet::Transformed { to_object, kind } => {
                            if let Some((t, x, y)) =
                                transformed_packet(ray, to_object, *kind, t_max)
                            {
                                t_max = t;
                                best = Some(((first + pi) as u32, t, x, y));
                                best_lane = 0;
                            }
                        }
                    }
                }
            }
            // Pop the next entry that may still hold a closer hit.
            loop {
                if sp == 0 {
                    break 'outer;
                }
                sp -= 1;
                if stack_t[sp] <= t_max {
                    cur = stack_node[sp];
                    break;
                }
            }
        }
        std::hint::black_box(sink);
        best.map(|(p, t, u, v)| {
            let [shape, prim] = self.ids[p as usize][best_lane];
            RawHit {
                t,
                shape,
                prim,
                u,
                v,
            }
        })
    }

    #[inline(never)]
    fn occluded_n<const N: usize>(&self, ray: &Ray, t_max: f32) -> bool {
        if self.root == EMPTY {
            return false;
        }
        let tr = TravRay::new(ray);
        // The triangle test's constants, made when the first leaf is reached: most shadow
        // rays in small scenes reach none.
        let mut woop: Option<WoopRay4> = None;
        let mut stack = [0u32; N];
        let mut sp = 0usize;
        let mut cur = self.root;
        let mut sink = 0u32;
        loop {
            if cur & LEAF_BIT == 0 {
                let node = &self.nodes[cur as usize];
                let (_, mut mask) = tr.hit_node(node, t_max);
                if mask != 0 {
                    cur = node.child[mask.trailing_zeros() as usize];
                    mask &= mask - 1;
                    if self.prefetch {
                        let mut m = mask;
                        while m != 0 {
                            sink ^= self.touch(node.child[m.trailing_zeros() as usize]);
                            m &= m - 1;
                        }
                    }
                    while mask != 0 {
                        stack[sp] = node.child[mask.trailing_zeros() as usize];
                        sp += 1;
                        mask &= mask - 1;
                    }
                    continue;
                }
            } else {
                let first = (cur & FIRST_MASK) as usize;
                let count = ((cur & !LEAF_BIT) >> COUNT_SHIFT) as usize;
                for p in &self.packets[first..first + count] {
                    let hit = match p {
                        Packet::Tri4(tri) => {
                            let w = woop.get_or_insert_with(|| WoopRay4::new(&WoopRay::new(ray)));
                            tri4_any(w, tri, t_max)
                        }
                        Packet::Sphere { center, radius } => {
                            sphere_packet(ray, *center, *radius, t_max).is_some()
                        }
                        Packet::Transformed { to_object, kind } => {
                            transformed_packet(ray, to_object, *kind, t_max).is_some()
                        }
                    };
                    if hit {
                        return true;
                    }
                }
            }
            if sp == 0 {
                std::hint::black_box(sink);
                return false;
            }
            sp -= 1;
            cur = stack[sp];
        }
    }
}

/// The sphere test, kept out of line in the traversal loops: inlined, its per-ray constants
/// are hoisted into the set-up of every ray, including the many that never reach a sphere.
#[inline(never)]
fn sphere_packet(ray: &Ray, center: Vec3, radius: f32, t_max: f32) -> Option<f32> {
    intersect_sphere(ray, center, radius, t_max)
}

/// The disk and ellipsoid tests, out of line for the same reason as [`sphere_packet`]:
/// `(t, x, y)` with the disk's object-space hit `x, y` (0 for ellipsoids).
#[inline(never)]
fn transformed_packet(
    ray: &Ray,
    to_object: &Mat4,
    kind: Unit,
    t_max: f32,
) -> Option<(f32, f32, f32)> {
    match kind {
        Unit::Disk => intersect_disk(ray, to_object, t_max),
        Unit::Sphere => intersect_ellipsoid(ray, to_object, t_max).map(|t| (t, 0.0, 0.0)),
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

    fn subtree_counts(&self) -> Vec<u32> {
        let mut counts = vec![0u32; self.nodes.len()];
        for &(i, _) in self.preorder().iter().rev() {
            let n = &self.nodes[i as usize];
            counts[i as usize] = if n.is_leaf() {
                n.prim_count
            } else {
                counts[n.first_index as usize] + counts[n.first_index as usize + 1]
            };
        }
        counts
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
