//! Fresnel equations with Mitsuba 3's conventions (`include/mitsuba/render/fresnel.h`).

use crate::math::{Vec3, safe_sqrt};
use crate::spectral::lanes::Color;

/// Whether the per-lane relative indices `lane_eta` differ from the hero's `eta`: a
/// dispersive interface. Only spectral colours can be dispersive (RGB has one index per
/// material), so for 3-lane colours the test is a constant `false`.
#[inline]
pub fn lanes_disperse<C: Color>(lane_eta: C, eta: f32) -> bool {
    C::LANES == crate::spectral::N_SPECTRUM_SAMPLES
        && (0..C::LANES).any(|i| lane_eta.lane(i) != eta)
}

/// Unpolarised Fresnel reflectance of a smooth dielectric interface.
///
/// `eta` is the relative index η_inside/η_outside; `cos_theta_i` is signed: negative means the
/// incident direction lies inside the medium (then the roles of the two media swap).
///
/// Returns `(F, cos_theta_t, eta_it, eta_ti)`: the reflectance, the signed cosine of the
/// transmitted direction (on the opposite side of `cos_theta_i`), and the relative indices
/// η_t/η_i and η_i/η_t for this side. Total internal reflection gives `F = 1`.
#[inline]
pub fn fresnel_dielectric(cos_theta_i: f32, eta: f32) -> (f32, f32, f32, f32) {
    let outside = cos_theta_i >= 0.0;
    let rcp_eta = 1.0 / eta;
    let (eta_it, eta_ti) = if outside {
        (eta, rcp_eta)
    } else {
        (rcp_eta, eta)
    };

    let cos_t_sqr = 1.0 - eta_ti * eta_ti * (1.0 - cos_theta_i * cos_theta_i);
    let cos_i = cos_theta_i.abs();
    let cos_t = safe_sqrt(cos_t_sqr);

    let r = if eta == 1.0 {
        0.0
    } else if cos_i == 0.0 || cos_t_sqr <= 0.0 {
        // Grazing incidence or total internal reflection.
        1.0
    } else {
        let a_s = (cos_i - eta_it * cos_t) / (cos_i + eta_it * cos_t);
        let a_p = (cos_t - eta_it * cos_i) / (cos_t + eta_it * cos_i);
        0.5 * (a_s * a_s + a_p * a_p)
    };
    let cos_theta_t = if cos_theta_i >= 0.0 { -cos_t } else { cos_t };
    (r, cos_theta_t, eta_it, eta_ti)
}

/// Unpolarised Fresnel reflectance of a conductor with complex relative index `eta + i k`
/// (one channel). `cos_theta_i` must be ≥ 0. `eta = k = 0` gives a perfect mirror (F = 1).
#[inline]
pub fn fresnel_conductor_1(cos_theta_i: f32, eta: f32, k: f32) -> f32 {
    if eta == 0.0 && k == 0.0 {
        return 1.0;
    }
    // "Optics", K. D. Moeller (1988), as in Mitsuba.
    let c2 = cos_theta_i * cos_theta_i;
    let s2 = (1.0 - c2).max(0.0);
    let s4 = s2 * s2;
    let temp1 = eta * eta - k * k - s2;
    let a2pb2 = safe_sqrt(temp1 * temp1 + 4.0 * k * k * eta * eta);
    let a = safe_sqrt(0.5 * (a2pb2 + temp1));
    let term1 = a2pb2 + c2;
    let term2 = 2.0 * cos_theta_i * a;
    let rs = (term1 - term2) / (term1 + term2);
    let term3 = a2pb2 * c2 + s4;
    let term4 = term2 * s2;
    let denom = term3 + term4;
    let rp = if denom > 0.0 {
        rs * (term3 - term4) / denom
    } else {
        rs
    };
    0.5 * (rs + rp)
}

/// [`fresnel_conductor_1`] per lane (RGB channel or wavelength).
#[inline]
pub fn fresnel_conductor<C: Color>(cos_theta_i: f32, eta: C, k: C) -> C {
    C::from_fn(|i| fresnel_conductor_1(cos_theta_i, eta.lane(i), k.lane(i)))
}

/// Hemispherical average of the dielectric Fresnel reflectance ∫ F(μ) 2μ dμ, with the fits
/// Mitsuba uses (Egan & Hilgeman 1973 for η < 1, d'Eon & Irving 2011 otherwise).
pub fn fresnel_diffuse_reflectance(eta: f32) -> f32 {
    let inv = 1.0 / eta;
    if eta < 1.0 {
        0.0636 * inv + eta * (eta * -1.4399 + 0.7099) + 0.6681
    } else {
        // Horner form in 1/η.
        let c = [0.919317, -3.4793, 6.75335, -7.80989, 4.98554, -1.36881];
        c.iter().rev().fold(0.0, |acc, &ci| acc * inv + ci)
    }
}

/// Specular refraction about the normal (+z): `wi` given the signed `cos_theta_t` and
/// `eta_ti` from [`fresnel_dielectric`].
#[inline]
pub fn refract_z(wi: Vec3, cos_theta_t: f32, eta_ti: f32) -> Vec3 {
    Vec3::new(-eta_ti * wi.x, -eta_ti * wi.y, cos_theta_t)
}

/// Refraction about the microfacet normal `m` (with `cos_theta_t`, `eta_ti` from
/// [`fresnel_dielectric`] evaluated at `dot(wi, m)`).
#[inline]
pub fn refract_m(wi: Vec3, m: Vec3, cos_theta_t: f32, eta_ti: f32) -> Vec3 {
    m * (wi.dot(m) * eta_ti + cos_theta_t) - wi * eta_ti
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_normal_incidence_and_tir() {
        let (f, ct, eit, eti) = fresnel_dielectric(1.0, 1.5);
        assert!((f - 0.04).abs() < 1e-6);
        assert!((ct + 1.0).abs() < 1e-6 && eit == 1.5 && (eti - 1.0 / 1.5).abs() < 1e-7);
        // Inside, beyond the critical angle: total internal reflection.
        let (f, ..) = fresnel_dielectric(-0.5, 1.5);
        assert_eq!(f, 1.0);
        // Inside, normal incidence: same reflectance as from outside.
        let (f, ct, ..) = fresnel_dielectric(-1.0, 1.5);
        assert!((f - 0.04).abs() < 1e-6 && (ct - 1.0).abs() < 1e-6);
        // Index-matched.
        assert_eq!(fresnel_dielectric(0.3, 1.0).0, 0.0);
    }

    #[test]
    fn refraction_obeys_snell() {
        let wi = Vec3::new(0.6, 0.0, 0.8);
        let (_, ct, _, eti) = fresnel_dielectric(wi.z, 1.5);
        let wt = refract_z(wi, ct, eti);
        assert!((wt.length() - 1.0).abs() < 1e-5);
        assert!((wt.x.abs() * 1.5 - 0.6).abs() < 1e-5 && wt.z < 0.0);
        let wt2 = refract_m(wi, Vec3::Z, ct, eti);
        assert!((wt - wt2).length() < 1e-5);
    }

    #[test]
    fn conductor_limits() {
        // k = 0 conductor equals the dielectric formula.
        for c in [0.1f32, 0.5, 0.9, 1.0] {
            let a = fresnel_conductor_1(c, 1.5, 0.0);
            let b = fresnel_dielectric(c, 1.5).0;
            assert!((a - b).abs() < 1e-5, "{a} {b}");
        }
        assert_eq!(fresnel_conductor_1(1.0, 0.0, 0.0), 1.0);
        assert!((fresnel_conductor_1(0.7, 0.0, 1.0) - 1.0).abs() < 1e-6);
        // Gold-ish at normal incidence: ((n-1)^2 + k^2) / ((n+1)^2 + k^2).
        let (n, k) = (0.2f32, 3.0f32);
        let expect = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
        assert!((fresnel_conductor_1(1.0, n, k) - expect).abs() < 1e-5);
    }

    #[test]
    fn diffuse_reflectance_matches_quadrature() {
        for eta in [0.6f32, 0.8, 1.33, 1.5, 2.0] {
            let n = 20000;
            let mut s = 0.0f64;
            for i in 0..n {
                let mu = (i as f64 + 0.5) / n as f64;
                s += fresnel_dielectric(mu as f32, eta).0 as f64 * 2.0 * mu / n as f64;
            }
            let fit = fresnel_diffuse_reflectance(eta) as f64;
            assert!(
                (fit - s).abs() < 0.01 * s.max(0.05),
                "eta {eta}: {fit} vs {s}"
            );
        }
    }
}
