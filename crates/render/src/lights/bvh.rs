//! A light BVH for many-light selection (Conty Estevez & Kulla 2018, "Importance Sampling of
//! Many Lights with Adaptive Tree Splitting", in the form of pbrt-v4's `BVHLightSampler`).
//!
//! Every bounded light with non-zero power gets [`LightBounds`]: an axis-aligned box, the
//! normal cone (axis `w`, spread `θo`) its surface normals lie in, the angle `θe` beyond the
//! normals in which it still emits (π/2 for area lights), its power and two-sidedness. The
//! tree is built top-down, splitting at the cheapest of 12 buckets per axis under pbrt's
//! cost model (power × solid-angle measure of the cone × box surface area × aspect). A
//! receiver walks down from the root, choosing each child with probability proportional to
//! its [`LightBounds::importance`] (a conservative bound of power × cosines / distance²).
//! Infinite lights are not in the tree: one of them is chosen (uniformly) with probability
//! `n_inf / (n_inf + 1)` and the tree otherwise.
//!
//! [`LightBvh::pmf`] replays the descent along the path to the light's leaf (its "bit
//! trail"), with the very same float expressions as [`LightBvh::sample`], so the two agree
//! exactly.

use crate::math::{PI, Vec3, safe_sqrt};
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

/// cos(max(0, a − b)) from the sines and cosines of a and b.
#[inline]
fn cos_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        1.0
    } else {
        cos_a * cos_b + sin_a * sin_b
    }
}

/// sin(max(0, a − b)).
#[inline]
fn sin_sub_clamped(sin_a: f32, cos_a: f32, sin_b: f32, cos_b: f32) -> f32 {
    if cos_a > cos_b {
        0.0
    } else {
        sin_a * cos_b - cos_a * sin_b
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
        NodeBounds::new(self).importance(r)
    }
}

/// [`LightBounds`] with what `importance` needs precomputed.
#[derive(Clone, Copy, Debug)]
struct NodeBounds {
    centre: Vec3,
    w: Vec3,
    phi: f32,
    /// Half the box diagonal (pbrt's lower bound of d²) and its square (the bounding sphere).
    half_diag: f32,
    radius2: f32,
    cos_o: f32,
    sin_o: f32,
    cos_e: f32,
    two_sided: bool,
}

impl NodeBounds {
    fn new(b: &LightBounds) -> NodeBounds {
        let half_diag = 0.5 * (b.hi - b.lo).length();
        NodeBounds {
            centre: b.centroid(),
            w: b.w,
            phi: b.phi,
            half_diag,
            radius2: half_diag * half_diag,
            cos_o: b.cos_o,
            sin_o: safe_sqrt(1.0 - b.cos_o * b.cos_o),
            cos_e: b.cos_e,
            two_sided: b.two_sided,
        }
    }

    #[inline]
    fn importance(&self, r: &Receiver) -> f32 {
        let d = r.p - self.centre;
        let dist2 = d.length_squared();
        let d2 = dist2.max(self.half_diag);
        let inv_dist = if dist2 > 0.0 {
            dist2.sqrt().recip()
        } else {
            0.0
        };
        let wi = d * inv_dist;
        let mut cos_w = self.w.dot(wi);
        if self.two_sided {
            cos_w = cos_w.abs();
        }
        let sin_w = safe_sqrt(1.0 - cos_w * cos_w);
        // The cone of directions from p that the box subtends (its bounding sphere; every
        // direction when p is inside that sphere, which holds for p inside the box).
        let (cos_b, sin_b) = if dist2 < self.radius2 {
            (-1.0, 0.0)
        } else {
            let sin_b = (self.half_diag * inv_dist).min(1.0);
            (safe_sqrt(1.0 - sin_b * sin_b), sin_b)
        };
        let cos_x = cos_sub_clamped(sin_w, cos_w, self.sin_o, self.cos_o);
        let sin_x = sin_sub_clamped(sin_w, cos_w, self.sin_o, self.cos_o);
        let cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
        // `<` rather than pbrt's `<=`: a hard-edged spot (θe = 0) must keep its inside.
        if cos_p < self.cos_e {
            return 0.0;
        }
        let mut importance = self.phi * cos_p / d2;
        if r.n != Vec3::ZERO {
            let cos_i = wi.dot(r.n).abs();
            let sin_i = safe_sqrt(1.0 - cos_i * cos_i);
            importance *= cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
        }
        if importance.is_finite() {
            importance.max(0.0)
        } else {
            0.0
        }
    }
}

#[derive(Clone, Copy, Debug)]
enum NodeKind {
    Leaf {
        light: u32,
    },
    /// The first child is the next node; the second is at this index.
    Interior {
        second: u32,
    },
}

#[derive(Clone, Debug)]
struct Node {
    bounds: NodeBounds,
    kind: NodeKind,
}

/// The light BVH with the infinite lights beside it.
#[derive(Clone, Debug)]
pub struct LightBvh {
    nodes: Vec<Node>,
    infinite: Vec<u32>,
    /// For every light of the scene: its path from the root (bit i: second child at depth
    /// i), `None` when it is not in the tree.
    trail: Vec<Option<u64>>,
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
            nodes: Vec::with_capacity(2 * items.len()),
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
            bvh.build(&mut items, 0, 0);
        }
        bvh
    }

    fn build(&mut self, items: &mut [(u32, LightBounds)], trail: u64, depth: u32) -> LightBounds {
        if let [(light, b)] = items {
            self.trail[*light as usize] = Some(trail);
            self.nodes.push(Node {
                bounds: NodeBounds::new(b),
                kind: NodeKind::Leaf { light: *light },
            });
            return *b;
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
        let at = self.nodes.len();
        self.nodes.push(Node {
            bounds: NodeBounds::new(&items[0].1),
            kind: NodeKind::Interior { second: 0 },
        });
        let (left, right) = items.split_at_mut(mid);
        let b0 = self.build(left, trail, depth + 1);
        let second = self.nodes.len() as u32;
        let b1 = self.build(right, trail | (1u64 << depth), depth + 1);
        let b = b0.union(&b1);
        self.nodes[at] = Node {
            bounds: NodeBounds::new(&b),
            kind: NodeKind::Interior { second },
        };
        b
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
            match self.nodes[at].kind {
                NodeKind::Interior { second } => {
                    let c0 = self.nodes[at + 1].bounds.importance(r);
                    let c1 = self.nodes[second as usize].bounds.importance(r);
                    if c0 == 0.0 && c1 == 0.0 {
                        return None;
                    }
                    let sum = c0 + c1;
                    let p0 = c0 / sum;
                    if u < p0 {
                        pmf *= c0 / sum;
                        u = (u / p0).min(ONE_MINUS_EPSILON);
                        at += 1;
                    } else {
                        pmf *= c1 / sum;
                        u = ((u - p0) / (1.0 - p0)).clamp(0.0, ONE_MINUS_EPSILON);
                        at = second as usize;
                    }
                }
                NodeKind::Leaf { light } => {
                    return (at > 0 || self.nodes[0].bounds.importance(r) > 0.0)
                        .then_some((light, pmf));
                }
            }
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
            match self.nodes[at].kind {
                NodeKind::Interior { second } => {
                    let c0 = self.nodes[at + 1].bounds.importance(r);
                    let c1 = self.nodes[second as usize].bounds.importance(r);
                    if c0 == 0.0 && c1 == 0.0 {
                        return 0.0;
                    }
                    let sum = c0 + c1;
                    if trail & 1 == 0 {
                        pmf *= c0 / sum;
                        at += 1;
                    } else {
                        pmf *= c1 / sum;
                        at = second as usize;
                    }
                    trail >>= 1;
                }
                NodeKind::Leaf { .. } => {
                    return if at > 0 || self.nodes[0].bounds.importance(r) > 0.0 {
                        pmf
                    } else {
                        0.0
                    };
                }
            }
        }
    }

    /// Number of tree nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// Depth of the deepest leaf (0 for a single light or none).
    pub fn depth(&self) -> u32 {
        self.trail
            .iter()
            .flatten()
            .map(|t| 64 - t.leading_zeros())
            .max()
            .unwrap_or(0)
    }
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
        assert_eq!(one_sided.node_count(), 2 * 200 - 1);
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
