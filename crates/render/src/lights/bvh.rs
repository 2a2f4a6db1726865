//! A light BVH for many-light selection (Conty Estevez & Kulla 2018, "Importance Sampling of
//! Many Lights with Adaptive Tree Splitting", in the form of pbrt-v4's `BVHLightSampler`).
//!
//! Every bounded light with non-zero power gets [`LightBounds`]: an axis-aligned box, the
//! normal cone (axis `w`, spread `θo`) its surface normals lie in, the angle `θe` beyond the
//! normals in which it still emits (π/2 for area lights), its power and two-sidedness. The
//! binary tree is built top-down, splitting at the cheapest of 12 buckets per axis under
//! pbrt's cost model (power × solid-angle measure of the cone × box surface area × aspect),
//! then collapsed to a 4-wide tree whose nodes store their children's bounds in
//! structure-of-arrays form. A receiver walks down from the root, choosing among a node's
//! children with probability proportional to their [`LightBounds::importance`] (a
//! conservative bound of power × cosines / distance², pbrt-v4's), evaluated for the four at
//! once with SIMD. Compared with pbrt's binary walk this is a quarter of the evaluations and
//! half the levels; it halved the selection's cost on our demo scenes. Infinite lights are not
//! in the tree: one of them is chosen (uniformly) with probability `n_inf / (n_inf + 1)` and
//! the tree otherwise.
//!
//! [`LightBvh::pmf`] replays the descent along the path to the light's leaf (its "trail" of
//! child slots, two bits per level), with the very same float expressions as
//! [`LightBvh::sample`], so the two agree exactly.

use crate::math::{PI, Vec3, Vec4, safe_sqrt};
use crate::sampling::distrib::ONE_MINUS_EPSILON;

use super::Receiver;

/// Spatial and directional bounds of the emission of one light or a cluster of lights.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    pub lo: Vec3,
    pub hi: Vec3,
    /// Axis of the normal cone (unit).
    pub w: Vec3,
    /// Emitted power (any positive measure proportional to it).
    pub phi: f32,
    /// cos θo: every normal is within θo of `w` (−1: any direction).
    pub cos_o: f32,
    /// cos θe: emission reaches θe beyond the normals (0 for area lights, θe = π/2).
    pub cos_e: f32,
    pub two_sided: bool,
}

#[inline]
fn safe_acos(x: f32) -> f32 {
    x.clamp(-1.0, 1.0).acos()
}

/// Angle between unit vectors, accurate near 0 and π.
#[inline]
fn angle_between(a: Vec3, b: Vec3) -> f32 {
    if a.dot(b) < 0.0 {
        PI - 2.0 * ((a + b).length() * 0.5).clamp(-1.0, 1.0).asin()
    } else {
        2.0 * ((b - a).length() * 0.5).clamp(-1.0, 1.0).asin()
    }
}

/// Rotate `v` by `angle` around the unit axis `k` (Rodrigues).
#[inline]
fn rotate(v: Vec3, k: Vec3, angle: f32) -> Vec3 {
    let (s, c) = angle.sin_cos();
    v * c + k.cross(v) * s + k * k.dot(v) * (1.0 - c)
}

/// The smallest cone (as pbrt-v4's `Union(DirectionCone, DirectionCone)`) holding both.
fn cone_union(wa: Vec3, cos_a: f32, wb: Vec3, cos_b: f32) -> (Vec3, f32) {
    let (ta, tb) = (safe_acos(cos_a), safe_acos(cos_b));
    let td = angle_between(wa, wb);
    if (td + tb).min(PI) <= ta {
        return (wa, cos_a);
    }
    if (td + ta).min(PI) <= tb {
        return (wb, cos_b);
    }
    let to = 0.5 * (ta + td + tb);
    if to >= PI {
        return (wa, -1.0);
    }
    let wr = wa.cross(wb);
    if wr.length_squared() < 1e-12 {
        return (wa, -1.0);
    }
    let w = rotate(wa, wr.normalize(), to - ta).normalize();
    (w, to.cos())
}

impl LightBounds {
    /// Bounds of both (a zero-power side is ignored).
    pub fn union(&self, o: &LightBounds) -> LightBounds {
        if self.phi == 0.0 {
            return *o;
        }
        if o.phi == 0.0 {
            return *self;
        }
        let (w, cos_o) = cone_union(self.w, self.cos_o, o.w, o.cos_o);
        LightBounds {
            lo: self.lo.min(o.lo),
            hi: self.hi.max(o.hi),
            w,
            phi: self.phi + o.phi,
            cos_o,
            cos_e: self.cos_e.min(o.cos_e),
            two_sided: self.two_sided || o.two_sided,
        }
    }

    #[inline]
    fn centroid(&self) -> Vec3 {
        0.5 * (self.lo + self.hi)
    }

    /// Conservative importance of these lights for a receiver at `r.p` with normal `r.n`
    /// (zero normal: none): φ · cos θ' / d² (· cos θ'_i), as pbrt-v4's `LightBounds::Importance`.
    pub fn importance(&self, r: &Receiver) -> f32 {
        Bounds4::new(std::slice::from_ref(self)).importance(r).x
    }
}

/// The bounds of up to four sibling clusters in structure-of-arrays form, with what
/// `importance` needs precomputed. Unused lanes have zero power (importance 0).
#[derive(Clone, Copy, Debug)]
struct Bounds4 {
    cx: Vec4,
    cy: Vec4,
    cz: Vec4,
    wx: Vec4,
    wy: Vec4,
    wz: Vec4,
    phi: Vec4,
    /// Half the box diagonal (pbrt's lower bound of d²) and its square (the bounding sphere).
    half_diag: Vec4,
    radius2: Vec4,
    cos_o: Vec4,
    sin_o: Vec4,
    cos_e: Vec4,
    /// 1 for two-sided clusters, 0 otherwise.
    two_sided: Vec4,
}

impl Bounds4 {
    fn new(lanes: &[LightBounds]) -> Bounds4 {
        debug_assert!(lanes.len() <= 4);
        let get = |f: &dyn Fn(&LightBounds) -> f32, zero: f32| {
            Vec4::from_array(std::array::from_fn(|i| lanes.get(i).map_or(zero, f)))
        };
        let half_diag = get(&|b| 0.5 * (b.hi - b.lo).length(), 0.0);
        Bounds4 {
            cx: get(&|b| b.centroid().x, 0.0),
            cy: get(&|b| b.centroid().y, 0.0),
            cz: get(&|b| b.centroid().z, 0.0),
            wx: get(&|b| b.w.x, 0.0),
            wy: get(&|b| b.w.y, 0.0),
            wz: get(&|b| b.w.z, 1.0),
            phi: get(&|b| b.phi, 0.0),
            half_diag,
            radius2: half_diag * half_diag,
            cos_o: get(&|b| b.cos_o, 1.0),
            sin_o: get(&|b| safe_sqrt(1.0 - b.cos_o * b.cos_o), 0.0),
            cos_e: get(&|b| b.cos_e, 1.0),
            two_sided: get(&|b| if b.two_sided { 1.0 } else { 0.0 }, 0.0),
        }
    }

    /// pbrt-v4's `LightBounds::Importance` for the four lanes (0 for unused lanes).
    #[inline]
    fn importance(&self, r: &Receiver) -> Vec4 {
        let zero = Vec4::ZERO;
        let one = Vec4::ONE;
        let ssqrt = |x: Vec4| x.max(zero).sqrt();
        // cos(max(0, a − b)) and sin(max(0, a − b)) from sines and cosines.
        let cos_sub = |sa: Vec4, ca: Vec4, sb: Vec4, cb: Vec4| {
            Vec4::select(ca.cmpgt(cb), one, ca * cb + sa * sb)
        };
        let sin_sub = |sa: Vec4, ca: Vec4, sb: Vec4, cb: Vec4| {
            Vec4::select(ca.cmpgt(cb), zero, sa * cb - ca * sb)
        };
        let dx = Vec4::splat(r.p.x) - self.cx;
        let dy = Vec4::splat(r.p.y) - self.cy;
        let dz = Vec4::splat(r.p.z) - self.cz;
        let dist2 = dx * dx + dy * dy + dz * dz;
        let d2 = dist2.max(self.half_diag);
        let inv_dist = Vec4::select(dist2.cmpgt(zero), dist2.sqrt().recip(), zero);
        let (wix, wiy, wiz) = (dx * inv_dist, dy * inv_dist, dz * inv_dist);
        let cos_w = self.wx * wix + self.wy * wiy + self.wz * wiz;
        let cos_w = Vec4::select(self.two_sided.cmpgt(zero), cos_w.abs(), cos_w);
        let sin_w = ssqrt(one - cos_w * cos_w);
        // The cone of directions from p that the box subtends (its bounding sphere; every
        // direction when p is inside that sphere, which holds for p inside the box).
        let inside = dist2.cmplt(self.radius2);
        let sin_b = (self.half_diag * inv_dist).min(one);
        let cos_b = Vec4::select(inside, Vec4::NEG_ONE, ssqrt(one - sin_b * sin_b));
        let sin_b = Vec4::select(inside, zero, sin_b);
        let cos_x = cos_sub(sin_w, cos_w, self.sin_o, self.cos_o);
        let sin_x = sin_sub(sin_w, cos_w, self.sin_o, self.cos_o);
        let cos_p = cos_sub(sin_x, cos_x, sin_b, cos_b);
        let mut imp = self.phi * cos_p / d2;
        if r.n != Vec3::ZERO {
            let cos_i = (wix * r.n.x + wiy * r.n.y + wiz * r.n.z).abs();
            let sin_i = ssqrt(one - cos_i * cos_i);
            imp *= cos_sub(sin_i, cos_i, sin_b, cos_b);
        }
        // `<` rather than pbrt's `<=`: a hard-edged spot (θe = 0) must keep its inside. The
        // comparisons are false for NaN, so NaN and ∞ (a receiver on a point light) give 0.
        let ok = cos_p.cmpge(self.cos_e) & imp.cmpgt(zero) & imp.cmplt(Vec4::splat(f32::INFINITY));
        Vec4::select(ok, imp, zero)
    }
}

/// A 4-wide node: its children's bounds and references ([`LEAF`] | light index for a leaf,
/// else a node index; unused slots have zero power).
#[derive(Clone, Debug)]
struct Node {
    bounds: Bounds4,
    child: [u32; 4],
}

const LEAF: u32 = 1 << 31;

/// The light BVH with the infinite lights beside it.
#[derive(Clone, Debug)]
pub struct LightBvh {
    nodes: Vec<Node>,
    infinite: Vec<u32>,
    /// For every light of the scene: its path from the root (two bits per level: the child
    /// slot), `None` when it is not in the tree.
    trail: Vec<Option<u128>>,
    is_infinite: Vec<bool>,
}

/// Beyond this depth the build splits at the median (so the depth stays below 64).
const SAH_MAX_DEPTH: u32 = 32;
const BUCKETS: usize = 12;

/// pbrt-v4's cost of a cluster: φ · M_Ω(θo, θe) · surface area · aspect along `dim`.
fn cost(b: &LightBounds, all: &LightBounds, dim: usize) -> f32 {
    let theta_o = safe_acos(b.cos_o);
    let theta_e = safe_acos(b.cos_e);
    let theta_w = (theta_o + theta_e).min(PI);
    let sin_o = safe_sqrt(1.0 - b.cos_o * b.cos_o);
    let m_omega = 2.0 * PI * (1.0 - b.cos_o)
        + PI / 2.0
            * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o
                + b.cos_o);
    let diag = all.hi - all.lo;
    let kr = diag.max_element() / diag[dim];
    let e = b.hi - b.lo;
    let area = 2.0 * (e.x * e.y + e.y * e.z + e.z * e.x);
    b.phi * m_omega * kr * area
}

/// The binary tree of the build, before it is collapsed.
enum Tree {
    Leaf(u32, LightBounds),
    Inner(Box<[Tree; 2]>, LightBounds),
}

impl Tree {
    fn bounds(&self) -> &LightBounds {
        match self {
            Tree::Leaf(_, b) | Tree::Inner(_, b) => b,
        }
    }
}

impl LightBvh {
    /// `bounds[i]`: the bounds of light `i` (`None` for a light the tree leaves out: zero
    /// power or infinite); `infinite`: the infinite lights.
    pub fn new(bounds: &[Option<LightBounds>], infinite: &[u32]) -> LightBvh {
        let mut items: Vec<(u32, LightBounds)> = bounds
            .iter()
            .enumerate()
            .filter_map(|(i, b)| b.filter(|b| b.phi > 0.0).map(|b| (i as u32, b)))
            .collect();
        let mut bvh = LightBvh {
            nodes: Vec::with_capacity(items.len() / 2 + 1),
            infinite: infinite.to_vec(),
            trail: vec![None; bounds.len()],
            is_infinite: vec![false; bounds.len()],
        };
        for &i in infinite {
            if let Some(f) = bvh.is_infinite.get_mut(i as usize) {
                *f = true;
            }
        }
        if !items.is_empty() {
            let tree = build_binary(&mut items, 0);
            match tree {
                Tree::Inner(..) => {
                    bvh.collapse(tree, 0, 0);
                }
                // A single light: a root with one used slot.
                leaf => {
                    bvh.collapse(Tree::Inner(Box::new([leaf, EMPTY_TREE]), EMPTY), 0, 0);
                }
            }
        }
        bvh
    }

    /// Emits the 4-wide node for binary node `tree` (its two children, each interior child
    /// of largest power opened while there is room) and, recursively, its subtrees.
    fn collapse(&mut self, tree: Tree, trail: u128, depth: u32) -> u32 {
        let Tree::Inner(children, _) = tree else {
            unreachable!("collapse starts at an inner node")
        };
        let mut kids: Vec<Tree> = Vec::from(*children);
        kids.retain(|t| t.bounds().phi > 0.0);
        while kids.len() < 4 {
            let open = kids
                .iter()
                .enumerate()
                .filter(|(_, t)| matches!(t, Tree::Inner(..)))
                .max_by(|a, b| a.1.bounds().phi.total_cmp(&b.1.bounds().phi))
                .map(|(i, _)| i);
            let Some(i) = open else { break };
            let Tree::Inner(grand, _) = kids.swap_remove(i) else {
                unreachable!()
            };
            kids.extend(*grand);
        }
        let at = self.nodes.len();
        let lanes: Vec<LightBounds> = kids.iter().map(|t| *t.bounds()).collect();
        self.nodes.push(Node {
            bounds: Bounds4::new(&lanes),
            child: [LEAF; 4],
        });
        for (slot, kid) in kids.into_iter().enumerate() {
            let t = trail | (slot as u128) << (2 * depth);
            let c = match kid {
                Tree::Leaf(light, _) => {
                    self.trail[light as usize] = Some(t);
                    LEAF | light
                }
                inner => self.collapse(inner, t, depth + 1),
            };
            self.nodes[at].child[slot] = c;
        }
        at as u32
    }

    /// Probability of picking the tree rather than an infinite light.
    #[inline]
    fn p_infinite(&self) -> f32 {
        let n = self.infinite.len() as f32;
        if self.nodes.is_empty() {
            if n > 0.0 { 1.0 } else { 0.0 }
        } else {
            n / (n + 1.0)
        }
    }

    /// Chooses a light for `r`: its index and probability; `None` when no light can
    /// contribute.
    pub fn sample(&self, u: f32, r: &Receiver) -> Option<(u32, f32)> {
        let p_inf = self.p_infinite();
        if u < p_inf {
            let n = self.infinite.len();
            let i = ((u / p_inf * n as f32) as usize).min(n - 1);
            return Some((self.infinite[i], p_inf / n as f32));
        }
        if self.nodes.is_empty() {
            return None;
        }
        let mut u = ((u - p_inf) / (1.0 - p_inf)).clamp(0.0, ONE_MINUS_EPSILON);
        let mut pmf = 1.0 - p_inf;
        let mut at = 0usize;
        loop {
            let node = &self.nodes[at];
            let imp = node.bounds.importance(r).to_array();
            let sum = imp[0] + imp[1] + imp[2] + imp[3];
            if sum == 0.0 {
                return None;
            }
            // The slot whose share of `sum` holds u·sum (the last non-zero one if rounding
            // leaves u beyond them all).
            let target = u * sum;
            let (mut slot, mut below) = (4, 0.0);
            let mut acc = 0.0;
            for (i, &c) in imp.iter().enumerate() {
                if c > 0.0 {
                    slot = i;
                    below = acc;
                    acc += c;
                    if target < acc {
                        break;
                    }
                }
            }
            let c = imp[slot];
            pmf *= c / sum;
            u = ((target - below) / c).clamp(0.0, ONE_MINUS_EPSILON);
            let child = node.child[slot];
            if child & LEAF != 0 {
                return Some((child & !LEAF, pmf));
            }
            at = child as usize;
        }
    }

    /// Probability that [`Self::sample`] picks `light` for `r`.
    pub fn pmf(&self, r: &Receiver, light: u32) -> f32 {
        let p_inf = self.p_infinite();
        if self
            .is_infinite
            .get(light as usize)
            .copied()
            .unwrap_or(false)
        {
            return p_inf / self.infinite.len() as f32;
        }
        let Some(Some(mut trail)) = self.trail.get(light as usize).copied() else {
            return 0.0;
        };
        let mut pmf = 1.0 - p_inf;
        let mut at = 0usize;
        loop {
            let node = &self.nodes[at];
            let imp = node.bounds.importance(r).to_array();
            let sum = imp[0] + imp[1] + imp[2] + imp[3];
            let slot = (trail & 3) as usize;
            let c = imp[slot];
            if c == 0.0 {
                return 0.0;
            }
            pmf *= c / sum;
            trail >>= 2;
            let child = node.child[slot];
            if child & LEAF != 0 {
                return pmf;
            }
            at = child as usize;
        }
    }

    /// Number of 4-wide tree nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Depth of the deepest leaf in 4-wide levels (1 when the root holds every light).
    pub fn depth(&self) -> u32 {
        fn depth(nodes: &[Node], at: usize) -> u32 {
            1 + nodes[at]
                .child
                .iter()
                .filter(|&&c| c & LEAF == 0)
                .map(|&c| depth(nodes, c as usize))
                .max()
                .unwrap_or(0)
        }
        if self.nodes.is_empty() {
            0
        } else {
            depth(&self.nodes, 0)
        }
    }
}

/// An absent child (zero power).
const EMPTY_TREE: Tree = Tree::Leaf(u32::MAX, EMPTY);
const EMPTY: LightBounds = LightBounds {
    lo: Vec3::ZERO,
    hi: Vec3::ZERO,
    w: Vec3::Z,
    phi: 0.0,
    cos_o: 1.0,
    cos_e: 1.0,
    two_sided: false,
};

/// The binary tree over `items` (SAH buckets, median splits beyond [`SAH_MAX_DEPTH`]).
fn build_binary(items: &mut [(u32, LightBounds)], depth: u32) -> Tree {
    if let [(light, b)] = items {
        return Tree::Leaf(*light, *b);
    }
    let mid = if depth < SAH_MAX_DEPTH {
        sah_split(items)
    } else {
        None
    }
    .unwrap_or_else(|| {
        // Median by centroid along the widest axis.
        let (clo, chi) = centroid_bounds(items);
        let dim = (chi - clo).max_position();
        let mid = items.len() / 2;
        items.select_nth_unstable_by(mid, |a, b| {
            a.1.centroid()[dim].total_cmp(&b.1.centroid()[dim])
        });
        mid
    });
    let (left, right) = items.split_at_mut(mid);
    let l = build_binary(left, depth + 1);
    let r = build_binary(right, depth + 1);
    let b = l.bounds().union(r.bounds());
    Tree::Inner(Box::new([l, r]), b)
}

fn centroid_bounds(items: &[(u32, LightBounds)]) -> (Vec3, Vec3) {
    items.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), (_, b)| (lo.min(b.centroid()), hi.max(b.centroid())),
    )
}

/// The cheapest bucket split (partitioning `items`): the index of the first item of the
/// second half, or `None` when the centroids coincide.
fn sah_split(items: &mut [(u32, LightBounds)]) -> Option<usize> {
    let all = items[1..]
        .iter()
        .fold(items[0].1, |acc, (_, b)| acc.union(b));
    let (clo, chi) = centroid_bounds(items);
    let bucket_of = |c: f32, dim: usize| {
        let t = (c - clo[dim]) / (chi[dim] - clo[dim]);
        ((t * BUCKETS as f32) as usize).min(BUCKETS - 1)
    };
    let mut best: Option<(f32, usize, usize)> = None;
    for dim in 0..3 {
        if chi[dim] <= clo[dim] || chi[dim].is_nan() || clo[dim].is_nan() {
            continue;
        }
        let mut buckets: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
        for (_, b) in items.iter() {
            let k = bucket_of(b.centroid()[dim], dim);
            buckets[k] = Some(match buckets[k] {
                Some(acc) => acc.union(b),
                None => *b,
            });
        }
        // Bounds of buckets 0..=k (`below[k]`) and k+1.. (`above[k]`), by one sweep each way.
        let join = |acc: Option<LightBounds>, b: &Option<LightBounds>| match (acc, b) {
            (Some(a), Some(b)) => Some(a.union(b)),
            (a, b) => a.or(*b),
        };
        let mut acc = None;
        let below = buckets.map(|b| {
            acc = join(acc, &b);
            acc
        });
        let mut above = [None; BUCKETS];
        let mut acc = None;
        for (a, b) in above.iter_mut().zip(&buckets[1..]).rev() {
            acc = join(acc, b);
            *a = acc;
        }
        for split in 0..BUCKETS - 1 {
            let (Some(b0), Some(b1)) = (below[split], above[split]) else {
                continue;
            };
            let c = cost(&b0, &all, dim) + cost(&b1, &all, dim);
            if c.is_finite() && best.is_none_or(|(bc, _, _)| c < bc) {
                best = Some((c, dim, split));
            }
        }
    }
    let (_, dim, split) = best?;
    let mut mid = 0;
    for i in 0..items.len() {
        if bucket_of(items[i].1.centroid()[dim], dim) <= split {
            items.swap(i, mid);
            mid += 1;
        }
    }
    (mid > 0 && mid < items.len()).then_some(mid)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(p: Vec3, phi: f32) -> LightBounds {
        LightBounds {
            lo: p,
            hi: p,
            w: Vec3::Z,
            phi,
            cos_o: -1.0,
            cos_e: 0.0,
            two_sided: false,
        }
    }

    #[test]
    fn cone_union_contains_both() {
        let (w, c) = cone_union(Vec3::X, 1.0, Vec3::Y, 1.0);
        assert!((c - std::f32::consts::FRAC_PI_4.cos()).abs() < 1e-5);
        assert!((w - Vec3::new(1.0, 1.0, 0.0).normalize()).length() < 1e-5);
        let (_, c) = cone_union(Vec3::X, 1.0, -Vec3::X, 1.0);
        assert_eq!(c, -1.0);
        let (w, c) = cone_union(Vec3::Z, 0.0, Vec3::Z, 1.0);
        assert_eq!((w, c), (Vec3::Z, 0.0));
    }

    #[test]
    fn pmf_sums_to_one_and_matches_sampling() {
        // A deterministic pseudo-random cloud of oriented lights.
        let mut s = 1u64;
        let mut rnd = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((s >> 40) as f32) / (1u64 << 24) as f32
        };
        let mut bounds = Vec::new();
        for i in 0..200 {
            let p = Vec3::new(rnd(), rnd(), rnd()) * 10.0;
            let w = Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize();
            let mut b = point(p, 0.1 + rnd() * 5.0);
            b.hi += Vec3::splat(0.1);
            b.w = w;
            b.cos_o = 1.0;
            b.two_sided = i % 7 == 0;
            bounds.push(Some(b));
        }
        bounds.push(None); // an infinite light
        let one_sided = LightBvh::new(&bounds, &[200]);
        assert!(one_sided.trail[..200].iter().all(Option::is_some));
        assert!(one_sided.node_count() < 200 / 2 && one_sided.depth() >= 4);
        // Two-sided lights of positive extent never get zero importance: the pmf sums to 1.
        for b in bounds.iter_mut().flatten() {
            b.two_sided = true;
        }
        let two_sided = LightBvh::new(&bounds, &[200]);
        for k in 0..40 {
            let bvh = if k % 4 < 2 { &one_sided } else { &two_sided };
            let r = Receiver {
                p: Vec3::new(rnd(), rnd(), rnd()) * 12.0 - 1.0,
                n: if k % 2 == 0 {
                    Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5).normalize()
                } else {
                    Vec3::ZERO
                },
            };
            let sum: f64 = (0..201).map(|i| bvh.pmf(&r, i) as f64).sum();
            if k % 4 < 2 {
                assert!(sum < 1.0 + 1e-4, "Σ pmf = {sum}");
            } else {
                assert!((sum - 1.0).abs() < 1e-4, "Σ pmf = {sum}");
            }
            for j in 0..500 {
                let u = (j as f32 + 0.5) / 500.0;
                if let Some((i, p)) = bvh.sample(u, &r) {
                    assert_eq!(p, bvh.pmf(&r, i), "light {i}");
                    assert!(p > 0.0);
                }
            }
        }
    }
}
