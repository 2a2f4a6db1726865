//! Mitsuba 3's `blendbsdf`: (1 − w)·first + w·second, w ∈ [0, 1] (a constant or a texture,
//! clamped).
//!
//! `eval` and `pdf` blend the two. `sample` picks the second with probability w (`u1 ≤ w`,
//! the rest of `u1` rescaled for the chosen one), samples it, and returns what Mitsuba 3.9's
//! blend returns: the density w_i·p_i + w_j·p_j(wi) of the mixture and the weight
//! (w_i·weight_i·p_i + w_j·f_j(wi)) / that density — eval/pdf of the blend for non-delta
//! lobes. A delta sample keeps its delta flag and is weighed the same way, its discrete
//! probability standing in for a density (Mitsuba's behaviour, kept so that renders agree).

use super::{Bsdf, BsdfModel, BsdfSample, TransportMode, is_positive};
use crate::math::{Vec2, Vec3};
use crate::spectral::lanes::Color;

#[derive(Clone, Debug)]
pub struct Blend<C: Color = Vec3> {
    /// The second model's share, in [0, 1].
    pub weight: f32,
    pub bsdfs: [Bsdf<C>; 2],
}

impl<C: Color> Blend<C> {
    pub fn new(weight: f32, first: Bsdf<C>, second: Bsdf<C>) -> Blend<C> {
        Blend {
            weight: if weight.is_nan() {
                0.0
            } else {
                weight.clamp(0.0, 1.0)
            },
            bsdfs: [first, second],
        }
    }

    #[inline]
    fn weights(&self) -> [f32; 2] {
        [1.0 - self.weight, self.weight]
    }
}

impl<C: Color> BsdfModel<C> for Blend<C> {
    fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> C {
        let [w0, w1] = self.weights();
        self.bsdfs[0].eval(wo, wi, mode) * w0 + self.bsdfs[1].eval(wo, wi, mode) * w1
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let [w0, w1] = self.weights();
        self.bsdfs[0].pdf(wo, wi) * w0 + self.bsdfs[1].pdf(wo, wi) * w1
    }

    fn eval_pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> (C, f32) {
        let [w0, w1] = self.weights();
        let (f0, p0) = self.bsdfs[0].eval_pdf(wo, wi, mode);
        let (f1, p1) = self.bsdfs[1].eval_pdf(wo, wi, mode);
        (f0 * w0 + f1 * w1, p0 * w0 + p1 * w1)
    }

    fn sample(&self, wo: Vec3, u1: f32, u2: Vec2, mode: TransportMode) -> Option<BsdfSample<C>> {
        let w = self.weights();
        let (i, u) = if u1 > self.weight || self.weight == 0.0 {
            (0, (u1 - self.weight) / (1.0 - self.weight))
        } else {
            (1, u1 / self.weight)
        };
        let s = self.bsdfs[i].sample(wo, u.min(1.0 - f32::EPSILON), u2, mode)?;
        let (f_other, p_other) = self.bsdfs[1 - i].eval_pdf(wo, s.wi, mode);
        let pdf = w[i] * s.pdf + w[1 - i] * p_other;
        if !is_positive(pdf) || !pdf.is_finite() {
            return None;
        }
        let value = s.weight * (w[i] * s.pdf) + f_other * w[1 - i];
        Some(BsdfSample {
            weight: value / pdf,
            pdf,
            ..s
        })
    }

    fn has_delta(&self) -> bool {
        self.bsdfs.iter().any(Bsdf::has_delta)
    }
    fn has_smooth(&self) -> bool {
        self.bsdfs.iter().any(Bsdf::has_smooth)
    }
    fn albedo(&self) -> C {
        let [w0, w1] = self.weights();
        self.bsdfs[0].albedo() * w0 + self.bsdfs[1].albedo() * w1
    }
}
