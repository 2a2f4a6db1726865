//! Rough dielectric interface (Mitsuba `roughdielectric`): the microfacet BSDF of Walter et
//! al. 2007 ("Microfacet Models for Refraction through Rough Surfaces") with Smith G, plus the
//! radiance-compression factor 1/η² for refraction in `Radiance` mode that the paper omits.
//!
//! Parameters: `distribution` (Beckmann default, or GGX), `alpha_u`/`alpha_v` (default 0.1),
//! `int_ior` (BK7), `ext_ior` (air), `specular_reflectance`, `specular_transmittance`
//! (default 1). Sampling draws a visible normal for the incident side, then reflection or
//! refraction with probability F / 1 − F, so the weight is G1(wi, m) (times the tint and the
//! radiance scale). Naturally two-sided: `wo.z < 0` means the query comes from inside.
//!
//! **Dispersion** (spectral mode, issue 21): when the lanes' indices differ
//! ([`RoughDielectric::lane_eta`]), every lane is kept by one-sample MIS over the four
//! wavelengths with the balance heuristic. `sample` picks a lane j uniformly (from `u1`,
//! whose remainder then chooses reflection or refraction), samples `wi` with lane j's index,
//! and weighs lane i by f_i(wo, wi) / p̄(wo, wi), where p̄ = ¼ Σ_j p_j is the mixture of the
//! four lanes' densities: the density with which the procedure really produces `wi`. `pdf`
//! and `eval_pdf` return that same p̄, so next-event estimation's MIS against light sampling
//! uses the one density the BSDF samples with, and the integrators need no change.
//!
//! The lane is drawn afresh at each vertex rather than being the path's hero (lane 0). With a
//! fixed hero the per-vertex weights f_i/p̄ are unbiased only on average over which lane of
//! the stratified set is the hero, and that average does not factor over vertices: past the
//! first dispersive rough vertex the hero is no longer uniform among the lanes given the
//! directions already sampled with it, and a path through two such vertices (the two faces
//! of a glass object) is biased (`tests/it/dispersion.rs` measures it). A lane chosen per vertex
//! makes each vertex an unbiased estimator on its own, whatever came before.

use super::fresnel::{fresnel_dielectric, refract_m};
use super::microfacet::{Microfacet, MicrofacetType};
use super::{BsdfModel, BsdfSample, TransportMode, is_positive, reflect_z_about};
use crate::math::{Vec2, Vec3};
use crate::spectral::lanes::Color;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughDielectric<C: Color = Vec3> {
    pub distribution: Microfacet,
    /// Relative index int_ior / ext_ior, shared by every lane unless the interface is
    /// dispersive (then lane 0's, [`Self::lane_eta`]).
    pub eta: f32,
    /// Each lane's relative index: `eta` in every lane (RGB; spectral mode with a
    /// non-dispersive index, or once the path's secondary wavelengths are terminated), or in
    /// spectral mode with a dispersive index, the index at each wavelength, which turns on the
    /// MIS over the lanes of the module documentation.
    pub lane_eta: C,
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
    /// One index for every lane.
    pub fn with_lanes(
        kind: MicrofacetType,
        alpha_u: f32,
        alpha_v: f32,
        int_ior: f32,
        ext_ior: f32,
    ) -> RoughDielectric<C> {
        RoughDielectric::with_lane_ior(kind, alpha_u, alpha_v, C::splat(int_ior), ext_ior)
    }

    /// An index per lane (`int_ior` from `ColorMode::lane_ior`): dispersive when the lanes
    /// differ. Lane 0's index becomes [`Self::eta`]; one index in every lane gives exactly
    /// [`Self::with_lanes`].
    pub fn with_lane_ior(
        kind: MicrofacetType,
        alpha_u: f32,
        alpha_v: f32,
        int_ior: C,
        ext_ior: f32,
    ) -> RoughDielectric<C> {
        RoughDielectric {
            distribution: Microfacet::new(kind, alpha_u, alpha_v),
            eta: int_ior.lane(0) / ext_ior,
            lane_eta: int_ior / ext_ior,
            specular_reflectance: C::ONE,
            specular_transmittance: C::ONE,
        }
    }

    /// Whether the lanes' indices differ (only ever in spectral mode: RGB has one index per
    /// material, and the test is a constant `false` for 3-lane colours).
    #[inline]
    pub fn is_dispersive(&self) -> bool {
        super::fresnel::lanes_disperse(self.lane_eta, self.eta)
    }

    /// Generalised half vector (pointing to the +z side), the relative index η_i/η_o seen from
    /// `wo`'s side, and whether the pair is a reflection, at relative index `eta`. `None` for
    /// grazing or back-facing configurations.
    #[inline]
    fn half_vector(wo: Vec3, wi: Vec3, eta: f32) -> Option<(Vec3, f32, bool)> {
        let (cos_o, cos_i) = (wo.z, wi.z);
        if cos_o == 0.0 || cos_i == 0.0 {
            return None;
        }
        let reflect = cos_o * cos_i > 0.0;
        let eta = if cos_o > 0.0 { eta } else { 1.0 / eta };
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

    /// f(wo, wi)·|cos θi| without the tint, at relative index `eta_rel` (int/ext); the tint is
    /// the reflectance when `wo` and `wi` lie on one side, the transmittance otherwise.
    #[inline]
    fn value_at(&self, wo: Vec3, wi: Vec3, eta_rel: f32, mode: TransportMode) -> f32 {
        let Some((m, eta, reflect)) = Self::half_vector(wo, wi, eta_rel) else {
            return 0.0;
        };
        let d = self.distribution.eval(m);
        if d == 0.0 {
            return 0.0;
        }
        let f = fresnel_dielectric(wo.dot(m), eta_rel).0;
        let g = self.distribution.g(wo, wi, m);
        if reflect {
            f * d * g / (4.0 * wo.z.abs())
        } else {
            let (wo_m, wi_m) = (wo.dot(m), wi.dot(m));
            let denom = wo_m + eta * wi_m;
            let scale = match mode {
                TransportMode::Radiance => 1.0 / (eta * eta),
                TransportMode::Importance => 1.0,
            };
            let v = scale * (1.0 - f) * d * g * eta * eta * wo_m * wi_m / (wo.z * denom * denom);
            v.abs()
        }
    }

    /// The density with which sampling at relative index `eta_rel` produces `wi`.
    #[inline]
    fn pdf_at(&self, wo: Vec3, wi: Vec3, eta_rel: f32) -> f32 {
        let Some((m, eta, reflect)) = Self::half_vector(wo, wi, eta_rel) else {
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
        let f = fresnel_dielectric(wo_m, eta_rel).0;
        let prob = self.distribution.pdf(wo_up, m) * if reflect { f } else { 1.0 - f };
        prob * jacobian
    }

    #[inline]
    fn tint(&self, wo: Vec3, wi: Vec3) -> C {
        if wo.z * wi.z > 0.0 {
            self.specular_reflectance
        } else {
            self.specular_transmittance
        }
    }

    /// A dispersive interface: each lane's f·|cos θi| at its own index, and the mixture
    /// density ¼ Σ_j p_j of the lanes' sampling densities.
    fn eval_pdf_lanes(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> (C, f32) {
        let mut pdf = 0.0;
        let f = C::from_fn(|i| {
            let eta = self.lane_eta.lane(i);
            pdf += self.pdf_at(wo, wi, eta);
            self.value_at(wo, wi, eta, mode)
        });
        (self.tint(wo, wi) * f, pdf / C::LANES as f32)
    }

    /// The sample of a dispersive interface (module documentation): a lane chosen by `u1`,
    /// `wi` sampled at its index, every lane weighed by its f over the mixture density.
    fn sample_lanes(
        &self,
        wo: Vec3,
        u1: f32,
        u2: Vec2,
        mode: TransportMode,
    ) -> Option<BsdfSample<C>> {
        let cos_o = wo.z;
        if cos_o == 0.0 {
            return None;
        }
        let n = C::LANES as f32;
        let lane = ((u1 * n) as usize).min(C::LANES - 1);
        let u1 = u1 * n - lane as f32;
        let eta_lane = self.lane_eta.lane(lane);
        let wo_up = if cos_o < 0.0 { -wo } else { wo };
        let (m, pdf_m) = self.distribution.sample(wo_up, u2);
        if !is_positive(pdf_m) {
            return None;
        }
        let (f, cos_t, eta_it, eta_ti) = fresnel_dielectric(wo.dot(m), eta_lane);
        let reflect = u1 <= f;
        let wi = if reflect {
            reflect_z_about(wo, m)
        } else {
            refract_m(wo, m, cos_t, eta_ti)
        };
        if (wi.z * cos_o > 0.0) != reflect || wi.z == 0.0 {
            return None;
        }
        let (value, pdf) = self.eval_pdf_lanes(wo, wi, mode);
        if !is_positive(pdf) || !pdf.is_finite() {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight: value / pdf,
            pdf,
            delta: false,
            transmission: !reflect,
            eta: if reflect { 1.0 } else { eta_it },
        })
    }
}

impl<C: Color> BsdfModel<C> for RoughDielectric<C> {
    fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> C {
        if self.is_dispersive() {
            return self.eval_pdf_lanes(wo, wi, mode).0;
        }
        self.tint(wo, wi) * self.value_at(wo, wi, self.eta, mode)
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if self.is_dispersive() {
            let sum: f32 = (0..C::LANES)
                .map(|i| self.pdf_at(wo, wi, self.lane_eta.lane(i)))
                .sum();
            return sum / C::LANES as f32;
        }
        self.pdf_at(wo, wi, self.eta)
    }

    fn eval_pdf(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> (C, f32) {
        if self.is_dispersive() {
            return self.eval_pdf_lanes(wo, wi, mode);
        }
        (self.eval(wo, wi, mode), self.pdf(wo, wi))
    }

    fn sample(&self, wo: Vec3, u1: f32, u2: Vec2, mode: TransportMode) -> Option<BsdfSample<C>> {
        if self.is_dispersive() {
            return self.sample_lanes(wo, u1, u2, mode);
        }
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
