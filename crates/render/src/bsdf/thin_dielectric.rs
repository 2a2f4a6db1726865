//! Thin dielectric sheet (Mitsuba `thindielectric`): an infinitesimally thin slab whose two
//! interfaces reflect and transmit without refraction offset. Internal inter-reflections are
//! summed in closed form: R' = R + T²R/(1 − R²) = 2R/(1 + R), T' = 1 − R'. Transmitted light
//! continues in the direction −wo; `eta` of the sample is 1 (no net change of medium).
//!
//! Parameters: `int_ior` (BK7), `ext_ior` (air), `specular_reflectance`,
//! `specular_transmittance` (default 1). Two-sided.
//!
//! **Dispersion** (spectral mode, issue 21): both outgoing directions (the mirror one and −wo)
//! are the same at every wavelength, so a dispersive sheet keeps all four wavelengths with no
//! termination and no colour noise from it: each lane has its own reflectance R_i at its own
//! index ([`ThinDielectric::lane_eta`]), reflection is chosen with the lanes' mean
//! R̄ = ¼ Σ R_i, and lane i's weight is R_i/R̄ (reflection) or (1 − R_i)/(1 − R̄)
//! (transmission): unbiased per lane whenever R̄ ∈ (0, 1).

use super::fresnel::fresnel_dielectric;
use super::{BsdfModel, BsdfSample, TransportMode, reflect_z};
use crate::math::{Vec2, Vec3};
use crate::spectral::lanes::Color;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThinDielectric<C: Color = Vec3> {
    /// Relative index int_ior / ext_ior, shared by every lane unless the sheet is dispersive
    /// (then lane 0's).
    pub eta: f32,
    /// Each lane's relative index: `eta` in every lane but in spectral mode with a dispersive
    /// index, where it is the index at each wavelength.
    pub lane_eta: C,
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
    /// One index for every lane.
    pub fn with_lanes(int_ior: f32, ext_ior: f32) -> ThinDielectric<C> {
        ThinDielectric::with_lane_ior(C::splat(int_ior), ext_ior)
    }

    /// An index per lane (`ColorMode::lane_ior`): dispersive when the lanes differ.
    pub fn with_lane_ior(int_ior: C, ext_ior: f32) -> ThinDielectric<C> {
        ThinDielectric {
            eta: int_ior.lane(0) / ext_ior,
            lane_eta: int_ior / ext_ior,
            specular_reflectance: C::ONE,
            specular_transmittance: C::ONE,
        }
    }

    /// Whether the lanes' indices differ (never for RGB's 3 lanes).
    #[inline]
    pub fn is_dispersive(&self) -> bool {
        super::fresnel::lanes_disperse(self.lane_eta, self.eta)
    }

    /// Total reflectance of the slab for a direction with cosine `cos_theta`.
    pub fn reflectance(&self, cos_theta: f32) -> f32 {
        slab_reflectance(cos_theta, self.eta)
    }

    /// The dispersive sample (module documentation).
    fn sample_lanes(&self, wo: Vec3, u1: f32) -> BsdfSample<C> {
        let r = C::from_fn(|i| slab_reflectance(wo.z, self.lane_eta.lane(i)));
        let p = r.mean();
        if u1 < p {
            BsdfSample {
                wi: reflect_z(wo),
                weight: self.specular_reflectance * r / p,
                pdf: p,
                delta: true,
                transmission: false,
                eta: 1.0,
            }
        } else {
            BsdfSample {
                wi: -wo,
                weight: self.specular_transmittance * (C::ONE - r) / (1.0 - p),
                pdf: 1.0 - p,
                delta: true,
                transmission: true,
                eta: 1.0,
            }
        }
    }
}

/// R' = 2R/(1 + R) of a slab of relative index `eta`.
#[inline]
fn slab_reflectance(cos_theta: f32, eta: f32) -> f32 {
    let r = fresnel_dielectric(cos_theta.abs(), eta).0;
    r * 2.0 / (1.0 + r)
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
        if self.is_dispersive() {
            return Some(self.sample_lanes(wo, u1));
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
