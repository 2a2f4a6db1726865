//! Russian roulette: a path goes on with probability q and its throughput is divided by q, so
//! the estimate keeps its mean. Two rules choose q:
//!
//! - [`throughput`]: Mitsuba's and pbrt-v4's, min(max β · η², 0.95) — β the throughput, η
//!   the product of the relative indices of refraction crossed (pbrt-v4's `etaScale`):
//!   radiance is scaled by 1/η² entering glass and back leaving it, so inside a dense glass β
//!   alone would end most paths that are about to leave it again;
//! - [`by_power`]: pbrt-v4's for photons, whose power should stay about constant: the ratio
//!   of the largest channel after a scattering event to before it.
//!
//! The courses' fixed probabilities are a q of their own ([`survive`] takes any).

use crate::spectral::lanes::Color;

/// The continuation probability of the throughput rule, from the largest live channel of the
/// throughput and the product `eta` of relative indices crossed (1 where it does not apply).
#[inline(always)]
pub fn throughput(live_max: f32, eta: f32) -> f32 {
    (live_max * eta * eta).min(0.95)
}

/// Roulette with continuation probability `q` and the uniform number `u`: `false` ends the
/// path; a survivor's `beta` is divided by `q`. A `q` of 1 or more (no roulette) keeps the
/// path and its throughput.
#[inline(always)]
pub fn survive<C: Color>(beta: &mut C, q: f32, u: f32) -> bool {
    if q < 1.0 {
        if u >= q {
            return false;
        }
        *beta /= q;
    }
    true
}

/// pbrt-v4's photon roulette on the change of power at a scattering event, `before` and
/// `after` the largest live channel of the photon's power: the photon ends with probability
/// max(0, 1 − after/before) (`u` below it), else its throughput is divided by the
/// continuation probability.
#[inline(always)]
pub fn by_power<C: Color>(beta: &mut C, before: f32, after: f32, u: f32) -> bool {
    let q = (1.0 - after / before).max(0.0);
    if u < q {
        return false;
    }
    *beta /= 1.0 - q;
    true
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec3;

    /// Roulette keeps the mean: over a fine grid of u, the survivors' throughput averages to
    /// the throughput it started with.
    #[test]
    fn roulette_keeps_the_mean() {
        let n = 100_000;
        for q in [0.05f32, 0.4, 0.95, 1.0, 3.0] {
            let mut sum = 0.0f64;
            for k in 0..n {
                let mut b = Vec3::splat(0.7);
                if survive(&mut b, q, (k as f32 + 0.5) / n as f32) {
                    sum += b.x as f64;
                }
            }
            assert!(
                (sum / n as f64 - 0.7).abs() < 1e-3,
                "q {q}: {}",
                sum / n as f64
            );
        }
        for (before, after) in [(1.0f32, 0.3f32), (1.0, 2.0), (0.5, 0.49)] {
            let mut sum = 0.0f64;
            for k in 0..n {
                let mut b = Vec3::splat(after);
                if by_power(&mut b, before, after, (k as f32 + 0.5) / n as f32) {
                    sum += b.x as f64;
                }
            }
            assert!(
                (sum / n as f64 - after as f64).abs() < 1e-3,
                "{before} → {after}"
            );
        }
        assert_eq!(throughput(2.0, 1.5), 0.95);
        assert_eq!(throughput(0.3, 1.0), 0.3);
    }
}
