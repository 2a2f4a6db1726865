//! Mitsuba 3's `principledthin` BSDF (Burley 2015's thin-surface variant, as Mitsuba 3.9
//! defines it in `src/bsdfs/principledthin.cpp`): a two-sided sheet with no interior.
//!
//! Both sides are fronts: a query with `wo.z < 0` is mirrored to the upper side first. With
//! `st` = spec_trans and `dt` = diff_trans / 2 (Mitsuba's parameter runs over 0..2):
//! - specular reflection: st·F·D·G / (4 cos θo), GGX of (roughness, anisotropic) as in
//!   `principled`, F the dielectric Fresnel at the half vector blended by `spec_tint` with
//!   Schlick's of the luminance-normalised base colour times ((η − 1)/(η + 1))²;
//! - specular transmission without bending: the reflected direction mirrored through the
//!   sheet, st·base_color·(1 − F)·D'·G' / (4 cos θo) with D' a GGX of roughness scaled by
//!   0.65η − 0.35 (Burley 2015, fig. 15), at the half vector of the unmirrored reflection;
//! - diffuse reflection (with retro-reflection and `flatness`'s fake subsurface) and sheen,
//!   both times (1 − st)(1 − dt), only while st < 1 and dt < 1;
//! - Lambertian transmission (1 − st)·dt·base_color / π.
//!
//! Sampling is Mitsuba's: lobes chosen with probabilities ∝ st·rate_sr/2, st·rate_st/2,
//! (1 − st)(1 − dt)·rate_dr and (1 − st)·dt·rate_dt; visible GGX normals for the specular
//! lobes, cosine-weighted directions for the diffuse ones; `sample` returns eval/pdf of the
//! whole mixture. Light passes straight through (η = 1 along the path); the transport mode is
//! ignored, as Mitsuba does.

use super::fresnel::fresnel_dielectric;
use super::microfacet::{Microfacet, MicrofacetType};
use super::principled::{
    disney_alphas, disney_diffuse, luminance, microfacet_compatible, schlick, schlick_r0,
    schlick_weight, schlick_weight_at,
};
use super::{BsdfModel, BsdfSample, TransportMode, is_positive, reflect_z_about};
use crate::math::{INV_PI, Vec2, Vec3};
use crate::sampling::warp::square_to_cosine_hemisphere;
use crate::spectral::lanes::Color;

/// Mitsuba's `principledthin`, parameters evaluated at one point.
#[derive(Clone, Debug, PartialEq)]
pub struct PrincipledThin<C: Color = Vec3> {
    pub base_color: C,
    /// base_color / its luminance (1 where the luminance is 0): the tint of `spec_tint` and
    /// `sheen_tint`.
    pub tint: C,
    pub roughness: f32,
    pub anisotropic: f32,
    pub spec_trans: f32,
    pub spec_tint: f32,
    pub sheen: f32,
    pub sheen_tint: f32,
    pub flatness: f32,
    /// Mitsuba's `diff_trans`, in 0..2 (2: all diffuse energy transmitted).
    pub diff_trans: f32,
    /// Index of the sheet relative to the outside (Fresnel, tint and transmission roughness).
    pub eta: f32,
    /// Sampling rates: specular reflection, specular transmission, diffuse reflection,
    /// diffuse transmission.
    pub rates: [f32; 4],
}

impl PrincipledThin {
    /// An RGB thin principled BSDF with Mitsuba's defaults but for `base_color`.
    pub fn new(base_color: Vec3) -> PrincipledThin {
        PrincipledThin::with_base(base_color, base_color)
    }
}

impl<C: Color> PrincipledThin<C> {
    /// Mitsuba's defaults (roughness 0.5, η 1.5, everything else 0, rates 1) with the base
    /// colour in the path's colour type and its RGB value (for the luminance of the tints).
    pub fn with_base(base_color: C, base_rgb: Vec3) -> PrincipledThin<C> {
        let lum = luminance(base_rgb);
        PrincipledThin {
            base_color,
            tint: if lum > 0.0 { base_color / lum } else { C::ONE },
            roughness: 0.5,
            anisotropic: 0.0,
            spec_trans: 0.0,
            spec_tint: 0.0,
            sheen: 0.0,
            sheen_tint: 0.0,
            flatness: 0.0,
            diff_trans: 0.0,
            eta: 1.5,
            rates: [1.0; 4],
        }
    }

    /// Has a transmission lobe.
    pub fn transmits(&self) -> bool {
        self.spec_trans > 0.0 || self.diff_trans > 0.0
    }

    /// The GGX of the specular reflection.
    fn reflection_distribution(&self) -> Microfacet {
        let (au, av) = disney_alphas(self.anisotropic, self.roughness);
        Microfacet::new(MicrofacetType::Ggx, au, av)
    }

    /// The GGX of the specular transmission: roughness scaled by 0.65η − 0.35.
    fn transmission_distribution(&self) -> Microfacet {
        let r = (0.65 * self.eta - 0.35) * self.roughness;
        let (au, av) = disney_alphas(self.anisotropic, r);
        Microfacet::new(MicrofacetType::Ggx, au, av)
    }

    /// Lobe probabilities (specular reflection, specular transmission, diffuse reflection,
    /// diffuse transmission), normalised; `None` when none can be sampled.
    fn lobe_probs(&self) -> Option<[f32; 4]> {
        let (st, dt) = (self.spec_trans, 0.5 * self.diff_trans);
        let [sr, srt, dr, drt] = self.rates;
        let p = [
            st * sr * 0.5,
            st * srt * 0.5,
            dr * (1.0 - st) * (1.0 - dt),
            drt * (1.0 - st) * dt,
        ];
        let total = p[0] + p[1] + p[2] + p[3];
        is_positive(total).then(|| p.map(|x| x / total))
    }

    /// Both directions mirrored so that `wo` is above the sheet, and the half vector of `wo`
    /// and `wi` brought above it (the reflection's half vector, also for transmission).
    #[inline]
    fn upper(wo: Vec3, wi: Vec3) -> (Vec3, Vec3, Vec3) {
        let s = if wo.z < 0.0 { -1.0 } else { 1.0 };
        let (wo, wi) = (wo * s, wi * s);
        let wi_r = Vec3::new(wi.x, wi.y, wi.z.abs());
        (wo, wi, (wo + wi_r).normalize_or_zero())
    }
}

impl<C: Color> BsdfModel<C> for PrincipledThin<C> {
    fn eval(&self, wo: Vec3, wi: Vec3, _mode: TransportMode) -> C {
        if wo.z == 0.0 {
            return C::ZERO;
        }
        let (wo, wi, h) = Self::upper(wo, wi);
        let (cos_o, cos_i) = (wo.z, wi.z);
        let (reflect, refract) = (cos_i > 0.0, cos_i < 0.0);
        let (st, dt) = (self.spec_trans, 0.5 * self.diff_trans);
        let mut value = C::ZERO;
        if st > 0.0 {
            let wo_h = wo.dot(h);
            let f = fresnel_dielectric(wo_h, self.eta).0;
            if reflect && microfacet_compatible(h, wo, wi, cos_o, true) {
                let distr = self.reflection_distribution();
                let dg = distr.eval(h) * distr.g(wo, wi, h);
                let mut fresnel = C::splat(f * (1.0 - self.spec_tint));
                if self.spec_tint > 0.0 {
                    let w = schlick_weight_at(wo_h, self.eta);
                    fresnel += schlick(self.tint * schlick_r0(self.eta), w) * self.spec_tint;
                }
                value += fresnel * (st * dg / (4.0 * cos_o));
            }
            if refract && microfacet_compatible(h, wo, wi, cos_o, false) {
                let distr = self.transmission_distribution();
                let dg = distr.eval(h) * distr.g(wo, wi, h);
                value += self.base_color * (st * (1.0 - f) * dg / (4.0 * cos_o));
            }
        }
        if reflect && st < 1.0 && dt < 1.0 {
            let cos_d = h.dot(wi);
            let d = disney_diffuse(cos_o, cos_i, cos_d, self.roughness, self.flatness);
            let w = (1.0 - st) * (1.0 - dt);
            value += self.base_color * (w * cos_i * INV_PI * d);
            if self.sheen > 0.0 {
                let fd = schlick_weight(cos_d.abs());
                let c_sheen = C::ONE + (self.tint - C::ONE) * self.sheen_tint;
                value += c_sheen * (self.sheen * w * fd * cos_i);
            }
        }
        if refract && st < 1.0 && dt > 0.0 {
            value += self.base_color * ((1.0 - st) * dt * INV_PI * -cos_i);
        }
        value
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if wo.z == 0.0 {
            return 0.0;
        }
        let Some([p_sr, p_st, p_dr, p_dt]) = self.lobe_probs() else {
            return 0.0;
        };
        let (wo, wi, h) = Self::upper(wo, wi);
        let mut pdf = 0.0;
        if wi.z > 0.0 {
            if p_sr > 0.0 && microfacet_compatible(h, wo, wi, wo.z, true) {
                let jacobian = 1.0 / (4.0 * wi.dot(h)).abs();
                pdf += p_sr * self.reflection_distribution().pdf(wo, h) * jacobian;
            }
            pdf += p_dr * wi.z * INV_PI;
        } else if wi.z < 0.0 {
            if p_st > 0.0 && microfacet_compatible(h, wo, wi, wo.z, false) {
                let wi_r = Vec3::new(wi.x, wi.y, -wi.z);
                let jacobian = 1.0 / (4.0 * wi_r.dot(h)).abs();
                pdf += p_st * self.transmission_distribution().pdf(wo, h) * jacobian;
            }
            pdf += p_dt * -wi.z * INV_PI;
        }
        if pdf.is_finite() { pdf } else { 0.0 }
    }

    fn sample(&self, wo: Vec3, u1: f32, u2: Vec2, mode: TransportMode) -> Option<BsdfSample<C>> {
        if wo.z == 0.0 {
            return None;
        }
        let [p_sr, p_st, p_dr, p_dt] = self.lobe_probs()?;
        let s = if wo.z < 0.0 { -1.0 } else { 1.0 };
        let wo_up = wo * s;
        let wi_up = if u1 < p_sr {
            let m = self.reflection_distribution().sample(wo_up, u2).0;
            let wi = reflect_z_about(wo_up, m);
            if wi.z <= 0.0 || !microfacet_compatible(m, wo_up, wi, wo_up.z, true) {
                return None;
            }
            wi
        } else if u1 < p_sr + p_st {
            let m = self.transmission_distribution().sample(wo_up, u2).0;
            let r = reflect_z_about(wo_up, m);
            let wi = Vec3::new(r.x, r.y, -r.z);
            if wi.z >= 0.0 || !microfacet_compatible(m, wo_up, wi, wo_up.z, false) {
                return None;
            }
            wi
        } else if u1 < p_sr + p_st + p_dr || p_dt <= 0.0 {
            square_to_cosine_hemisphere(u2)
        } else {
            -square_to_cosine_hemisphere(u2)
        };
        if wi_up.z == 0.0 {
            return None;
        }
        let wi = wi_up * s;
        let pdf = self.pdf(wo, wi);
        if !is_positive(pdf) {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight: self.eval(wo, wi, mode) / pdf,
            pdf,
            delta: false,
            transmission: wi_up.z < 0.0,
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
        self.base_color
    }
}
