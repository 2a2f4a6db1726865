//! Smooth plastic (Mitsuba `plastic`): a diffuse base under a smooth dielectric coating.
//!
//! Parameters: `diffuse_reflectance` (default 0.5), `specular_reflectance` (default 1),
//! `int_ior` (default polypropylene, 1.49), `ext_ior` (default air, 1.000277), `nonlinear`
//! (default false). The coating reflects F(cos θo) specularly (a delta lobe); the diffuse part
//! is f = ρ/(1 − F_dr)·(1 − F(cos θo))(1 − F(cos θi))/(η² π), where F_dr is the diffuse
//! Fresnel reflectance of the inner side (internal scattering summed as a geometric series);
//! with `nonlinear` the series uses ρ·F_dr, which darkens and saturates colours.
//!
//! The specular lobe is picked with probability ∝ F·w_s versus (1 − F)(1 − w_s), where the
//! `specular_sampling_weight` w_s = mean(specular) / (mean(diffuse) + mean(specular)) is
//! computed from the *texture means* (the caller passes it when the diffuse is textured).

use super::fresnel::{fresnel_dielectric, fresnel_diffuse_reflectance};
use super::{BsdfModel, BsdfSample, TransportMode, is_positive, mean, reflect_z};
use crate::math::{INV_PI, Vec2, Vec3};
use crate::sampling::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use crate::spectral::lanes::Color;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plastic<C: Color = Vec3> {
    pub diffuse_reflectance: C,
    pub specular_reflectance: C,
    /// Relative index int_ior / ext_ior.
    pub eta: f32,
    pub nonlinear: bool,
    /// Probability weight of the specular lobe (see the module docs). Always computed from
    /// the RGB parameters (channel means, fixed 3-channel arithmetic), also in spectral mode:
    /// RGB stays bit-exact and the lobe choice does not depend on the path's wavelengths.
    pub specular_sampling_weight: f32,
    /// Diffuse Fresnel reflectance of the inside of the coating, F_dr(1/η).
    pub fdr_int: f32,
}

impl Plastic {
    /// A plastic with constant parameters (the sampling weight uses these values).
    pub fn new(
        diffuse_reflectance: Vec3,
        specular_reflectance: Vec3,
        int_ior: f32,
        ext_ior: f32,
        nonlinear: bool,
    ) -> Plastic {
        Plastic::with_weight(
            diffuse_reflectance,
            specular_reflectance,
            int_ior,
            ext_ior,
            nonlinear,
            rgb_sampling_weight(diffuse_reflectance, specular_reflectance),
        )
    }
}

/// The specular sampling weight of RGB reflectances (fixed 3-channel means; see
/// [`Plastic::specular_sampling_weight`]).
pub fn rgb_sampling_weight(diffuse: Vec3, specular: Vec3) -> f32 {
    sampling_weight(mean(diffuse), mean(specular))
}

impl<C: Color> Plastic<C> {
    /// A plastic in any colour type, with the specular sampling weight given (computed from
    /// the RGB parameters by [`rgb_sampling_weight`]).
    pub fn with_weight(
        diffuse_reflectance: C,
        specular_reflectance: C,
        int_ior: f32,
        ext_ior: f32,
        nonlinear: bool,
        specular_sampling_weight: f32,
    ) -> Plastic<C> {
        let eta = int_ior / ext_ior;
        Plastic {
            diffuse_reflectance,
            specular_reflectance,
            eta,
            nonlinear,
            specular_sampling_weight,
            fdr_int: fresnel_diffuse_reflectance(1.0 / eta),
        }
    }

    /// Diffuse albedo after the internal-scattering correction.
    #[inline]
    fn corrected_diffuse(&self) -> C {
        let d = self.diffuse_reflectance;
        if self.nonlinear {
            d / (C::ONE - d * self.fdr_int)
        } else {
            d / (1.0 - self.fdr_int)
        }
    }

    /// Probability of choosing the specular lobe given the coating reflectance `f_o`.
    #[inline]
    fn prob_specular(&self, f_o: f32) -> f32 {
        let ps = f_o * self.specular_sampling_weight;
        let pd = (1.0 - f_o) * (1.0 - self.specular_sampling_weight);
        if ps + pd > 0.0 { ps / (ps + pd) } else { 0.0 }
    }
}

/// Mitsuba's specular sampling weight from the means of the two reflectances.
pub fn sampling_weight(diffuse_mean: f32, specular_mean: f32) -> f32 {
    let s = diffuse_mean + specular_mean;
    if s > 0.0 { specular_mean / s } else { 0.5 }
}

impl<C: Color> BsdfModel<C> for Plastic<C> {
    fn eval(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> C {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return C::ZERO;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta).0;
        let f_i = fresnel_dielectric(wi.z, self.eta).0;
        let s = (1.0 - f_o) * (1.0 - f_i) / (self.eta * self.eta) * INV_PI * wi.z;
        self.corrected_diffuse() * s
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta).0;
        (1.0 - self.prob_specular(f_o)) * cosine_hemisphere_pdf(wi)
    }

    fn sample(&self, wo: Vec3, u1: f32, u2: Vec2, _mode: TransportMode) -> Option<BsdfSample<C>> {
        if wo.z <= 0.0 {
            return None;
        }
        let f_o = fresnel_dielectric(wo.z, self.eta).0;
        let p_spec = self.prob_specular(f_o);
        if u1 < p_spec {
            Some(BsdfSample {
                wi: reflect_z(wo),
                weight: self.specular_reflectance * (f_o / p_spec),
                pdf: p_spec,
                delta: true,
                transmission: false,
                eta: 1.0,
            })
        } else {
            let p_diff = 1.0 - p_spec;
            let wi = square_to_cosine_hemisphere(u2);
            let pdf = p_diff * cosine_hemisphere_pdf(wi);
            if !is_positive(pdf) {
                return None;
            }
            let f_i = fresnel_dielectric(wi.z, self.eta).0;
            let s = (1.0 - f_o) * (1.0 - f_i) / (self.eta * self.eta * p_diff);
            Some(BsdfSample::glossy_reflection(
                wi,
                self.corrected_diffuse() * s,
                pdf,
            ))
        }
    }

    fn has_delta(&self) -> bool {
        true
    }
    fn has_smooth(&self) -> bool {
        true
    }
    fn albedo(&self) -> C {
        self.diffuse_reflectance
    }
}
