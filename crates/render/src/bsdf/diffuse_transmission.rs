//! pbrt-v4's `diffusetransmission`: Lambertian reflection `reflectance` on the side the light
//! comes from and Lambertian transmission `transmittance` to the other side, from either
//! side. One lobe is sampled with probability proportional to its largest channel (of the
//! RGB values, in every colour mode), then a cosine-weighted direction on its side.

use super::{BsdfModel, BsdfSample, TransportMode, is_positive};
use crate::math::{INV_PI, Vec2, Vec3};
use crate::sampling::warp::square_to_cosine_hemisphere;
use crate::spectral::lanes::Color;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DiffuseTransmission<C: Color = Vec3> {
    pub reflectance: C,
    pub transmittance: C,
    /// The probability of sampling reflection.
    p_reflect: f32,
}

impl<C: Color> DiffuseTransmission<C> {
    /// `weights`: the largest channels of the reflectance and transmittance, which pick the
    /// lobe to sample.
    pub fn new(reflectance: C, transmittance: C, weights: (f32, f32)) -> DiffuseTransmission<C> {
        let (r, t) = (weights.0.max(0.0), weights.1.max(0.0));
        DiffuseTransmission {
            reflectance,
            transmittance,
            p_reflect: if r + t > 0.0 { r / (r + t) } else { 0.5 },
        }
    }
}

impl<C: Color> BsdfModel<C> for DiffuseTransmission<C> {
    fn eval(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> C {
        if wo.z == 0.0 || wi.z == 0.0 {
            return C::ZERO;
        }
        let lobe = if wo.z * wi.z > 0.0 {
            self.reflectance
        } else {
            self.transmittance
        };
        lobe * (INV_PI * wi.z.abs())
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z == 0.0 || wi.z == 0.0 {
            return 0.0;
        }
        let p = if wo.z * wi.z > 0.0 {
            self.p_reflect
        } else {
            1.0 - self.p_reflect
        };
        p * INV_PI * wi.z.abs()
    }

    fn sample(&self, wo: Vec3, u1: f32, u2: Vec2, _mode: TransportMode) -> Option<BsdfSample<C>> {
        if wo.z == 0.0 {
            return None;
        }
        let mut wi = square_to_cosine_hemisphere(u2);
        let reflect = u1 < self.p_reflect;
        // Cosine-weighted on wo's side for reflection, on the other side for transmission.
        if (wo.z < 0.0) == reflect {
            wi.z = -wi.z;
        }
        let (lobe, p) = if reflect {
            (self.reflectance, self.p_reflect)
        } else {
            (self.transmittance, 1.0 - self.p_reflect)
        };
        let pdf = p * INV_PI * wi.z.abs();
        if !is_positive(pdf) {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight: lobe / p,
            pdf,
            delta: false,
            transmission: !reflect,
            eta: 1.0,
        })
    }

    fn has_delta(&self) -> bool {
        false
    }
    fn has_smooth(&self) -> bool {
        true
    }
    fn albedo(&self) -> C {
        self.reflectance + self.transmittance
    }
}
