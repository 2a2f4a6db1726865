//! The photon-mapping family's estimate of in-scattering along a camera segment through a
//! homogeneous medium without emission, with point or spot lights about: one distance from
//! [`SegmentMixture`], where the integrator estimates the in-scattered radiance (next-event
//! estimation, the volume photons), and the segment crossed with its exact transmittance
//! ([`segment_point`]).

use super::camera::{Segment, Vertex};
use crate::integrators::transport::Scatterer;
use crate::math::Vec3;
use crate::media::MediumKind;
use crate::sampling::{Equiangular, Sampler};
use crate::spectral::lanes::{Color, PathMode};

/// Where a camera segment is estimated (see [`segment_point`]).
pub struct SegmentPoint<'a, C: Color> {
    /// The point at the sampled distance, a medium vertex whose throughput is the segment's
    /// times T(t)/pdf(t) (`None` when none was sampled or the path has no room for it).
    pub x: Option<Vertex<'a, C>>,
    /// σs at the point.
    pub sigma_s: C,
    /// The transmittance of the whole segment: the weight the walk crosses it with.
    pub tr: C,
}

/// The segment estimate of walk segment `seg` (in a homogeneous medium without emission,
/// with the point lights at `points`; `None` elsewhere): two 1D numbers drawn, a distance
/// from [`SegmentMixture`] if `room` (the path may grow by the point's edge).
pub fn segment_point<'a, M: PathMode>(
    points: &[Vec3],
    seg: &Segment<'a, M::C>,
    room: bool,
    sampler: &mut Sampler,
    m: &M,
) -> Option<SegmentPoint<'a, M::C>> {
    let MediumKind::Homogeneous(h) = &seg.medium.kind else {
        return None;
    };
    if points.is_empty() || seg.medium.emission.is_some() {
        return None;
    }
    let ray = &seg.walker.ray;
    let sigma_bar = m.unbounded(h.sigma_t).mean();
    let (u, v) = (sampler.next_1d(), sampler.next_1d());
    let (_, sigma_s) = h.coefficients(m);
    let x = (sigma_bar > 0.0 && room)
        .then(|| SegmentMixture::new(points, ray.o, ray.d, seg.end, sigma_bar).sample(u, v))
        .flatten()
        .map(|(t, pdf)| Vertex {
            at: Scatterer::Medium {
                phase: &seg.medium.phase,
                wo: -ray.d,
            },
            si: None,
            p: ray.at(t),
            medium: seg.walker.medium,
            depth: seg.depth + 1,
            beta: seg.beta * h.transmittance_in(t, m) * (1.0 / pdf),
            time: ray.time,
            hero: seg.walker.hero,
        });
    Some(SegmentPoint {
        x,
        sigma_s,
        tr: h.transmittance_in(seg.end, m),
    })
}

/// The in-scattered light along a segment of a homogeneous medium without emission, towards
/// point lights: one distance from a mixture of free-flight sampling (σt averaged over the
/// channels, truncated to the segment) and equiangular sampling towards each point light
/// (Kulla & Fajardo 2012), so that collisions land where a point light's singular
/// single scattering is, which free flights alone almost never do (in `media-fog` a
/// quarter of the light sat in the few pixels around the spot light, found by rare
/// collisions).
pub struct SegmentMixture<'a> {
    points: &'a [Vec3],
    o: Vec3,
    d: Vec3,
    end: f32,
    /// Point lights off the ray's line (those with an equiangular distribution).
    n_eq: usize,
    /// Probability of the free-flight strategy.
    p_ff: f32,
    sigma: f32,
    /// Free-flight mass on the segment, 1 − e^{−σ·end} (1 for an infinite one).
    mass: f32,
}

impl<'a> SegmentMixture<'a> {
    pub(super) fn new(
        points: &'a [Vec3],
        o: Vec3,
        d: Vec3,
        end: f32,
        sigma: f32,
    ) -> SegmentMixture<'a> {
        let mut m = SegmentMixture {
            points,
            o,
            d,
            end,
            n_eq: 0,
            p_ff: 1.0,
            sigma,
            mass: if end.is_finite() {
                -(-sigma * end).exp_m1()
            } else {
                1.0
            },
        };
        m.n_eq = m.eqs().count();
        if m.n_eq > 0 {
            m.p_ff = 0.5;
        }
        m
    }

    /// The equiangular distributions (made on the fly: no allocation per ray).
    fn eqs(&self) -> impl Iterator<Item = Equiangular> + '_ {
        self.points
            .iter()
            .filter_map(|&q| Equiangular::new(self.o, self.d, self.end, q))
    }

    /// A distance and its density, from uniform `u` (strategy and free flight) and `v`
    /// (equiangular).
    pub fn sample(&self, u: f32, v: f32) -> Option<(f32, f32)> {
        let t = if u < self.p_ff {
            // F(t) = (1 − e^{−σt})/mass, inverted.
            -(-(u / self.p_ff * self.mass)).ln_1p() / self.sigma
        } else {
            let k = (((u - self.p_ff) / (1.0 - self.p_ff) * self.n_eq as f32) as usize)
                .min(self.n_eq - 1);
            self.eqs().nth(k)?.sample(v)
        };
        let pdf = self.pdf(t);
        (pdf > 0.0 && pdf.is_finite()).then_some((t, pdf))
    }

    /// The density of distance `t` (0 outside the segment).
    fn pdf(&self, t: f32) -> f32 {
        if !(t >= 0.0 && t < self.end) {
            return 0.0;
        }
        let mut pdf = self.p_ff * self.sigma * (-self.sigma * t).exp() / self.mass;
        if self.n_eq > 0 {
            let eq: f32 = self.eqs().map(|e| e.pdf(t)).sum();
            pdf += (1.0 - self.p_ff) / self.n_eq as f32 * eq;
        }
        pdf
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Vec2;
    use crate::stats::{Chi2Config, chi2_test_2d, sidak};

    /// `SegmentMixture::sample` draws distances by the density `SegmentMixture::pdf` says: the density
    /// integrates to 1 over a finite segment, and a χ² test (t mapped to s = 1 − e^{−t/2} on
    /// [0, 1), a uniform second coordinate; 32 × 32 cells, 10⁶ samples) does not reject it,
    /// α = 0.01 Šidák-corrected over the 3 cases: two point lights near the ray, one very
    /// near on a short segment, one on an infinite segment.
    #[test]
    fn segment_distances_follow_their_density() {
        let o = Vec3::ZERO;
        let d = Vec3::X;
        let sigma = 0.35;
        let cases: [(Vec<Vec3>, f32); 3] = [
            (
                vec![Vec3::new(2.0, 0.1, 0.0), Vec3::new(4.0, -0.5, 0.3)],
                6.0,
            ),
            (vec![Vec3::new(1.0, 0.05, 0.0)], 3.0),
            (vec![Vec3::new(1.0, 0.2, 0.0)], f32::INFINITY),
        ];
        let level = sidak(0.01, cases.len());
        for (points, end) in cases {
            let mix = SegmentMixture::new(&points, o, d, end, sigma);
            if end.is_finite() {
                let n = 200_000;
                let h = end / n as f32;
                let total: f64 = (0..n)
                    .map(|k| mix.pdf((k as f32 + 0.5) * h) as f64)
                    .sum::<f64>()
                    * h as f64;
                assert!((total - 1.0).abs() < 1e-3, "∫pdf = {total}");
            }
            let scale = 2.0f32;
            let cfg = Chi2Config {
                res: 32,
                sample_count: 1_000_000,
                significance: level,
                seed: 3,
                ..Chi2Config::default()
            };
            let r = chi2_test_2d(
                |u2, u1| {
                    let (t, pdf) = mix.sample(u2.x, u2.y)?;
                    assert!((pdf - mix.pdf(t)).abs() <= 1e-5 * pdf);
                    Some(Vec2::new(-(-t / scale).exp_m1(), u1))
                },
                |p| {
                    let t = -scale * (-p.x).ln_1p();
                    let pdf = mix.pdf(t);
                    if pdf > 0.0 {
                        pdf * scale / (1.0 - p.x)
                    } else {
                        0.0
                    }
                },
                Vec2::ZERO,
                Vec2::ONE,
                &cfg,
            );
            assert!(r.passed, "{points:?}, end {end}: {}", r.message);
        }
    }
}
