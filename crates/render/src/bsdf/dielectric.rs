//! Smooth dielectric interface (Mitsuba `dielectric`).
//!
//! Parameters: `int_ior` (default BK7, 1.5046), `ext_ior` (default air, 1.000277),
//! `specular_reflectance` and `specular_transmittance` (default 1; physically they should stay
//! 1). Reflection or refraction is chosen with probability F / 1 − F, so the weight is the
//! tint alone, times (η_i/η_t)² for refraction in `Radiance` mode (radiance compression).
//! Naturally two-sided: `wo.z < 0` means the query comes from inside. Total internal
//! reflection gives F = 1.

use super::fresnel::{fresnel_dielectric, refract_z};
use super::{BsdfModel, BsdfSample, TransportMode, reflect_z};
use crate::math::{Vec2, Vec3};
use crate::spectral::lanes::Color;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric<C: Color = Vec3> {
    /// Relative index int_ior / ext_ior. One scalar for every lane: in spectral mode a
    /// dispersive index is resolved at the hero wavelength by the `ColorMode`, which then
    /// terminates the secondary wavelengths.
    pub eta: f32,
    pub specular_reflectance: C,
    pub specular_transmittance: C,
}

impl Dielectric {
    /// An RGB dielectric (the constructor names no colour, so it cannot infer the lanes).
    pub fn new(int_ior: f32, ext_ior: f32) -> Dielectric {
        Dielectric::with_lanes(int_ior, ext_ior)
    }
}

impl<C: Color> Dielectric<C> {
    pub fn with_lanes(int_ior: f32, ext_ior: f32) -> Dielectric<C> {
        Dielectric {
            eta: int_ior / ext_ior,
            specular_reflectance: C::ONE,
            specular_transmittance: C::ONE,
        }
    }
}

impl<C: Color> BsdfModel<C> for Dielectric<C> {
    fn eval(&self, _wo: Vec3, _wi: Vec3, _mode: TransportMode) -> C {
        C::ZERO
    }

    fn pdf(&self, _wo: Vec3, _wi: Vec3) -> f32 {
        0.0
    }

    fn sample(&self, wo: Vec3, u1: f32, _u2: Vec2, mode: TransportMode) -> Option<BsdfSample<C>> {
        if wo.z == 0.0 {
            return None;
        }
        let (r, cos_t, eta_it, eta_ti) = fresnel_dielectric(wo.z, self.eta);
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
            let scale = match mode {
                TransportMode::Radiance => eta_ti * eta_ti,
                TransportMode::Importance => 1.0,
            };
            Some(BsdfSample {
                wi: refract_z(wo, cos_t, eta_ti),
                weight: self.specular_transmittance * scale,
                pdf: 1.0 - r,
                delta: true,
                transmission: true,
                eta: eta_it,
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
