//! Mitsuba 3's `pplastic` (polarized plastic, Baek et al. 2018) as its unpolarised (RGB and
//! spectral) variants evaluate it: a rough dielectric reflection F(wo·h)·D·G/(4 cos θo)
//! tinted by `specular_reflectance`, plus a Lambertian base attenuated by the smooth
//! transmittances into and out of the material, (1 − F(cos θo))(1 − F(cos θi))·ρ/π. Not
//! energy conserving (Mitsuba says so). Sampling: visible normals with probability
//! mean(specular)/(mean(diffuse) + mean(specular)), else cosine-weighted; `pdf` and the
//! weight are the mixture's.

use super::fresnel::fresnel_dielectric;
use super::microfacet::Microfacet;
use super::{BsdfModel, BsdfSample, TransportMode, mixture_reflection_sample, reflect_z_about};
use crate::math::{INV_PI, Vec2, Vec3};
use crate::sampling::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use crate::spectral::lanes::Color;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PolarizedPlastic<C: Color = Vec3> {
    pub distribution: Microfacet,
    /// int_ior / ext_ior.
    pub eta: f32,
    pub diffuse_reflectance: C,
    pub specular_reflectance: C,
    pub specular_sampling_weight: f32,
}

impl<C: Color> BsdfModel<C> for PolarizedPlastic<C> {
    fn eval(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> C {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return C::ZERO;
        }
        let h = (wo + wi).normalize();
        let d = self.distribution.eval(h);
        let f = fresnel_dielectric(wo.dot(h), self.eta).0;
        let g = self.distribution.g(wo, wi, h);
        let spec = self.specular_reflectance * (f * d * g / (4.0 * wo.z));
        let t_o = 1.0 - fresnel_dielectric(wo.z, self.eta).0;
        let t_i = 1.0 - fresnel_dielectric(wi.z, self.eta).0;
        spec + self.diffuse_reflectance * (t_o * t_i * INV_PI * wi.z)
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        let spec = if wo.dot(h) <= 0.0 || wi.dot(h) <= 0.0 {
            0.0
        } else {
            self.distribution.eval(h) * self.distribution.smith_g1(wo, h) / (4.0 * wo.z)
        };
        let ps = self.specular_sampling_weight;
        ps * spec + (1.0 - ps) * cosine_hemisphere_pdf(wi)
    }

    fn sample(&self, wo: Vec3, u1: f32, u2: Vec2, mode: TransportMode) -> Option<BsdfSample<C>> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = if u1 < self.specular_sampling_weight {
            reflect_z_about(wo, self.distribution.sample(wo, u2).0)
        } else {
            square_to_cosine_hemisphere(u2)
        };
        mixture_reflection_sample(self, wo, wi, mode)
    }

    fn has_delta(&self) -> bool {
        false
    }
    fn has_smooth(&self) -> bool {
        true
    }
    fn albedo(&self) -> C {
        self.diffuse_reflectance
    }
}
