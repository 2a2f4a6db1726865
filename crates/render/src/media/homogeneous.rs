//! A homogeneous medium: constant σt and albedo (per RGB channel).
//!
//! Free flights are sampled with the path's hero channel h: the distance from
//! σt,h·e^{−σt,h·t}. Each flight returns the throughput factor f/p_h and the ratios p_c/p_h
//! of every channel's density to the hero's; the path multiplies them up and divides its
//! contributions by the mean ratio, which is spectral MIS over the choice of hero at the
//! level of the whole path (pbrt-v4's `r_u`; Miller et al. 2019). The weights stay bounded
//! for coloured extinction, where per-event weights multiply into heavy tails over many
//! collisions. Grey media reduce to the classic estimator (weight = albedo at a collision, 1
//! through, ratios 1). Transmittance is analytic.

use crate::math::Vec3;
use crate::spectral::lanes::{Color, ColorMode, RgbMode};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Homogeneous {
    /// Extinction per unit length, per channel.
    pub sigma_t: Vec3,
    /// Scattering coefficient σs = albedo·σt.
    pub sigma_s: Vec3,
    /// The single-scattering albedo σs/σt as declared (spectral mode upsamples it as a
    /// reflectance and σt as an unbounded spectrum, as Mitsuba does).
    pub albedo: Vec3,
}

/// The outcome of sampling a free flight over a segment of length `d_max` with a hero
/// channel: the path's throughput is multiplied by `weight` (f/p_hero) and its channel
/// density ratios by `ratio` (p_c/p_hero).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Flight<C = Vec3> {
    /// A real collision at distance `d` (weight T(d)·σs/p_h(d)), after which the phase
    /// function scatters the path. `emit` (T(d)·σa/p_h(d)) weighs the medium's emitted
    /// radiance there: the collision estimator of emission.
    Scatter {
        d: f32,
        weight: C,
        ratio: C,
        emit: C,
    },
    /// No collision before `d_max` (weight T/P_h(pass)).
    Pass { weight: C, ratio: C },
}

impl<C: Color> Flight<C> {
    /// No collision, throughput unchanged.
    pub const THROUGH: Flight<C> = Flight::Pass {
        weight: C::ONE,
        ratio: C::ONE,
    };
    /// No estimate at all (a zero-density sample): the path ends.
    pub const ABSORBED: Flight<C> = Flight::Pass {
        weight: C::ZERO,
        ratio: C::ONE,
    };
}

impl Homogeneous {
    pub fn new(sigma_t: Vec3, albedo: Vec3) -> Homogeneous {
        Homogeneous {
            sigma_t,
            sigma_s: sigma_t * albedo,
            albedo,
        }
    }

    /// σt and σs in the colour of `m`: in RGB mode the fields themselves (σs = σt·albedo
    /// is the same product), in spectral mode σt upsampled as an unbounded spectrum times
    /// the albedo upsampled as a reflectance.
    #[inline]
    pub fn coefficients<M: ColorMode>(&self, m: &M) -> (M::C, M::C) {
        let sigma_t = m.unbounded(self.sigma_t);
        (sigma_t, sigma_t * m.albedo(self.albedo))
    }

    /// [`Self::transmittance`] in the colour of `m`.
    #[inline]
    pub fn transmittance_in<M: ColorMode>(&self, d: f32, m: &M) -> M::C {
        transmittance(m.unbounded(self.sigma_t), d)
    }

    /// Transmittance over a distance `d`: `(-sigma_t * d).exp()` for finite `d` (the path
    /// tracer's Beer–Lambert factor relies on exactly this expression), 0 or 1 per channel
    /// over an infinite one.
    #[inline]
    pub fn transmittance(&self, d: f32) -> Vec3 {
        transmittance(self.sigma_t, d)
    }

    /// Sample a free flight over `[0, d_max)` with hero channel `hero` from one uniform
    /// number `u`.
    #[inline]
    pub fn sample(&self, d_max: f32, u: f32, hero: usize) -> Flight {
        self.sample_in(d_max, u, hero, &RgbMode)
    }

    /// [`Self::sample`] in the colour of `m` (`hero` a lane of it).
    #[inline]
    pub fn sample_in<M: ColorMode>(&self, d_max: f32, u: f32, hero: usize, m: &M) -> Flight<M::C> {
        let (sigma_t, sigma_s) = self.coefficients(m);
        let s = sigma_t.lane(hero);
        let d = if s > 0.0 {
            -(1.0 - u).ln() / s
        } else {
            f32::INFINITY
        };
        if d < d_max {
            let tr = transmittance(sigma_t, d);
            let pdf = sigma_t * tr;
            let p_h = pdf.lane(hero);
            if p_h.is_nan() || p_h <= 0.0 {
                return Flight::ABSORBED;
            }
            Flight::Scatter {
                d,
                weight: tr * sigma_s / p_h,
                ratio: pdf / p_h,
                emit: tr * (sigma_t - sigma_s) / p_h,
            }
        } else {
            let tr = transmittance(sigma_t, d_max);
            let p_h = tr.lane(hero);
            if p_h.is_nan() || p_h <= 0.0 {
                return Flight::ABSORBED;
            }
            Flight::Pass {
                weight: tr / p_h,
                ratio: tr / p_h,
            }
        }
    }
}

/// e^{−σt·d} per lane: the float expression `(-sigma_t * d).exp()` for finite `d`; 0 or 1
/// per lane over an infinite one.
#[inline]
fn transmittance<C: Color>(sigma_t: C, d: f32) -> C {
    if d.is_infinite() {
        return C::from_fn(|i| if sigma_t.lane(i) > 0.0 { 0.0 } else { 1.0 });
    }
    (-sigma_t * d).exp()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The transmittance over a finite distance is the one expression
    /// `(-sigma_t * d).exp()`, bit for bit (the path tracer's images depend on it), and an
    /// infinite distance lets through only the channels without extinction.
    #[test]
    fn transmittance_is_the_beer_lambert_expression() {
        let sigma = Vec3::new(0.105_360_5, 0.510_825_6, 1.609_438);
        let m = Homogeneous::new(sigma, Vec3::ZERO);
        assert_eq!(m.sigma_s, Vec3::ZERO);
        for (t, len) in [
            (0.37f32, 1.0f32),
            (1.234_567, 0.999_999_9),
            (1e-4, 3.0),
            (7.5, 1.2),
        ] {
            let d = t * len;
            assert_eq!(m.transmittance(d).to_array(), (-sigma * d).exp().to_array());
        }
        let m = Homogeneous::new(Vec3::new(0.5, 0.0, 2.0), Vec3::ZERO);
        assert_eq!(m.transmittance(f32::INFINITY), Vec3::new(0.0, 1.0, 0.0));
    }

    /// With a uniformly chosen hero and the MIS division by the mean ratio,
    /// E[weight/mean(ratio)·1{pass}] = T(d_max) and E[…·1{scatter before x}] = ∫₀ˣ T·σs, per
    /// channel, for a coloured medium.
    #[test]
    fn flights_are_unbiased_per_channel() {
        let m = Homogeneous::new(Vec3::new(0.5, 1.0, 3.0), Vec3::new(0.9, 0.5, 0.2));
        let (d_max, x) = (1.3f32, 0.6f32);
        let n = 400_000;
        let (mut pass, mut early) = (Vec3::ZERO, Vec3::ZERO);
        for i in 0..n {
            let u = (i as f32 + 0.5) / n as f32;
            let hero = ((u * 3.0) as usize).min(2);
            let u = u * 3.0 - hero as f32;
            match m.sample(d_max, u, hero) {
                Flight::Pass { weight, ratio } => pass += weight / (ratio.element_sum() / 3.0),
                Flight::Scatter {
                    d, weight, ratio, ..
                } if d < x => early += weight / (ratio.element_sum() / 3.0),
                Flight::Scatter { .. } => {}
            }
        }
        let (pass, early) = (pass / n as f32, early / n as f32);
        let t = m.transmittance(d_max);
        let want = m.sigma_s / m.sigma_t * (Vec3::ONE - m.transmittance(x));
        assert!((pass - t).abs().max_element() < 2e-3, "{pass} vs {t}");
        assert!(
            (early - want).abs().max_element() < 2e-3,
            "{early} vs {want}"
        );
    }
}
