//! Mitsuba 3's Disney-style `principled` BSDF (Burley 2012, 2015, as Mitsuba 3.9 defines it
//! in `src/bsdfs/principled.cpp`), and the helpers its thin variant shares.
//!
//! Lobes, in Mitsuba's weights (`brdf` = (1 − metallic)(1 − spec_trans),
//! `bsdf` = (1 − metallic)·spec_trans):
//! - main specular reflection: anisotropic GGX (α = max(10⁻³, r²/a), max(10⁻³, r²·a) with
//!   a = √(1 − 0.9·anisotropic)), Smith G, and a Fresnel term blending the dielectric one
//!   (weight (1 − metallic)(1 − spec_tint)) with Schlick's of the base colour (metallic) and
//!   of the tinted dielectric F0 (spec_tint); from inside, bsdf·F only;
//! - specular transmission: √base_color·bsdf times Walter et al.'s rough refraction;
//! - clearcoat: 0.25·clearcoat·F_schlick(0.04)·D_GTR1·G(α = 0.25)·|cos θi| — Mitsuba's value,
//!   without the 1/(4 cos θo cos θi) of the course notes;
//! - diffuse with retro-reflection, blended towards Hanrahan–Krueger's fake subsurface by
//!   `flatness`; and sheen, which Mitsuba's vectorised variants add wherever sheen > 0 and
//!   metallic < 1, also where `brdf` is 0 (its scalar variants skip it there).
//!
//! Sampling is Mitsuba's: a lobe chosen with probabilities ∝ main_specular_sampling_rate·
//! (1 − bsdf(1 − F)) (reflection), ·bsdf(1 − F) (transmission), 0.25·clearcoat·
//! clearcoat_sampling_rate, brdf·diffuse_reflectance_sampling_rate (from inside: F and 1 − F
//! only), F the dielectric Fresnel at the visible normal drawn for the specular lobes (or at
//! the half vector, for the density); GTR1 normals (not visible ones) for the clearcoat,
//! cosine-weighted directions for the diffuse lobe. `sample` returns eval/pdf of the whole
//! mixture, as Mitsuba does.
//!
//! `eta` is the interior/exterior index (from `specular` s: η = 2/(1 − √(0.08 s)) − 1); the
//! model is two-sided through its transmission lobe: `wo.z < 0` is a query from inside.

use super::fresnel::{fresnel_dielectric, refract_m};
use super::microfacet::{Microfacet, MicrofacetType};
use super::{BsdfModel, BsdfSample, TransportMode, is_positive, reflect_z_about};
use crate::math::{INV_PI, PI, Vec2, Vec3, safe_sqrt};
use crate::sampling::warp::{self, square_to_cosine_hemisphere};
use crate::spectral::lanes::Color;

/// Rec. 709 luminance of linear RGB (Mitsuba's `luminance` in its RGB variants).
#[inline]
pub fn luminance(rgb: Vec3) -> f32 {
    0.212_671 * rgb.x + 0.715_160 * rgb.y + 0.072_169 * rgb.z
}

/// (1 − cos)⁵ clamped (Schlick's weight).
#[inline]
pub(crate) fn schlick_weight(cos: f32) -> f32 {
    let m = (1.0 - cos).clamp(0.0, 1.0);
    let m2 = m * m;
    m2 * m2 * m
}

/// Schlick's Fresnel with reflectance `r0` at normal incidence, at the signed cosine
/// `cos_i` of an interface of relative index `eta`: from the denser side, the transmitted
/// angle's cosine is used (Mitsuba's `calc_schlick`).
#[inline]
pub(crate) fn schlick_weight_at(cos_i: f32, eta: f32) -> f32 {
    let outside = cos_i >= 0.0;
    let (eta_it, eta_ti) = if outside {
        (eta, 1.0 / eta)
    } else {
        (1.0 / eta, eta)
    };
    if eta_it > 1.0 {
        schlick_weight(cos_i.abs())
    } else {
        let cos_t = safe_sqrt(1.0 - eta_ti * eta_ti * (1.0 - cos_i * cos_i));
        schlick_weight(cos_t)
    }
}

/// `r0 + (1 − r0)·w` per lane.
#[inline]
pub(crate) fn schlick<C: Color>(r0: C, w: f32) -> C {
    r0 * (1.0 - w) + C::splat(w)
}

/// ((η − 1)/(η + 1))².
#[inline]
pub(crate) fn schlick_r0(eta: f32) -> f32 {
    let r = (eta - 1.0) / (eta + 1.0);
    r * r
}

/// Disney's roughness and anisotropy → GGX (α_u, α_v), Mitsuba's `calc_dist_params`.
#[inline]
pub fn disney_alphas(anisotropic: f32, roughness: f32) -> (f32, f32) {
    let r2 = roughness * roughness;
    let aspect = (1.0 - 0.9 * anisotropic).max(0.0).sqrt();
    ((r2 / aspect).max(1e-3), (r2 * aspect).max(1e-3))
}

/// Both directions on the sides a microfacet `m` allows, for the macro side of `cos_o`:
/// a reflection keeps both in front of `m`, a transmission puts `wi` behind it.
#[inline]
pub(crate) fn microfacet_compatible(
    m: Vec3,
    wo: Vec3,
    wi: Vec3,
    cos_o: f32,
    reflect: bool,
) -> bool {
    let m = if cos_o < 0.0 { -m } else { m };
    wo.dot(m) > 0.0
        && if reflect {
            wi.dot(m) > 0.0
        } else {
            wi.dot(m) < 0.0
        }
}

/// Per-lane square root (of non-negative values).
#[inline]
pub(crate) fn sqrt_lanes<C: Color>(c: C) -> C {
    C::from_fn(|i| c.lane(i).max(0.0).sqrt())
}

/// Burley's GTR1 (Berry) distribution of the clearcoat normals, with α ∈ (0, 1).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Gtr1 {
    alpha: f32,
}

impl Gtr1 {
    fn eval(&self, m: Vec3) -> f32 {
        let a2 = self.alpha * self.alpha;
        let c = m.z;
        let d = (a2 - 1.0) / (PI * a2.ln() * (1.0 + (a2 - 1.0) * c * c));
        if d * c > 1e-20 { d } else { 0.0 }
    }

    fn pdf(&self, m: Vec3) -> f32 {
        if m.z < 0.0 { 0.0 } else { m.z * self.eval(m) }
    }

    fn sample(&self, u: Vec2) -> Vec3 {
        let (sp, cp) = warp::sin_cos_2pi(u.x);
        let a2 = self.alpha * self.alpha;
        let cos2 = (1.0 - a2.powf(1.0 - u.y)) / (1.0 - a2);
        let sin_t = (1.0 - cos2).max(0.0).sqrt();
        Vec3::new(cp * sin_t, sp * sin_t, cos2.max(0.0).sqrt())
    }
}

/// Smith's G1 of an isotropic GGX of roughness `alpha` (the clearcoat's, α = 0.25).
fn smith_ggx1(v: Vec3, m: Vec3, alpha: f32) -> f32 {
    if v.dot(m) * v.z <= 0.0 {
        return 0.0;
    }
    if v.z == 1.0 {
        return 1.0;
    }
    let c2 = v.z * v.z;
    let tan2 = (1.0 - c2) / c2;
    2.0 / (1.0 + (1.0 + alpha * alpha * tan2).sqrt())
}

/// The diffuse, retro-reflection and fake-subsurface factor (times 1/π it is the diffuse
/// BRDF per unit base colour), from the cosines and the half-vector cosine `cos_d`.
#[inline]
pub(crate) fn disney_diffuse(
    cos_o: f32,
    cos_i: f32,
    cos_d: f32,
    roughness: f32,
    flatness: f32,
) -> f32 {
    let (fo, fi) = (schlick_weight(cos_i.abs()), schlick_weight(cos_o.abs()));
    let f_diff = (1.0 - 0.5 * fi) * (1.0 - 0.5 * fo);
    let rr = 2.0 * roughness * cos_d * cos_d;
    let f_retro = rr * (fo + fi + fo * fi * (rr - 1.0));
    let lambert = f_diff + f_retro;
    if flatness == 0.0 {
        return lambert;
    }
    let fss90 = rr * 0.5;
    let fss = (1.0 + (fss90 - 1.0) * fo) * (1.0 + (fss90 - 1.0) * fi);
    let f_ss = 1.25 * (fss * (1.0 / (cos_i.abs() + cos_o.abs()) - 0.5) + 0.5);
    lambert + (f_ss - lambert) * flatness
}

/// Mitsuba's `principled`, parameters evaluated at one point.
#[derive(Clone, Debug, PartialEq)]
pub struct Principled<C: Color = Vec3> {
    pub base_color: C,
    /// base_color / its luminance (1 where the luminance is 0): the tint of `spec_tint` and
    /// `sheen_tint`.
    pub tint: C,
    pub roughness: f32,
    pub anisotropic: f32,
    pub metallic: f32,
    pub spec_trans: f32,
    pub spec_tint: f32,
    pub sheen: f32,
    pub sheen_tint: f32,
    pub flatness: f32,
    pub clearcoat: f32,
    pub clearcoat_gloss: f32,
    /// Interior / exterior index.
    pub eta: f32,
    /// `main_specular_sampling_rate`, `clearcoat_sampling_rate`,
    /// `diffuse_reflectance_sampling_rate`.
    pub rates: [f32; 3],
}

impl Principled {
    /// An RGB principled BSDF with Mitsuba's defaults but for `base_color` and `eta`.
    pub fn new(base_color: Vec3, eta: f32) -> Principled {
        Principled::with_base(base_color, base_color, eta)
    }
}

impl<C: Color> Principled<C> {
    /// Mitsuba's defaults (roughness 0.5, everything else 0, rates 1) with the base colour in
    /// the path's colour type and its RGB value (for the luminance of the tints).
    pub fn with_base(base_color: C, base_rgb: Vec3, eta: f32) -> Principled<C> {
        let lum = luminance(base_rgb);
        Principled {
            base_color,
            tint: if lum > 0.0 { base_color / lum } else { C::ONE },
            roughness: 0.5,
            anisotropic: 0.0,
            metallic: 0.0,
            spec_trans: 0.0,
            spec_tint: 0.0,
            sheen: 0.0,
            sheen_tint: 0.0,
            flatness: 0.0,
            clearcoat: 0.0,
            clearcoat_gloss: 0.0,
            eta,
            rates: [1.0; 3],
        }
    }

    fn distribution(&self) -> Microfacet {
        let (au, av) = disney_alphas(self.anisotropic, self.roughness);
        Microfacet::new(MicrofacetType::Ggx, au, av)
    }

    fn clearcoat_distribution(&self) -> Gtr1 {
        Gtr1 {
            alpha: 0.1 + (0.001 - 0.1) * self.clearcoat_gloss,
        }
    }

    /// (brdf, bsdf) lobe weights.
    #[inline]
    fn weights(&self) -> (f32, f32) {
        let m = 1.0 - self.metallic;
        (m * (1.0 - self.spec_trans), m * self.spec_trans)
    }

    /// Lobe probabilities (specular reflection, transmission, clearcoat, diffuse) given the
    /// dielectric Fresnel `f` of the specular normal.
    #[inline]
    fn lobe_probs(&self, front: bool, f: f32) -> [f32; 4] {
        let (brdf, bsdf) = self.weights();
        let [spec, cc, diff] = self.rates;
        let p = if front {
            [
                spec * (1.0 - bsdf * (1.0 - f)),
                spec * bsdf * (1.0 - f),
                0.25 * self.clearcoat * cc,
                brdf * diff,
            ]
        } else {
            [f, if bsdf > 0.0 { 1.0 - f } else { 0.0 }, 0.0, 0.0]
        };
        let total = p[0] + p[1] + p[2] + p[3];
        if !is_positive(total) {
            return [0.0; 4];
        }
        p.map(|x| x / total)
    }

    /// The generalised half vector (towards +z), its side masks, and η along the path.
    #[inline]
    fn half(&self, wo: Vec3, wi: Vec3) -> (Vec3, bool, bool, f32) {
        let (cos_o, cos_i) = (wo.z, wi.z);
        let reflect = cos_o * cos_i > 0.0;
        let refract = cos_o * cos_i < 0.0;
        let eta_path = if cos_o > 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        };
        let h = (wo + wi * if reflect { 1.0 } else { eta_path }).normalize_or_zero();
        let h = if h.z < 0.0 { -h } else { h };
        (h, reflect, refract, eta_path)
    }

    /// The Fresnel term of the main specular reflection (Mitsuba's `principled_fresnel`).
    fn principled_fresnel(&self, f_dielectric: f32, cos_i: f32, front: bool, bsdf: f32) -> C {
        if !front {
            return C::splat(bsdf * f_dielectric);
        }
        let w = schlick_weight_at(cos_i, self.eta);
        let eta_it = if cos_i >= 0.0 {
            self.eta
        } else {
            1.0 / self.eta
        };
        let metallic = self.metallic;
        let mut f = C::splat((1.0 - metallic) * (1.0 - self.spec_tint) * f_dielectric);
        if metallic > 0.0 {
            f += schlick(self.base_color, w) * metallic;
        }
        if self.spec_tint > 0.0 {
            f += schlick(self.tint * schlick_r0(eta_it), w) * ((1.0 - metallic) * self.spec_tint);
        }
        f
    }
}

impl<C: Color> BsdfModel<C> for Principled<C> {
    fn eval(&self, wo: Vec3, wi: Vec3, mode: TransportMode) -> C {
        let (cos_o, cos_i) = (wo.z, wi.z);
        if cos_o == 0.0 {
            return C::ZERO;
        }
        let (brdf, bsdf) = self.weights();
        let front = cos_o > 0.0;
        let (h, reflect, refract, eta_path) = self.half(wo, wi);
        let wo_h = wo.dot(h);
        let f = fresnel_dielectric(wo_h, self.eta).0;
        let distr = self.distribution();
        let refl_ok = reflect && microfacet_compatible(h, wo, wi, cos_o, true);
        let mut value = C::ZERO;
        if refl_ok && f > 0.0 {
            let dg = distr.eval(h) * distr.g(wo, wi, h);
            if dg > 0.0 {
                value += self.principled_fresnel(f, wo_h, front, bsdf) * (dg / (4.0 * cos_o.abs()));
            }
        }
        if bsdf > 0.0 && refract && f < 1.0 && microfacet_compatible(h, wo, wi, cos_o, false) {
            let scale = match mode {
                TransportMode::Radiance => 1.0 / (eta_path * eta_path),
                TransportMode::Importance => 1.0,
            };
            let wi_h = wi.dot(h);
            let denom = wo_h + eta_path * wi_h;
            let v = scale
                * (1.0 - f)
                * distr.eval(h)
                * distr.g(wo, wi, h)
                * eta_path
                * eta_path
                * wo_h
                * wi_h
                / (cos_o * denom * denom);
            value += sqrt_lanes(self.base_color) * (bsdf * v.abs());
        }
        if front && reflect {
            if self.clearcoat > 0.0 && refl_ok {
                let fcc = 0.04 + 0.96 * schlick_weight_at(wo_h, self.eta);
                let dcc = self.clearcoat_distribution().eval(h);
                let gcc = smith_ggx1(wo, h, 0.25) * smith_ggx1(wi, h, 0.25);
                value += C::splat(self.clearcoat * 0.25 * fcc * dcc * gcc * cos_i.abs());
            }
            let cos_d = h.dot(wi);
            if brdf > 0.0 {
                let d = disney_diffuse(cos_o, cos_i, cos_d, self.roughness, self.flatness);
                value += self.base_color * (brdf * cos_i.abs() * INV_PI * d);
            }
            if self.sheen > 0.0 && self.metallic < 1.0 {
                let fd = schlick_weight(cos_d.abs());
                let c_sheen = C::ONE + (self.tint - C::ONE) * self.sheen_tint;
                value += c_sheen * (self.sheen * (1.0 - self.metallic) * fd * cos_i.abs());
            }
        }
        value
    }

    fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        let cos_o = wo.z;
        if cos_o == 0.0 {
            return 0.0;
        }
        let front = cos_o > 0.0;
        let (_, bsdf) = self.weights();
        if !front && bsdf <= 0.0 {
            return 0.0;
        }
        let (h, reflect, refract, eta_path) = self.half(wo, wi);
        let f = fresnel_dielectric(wo.dot(h), self.eta).0;
        let [p_refl, p_trans, p_cc, p_diff] = self.lobe_probs(front, f);
        let (wo_h, wi_h) = (wo.dot(h), wi.dot(h));
        let jacobian = if reflect {
            (1.0 / (4.0 * wi_h)).abs()
        } else {
            (eta_path * eta_path * wi_h / ((wo_h + eta_path * wi_h) * (wo_h + eta_path * wi_h)))
                .abs()
        };
        let wo_up = if front { wo } else { -wo };
        let distr = self.distribution();
        let mut pdf = 0.0;
        if reflect {
            if microfacet_compatible(h, wo, wi, cos_o, true) {
                pdf += p_refl * distr.pdf(wo_up, h) * jacobian;
                if p_cc > 0.0 {
                    pdf += p_cc * self.clearcoat_distribution().pdf(h) * jacobian;
                }
            }
            pdf += p_diff * wi.z.abs() * INV_PI;
        } else if refract && p_trans > 0.0 && microfacet_compatible(h, wo, wi, cos_o, false) {
            pdf += p_trans * distr.pdf(wo_up, h) * jacobian;
        }
        if pdf.is_finite() { pdf } else { 0.0 }
    }

    fn sample(&self, wo: Vec3, u1: f32, u2: Vec2, mode: TransportMode) -> Option<BsdfSample<C>> {
        let cos_o = wo.z;
        if cos_o == 0.0 {
            return None;
        }
        let front = cos_o > 0.0;
        let (_, bsdf) = self.weights();
        if !front && bsdf <= 0.0 {
            return None;
        }
        let wo_up = if front { wo } else { -wo };
        let distr = self.distribution();
        let (m, _) = distr.sample(wo_up, u2);
        let (f, cos_t, eta_it, eta_ti) = fresnel_dielectric(wo.dot(m), self.eta);
        let [_, p_trans, p_cc, p_diff] = self.lobe_probs(front, f);
        let (wi, transmission) = if u1 < p_diff {
            let wi = square_to_cosine_hemisphere(u2);
            (if front { wi } else { -wi }, false)
        } else if u1 < p_diff + p_cc {
            let m = self.clearcoat_distribution().sample(u2);
            let wi = reflect_z_about(wo, m);
            if !microfacet_compatible(m, wo, wi, cos_o, true) {
                return None;
            }
            (wi, false)
        } else if u1 < p_diff + p_cc + p_trans {
            let wi = refract_m(wo, m, cos_t, eta_ti);
            if !microfacet_compatible(m, wo, wi, cos_o, false) {
                return None;
            }
            (wi, true)
        } else {
            let wi = reflect_z_about(wo, m);
            if !microfacet_compatible(m, wo, wi, cos_o, true) {
                return None;
            }
            (wi, false)
        };
        if (cos_o * wi.z > 0.0) == transmission || wi.z == 0.0 {
            return None;
        }
        let pdf = self.pdf(wo, wi);
        if !is_positive(pdf) {
            return None;
        }
        Some(BsdfSample {
            wi,
            weight: self.eval(wo, wi, mode) / pdf,
            pdf,
            delta: false,
            transmission,
            eta: if transmission { eta_it } else { 1.0 },
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
