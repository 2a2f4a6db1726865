//! Lambertian reflector (Mitsuba `diffuse`).
//!
//! Parameters: `reflectance` (default 0.5). f = reflectance/π on the front side; sampled with
//! the cosine-weighted hemisphere, so the sample weight is exactly `reflectance`.

use super::{BsdfModel, BsdfSample, TransportMode, is_positive};
use crate::math::{INV_PI, Vec2, Vec3};
use crate::sampling::warp::{cosine_hemisphere_pdf, square_to_cosine_hemisphere};
use crate::spectral::lanes::Color;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Diffuse<C: Color = Vec3> {
    pub reflectance: C,
}

impl Default for Diffuse {
    fn default() -> Self {
        Diffuse {
            reflectance: Vec3::splat(0.5),
        }
    }
}

impl<C: Color> Diffuse<C> {
    pub fn new(reflectance: C) -> Diffuse<C> {
        Diffuse { reflectance }
    }
}

impl<C: Color> BsdfModel<C> for Diffuse<C> {
    fn eval(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> C {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return C::ZERO;
        }
        self.reflectance * (INV_PI * wi.z)
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return 0.0;
        }
        cosine_hemisphere_pdf(wi)
    }

    fn eval_pdf(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> (C, f32) {
        if wo.z <= 0.0 || wi.z <= 0.0 {
            return (C::ZERO, 0.0);
        }
        (
            self.reflectance * (INV_PI * wi.z),
            cosine_hemisphere_pdf(wi),
        )
    }

    fn sample(&self, wo: Vec3, _u1: f32, u2: Vec2, _mode: TransportMode) -> Option<BsdfSample<C>> {
        if wo.z <= 0.0 {
            return None;
        }
        let wi = square_to_cosine_hemisphere(u2);
        let pdf = cosine_hemisphere_pdf(wi);
        if !is_positive(pdf) {
            return None;
        }
        Some(BsdfSample::glossy_reflection(wi, self.reflectance, pdf))
    }

    fn has_delta(&self) -> bool {
        false
    }
    fn has_smooth(&self) -> bool {
        true
    }
    fn albedo(&self) -> C {
        self.reflectance
    }
}
