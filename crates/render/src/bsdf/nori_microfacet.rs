//! Nori's `microfacet` BRDF (assignment PA5): a Beckmann specular lobe with dielectric Fresnel
//! over a Lambertian base, *not* energy-coupled:
//!
//! f(wo, wi) = kd/π + ks·D(h)·F(h·wo; η_ext, η_int)·G(wo, wi, h) / (4 cos θo cos θi),
//! ks = 1 − max(kd),
//!
//! with D the isotropic Beckmann distribution, G = G1(wo)·G1(wi) the Smith rational
//! approximation, F the unpolarised dielectric Fresnel at η = intIOR/extIOR. Sampling picks
//! the specular lobe with probability ks (normals from D(m) cos θm, reflected) and the
//! cosine-weighted diffuse lobe otherwise; pdf = ks·D(h)cos θh/(4 h·wi) + (1 − ks)·cos θi/π.
//!
//! Parameters (Nori names): `alpha` (0.1), `intIOR` (1.5046), `extIOR` (1.000277), `kd` (0.5).

use super::fresnel::fresnel_dielectric;
use super::microfacet::{Microfacet, MicrofacetType};
use super::{BsdfModel, BsdfSample, TransportMode, mixture_reflection_sample, reflect_z_about};
use crate::math::{INV_PI, Vec2, Vec3};
use crate::sampling::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use crate::spectral::lanes::Color;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NoriMicrofacet<C: Color = Vec3> {
    pub distribution: Microfacet,
    /// Relative index intIOR / extIOR.
    pub eta: f32,
    pub kd: C,
    /// 1 − max(kd) over the RGB channels (fixed 3-channel arithmetic, kept in spectral mode:
    /// a scalar specular weight, the same at every wavelength).
    pub ks: f32,
}

impl NoriMicrofacet {
    pub fn new(alpha: f32, int_ior: f32, ext_ior: f32, kd: Vec3) -> NoriMicrofacet {
        NoriMicrofacet {
            distribution: Microfacet::isotropic(MicrofacetType::Beckmann, alpha),
            eta: int_ior / ext_ior,
            kd,
            ks: (1.0 - kd.max_element()).clamp(0.0, 1.0),
        }
    }

    /// The same BSDF with `kd` converted by `f` (e.g. a `ColorMode`'s albedo upsampling);
    /// `ks` stays the RGB one.
    pub fn map_lanes<D: Color>(&self, f: impl Fn(Vec3) -> D) -> NoriMicrofacet<D> {
        NoriMicrofacet {
            distribution: self.distribution,
            eta: self.eta,
            kd: f(self.kd),
            ks: self.ks,
        }
    }
}

impl<C: Color> BsdfModel<C> for NoriMicrofacet<C> {
    fn eval(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> C {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return C::ZERO;
        }
        let h = (wo + wi).normalize();
        let d = self.distribution.eval(h);
        let spec = if d > 0.0 {
            let f = fresnel_dielectric(h.dot(wo), self.eta).0;
            let g = self.distribution.g(wo, wi, h);
            self.ks * d * f * g / (4.0 * wo.z * wi.z)
        } else {
            0.0
        };
        (self.kd * INV_PI + C::splat(spec)) * wi.z
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let h = (wo + wi).normalize();
        let spec = self.distribution.eval(h) * h.z / (4.0 * h.dot(wi));
        self.ks * spec + (1.0 - self.ks) * cosine_hemisphere_pdf(wi)
    }

    fn sample(&self, wo: Vec3, u1: f32, u2: Vec2, mode: TransportMode) -> Option<BsdfSample<C>> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = if u1 < self.ks {
            let m = self.distribution.sample_all(u2);
            reflect_z_about(wo, m)
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
        self.kd
    }
}
