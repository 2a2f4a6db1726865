//! Rough plastic (Mitsuba `roughplastic`): a diffuse base under a rough dielectric coating.
//!
//! Parameters: `distribution` (Beckmann default, or GGX; isotropic only), `alpha` (default
//! 0.1), `diffuse_reflectance` (0.5), `specular_reflectance` (1), `int_ior` (polypropylene
//! 1.49), `ext_ior` (air), `nonlinear` (false).
//!
//! f = F·D·G/(4 cos θo cos θi)·specular + ρ/(1 − R_int)·T(cos θo)·T(cos θi)/(η² π), where
//! T(μ) is the coating's single-scattering transmittance (tabulated at 64 cosines and
//! interpolated linearly, as Mitsuba) and R_int = 2∫ R_{1/η}(μ) μ dμ the internal
//! hemispherical reflectance (`nonlinear` uses ρ·R_int). Both lobes are sampled: the
//! specular one (visible normals) with probability ∝ (1 − T(cos θo))·w_s, the diffuse one
//! ∝ T(cos θo)·(1 − w_s); pdf and weight are those of the mixture.
//!
//! The tables cost ~10⁵ distribution samples to build: build a [`RoughPlasticTables`] once per
//! material (at scene build time) and share it (an `Arc`) with each per-hit `RoughPlastic`:
//! stored inline, the 64-entry table made every `Bsdf` ~300 bytes, copied several times per
//! hit whatever the material.

use std::sync::Arc;

use super::fresnel::fresnel_dielectric;
use super::microfacet::{Microfacet, MicrofacetType, eval_reflectance, eval_transmittance};
use super::plastic::rgb_sampling_weight;
use super::{BsdfModel, BsdfSample, TransportMode, mixture_reflection_sample, reflect_z_about};
use crate::math::{INV_PI, Vec2, Vec3};
use crate::sampling::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use crate::spectral::lanes::Color;

/// Resolution of the transmittance table (Mitsuba's `MI_ROUGH_TRANSMITTANCE_RES`).
pub const ROUGH_TRANSMITTANCE_RES: usize = 64;

/// Precomputed coating transmittance and internal reflectance for one (distribution, α, η).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoughPlasticTables {
    pub external_transmittance: [f32; ROUGH_TRANSMITTANCE_RES],
    pub internal_reflectance: f32,
}

impl RoughPlasticTables {
    pub fn new(distribution: Microfacet, eta: f32) -> RoughPlasticTables {
        use rayon::prelude::*;
        // The 64 cosines are independent: evaluated in parallel (on the current rayon pool),
        // then summed in order, so that the tables are the sequential loop's bit for bit
        // (tested below). A material edit from Python (`scene.update`) rebuilds one table.
        let rows: Vec<(f32, f32)> = (0..ROUGH_TRANSMITTANCE_RES)
            .into_par_iter()
            .map(|i| {
                let mu = (i as f32 / (ROUGH_TRANSMITTANCE_RES - 1) as f32).max(1e-6);
                (
                    eval_transmittance(&distribution, mu, eta),
                    eval_reflectance(&distribution, mu, 1.0 / eta) * mu,
                )
            })
            .collect();
        let mut external_transmittance = [0.0; ROUGH_TRANSMITTANCE_RES];
        let mut internal = 0.0f64;
        for (t, (transmittance, reflectance)) in external_transmittance.iter_mut().zip(rows) {
            *t = transmittance;
            internal += reflectance as f64;
        }
        RoughPlasticTables {
            external_transmittance,
            internal_reflectance: (2.0 * internal / ROUGH_TRANSMITTANCE_RES as f64) as f32,
        }
    }

    /// Linear interpolation of the transmittance table at cosine `x` ∈ [0, 1].
    #[inline]
    pub fn transmittance(&self, x: f32) -> f32 {
        let x = x.clamp(0.0, 1.0) * (ROUGH_TRANSMITTANCE_RES - 1) as f32;
        let i = (x as usize).min(ROUGH_TRANSMITTANCE_RES - 2);
        let w = x - i as f32;
        let t = &self.external_transmittance;
        (1.0 - w) * t[i] + w * t[i + 1]
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct RoughPlastic<C: Color = Vec3> {
    pub distribution: Microfacet,
    /// Relative index int_ior / ext_ior.
    pub eta: f32,
    pub diffuse_reflectance: C,
    pub specular_reflectance: C,
    pub nonlinear: bool,
    /// mean(specular) / (mean(diffuse) + mean(specular)), from the texture means. Always
    /// computed from the RGB parameters (fixed 3-channel means), also in spectral mode.
    pub specular_sampling_weight: f32,
    /// Shared with the material (built once per material): keeps the per-hit `Bsdf` small.
    pub tables: Arc<RoughPlasticTables>,
}

impl RoughPlastic {
    /// Builds the tables (expensive; see the module docs).
    pub fn new(
        kind: MicrofacetType,
        alpha: f32,
        int_ior: f32,
        ext_ior: f32,
        diffuse_reflectance: Vec3,
        specular_reflectance: Vec3,
        nonlinear: bool,
    ) -> RoughPlastic {
        let distribution = Microfacet::isotropic(kind, alpha);
        let eta = int_ior / ext_ior;
        RoughPlastic::with_tables(
            distribution,
            eta,
            Arc::new(RoughPlasticTables::new(distribution, eta)),
            diffuse_reflectance,
            specular_reflectance,
            nonlinear,
        )
    }

    /// Cheap constructor from precomputed tables (must match `distribution` and `eta`).
    pub fn with_tables(
        distribution: Microfacet,
        eta: f32,
        tables: Arc<RoughPlasticTables>,
        diffuse_reflectance: Vec3,
        specular_reflectance: Vec3,
        nonlinear: bool,
    ) -> RoughPlastic {
        RoughPlastic::with_tables_weighted(
            distribution,
            eta,
            tables,
            diffuse_reflectance,
            specular_reflectance,
            nonlinear,
            rgb_sampling_weight(diffuse_reflectance, specular_reflectance),
        )
    }
}

impl<C: Color> RoughPlastic<C> {
    /// [`RoughPlastic::with_tables`] in any colour type, with the specular sampling weight
    /// given (computed from the RGB parameters by [`rgb_sampling_weight`]).
    pub fn with_tables_weighted(
        distribution: Microfacet,
        eta: f32,
        tables: Arc<RoughPlasticTables>,
        diffuse_reflectance: C,
        specular_reflectance: C,
        nonlinear: bool,
        specular_sampling_weight: f32,
    ) -> RoughPlastic<C> {
        RoughPlastic {
            distribution,
            eta,
            diffuse_reflectance,
            specular_reflectance,
            nonlinear,
            specular_sampling_weight,
            tables,
        }
    }

    #[inline]
    fn prob_specular(&self, t_o: f32) -> f32 {
        let ps = (1.0 - t_o) * self.specular_sampling_weight;
        let pd = t_o * (1.0 - self.specular_sampling_weight);
        if ps + pd > 0.0 { ps / (ps + pd) } else { 0.0 }
    }
}

impl<C: Color> BsdfModel<C> for RoughPlastic<C> {
    fn eval(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> C {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return C::ZERO;
        }
        let h = (wo + wi).normalize();
        let d = self.distribution.eval(h);
        let spec = if d > 0.0 {
            let f = fresnel_dielectric(wo.dot(h), self.eta).0;
            let g = self.distribution.g(wo, wi, h);
            self.specular_reflectance * (f * d * g / (4.0 * wo.z))
        } else {
            C::ZERO
        };
        let t_o = self.tables.transmittance(wo.z);
        let t_i = self.tables.transmittance(wi.z);
        let rd = self.diffuse_reflectance;
        let r_int = self.tables.internal_reflectance;
        let diff = if self.nonlinear {
            rd / (C::ONE - rd * r_int)
        } else {
            rd / (1.0 - r_int)
        };
        spec + diff * (INV_PI / (self.eta * self.eta) * wi.z * t_o * t_i)
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let p_spec = self.prob_specular(self.tables.transmittance(wo.z));
        let h = (wo + wi).normalize();
        let spec = self.distribution.eval(h) * self.distribution.smith_g1(wo, h) / (4.0 * wo.z);
        p_spec * spec + (1.0 - p_spec) * cosine_hemisphere_pdf(wi)
    }

    fn sample(&self, wo: Vec3, u1: f32, u2: Vec2, mode: TransportMode) -> Option<BsdfSample<C>> {
        if wo.z <= 0.0 {
            return None;
        }
        let p_spec = self.prob_specular(self.tables.transmittance(wo.z));
        let wi = if u1 < p_spec {
            let (m, _) = self.distribution.sample(wo, u2);
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
        self.diffuse_reflectance
    }
}

#[cfg(test)]
mod table_tests {
    use super::*;

    /// The parallel tables are the sequential loop's (Mitsuba's order of summation), bit for
    /// bit: renders do not change with the thread count.
    #[test]
    fn tables_are_the_sequential_loops_bit_for_bit() {
        for kind in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
            for (alpha, eta) in [(0.05, 1.5), (0.3, 1.49), (0.7, 1.0 / 1.33)] {
                let d = Microfacet::isotropic(kind, alpha);
                let mut t = [0.0f32; ROUGH_TRANSMITTANCE_RES];
                let mut internal = 0.0f64;
                for (i, t) in t.iter_mut().enumerate() {
                    let mu = (i as f32 / (ROUGH_TRANSMITTANCE_RES - 1) as f32).max(1e-6);
                    *t = eval_transmittance(&d, mu, eta);
                    internal += (eval_reflectance(&d, mu, 1.0 / eta) * mu) as f64;
                }
                let r = (2.0 * internal / ROUGH_TRANSMITTANCE_RES as f64) as f32;
                let tables = RoughPlasticTables::new(d, eta);
                assert_eq!(tables.internal_reflectance.to_bits(), r.to_bits());
                assert!(
                    tables
                        .external_transmittance
                        .iter()
                        .zip(&t)
                        .all(|(a, b)| a.to_bits() == b.to_bits())
                );
            }
        }
    }
}
