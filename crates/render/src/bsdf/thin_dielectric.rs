//! Thin dielectric sheet (Mitsuba `thindielectric`): an infinitesimally thin slab whose two
//! interfaces reflect and transmit without refraction offset. Internal inter-reflections are
//! summed in closed form: R' = R + T²R/(1 − R²) = 2R/(1 + R), T' = 1 − R'. Transmitted light
//! continues in the direction −wo; `eta` of the sample is 1 (no net change of medium).
//!
//! Parameters: `int_ior` (BK7), `ext_ior` (air), `specular_reflectance`,
//! `specular_transmittance` (default 1). Two-sided.

use super::fresnel::fresnel_dielectric;
use super::{BsdfModel, BsdfSample, TransportMode, reflect_z};
use crate::math::{Vec2, Vec3};
use crate::spectral::lanes::Color;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinDielectric<C: Color = Vec3> {
    /// Relative index int_ior / ext_ior: one scalar for every lane (no dispersion).
    pub eta: f32,
    pub specular_reflectance: C,
    pub specular_transmittance: C,
}

impl ThinDielectric {
    /// An RGB thin dielectric (the constructor names no colour, so it cannot infer the lanes).
    pub fn new(int_ior: f32, ext_ior: f32) -> ThinDielectric {
        ThinDielectric::with_lanes(int_ior, ext_ior)
    }
}

impl<C: Color> ThinDielectric<C> {
    pub fn with_lanes(int_ior: f32, ext_ior: f32) -> ThinDielectric<C> {
        ThinDielectric {
            eta: int_ior / ext_ior,
            specular_reflectance: C::ONE,
            specular_transmittance: C::ONE,
        }
    }

    /// Total reflectance of the slab for a direction with cosine `cos_theta`.
    pub fn reflectance(&self, cos_theta: f32) -> f32 {
        let r = fresnel_dielectric(cos_theta.abs(), self.eta).0;
        r * 2.0 / (1.0 + r)
    }
}

impl<C: Color> BsdfModel<C> for ThinDielectric<C> {
    fn eval(&self, _wo: Vec3, _wi: Vec3, _mode: TransportMode) -> C {
        C::ZERO
    }

    fn pdf(&self, _wo: Vec3, _wi: Vec3) -> f32 {
        0.0
    }

    fn sample(&self, wo: Vec3, u1: f32, _u2: Vec2, _mode: TransportMode) -> Option<BsdfSample<C>> {
        if wo.z == 0.0 {
            return None;
        }
        let r = self.reflectance(wo.z);
        let t = 1.0 - r;
        if u1 <= r {
            Some(BsdfSample {
                wi: reflect_z(wo),
                weight: self.specular_reflectance,
                pdf: r,
                delta: true,
                transmission: false,
                eta: 1.0,
            })
        } else {
            Some(BsdfSample {
                wi: -wo,
                weight: self.specular_transmittance,
                pdf: t,
                delta: true,
                transmission: true,
                eta: 1.0,
            })
        }
    }

    fn has_delta(&self) -> bool {
        true
    }
    fn has_smooth(&self) -> bool {
        false
    }
    fn albedo(&self) -> C {
        self.specular_transmittance
    }
}
