//! The SD-tree of Müller et al. 2017, "Practical Path Guiding for Efficient Light-Transport
//! Simulation": a spatial binary tree over the scene's bounding cube whose leaves each hold a
//! directional quadtree over the square of directions (the cylindrical map
//! `(u, v) ↦ (cos θ = 2u − 1, φ = 2πv)`, area-preserving, so a density over the square is
//! 4π times the density over the sphere).
//!
//! Each leaf holds two quadtrees: the one sampled from in the current training iteration
//! ([`DTree`], read only while a pass renders) and the one being built from the samples of
//! this iteration ([`DBuild`]). Samples are recorded in 64-bit fixed point with atomic adds
//! (and counted with atomic adds): integer sums do not depend on the order the threads add
//! them in, so the trees, and so the image, are the same for any thread count. The tree
//! changes only in [`SdTree::refine`], between iterations (single-threaded, in a fixed
//! order): the built quadtrees become the sampled ones, leaves that saw more than
//! `c·√(2^k)` samples split in two (halving along x, y, z in turn), and each building
//! quadtree is re-subdivided where its cells hold more than ρ = 1 % of the leaf's energy
//! (up to depth 20) and merged where they hold less. A node budget bounds the memory: past
//! it no leaf splits and no quadtree grows.

use std::sync::atomic::{AtomicU64, Ordering};

use crate::math::{Vec2, Vec3};

/// Fixed-point units per unit of recorded energy (2⁻²⁰ resolution).
const UNITS: f64 = (1u64 << 20) as f64;
/// Largest energy one record adds (2³⁶ units): 2²⁸ records at the cap still fit in 64 bits.
const MAX_RECORD: f64 = (1u64 << 16) as f64;
/// A quadtree cell is subdivided when it holds more than this fraction of its tree's energy.
const RHO: f64 = 0.01;
/// Deepest quadtree level.
const MAX_DEPTH: u32 = 20;
/// Deepest spatial level.
const MAX_SPATIAL_DEPTH: u32 = 48;
/// Bytes of a sampled quadtree node, of a building one, of a spatial node and of a leaf.
const SAMPLED_BYTES: u64 = std::mem::size_of::<DNode>() as u64;
const BUILD_BYTES: u64 = std::mem::size_of::<BNode>() as u64;
const SPATIAL_BYTES: u64 = std::mem::size_of::<SNode>() as u64;
const LEAF_BYTES: u64 = std::mem::size_of::<Leaf>() as u64;

/// `atan2(y, x) / 2π` in `[0, 1)`: a minimax polynomial for atan on [0, 1] (error below
/// 1e-5 rad), the octant restored by swaps and reflections. libm's `atan2f` was a tenth of a
/// guided render's time.
#[inline(always)]
fn azimuth_turns(y: f32, x: f32) -> f32 {
    let (ax, ay) = (x.abs(), y.abs());
    let (lo, hi) = if ax > ay { (ay, ax) } else { (ax, ay) };
    if hi == 0.0 {
        return 0.0;
    }
    let t = lo / hi;
    let t2 = t * t;
    let mut a = t
        * (0.999_866
            + t2 * (-0.330_299_5 + t2 * (0.180_141 + t2 * (-0.085_133 + t2 * 0.020_835_1))));
    if ay > ax {
        a = std::f32::consts::FRAC_PI_2 - a;
    }
    if x < 0.0 {
        a = std::f32::consts::PI - a;
    }
    let turns = a * (0.5 * std::f32::consts::FRAC_1_PI);
    let turns = if y < 0.0 { 1.0 - turns } else { turns };
    if turns >= 1.0 { 0.0 } else { turns }
}

/// The square point of a unit direction.
#[inline]
pub fn dir_to_square(d: Vec3) -> Vec2 {
    let u = ((d.z + 1.0) * 0.5).clamp(0.0, 1.0);
    Vec2::new(u, azimuth_turns(d.y, d.x))
}

/// The unit direction of a square point.
#[inline]
pub fn square_to_dir(p: Vec2) -> Vec3 {
    let cos_t = 2.0 * p.x - 1.0;
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let (s, c) = crate::sampling::warp::sin_cos_2pi(p.y);
    Vec3::new(sin_t * c, sin_t * s, cos_t)
}

/// A sampled quadtree node: the energy of each quadrant (`i = x + 2y`) and its child node
/// (0: the quadrant is a leaf cell).
#[derive(Clone, Copy, Debug)]
struct DNode {
    e: [f32; 4],
    child: [u32; 4],
}

/// A directional distribution: a quadtree over the square of directions, each cell's
/// density proportional to its energy (piecewise constant over the leaf cells).
#[derive(Clone, Debug, Default)]
pub struct DTree {
    nodes: Vec<DNode>,
}

/// Quadrant `i` of a point in `[0, 1)²`, and the point rescaled into that quadrant.
#[inline]
fn quadrant(p: Vec2) -> (usize, Vec2) {
    let qx = (p.x >= 0.5) as usize;
    let qy = (p.y >= 0.5) as usize;
    let r = Vec2::new(
        (p.x * 2.0 - qx as f32).clamp(0.0, 1.0),
        (p.y * 2.0 - qy as f32).clamp(0.0, 1.0),
    );
    (qx + 2 * qy, r)
}

impl DTree {
    /// Whether it has energy to sample from.
    pub fn is_valid(&self) -> bool {
        self.nodes
            .first()
            .is_some_and(|n| n.e.iter().sum::<f32>() > 0.0)
    }

    /// Nodes held.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// A point of the square drawn with the tree's density from `u`, and that density
    /// (`is_valid` trees only).
    pub fn sample_square(&self, mut u: Vec2) -> (Vec2, f32) {
        const ONE_MINUS: f32 = 1.0 - f32::EPSILON;
        let mut origin = Vec2::ZERO;
        let mut scale = 1.0f32;
        let mut pdf = 1.0f32;
        let mut n = 0usize;
        loop {
            let e = self.nodes[n].e;
            let total = e[0] + e[1] + e[2] + e[3];
            // Column first (x), then the row within it (y).
            let left = (e[0] + e[2]) / total;
            let qx = if u.x < left {
                u.x = (u.x / left).min(ONE_MINUS);
                0
            } else {
                u.x = ((u.x - left) / (1.0 - left)).clamp(0.0, ONE_MINUS);
                1
            };
            let col = e[qx] + e[qx + 2];
            let low = e[qx] / col;
            let qy = if u.y < low {
                u.y = (u.y / low).min(ONE_MINUS);
                0
            } else {
                u.y = ((u.y - low) / (1.0 - low)).clamp(0.0, ONE_MINUS);
                1
            };
            let i = qx + 2 * qy;
            pdf *= 4.0 * e[i] / total;
            scale *= 0.5;
            origin += Vec2::new(qx as f32, qy as f32) * scale;
            match self.nodes[n].child[i] {
                0 => return (origin + u * scale, pdf),
                c => n = c as usize,
            }
        }
    }

    /// The density over the square at `p` (0 for an invalid tree).
    pub fn pdf_square(&self, mut p: Vec2) -> f32 {
        if !self.is_valid() {
            return 0.0;
        }
        let mut pdf = 1.0f32;
        let mut n = 0usize;
        loop {
            let node = &self.nodes[n];
            let (i, r) = quadrant(p);
            let total = node.e[0] + node.e[1] + node.e[2] + node.e[3];
            pdf *= 4.0 * node.e[i] / total;
            if pdf == 0.0 {
                return 0.0;
            }
            match node.child[i] {
                0 => return pdf,
                c => {
                    n = c as usize;
                    p = r;
                }
            }
        }
    }

    /// A unit direction drawn with the tree's density, and its solid-angle density.
    #[inline]
    pub fn sample(&self, u: Vec2) -> (Vec3, f32) {
        let (p, pdf) = self.sample_square(u);
        (square_to_dir(p), pdf * (0.25 * std::f32::consts::FRAC_1_PI))
    }

    /// The solid-angle density of the unit direction `d`.
    #[inline]
    pub fn pdf(&self, d: Vec3) -> f32 {
        self.pdf_square(dir_to_square(d)) * (0.25 * std::f32::consts::FRAC_1_PI)
    }

    /// A tree of the given quadrant energies per node (tests).
    #[doc(hidden)]
    pub fn from_nodes(nodes: &[([f32; 4], [u32; 4])]) -> DTree {
        DTree {
            nodes: nodes.iter().map(|&(e, child)| DNode { e, child }).collect(),
        }
    }
}

/// A quadtree being built: fixed-point energy sums per quadrant, added to atomically.
#[derive(Debug)]
struct BNode {
    sum: [AtomicU64; 4],
    child: [u32; 4],
}

impl BNode {
    fn new(child: [u32; 4]) -> BNode {
        BNode {
            sum: Default::default(),
            child,
        }
    }
    fn sums(&self) -> [u64; 4] {
        std::array::from_fn(|i| self.sum[i].load(Ordering::Relaxed))
    }
}

/// The quadtree an iteration records its samples into.
#[derive(Debug)]
struct DBuild {
    nodes: Vec<BNode>,
}

impl DBuild {
    fn single() -> DBuild {
        DBuild {
            nodes: vec![BNode::new([0; 4])],
        }
    }

    fn record(&self, mut p: Vec2, units: u64) {
        let mut n = 0usize;
        loop {
            let node = &self.nodes[n];
            let (i, r) = quadrant(p);
            node.sum[i].fetch_add(units, Ordering::Relaxed);
            match node.child[i] {
                0 => return,
                c => {
                    n = c as usize;
                    p = r;
                }
            }
        }
    }

    fn total(&self) -> u64 {
        self.nodes[0].sums().iter().sum()
    }

    /// The sampled tree of these sums (same topology).
    fn to_sampled(&self) -> DTree {
        DTree {
            nodes: self
                .nodes
                .iter()
                .map(|n| DNode {
                    e: n.sums().map(|s| (s as f64 / UNITS) as f32),
                    child: n.child,
                })
                .collect(),
        }
    }

    /// The next iteration's building tree: cells holding more than ρ of the energy are
    /// subdivided (a cell new to the tree is given a quarter of its parent's energy, so
    /// several levels may be added at once), the rest are leaves; at most `budget` nodes.
    fn refined(&self, budget: &mut u64) -> DBuild {
        let total = self.total() as f64;
        if total <= 0.0 {
            // Nothing to refine by (the leaf's sampled tree stays what it was).
            return DBuild::single();
        }
        let mut out = DBuild { nodes: Vec::new() };
        out.nodes.push(BNode::new([0; 4]));
        // (new node, old node if any, energies of its quadrants, depth)
        let mut stack: Vec<(usize, Option<usize>, [f64; 4], u32)> =
            vec![(0, Some(0), self.nodes[0].sums().map(|s| s as f64), 1)];
        while let Some((new, old, e, depth)) = stack.pop() {
            for (i, &ei) in e.iter().enumerate() {
                if ei / total > RHO && depth < MAX_DEPTH && *budget > 0 {
                    *budget -= 1;
                    let idx = out.nodes.len();
                    out.nodes.push(BNode::new([0; 4]));
                    out.nodes[new].child[i] = idx as u32;
                    let old_child = old
                        .map(|o| self.nodes[o].child[i])
                        .filter(|&c| c != 0)
                        .map(|c| c as usize);
                    let ce = match old_child {
                        Some(c) => self.nodes[c].sums().map(|s| s as f64),
                        None => [ei * 0.25; 4],
                    };
                    stack.push((idx, old_child, ce, depth + 1));
                }
            }
        }
        // The byte budget counts nodes: no spare capacity from the pushes.
        out.nodes.shrink_to_fit();
        out
    }
}

/// A spatial node: an inner node halving its box along `axis`, or a leaf.
#[derive(Clone, Copy, Debug)]
enum SNode {
    Inner { axis: u8, child: [u32; 2] },
    Leaf(u32),
}

/// A spatial leaf: its two quadtrees and the samples recorded into it this iteration.
#[derive(Debug)]
struct Leaf {
    sampled: DTree,
    building: DBuild,
    count: AtomicU64,
    depth: u32,
}

/// What an SD-tree holds (for the memory report).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SdStats {
    pub leaves: usize,
    pub directional_nodes: usize,
    pub bytes: u64,
    /// The node budget stopped a split or a subdivision.
    pub capped: bool,
}

/// The SD-tree (see the module docs).
#[derive(Debug)]
pub struct SdTree {
    lo: Vec3,
    inv_size: f32,
    nodes: Vec<SNode>,
    leaves: Vec<Leaf>,
    iteration: u32,
    /// `c` of the spatial split rule.
    split_threshold: f64,
    max_bytes: u64,
    capped: bool,
}

impl SdTree {
    /// A tree over the cube around the box `(lo, hi)`: one leaf, nothing learnt yet.
    /// `split_threshold` is `c` of Müller et al.'s rule (12000 there), `max_bytes` the
    /// memory it may grow to.
    pub fn new(lo: Vec3, hi: Vec3, split_threshold: f64, max_bytes: u64) -> SdTree {
        let (lo, hi) = if lo.is_finite() && hi.is_finite() && lo.cmple(hi).all() {
            (lo, hi)
        } else {
            (Vec3::splat(-1.0), Vec3::splat(1.0))
        };
        let size = (hi - lo).max_element().max(1e-6) * 1.001;
        let centre = (lo + hi) * 0.5;
        SdTree {
            lo: centre - Vec3::splat(size * 0.5),
            inv_size: 1.0 / size,
            nodes: vec![SNode::Leaf(0)],
            leaves: vec![Leaf {
                sampled: DTree::default(),
                building: DBuild::single(),
                count: AtomicU64::new(0),
                depth: 0,
            }],
            iteration: 0,
            split_threshold,
            max_bytes,
            capped: false,
        }
    }

    /// The leaf whose box holds `p` (points outside the cube: the nearest box).
    #[inline]
    pub fn leaf(&self, p: Vec3) -> u32 {
        let mut q = ((p - self.lo) * self.inv_size).clamp(Vec3::ZERO, Vec3::ONE);
        let mut n = 0usize;
        loop {
            match self.nodes[n] {
                SNode::Leaf(l) => return l,
                SNode::Inner { axis, child } => {
                    let a = axis as usize;
                    let x = q[a] * 2.0;
                    if x < 1.0 {
                        q[a] = x;
                        n = child[0] as usize;
                    } else {
                        q[a] = (x - 1.0).min(1.0);
                        n = child[1] as usize;
                    }
                }
            }
        }
    }

    /// The distribution to sample at leaf `leaf`, if it has learnt one.
    #[inline]
    pub fn guide(&self, leaf: u32) -> Option<&DTree> {
        let t = &self.leaves[leaf as usize].sampled;
        t.is_valid().then_some(t)
    }

    /// Record a sample at leaf `leaf`: incident radiance over the density it was sampled
    /// with (`value`, ≥ 0; non-finite values only count) arriving from the unit direction `d`.
    #[inline]
    pub fn record(&self, leaf: u32, d: Vec3, value: f32) {
        let leaf = &self.leaves[leaf as usize];
        leaf.count.fetch_add(1, Ordering::Relaxed);
        if value.is_finite() && value > 0.0 {
            let units = (value as f64).min(MAX_RECORD) * UNITS;
            let units = units.round() as u64;
            if units > 0 {
                leaf.building.record(dir_to_square(d), units);
            }
        }
    }

    /// Bytes the tree holds.
    pub fn bytes(&self) -> u64 {
        let dir: u64 = self
            .leaves
            .iter()
            .map(|l| {
                l.sampled.nodes.len() as u64 * SAMPLED_BYTES
                    + l.building.nodes.len() as u64 * BUILD_BYTES
            })
            .sum();
        dir + self.leaves.len() as u64 * LEAF_BYTES + self.nodes.len() as u64 * SPATIAL_BYTES
    }

    pub fn stats(&self) -> SdStats {
        SdStats {
            leaves: self.leaves.len(),
            directional_nodes: self
                .leaves
                .iter()
                .map(|l| l.sampled.nodes.len() + l.building.nodes.len())
                .sum(),
            bytes: self.bytes(),
            capped: self.capped,
        }
    }

    /// The end of a training iteration (see the module docs): the recorded quadtrees become
    /// the sampled ones, crowded leaves split, the building quadtrees are refined and
    /// cleared. Deterministic: a function of the integer sums and counts only.
    pub fn refine(&mut self) {
        let threshold = self.split_threshold * 2f64.powf(self.iteration as f64 * 0.5);
        self.iteration += 1;
        let per_leaf = |s: &DTree, b: &DBuild| {
            s.nodes.len() as u64 * SAMPLED_BYTES + b.nodes.len() as u64 * BUILD_BYTES + LEAF_BYTES
        };
        // 1. New sampled trees (a leaf that saw no energy keeps what it had).
        for l in &mut self.leaves {
            if l.building.total() > 0 {
                l.sampled = l.building.to_sampled();
            }
        }
        // 2. Spatial splits, leaf by leaf in index order (children appended).
        let mut used = self.bytes();
        let mut n = 0;
        while n < self.nodes.len() {
            if let SNode::Leaf(li) = self.nodes[n] {
                let l = &self.leaves[li as usize];
                let count = l.count.load(Ordering::Relaxed);
                if count as f64 > threshold && l.depth < MAX_SPATIAL_DEPTH {
                    let cost = per_leaf(&l.sampled, &l.building) + 2 * SPATIAL_BYTES;
                    if used + cost > self.max_bytes {
                        self.capped = true;
                    } else {
                        used += cost;
                        let depth = l.depth;
                        let half = count / 2;
                        let sampled = l.sampled.clone();
                        let building = DBuild {
                            nodes: l
                                .building
                                .nodes
                                .iter()
                                .map(|b| BNode {
                                    sum: std::array::from_fn(|i| {
                                        AtomicU64::new(b.sum[i].load(Ordering::Relaxed) / 2)
                                    }),
                                    child: b.child,
                                })
                                .collect(),
                        };
                        for b in &l.building.nodes {
                            for s in &b.sum {
                                let v = s.load(Ordering::Relaxed);
                                s.store(v / 2, Ordering::Relaxed);
                            }
                        }
                        l.count.store(half, Ordering::Relaxed);
                        let l = &mut self.leaves[li as usize];
                        l.depth = depth + 1;
                        let new_leaf = self.leaves.len() as u32;
                        self.leaves.push(Leaf {
                            sampled,
                            building,
                            count: AtomicU64::new(half),
                            depth: depth + 1,
                        });
                        let a = self.nodes.len() as u32;
                        self.nodes.push(SNode::Leaf(li));
                        self.nodes.push(SNode::Leaf(new_leaf));
                        self.nodes[n] = SNode::Inner {
                            axis: (depth % 3) as u8,
                            child: [a, a + 1],
                        };
                        // The children are visited later in this loop: they split again
                        // while they hold more than the threshold.
                    }
                }
            }
            n += 1;
        }
        // 3. Refined, cleared building trees, in leaf order, within the node budget: every
        //    building node counts as a sampled one too (what it becomes at the next
        //    iteration), so that the tree stays under `max_bytes` then as well.
        let overhead =
            self.leaves.len() as u64 * LEAF_BYTES + self.nodes.len() as u64 * SPATIAL_BYTES;
        let sampled: u64 = self
            .leaves
            .iter()
            .map(|l| l.sampled.nodes.len() as u64)
            .sum();
        // Every leaf keeps at least its root.
        let mut budget = (self
            .max_bytes
            .saturating_sub(overhead + sampled * SAMPLED_BYTES)
            / (SAMPLED_BYTES + BUILD_BYTES))
            .saturating_sub(self.leaves.len() as u64);
        for l in &mut self.leaves {
            l.building = l.building.refined(&mut budget);
            if budget == 0 {
                self.capped = true;
            }
            l.count.store(0, Ordering::Relaxed);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn azimuth_matches_atan2() {
        for k in 0..10_000 {
            let a = k as f32 * 0.000_628_3;
            let (y, x) = (a.sin() * 3.0, a.cos() * 3.0);
            let mut want = y.atan2(x) / (2.0 * std::f32::consts::PI);
            if want < 0.0 {
                want += 1.0;
            }
            let got = azimuth_turns(y, x);
            let d = (got - want).abs().min(1.0 - (got - want).abs());
            assert!(d < 4e-6, "{a}: {got} vs {want}");
        }
    }

    #[test]
    fn square_map_round_trip() {
        for &(u, v) in &[(0.1f32, 0.2f32), (0.5, 0.9), (0.99, 0.01), (0.3, 0.6)] {
            let p = dir_to_square(square_to_dir(Vec2::new(u, v)));
            assert!(
                (p.x - u).abs() < 1e-5 && (p.y - v).abs() < 1e-5,
                "{u} {v} {p}"
            );
        }
    }

    #[test]
    fn learns_a_direction_deterministically() {
        let run = || {
            let mut t = SdTree::new(Vec3::ZERO, Vec3::ONE, 100.0, 1 << 24);
            let d = Vec3::new(0.3, 0.4, 0.866).normalize();
            for it in 0..4 {
                for k in 0..2000 {
                    let p = Vec3::splat((k % 97) as f32 / 97.0);
                    let l = t.leaf(p);
                    t.record(l, d, 1.0);
                    t.record(l, -d, 0.01);
                }
                let _ = it;
                t.refine();
            }
            t
        };
        let t = run();
        let l = t.leaf(Vec3::splat(0.5));
        let g = t.guide(l).expect("a learnt distribution");
        let d = Vec3::new(0.3, 0.4, 0.866).normalize();
        assert!(g.pdf(d) > 10.0 * g.pdf(-d), "{} {}", g.pdf(d), g.pdf(-d));
        assert!(t.stats().leaves > 1);
        assert_eq!(t.stats(), run().stats());
    }
}
