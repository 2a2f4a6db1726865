//! Smooth conductor (Mitsuba `conductor`) and perfect mirror.
//!
//! Parameters: complex relative index `eta + i k` per RGB channel (Mitsuba's default material
//! is Cu; the caller resolves named materials) and `specular_reflectance` (default 1). The
//! reflectance is `specular_reflectance · F_conductor(cos θo)`. `eta = k = 0` means a perfect
//! mirror (F ≡ 1), which is what Mitsuba's `material="none"` and Nori's `mirror` denote.

use super::fresnel::fresnel_conductor;
use super::{BsdfModel, BsdfSample, TransportMode, reflect_z};
use crate::math::{Vec2, Vec3};
use crate::spectral::lanes::Color;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Conductor<C: Color = Vec3> {
    pub eta: C,
    pub k: C,
    pub specular_reflectance: C,
}

impl<C: Color> Conductor<C> {
    pub fn new(eta: C, k: C, specular_reflectance: C) -> Conductor<C> {
        Conductor {
            eta,
            k,
            specular_reflectance,
        }
    }

    /// A perfect mirror with the given reflectance.
    pub fn mirror(reflectance: C) -> Conductor<C> {
        Conductor::new(C::ZERO, C::ZERO, reflectance)
    }

    /// Reflectance for a direction with cosine `cos_theta` (> 0).
    pub fn reflectance(&self, cos_theta: f32) -> C {
        self.specular_reflectance * fresnel_conductor(cos_theta, self.eta, self.k)
    }
}

impl<C: Color> BsdfModel<C> for Conductor<C> {
    fn eval(&self, _wo: Vec3, _wi: Vec3, _mode: TransportMode) -> C {
        C::ZERO
    }

    fn pdf(&self, _wo: Vec3, _wi: Vec3) -> f32 {
        0.0
    }

    fn sample(&self, wo: Vec3, _u1: f32, _u2: Vec2, _mode: TransportMode) -> Option<BsdfSample<C>> {
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
    fn albedo(&self) -> C {
        self.reflectance(1.0)
    }
}
