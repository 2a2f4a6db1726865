//! What Mitsuba 3's `bumpmap` adds to its nested BSDF beyond the perturbed frame
//! (`src/bsdfs/perturbed_bsdf.h`): directions must lie on the same side of the unperturbed and
//! the perturbed shading normals (else 0), and, with `use_shadowing_function` (its default),
//! values and sample weights are scaled by Estevez et al.'s microfacet shadowing of the bump
//! terminator, G = 2 / (1 + √(1 + α²·tan²θ)) with α² = min(tan²θ_bump / 8, 1), θ the
//! direction's angle to the unperturbed normal and θ_bump the perturbed normal's.
//!
//! The model works in the perturbed frame; `n_orig` and `n_pert` are the unperturbed and the
//! perturbed normals in it (`n_pert` differs from +z only when a two-sided flip follows the
//! bump).

use super::{Bsdf, BsdfModel, BsdfSample, TransportMode};
use crate::math::{Vec2, Vec3};
use crate::spectral::lanes::Color;

#[derive(Clone, Debug)]
pub struct Bumped<C: Color = Vec3> {
    pub inner: Bsdf<C>,
    pub n_orig: Vec3,
    pub n_pert: Vec3,
    /// α² of the shadowing term; `None` without it.
    pub alpha2: Option<f32>,
}

impl<C: Color> Bumped<C> {
    /// Whether `w` lies on one side of both normals.
    #[inline]
    fn same_side(&self, w: Vec3) -> bool {
        w.dot(self.n_orig) * w.dot(self.n_pert) > 0.0
    }

    /// The shadowing factor of direction `w`.
    #[inline]
    fn shadowing(&self, w: Vec3) -> f32 {
        let Some(a2) = self.alpha2 else {
            return 1.0;
        };
        let c2 = w.dot(self.n_orig).powi(2);
        let tan2 = (1.0 - c2).max(0.0) / c2;
        2.0 / (1.0 + (1.0 + a2 * tan2).sqrt())
    }
}

impl<C: Color> BsdfModel<C> for Bumped<C> {
    fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> C {
        if !self.same_side(wi) {
            return C::ZERO;
        }
        self.inner.eval(wo, wi, mode) * self.shadowing(wi)
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if !self.same_side(wi) {
            return 0.0;
        }
        self.inner.pdf(wo, wi)
    }

    fn eval_pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> (C, f32) {
        if !self.same_side(wi) {
            return (C::ZERO, 0.0);
        }
        let (f, p) = self.inner.eval_pdf(wo, wi, mode);
        (f * self.shadowing(wi), p)
    }

    fn sample(&self, wo: Vec3, u1: f32, u2: Vec2, mode: TransportMode) -> Option<BsdfSample<C>> {
        let s = self.inner.sample(wo, u1, u2, mode)?;
        if s.weight.is_black() || !self.same_side(s.wi) {
            return None;
        }
        Some(BsdfSample {
            weight: s.weight * self.shadowing(s.wi),
            ..s
        })
    }

    fn has_delta(&self) -> bool {
        self.inner.has_delta()
    }
    fn has_smooth(&self) -> bool {
        self.inner.has_smooth()
    }
    fn albedo(&self) -> C {
        self.inner.albedo()
    }
}
