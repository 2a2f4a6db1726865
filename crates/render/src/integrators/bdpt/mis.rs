//! BDPT's MIS weights: the power heuristic over every strategy that could have made the
//! same path, from the forward and reverse area densities of its vertices (pbrt-v4's
//! `MISWeight`), with the joint's four densities overridden.
//!
//! With the free flights' densities in the weights (homogeneous media), a path's density
//! differs between the colour lanes where it crosses a chromatic medium, and by strategy:
//! a segment sampled by a free flight has density σt,c·e^{−σt,c·d} in lane c, one made by a
//! connection none. A camera sample draws one hero lane h and every strategy, so the weights
//! must sum to one over the (strategy, lane) pairs: strategy s's estimate f/p_{s,h} gets
//! N·p_{s,h}² / Σ_{t,c} p_{t,c}² (N live lanes). Weighing the strategies in the hero lane
//! and the lanes by the strategy's own densities (volpath's spectral MIS) instead sums to
//! one only where every strategy's lane densities are in the same proportion: not through
//! a chromatic medium behind a rough boundary, where BDPT was several per cent off.

use super::Bdpt;
use super::connect::Joins;
use super::vertex::{Joint, Kind, remap0};
use crate::spectral::lanes::{Color, PathMode};

impl<M: PathMode> Bdpt<'_, M> {
    /// Strategy (s, t)'s MIS weights, joined at `joint` (whose ends replace the vertices the
    /// strategy sampled afresh: the light point for s = 1, the lens point for t = 1), for its
    /// estimate in the hero lane whose lane densities relative to the hero's are `ratio`:
    /// the factor that estimate is multiplied by (see the module docs; without the flights'
    /// densities, the hero-lane weight times `m.hero_weight(ratio)`), and the hero-lane
    /// power-heuristic weight the strategy sinks are told.
    pub(super) fn mis(
        &self,
        j: &Joins<M>,
        joint: &Joint<M::C>,
        (s, t): (usize, usize),
        ratio: M::C,
        m: &M,
    ) -> (f32, f32) {
        let (w, lanes) = self.mis_sums(j, joint, (s, t));
        let factor = match lanes {
            Some(sums) => {
                let hero = if m.terminated() { Some(j.hero) } else { None };
                let (mut n, mut total) = (0.0f32, 0.0f32);
                for c in 0..M::C::LANES {
                    if hero.is_none_or(|h| h == c) {
                        let rho = ratio.lane(c);
                        n += 1.0;
                        total += rho * rho * sums.lane(c);
                    }
                }
                n / total
            }
            None => m.hero_weight(ratio) * w,
        };
        (if factor.is_finite() { factor } else { 0.0 }, w)
    }

    /// The hero-lane power-heuristic weight of strategy (s, t) and, with the free flights'
    /// densities in the weights, per lane c the sum over the strategies t' (s's included)
    /// of (p_{t',c} / p_{s,c})².
    fn mis_sums(
        &self,
        j: &Joins<M>,
        joint: &Joint<M::C>,
        (s, t): (usize, usize),
    ) -> (f32, Option<M::C>) {
        let (scene, cam, light) = (j.scene, j.cam, j.light);
        let lanes = self.flight_densities && !scene.media.is_empty();
        if s + t == 2 {
            return (1.0, lanes.then_some(M::C::ONE));
        }
        let (pt, qs) = (joint.pt, joint.qs);
        let pt_minus = if t >= 2 { Some(&cam[t - 2]) } else { None };
        let qs_minus = if s >= 2 { Some(&light[s - 2]) } else { None };
        // The joint's reverse densities: pt's from qs (or, for s = 0, as a light subpath's
        // origin), and on from pt back along the camera subpath and from qs back along the
        // light subpath.
        // Each carries its segment's free-flight factor and the σt of the vertex it is at
        // (both 1 without media).
        let pt_rev = match qs {
            Some(q) => self.pdf(scene, q, pt, joint.qs_to_pt) * joint.seg * pt.sigma,
            None => self.pdf_light_origin(scene, pt, pt_minus.expect("t ≥ 2 when s = 0")),
        };
        let pt_minus_rev = pt_minus.map(|pm| {
            let pdf = match qs {
                Some(_) => Self::pdf_back(pt, joint.pt_to_qs, pm),
                None => self.pdf_light(scene, pt, pm),
            };
            pdf * pt.seg * pm.sigma
        });
        let qs_rev = qs.map(|q| self.pdf(scene, pt, q, joint.pt_to_qs) * joint.seg * q.sigma);
        let qs_minus_rev = qs
            .zip(qs_minus)
            .map(|(q, qm)| Self::pdf_back(q, joint.qs_to_pt, qm) * q.seg * qm.sigma);
        // (pdf_fwd, pdf_rev, delta) of each vertex with the joint's overrides; the endpoints
        // are connectible, so not delta.
        // Per vertex (pdf_fwd, pdf_rev, delta, and the lanes' factor of rev/fwd relative to
        // the hero's: the free flight of the segment its reverse density crosses over that
        // of the segment its forward one crosses; the σt of the vertex cancels).
        let cam_at = |i: usize| -> (f32, f32, bool, M::C) {
            if i == t - 1 {
                (pt.pdf_fwd, pt_rev, false, joint.seg_lanes / pt.seg_lanes)
            } else if i + 2 == t {
                let v = &cam[i];
                let q = pt.seg_lanes / v.seg_lanes;
                (v.pdf_fwd, pt_minus_rev.unwrap_or(v.pdf_rev), v.delta, q)
            } else {
                let v = &cam[i];
                let q = cam[i + 1].seg_lanes / v.seg_lanes;
                (v.pdf_fwd, v.pdf_rev, v.delta, q)
            }
        };
        let light_at = |i: usize| -> (f32, f32, bool, M::C) {
            if i + 1 == s {
                let q = qs.expect("s > 0");
                let lanes = joint.seg_lanes / q.seg_lanes;
                (q.pdf_fwd, qs_rev.unwrap_or(q.pdf_rev), false, lanes)
            } else if i + 2 == s {
                let v = &light[i];
                let q = qs.expect("s > 1").seg_lanes / v.seg_lanes;
                (v.pdf_fwd, qs_minus_rev.unwrap_or(v.pdf_rev), v.delta, q)
            } else {
                let v = &light[i];
                let q = light[i + 1].seg_lanes / v.seg_lanes;
                (v.pdf_fwd, v.pdf_rev, v.delta, q)
            }
        };
        let mut sum = 0.0f32;
        let mut sum_lanes = M::C::ONE;
        let mut ri = 1.0f32;
        let mut ri_lanes = M::C::ONE;
        // Strategies (s + t − i, i) with fewer camera vertices ((1, 1) cannot occur: s + t
        // > 2 here).
        for i in (1..t).rev() {
            let (fwd, rev, delta, q) = cam_at(i);
            let r = remap0(rev) / remap0(fwd);
            ri *= r * r;
            if lanes {
                ri_lanes *= q * q * (r * r);
            }
            if !delta && !cam_at(i - 1).2 {
                sum += ri;
                sum_lanes += ri_lanes;
            }
        }
        ri = 1.0;
        ri_lanes = M::C::ONE;
        for i in (0..s).rev() {
            let (fwd, rev, delta, q) = light_at(i);
            let r = remap0(rev) / remap0(fwd);
            ri *= r * r;
            if lanes {
                ri_lanes *= q * q * (r * r);
            }
            let delta_before = if i > 0 {
                light_at(i - 1).2
            } else {
                // The light of the subpath's origin: a delta light is never hit.
                let origin = qs.filter(|_| s == 1).unwrap_or(&light[0]);
                matches!(origin.kind, Kind::Light(l) if scene.lights[l as usize].is_delta())
            };
            if !delta && !delta_before {
                sum += ri;
                sum_lanes += ri_lanes;
            }
        }
        let w = 1.0 / (1.0 + sum);
        (
            if w.is_finite() { w } else { 0.0 },
            lanes.then_some(sum_lanes),
        )
    }
}
