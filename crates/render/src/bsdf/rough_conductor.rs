//! Rough conductor (Mitsuba `roughconductor`): a Cook–Torrance microfacet BRDF
//! f = F(wo·m)·D(m)·G(wo, wi, m) / (4 cos θo cos θi) with complex conductor Fresnel.
//!
//! Parameters: `distribution` (Beckmann default, or GGX), `alpha_u`/`alpha_v` (default 0.1,
//! anisotropic when they differ), `eta`, `k`, `specular_reflectance` (default 1). Sampling
//! draws visible normals (Heitz 2018 for GGX, Heitz & d'Eon 2014 for Beckmann), so the sample
//! weight reduces to F·G1(wi, m).

use super::fresnel::fresnel_conductor;
use super::microfacet::{Microfacet, MicrofacetType};
use super::{BsdfModel, BsdfSample, TransportMode, is_positive, reflect_z_about};
use crate::math::{Vec2, Vec3};
use crate::spectral::lanes::Color;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughConductor<C: Color = Vec3> {
    pub distribution: Microfacet,
    pub eta: C,
    pub k: C,
    pub specular_reflectance: C,
}

impl<C: Color> RoughConductor<C> {
    pub fn new(
        kind: MicrofacetType,
        alpha_u: f32,
        alpha_v: f32,
        eta: C,
        k: C,
        specular_reflectance: C,
    ) -> RoughConductor<C> {
        RoughConductor {
            distribution: Microfacet::new(kind, alpha_u, alpha_v),
            eta,
            k,
            specular_reflectance,
        }
    }
}

impl<C: Color> BsdfModel<C> for RoughConductor<C> {
    fn eval(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> C {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return C::ZERO;
        }
        let h = (wo + wi).normalize();
        let d = self.distribution.eval(h);
        if d == 0.0 {
            return C::ZERO;
        }
        let g = self.distribution.g(wo, wi, h);
        let f = fresnel_conductor(wo.dot(h), self.eta, self.k);
        self.specular_reflectance * f * (d * g / (4.0 * wo.z))
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        self.distribution.eval(h) * self.distribution.smith_g1(wo, h) / (4.0 * wo.z)
    }

    fn sample(&self, wo: Vec3, _u1: f32, u2: Vec2, _mode: TransportMode) -> Option<BsdfSample<C>> {
        if wo.z <= 0.0 {
            return None;
        }
        let (m, pdf_m) = self.distribution.sample(wo, u2);
        let wi = reflect_z_about(wo, m);
        let wo_m = wo.dot(m);
        if wi.z <= 0.0 || !is_positive(pdf_m) || wo_m <= 0.0 {
            return None;
        }
        let pdf = pdf_m / (4.0 * wo_m);
        let f = fresnel_conductor(wo_m, self.eta, self.k);
        let weight = self.specular_reflectance * f * self.distribution.smith_g1(wi, m);
        Some(BsdfSample::glossy_reflection(wi, weight, pdf))
    }

    fn has_delta(&self) -> bool {
        false
    }
    fn has_smooth(&self) -> bool {
        true
    }
    fn albedo(&self) -> C {
        self.specular_reflectance * fresnel_conductor(1.0, self.eta, self.k)
    }
}
