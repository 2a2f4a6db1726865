//! Triangle meshes: the interaction at a hit (interpolated normals and uvs, or the flat
//! fast path), area, and uniform sampling by area.

use std::sync::Arc;

use super::{Reads, SurfaceInteraction, finish_interaction, gamma};
use crate::accel::Hit;
use crate::math::{Frame, Vec2, Vec3, normalize_or_zero_fast, rsqrt};
use crate::sampling::distrib::Distribution1D;

/// Surface area of the triangles `indices` of `positions`, each vertex mapped by `map`.
pub fn area(positions: &[Vec3], indices: &[[u32; 3]], map: impl Fn(Vec3) -> Vec3) -> f32 {
    indices
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| map(positions[i as usize]));
            0.5 * (b - a).cross(c - a).length()
        })
        .sum()
}

/// The interaction on the world-space triangle `p` (vertices `idx` of the mesh, for the
/// normals, mapped by `normal_to_world`, and uvs).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
pub(super) fn interaction(
    [p0, p1, p2]: [Vec3; 3],
    [i0, i1, i2]: [usize; 3],
    normals: Option<&[Vec3]>,
    normal_to_world: impl Fn(Vec3) -> Vec3,
    uvs: Option<&[Vec2]>,
    hit: &Hit,
    wo: Vec3,
    time: f32,
    flip: bool,
    reads: Reads,
) -> SurfaceInteraction {
    let (b1, b2) = (hit.u, hit.v);
    let b0 = 1.0 - b1 - b2;
    let p = b0 * p0 + b1 * p1 + b2 * p2;
    let p_error = gamma(7) * ((b0 * p0).abs() + (b1 * p1).abs() + (b2 * p2).abs());
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let ng = normalize_or_zero_fast(e1.cross(e2));
    let uv = match uvs {
        Some(t) if reads.uv => b0 * t[i0] + b1 * t[i1] + b2 * t[i2],
        _ => Vec2::new(b1, b2),
    };
    if normals.is_none() && (uvs.is_none() || !reads.tangent) {
        // Flat mesh without uvs (the common case for OBJ/PLY without `vt`/`vn`), or
        // one whose tangent does not matter: the shading frame is the geometric one,
        // with `s` along the first edge, which is already orthogonal to `ng`, so no
        // Gram–Schmidt step is needed.
        return flat(p, p_error, ng, e1, uv, wo, hit, time, flip);
    }
    let dpdu = match uvs {
        Some(t) if reads.tangent => {
            let (t0, t1, t2) = (t[i0], t[i1], t[i2]);
            let du1 = t1 - t0;
            let du2 = t2 - t0;
            let det = du1.x * du2.y - du1.y * du2.x;
            if det.abs() > 1e-12 {
                (e1 * du2.y - e2 * du1.y) / det
            } else {
                e1
            }
        }
        _ => e1,
    };
    let ns = match normals {
        Some(n) => {
            // `normalize_or`: comparing with zero component by component is a branch on
            // the normal's direction, which the predictor cannot learn.
            (b0 * normal_to_world(n[i0])
                + b1 * normal_to_world(n[i1])
                + b2 * normal_to_world(n[i2]))
            .normalize_or(ng)
        }
        None => ng,
    };
    finish_interaction(p, p_error, ng, ns, dpdu, uv, wo, hit, time, flip)
}

/// [`interaction`] for a triangle without shading normals or uvs: shading frame = geometric
/// frame, tangent along the edge `e1` (orthogonal to `ng` by construction).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn flat(
    p: Vec3,
    p_error: Vec3,
    ng: Vec3,
    e1: Vec3,
    uv: Vec2,
    wo: Vec3,
    hit: &Hit,
    time: f32,
    flip: bool,
) -> SurfaceInteraction {
    let n = if flip { -ng } else { ng };
    let len2 = e1.length_squared();
    // Accel drops zero-area triangles, so `e1` is non-zero; keep the generic fallback anyway.
    // `n` is unit or zero: its squared length is the one test (`!= Vec3::ZERO` compares
    // component by component, a branch on which way the surface faces).
    let shading = if len2 > 1e-12 && len2.is_finite() && n.length_squared() > 0.0 {
        let s = e1 * rsqrt(len2);
        Frame {
            s,
            t: n.cross(s),
            n,
        }
    } else {
        Frame::from_normal_tangent(n, e1)
    };
    SurfaceInteraction {
        p,
        p_error,
        ng: n,
        shading,
        uv,
        wo,
        t: hit.t,
        shape: hit.shape,
        prim: hit.prim,
        time,
    }
}

/// How an emitting mesh lit as a whole places a uniform point on its surface.
#[derive(Clone, Debug)]
pub enum MeshSampling {
    /// A triangle in proportion to its area, then a uniform point in it.
    ByArea(Arc<Distribution1D>),
    /// Two triangles forming a parallelogram (a meshed rectangle: the usual quad light).
    Parallelogram(Parallelogram),
}

impl MeshSampling {
    /// The sampling for a mesh with these triangles (whose areas are `areas`).
    pub fn new(positions: &[Vec3], indices: &[[u32; 3]], areas: &[f32]) -> MeshSampling {
        match Parallelogram::detect(positions, indices) {
            Some(q) => MeshSampling::Parallelogram(q),
            None => MeshSampling::ByArea(Arc::new(Distribution1D::new(areas))),
        }
    }
}

/// A mesh of two triangles that together form a parallelogram `a + s·e₁ + t·e₂`,
/// `(s, t) ∈ [0, 1]²`, split along the diagonal from `a + e₁` to `a + e₂`. One 2D sample gives
/// a uniform point with no discrete choice (an `f64` CDF search) and no triangle warp: the
/// same density as choosing a triangle by area, since the halves have equal areas.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Parallelogram {
    /// Per triangle (0 holds `a`, 1 the opposite corner), the barycentrics `b₁`, `b₂` of the
    /// point as affine functions of the sample: coefficients of `(1, s, t)`.
    coef: [[Vec3; 2]; 2],
    /// The unit normal of both triangles (by their winding), which they share.
    pub normal: Vec3,
}

impl Parallelogram {
    /// Relative tolerance on `a + (a + e₁ + e₂) = (a + e₁) + (a + e₂)`: corners placed by a
    /// float transform are off by a few ulp; the density error is of the same relative size.
    const TOLERANCE: f32 = 1e-5;

    /// The parallelogram formed by a two-triangle mesh, if it is one.
    pub fn detect(positions: &[Vec3], indices: &[[u32; 3]]) -> Option<Parallelogram> {
        let [t0, t1] = indices else { return None };
        let get = |i: u32| positions.get(i as usize).copied();
        let p0 = [get(t0[0])?, get(t0[1])?, get(t0[2])?];
        let p1 = [get(t1[0])?, get(t1[1])?, get(t1[2])?];
        // The diagonal: the two corners the triangles share (by position).
        let mut shared = Vec::with_capacity(3);
        for (i, a) in p0.iter().enumerate() {
            if let Some(j) = p1.iter().position(|b| b == a) {
                shared.push((i, j));
            }
        }
        let [(i0, i1), (j0, j1)] = shared[..] else {
            return None;
        };
        let k0 = 3 - i0 - j0;
        let l1 = 3 - i1 - j1;
        let (a, e1, e2) = (p0[k0], p0[i0] - p0[k0], p0[j0] - p0[k0]);
        let scale = e1.abs().max(e2.abs()).max_element();
        let face = |p: [Vec3; 3]| (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        let normal = face(p0);
        // Both windings alike (a mesh may flip one triangle: each then emits to its own side).
        let ok = (a + e1 + e2 - p1[l1]).abs().max_element() <= Self::TOLERANCE * scale
            && normal != Vec3::ZERO
            && normal.dot(face(p1)) > 0.0
            && scale.is_finite();
        if !ok {
            return None;
        }
        // Weights of the corners as coefficients of (1, s, t): in triangle 0, a, a + e₁, a + e₂
        // take 1 − s − t, s, t; in triangle 1, a + e₁, a + e₂, a + e₁ + e₂ take 1 − t, 1 − s,
        // s + t − 1. b₁, b₂ are the weights of the corners in vertex slots 1 and 2.
        let weights = [
            [Vec3::new(1.0, -1.0, -1.0), Vec3::Y, Vec3::Z],
            [
                Vec3::new(1.0, 0.0, -1.0),
                Vec3::new(1.0, -1.0, 0.0),
                Vec3::new(-1.0, 1.0, 1.0),
            ],
        ];
        let slots = [[k0, i0, j0], [i1, j1, l1]];
        let mut coef = [[Vec3::ZERO; 2]; 2];
        for (tri, (slots, weights)) in slots.iter().zip(weights).enumerate() {
            for (&slot, w) in slots.iter().zip(weights) {
                if slot > 0 {
                    coef[tri][slot - 1] = w;
                }
            }
        }
        Some(Parallelogram { coef, normal })
    }

    /// A uniform point: its triangle and its barycentrics `(b₁, b₂)` in that triangle's vertex
    /// order (`p = (1 − b₁ − b₂) p₀ + b₁ p₁ + b₂ p₂`).
    /// Always inlined: out of line, its result went through memory and the caller stalled
    /// reading it back.
    #[inline(always)]
    pub fn sample(&self, u: Vec2) -> (usize, Vec2) {
        let tri = (u.x + u.y > 1.0) as usize;
        let [c1, c2] = self.coef[tri];
        let x = Vec3::new(1.0, u.x, u.y);
        (tri, Vec2::new(c1.dot(x), c2.dot(x)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Mat3;

    /// The point a `Parallelogram` sample designates, from the mesh.
    fn point(pos: &[Vec3], idx: &[[u32; 3]], q: &Parallelogram, u: Vec2) -> Vec3 {
        let (tri, b) = q.sample(u);
        let [p0, p1, p2] = idx[tri].map(|i| pos[i as usize]);
        (1.0 - b.x - b.y) * p0 + b.x * p1 + b.y * p2
    }

    #[test]
    fn parallelogram_samples_are_the_bilinear_map_whatever_the_vertex_order() {
        let (a, e1, e2) = (
            Vec3::new(0.5, -1.0, 2.0),
            Vec3::new(2.0, 0.25, 0.0),
            Vec3::new(0.5, 0.0, 1.5),
        );
        let corners = [a, a + e1, a + e1 + e2, a + e2];
        // Split along either diagonal, with rotated and reversed (but matching) windings and unshared
        // vertices (the triangles share positions, not indices).
        let splits: [[[usize; 3]; 2]; 4] = [
            [[0, 1, 3], [1, 2, 3]],
            [[2, 3, 1], [3, 0, 1]],
            [[0, 2, 1], [0, 3, 2]],
            [[3, 0, 2], [2, 0, 1]],
        ];
        for split in splits {
            let pos: Vec<Vec3> = split.iter().flatten().map(|&c| corners[c]).collect();
            let idx = [[0, 1, 2], [3, 4, 5]];
            let q = Parallelogram::detect(&pos, &idx).expect("a parallelogram");
            for (s, t) in [(0.1, 0.2), (0.9, 0.8), (0.5, 0.5), (0.0, 0.99), (0.7, 0.31)] {
                let p = point(&pos, &idx, &q, Vec2::new(s, t));
                // Uniform in (s, t) over some parametrisation of the parallelogram: check the
                // point lies inside and that the map is affine within each half.
                let d = p - a;
                let m = Mat3::from_cols(e1.into(), e2.into(), e1.cross(e2).into());
                let st = m.inverse() * d;
                assert!(st.z.abs() < 1e-5, "{split:?} off the plane");
                assert!(
                    (-1e-5..=1.0 + 1e-5).contains(&st.x) && (-1e-5..=1.0 + 1e-5).contains(&st.y)
                );
            }
            // Area preserving: the Jacobian of u ↦ p is the same in both halves.
            let jac = |u: Vec2| {
                let h = 1e-3;
                let p = point(&pos, &idx, &q, u);
                let ds = point(&pos, &idx, &q, u + Vec2::new(h, 0.0)) - p;
                let dt = point(&pos, &idx, &q, u + Vec2::new(0.0, h)) - p;
                ds.cross(dt).length() / (h * h)
            };
            let area = e1.cross(e2).length();
            for u in [Vec2::new(0.2, 0.3), Vec2::new(0.7, 0.6)] {
                assert!((jac(u) / area - 1.0).abs() < 1e-2, "{split:?} {u:?}");
            }
        }
    }

    #[test]
    fn other_two_triangle_meshes_are_not_parallelograms() {
        let sq = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let quad = |p: [Vec3; 4]| Parallelogram::detect(&p, &[[0, 1, 3], [1, 2, 3]]);
        assert!(quad(sq).is_some());
        // A trapezoid, a folded quad, triangles sharing only a vertex, a degenerate one, and
        // a square whose second triangle is wound the other way.
        assert!(Parallelogram::detect(&sq, &[[0, 1, 3], [1, 3, 2]]).is_none());
        assert!(quad([sq[0], sq[1], Vec3::new(0.7, 1.0, 0.0), sq[3]]).is_none());
        assert!(quad([sq[0], sq[1], Vec3::new(1.0, 1.0, 0.5), sq[3]]).is_none());
        assert!(Parallelogram::detect(&sq, &[[0, 1, 2], [2, 3, 2]]).is_none());
        assert!(Parallelogram::detect(&sq, &[[0, 1, 2], [0, 2, 3], [0, 1, 3]]).is_none());
        assert!(Parallelogram::detect(&[Vec3::ZERO; 4], &[[0, 1, 3], [1, 2, 3]]).is_none());
        // Out-of-range indices are not a panic.
        assert!(Parallelogram::detect(&sq, &[[0, 1, 7], [1, 2, 3]]).is_none());
    }
}
