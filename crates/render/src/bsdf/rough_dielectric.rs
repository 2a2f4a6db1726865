//! Rough dielectric interface (Mitsuba `roughdielectric`): the microfacet BSDF of Walter et
//! al. 2007 ("Microfacet Models for Refraction through Rough Surfaces") with Smith G, plus the
//! radiance-compression factor 1/η² for refraction in `Radiance` mode that the paper omits.
//!
//! Parameters: `distribution` (Beckmann default, or GGX), `alpha_u`/`alpha_v` (default 0.1),
//! `int_ior` (BK7), `ext_ior` (air), `specular_reflectance`, `specular_transmittance`
//! (default 1). Sampling draws a visible normal for the incident side, then reflection or
//! refraction with probability F / 1 − F, so the weight is G1(wi, m) (times the tint and the
//! radiance scale). Naturally two-sided: `wo.z < 0` means the query comes from inside.

use super::fresnel::{fresnel_dielectric, refract_m};
use super::microfacet::{Microfacet, MicrofacetType};
use super::{BsdfModel, BsdfSample, TransportMode, is_positive, reflect_z_about};
use crate::math::{Vec2, Vec3};
use crate::spectral::lanes::Color;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughDielectric<C: Color = Vec3> {
    pub distribution: Microfacet,
    /// Relative index int_ior / ext_ior: one scalar for every lane (no dispersion; a
    /// dispersive rough interface would need the hero-wavelength termination of the smooth
    /// dielectric, not done here).
    pub eta: f32,
    pub specular_reflectance: C,
    pub specular_transmittance: C,
}

impl RoughDielectric {
    /// An RGB rough dielectric (the constructor names no colour, so it cannot infer the
    /// lanes).
    pub fn new(
        kind: MicrofacetType,
        alpha_u: f32,
        alpha_v: f32,
        int_ior: f32,
        ext_ior: f32,
    ) -> RoughDielectric {
        RoughDielectric::with_lanes(kind, alpha_u, alpha_v, int_ior, ext_ior)
    }
}

impl<C: Color> RoughDielectric<C> {
    pub fn with_lanes(
        kind: MicrofacetType,
        alpha_u: f32,
        alpha_v: f32,
        int_ior: f32,
        ext_ior: f32,
    ) -> RoughDielectric<C> {
        RoughDielectric {
            distribution: Microfacet::new(kind, alpha_u, alpha_v),
            eta: int_ior / ext_ior,
            specular_reflectance: C::ONE,
            specular_transmittance: C::ONE,
        }
    }

    /// Generalised half vector (pointing to the +z side), the relative index η_i/η_o seen from
    /// `wo`'s side, and whether the pair is a reflection. `None` for grazing or back-facing
    /// configurations.
    #[inline]
    fn half_vector(&self, wo: Vec3, wi: Vec3) -> Option<(Vec3, f32, bool)> {
        let (cos_o, cos_i) = (wo.z, wi.z);
        if cos_o == 0.0 || cos_i == 0.0 {
            return None;
        }
        let reflect = cos_o * cos_i > 0.0;
        let eta = if cos_o > 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        };
        let h = wo + wi * if reflect { 1.0 } else { eta };
        let len2 = h.length_squared();
        if !is_positive(len2) {
            return None;
        }
        let mut m = h / len2.sqrt();
        if m.z < 0.0 {
            m = -m;
        }
        // Discard back-facing microfacets.
        if wo.dot(m) * cos_o <= 0.0 || wi.dot(m) * cos_i <= 0.0 {
            return None;
        }
        Some((m, eta, reflect))
    }
}

impl<C: Color> BsdfModel<C> for RoughDielectric<C> {
    fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> C {
        let Some((m, eta, reflect)) = self.half_vector(wo, wi) else {
            return C::ZERO;
        };
        let d = self.distribution.eval(m);
        if d == 0.0 {
            return C::ZERO;
        }
        let f = fresnel_dielectric(wo.dot(m), self.eta).0;
        let g = self.distribution.g(wo, wi, m);
        if reflect {
            self.specular_reflectance * (f * d * g / (4.0 * wo.z.abs()))
        } else {
            let (wo_m, wi_m) = (wo.dot(m), wi.dot(m));
            let denom = wo_m + eta * wi_m;
            let scale = match mode {
                TransportMode::Radiance => 1.0 / (eta * eta),
                TransportMode::Importance => 1.0,
            };
            let v = scale * (1.0 - f) * d * g * eta * eta * wo_m * wi_m / (wo.z * denom * denom);
            self.specular_transmittance * v.abs()
        }
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let Some((m, eta, reflect)) = self.half_vector(wo, wi) else {
            return 0.0;
        };
        let (wo_m, wi_m) = (wo.dot(m), wi.dot(m));
        let jacobian = if reflect {
            1.0 / (4.0 * wi_m.abs())
        } else {
            let denom = wo_m + eta * wi_m;
            eta * eta * wi_m.abs() / (denom * denom)
        };
        let wo_up = if wo.z < 0.0 { -wo } else { wo };
        let f = fresnel_dielectric(wo_m, self.eta).0;
        let prob = self.distribution.pdf(wo_up, m) * if reflect { f } else { 1.0 - f };
        prob * jacobian
    }

    fn sample(&self, wo: Vec3, u1: f32, u2: Vec2, mode: TransportMode) -> Option<BsdfSample<C>> {
        let cos_o = wo.z;
        if cos_o == 0.0 {
            return None;
        }
        let wo_up = if cos_o < 0.0 { -wo } else { wo };
        let (m, pdf_m) = self.distribution.sample(wo_up, u2);
        if !is_positive(pdf_m) {
            return None;
        }
        let wo_m = wo.dot(m);
        let (f, cos_t, eta_it, eta_ti) = fresnel_dielectric(wo_m, self.eta);
        if u1 <= f {
            let wi = reflect_z_about(wo, m);
            if wi.z * cos_o <= 0.0 {
                return None;
            }
            let pdf = pdf_m * f / (4.0 * wi.dot(m).abs());
            let weight = self.specular_reflectance * self.distribution.smith_g1(wi, m);
            Some(BsdfSample::glossy_reflection(wi, weight, pdf))
        } else {
            let wi = refract_m(wo, m, cos_t, eta_ti);
            if wi.z * cos_o >= 0.0 {
                return None;
            }
            let wi_m = wi.dot(m);
            let denom = wo_m + eta_it * wi_m;
            let jacobian = eta_it * eta_it * wi_m.abs() / (denom * denom);
            let pdf = pdf_m * (1.0 - f) * jacobian;
            let scale = match mode {
                TransportMode::Radiance => eta_ti * eta_ti,
                TransportMode::Importance => 1.0,
            };
            let weight = self.specular_transmittance * (scale * self.distribution.smith_g1(wi, m));
            if !is_positive(pdf) || !pdf.is_finite() {
                return None;
            }
            Some(BsdfSample {
                wi,
                weight,
                pdf,
                delta: false,
                transmission: true,
                eta: eta_it,
            })
        }
    }

    fn has_delta(&self) -> bool {
        false
    }
    fn has_smooth(&self) -> bool {
        true
    }
    fn albedo(&self) -> C {
        self.specular_transmittance
    }
}
