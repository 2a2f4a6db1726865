//! BDPT's MIS weights: the power heuristic over every strategy that could have made the
//! same path, from the forward and reverse area densities of its vertices (pbrt-v4's
//! `MISWeight`), with the joint's four densities overridden.

use super::Bdpt;
use super::connect::Joins;
use super::vertex::{Joint, Kind, remap0};
use crate::spectral::lanes::PathMode;

impl<M: PathMode> Bdpt<'_, M> {
    /// The power-heuristic weight of strategy (s, t), joined at `joint` (whose ends replace
    /// the vertices the strategy sampled afresh: the light point for s = 1, the lens point
    /// for t = 1).
    pub(super) fn mis_weight(
        &self,
        j: &Joins<M>,
        joint: &Joint<M::C>,
        (s, t): (usize, usize),
    ) -> f32 {
        let (scene, cam, light) = (j.scene, j.cam, j.light);
        if s + t == 2 {
            return 1.0;
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
        let cam_at = |i: usize| -> (f32, f32, bool) {
            if i == t - 1 {
                (pt.pdf_fwd, pt_rev, false)
            } else if i + 2 == t {
                let v = &cam[i];
                (v.pdf_fwd, pt_minus_rev.unwrap_or(v.pdf_rev), v.delta)
            } else {
                (cam[i].pdf_fwd, cam[i].pdf_rev, cam[i].delta)
            }
        };
        let light_at = |i: usize| -> (f32, f32, bool) {
            if i + 1 == s {
                let q = qs.expect("s > 0");
                (q.pdf_fwd, qs_rev.unwrap_or(q.pdf_rev), false)
            } else if i + 2 == s {
                let v = &light[i];
                (v.pdf_fwd, qs_minus_rev.unwrap_or(v.pdf_rev), v.delta)
            } else {
                (light[i].pdf_fwd, light[i].pdf_rev, light[i].delta)
            }
        };
        let mut sum = 0.0f32;
        let mut ri = 1.0f32;
        // Strategies (s + t − i, i) with fewer camera vertices ((1, 1) cannot occur: s + t
        // > 2 here).
        for i in (1..t).rev() {
            let (fwd, rev, delta) = cam_at(i);
            let r = remap0(rev) / remap0(fwd);
            ri *= r * r;
            if !delta && !cam_at(i - 1).2 {
                sum += ri;
            }
        }
        ri = 1.0;
        for i in (0..s).rev() {
            let (fwd, rev, delta) = light_at(i);
            let r = remap0(rev) / remap0(fwd);
            ri *= r * r;
            let delta_before = if i > 0 {
                light_at(i - 1).2
            } else {
                // The light of the subpath's origin: a delta light is never hit.
                let origin = qs.filter(|_| s == 1).unwrap_or(&light[0]);
                matches!(origin.kind, Kind::Light(l) if scene.lights[l as usize].is_delta())
            };
            if !delta && !delta_before {
                sum += ri;
            }
        }
        let w = 1.0 / (1.0 + sum);
        if w.is_finite() { w } else { 0.0 }
    }
}
