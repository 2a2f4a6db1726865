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

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    /// Relative index int_ior / ext_ior.
    pub eta: f32,
    pub specular_reflectance: Vec3,
    pub specular_transmittance: Vec3,
}

impl Dielectric {
    pub fn new(int_ior: f32, ext_ior: f32) -> Dielectric {
        Dielectric {
            eta: int_ior / ext_ior,
            specular_reflectance: Vec3::ONE,
            specular_transmittance: Vec3::ONE,
        }
    }
}

impl BsdfModel for Dielectric {
    fn eval(&self, _wo: Vec3, _wi: Vec3, _mode: TransportMode) -> Vec3 {
        Vec3::ZERO
    }

    fn pdf(&self, _wo: Vec3, _wi: Vec3) -> f32 {
        0.0
    }

    fn sample(&self, wo: Vec3, u1: f32, _u2: Vec2, mode: TransportMode) -> Option<BsdfSample> {
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
    fn albedo(&self) -> Vec3 {
        self.specular_transmittance
    }
}
