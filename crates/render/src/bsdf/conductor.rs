//! Smooth conductor (Mitsuba `conductor`) and perfect mirror.
//!
//! Parameters: complex relative index `eta + i k` per RGB channel (Mitsuba's default material
//! is Cu; the caller resolves named materials) and `specular_reflectance` (default 1). The
//! reflectance is `specular_reflectance · F_conductor(cos θo)`. `eta = k = 0` means a perfect
//! mirror (F ≡ 1), which is what Mitsuba's `material="none"` and Nori's `mirror` denote.

use super::fresnel::fresnel_conductor;
use super::{BsdfModel, BsdfSample, TransportMode, reflect_z};
use crate::math::{Vec2, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor {
    pub eta: Vec3,
    pub k: Vec3,
    pub specular_reflectance: Vec3,
}

impl Conductor {
    pub fn new(eta: Vec3, k: Vec3, specular_reflectance: Vec3) -> Conductor {
        Conductor {
            eta,
            k,
            specular_reflectance,
        }
    }

    /// A perfect mirror with the given reflectance.
    pub fn mirror(reflectance: Vec3) -> Conductor {
        Conductor::new(Vec3::ZERO, Vec3::ZERO, reflectance)
    }

    /// Reflectance for a direction with cosine `cos_theta` (> 0).
    pub fn reflectance(&self, cos_theta: f32) -> Vec3 {
        self.specular_reflectance * fresnel_conductor(cos_theta, self.eta, self.k)
    }
}

impl BsdfModel for Conductor {
    fn eval(&self, _wo: Vec3, _wi: Vec3, _mode: TransportMode) -> Vec3 {
        Vec3::ZERO
    }

    fn pdf(&self, _wo: Vec3, _wi: Vec3) -> f32 {
        0.0
    }

    fn sample(&self, wo: Vec3, _u1: f32, _u2: Vec2, _mode: TransportMode) -> Option<BsdfSample> {
        if wo.z <= 0.0 {
            return None;
        }
        Some(BsdfSample {
            wi: reflect_z(wo),
            weight: self.reflectance(wo.z),
            pdf: 1.0,
            delta: true,
            transmission: false,
            eta: 1.0,
        })
    }

    fn has_delta(&self) -> bool {
        true
    }
    fn has_smooth(&self) -> bool {
        false
    }
    fn albedo(&self) -> Vec3 {
        self.reflectance(1.0)
    }
}
