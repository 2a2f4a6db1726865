//! Phase functions: isotropic and Henyey–Greenstein, with Mitsuba 3's conventions.
//!
//! Directions point away from the scattering point: `wo` towards where the path came from
//! (Mitsuba's `mi.wi`), `wi` the new direction. The scattering angle θ is between the
//! incident travel direction `-wo` and `wi`, so forward scattering (g > 0) favours `wi ≈ -wo`.
//! Both functions are sampled exactly: `sample` returns a direction whose weight
//! (value / pdf) is 1.

use crate::math::{Frame, INV_4PI, Vec2, Vec3, safe_sqrt, spherical_direction};
use crate::sampling::warp;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Phase {
    Isotropic,
    /// Henyey–Greenstein with mean cosine `g` ∈ (−1, 1).
    HenyeyGreenstein {
        g: f32,
    },
}

/// The Henyey–Greenstein density of the scattering-angle cosine `cos_theta` (per steradian).
#[inline]
pub fn hg(cos_theta: f32, g: f32) -> f32 {
    let denom = 1.0 + g * g - 2.0 * g * cos_theta;
    INV_4PI * (1.0 - g * g) / (denom * safe_sqrt(denom))
}

impl Phase {
    /// The phase function's value for scattering from `-wo` into `wi`; it is also the
    /// density `sample` gives `wi`.
    #[inline]
    pub fn eval(&self, wo: Vec3, wi: Vec3) -> f32 {
        match *self {
            Phase::Isotropic => INV_4PI,
            Phase::HenyeyGreenstein { g } => hg(-wo.dot(wi), g),
        }
    }

    /// A direction with density [`Phase::eval`], and that density.
    #[inline]
    pub fn sample(&self, wo: Vec3, u: Vec2) -> (Vec3, f32) {
        match *self {
            Phase::Isotropic => (warp::square_to_uniform_sphere(u), INV_4PI),
            Phase::HenyeyGreenstein { g } => {
                // Inversion of the cosine's CDF (pbrt-v4's form, stable near g = 0).
                let cos_theta = if g.abs() < 1e-3 {
                    1.0 - 2.0 * u.x
                } else {
                    let s = (1.0 - g * g) / (1.0 + g - 2.0 * g * u.x);
                    -(1.0 + g * g - s * s) / (2.0 * g)
                };
                // pbrt-v4 measures θ from `wo`; flip to measure it from the travel direction.
                let cos_theta = (-cos_theta).clamp(-1.0, 1.0);
                let sin_theta = safe_sqrt(1.0 - cos_theta * cos_theta);
                let phi = 2.0 * std::f32::consts::PI * u.y;
                let local = spherical_direction(sin_theta, cos_theta, phi);
                let wi = Frame::from_normal(-wo).to_world(local);
                (wi, hg(cos_theta, g))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Numerical integral of the value over the sphere is 1, and its mean cosine is g.
    #[test]
    fn hg_integrates_to_one_with_mean_cosine_g() {
        for g in [-0.9f32, -0.5, 0.0, 0.3, 0.9] {
            let n = 200_000;
            let (mut sum, mut mean) = (0.0f64, 0.0f64);
            for i in 0..n {
                let c = -1.0 + 2.0 * (i as f64 + 0.5) / n as f64;
                let v = hg(c as f32, g) as f64 * 2.0 * std::f64::consts::PI * 2.0 / n as f64;
                sum += v;
                mean += v * c;
            }
            assert!((sum - 1.0).abs() < 1e-3, "g={g}: ∫p = {sum}");
            assert!((mean - g as f64).abs() < 2e-3, "g={g}: mean cosine {mean}");
        }
    }

    #[test]
    fn samples_have_the_density_eval_reports() {
        let wo = Vec3::new(0.3, -0.5, 0.8).normalize();
        for phase in [Phase::Isotropic, Phase::HenyeyGreenstein { g: 0.7 }] {
            for u in [
                Vec2::new(0.1, 0.2),
                Vec2::new(0.9, 0.7),
                Vec2::new(0.5, 0.5),
            ] {
                let (wi, pdf) = phase.sample(wo, u);
                assert!((wi.length() - 1.0).abs() < 1e-5);
                assert!(
                    (pdf - phase.eval(wo, wi)).abs() < 1e-4 * pdf.max(1.0),
                    "{phase:?}"
                );
            }
        }
    }
}
