//! A heterogeneous medium: extinction from a density grid, σt(x) = scale·density(x), and an
//! albedo that is constant or a grid; the grid fills [0,1]³ of its space, placed in the
//! world by an affine map. Outside that box the medium is empty.
//!
//! Free flights are sampled by delta tracking against a majorant σ̄ ≥ σt: tentative
//! collisions at rate σ̄, each real with probability σt/σ̄; σ̄ is per cell of a coarse
//! majorant grid ([`MajorantGrid`]) walked along the ray, so sparse volumes stay cheap (as
//! do the delta, ratio and residual estimators; the others use the grid's maximum). Transmittance is estimated by one
//! of six unbiased estimators ([`Estimator`]: delta, ratio, residual ratio and next-flight
//! ratio tracking, the power-series CMF estimator and unbiased ray marching).

use base::TransmittanceEstimator as Estimator;

use super::grid::{self, VoxelGrid};
use super::homogeneous::Flight;
use super::majorant::MajorantGrid;
use crate::geometry::Ray;
use crate::math::{Mat4, Vec3};
use crate::sampling::Sampler;
use crate::spectral::lanes::{Color, ColorMode, RgbMode};

#[derive(Clone, Debug)]
pub enum Albedo {
    Const(Vec3),
    Grid(VoxelGrid),
    /// σs/σt with σs from its own grid (in the density's units, on the density's lattice):
    /// the two are interpolated apart and then divided, as pbrt-v4's `rgbgrid` does.
    Ratio(VoxelGrid),
}

#[derive(Clone, Debug)]
pub struct Heterogeneous {
    pub density: VoxelGrid,
    pub albedo: Albedo,
    pub scale: f32,
    /// World → grid space ([0,1]³).
    pub to_grid: Mat4,
    /// The majorant: scale · the largest density.
    pub majorant: f32,
    /// The smallest density (the residual tracker's control, times `scale`).
    pub min_density: f32,
    /// Per-cell bounds of σt, walked by the trackers.
    pub majorants: MajorantGrid,
}

impl Heterogeneous {
    pub fn new(density: VoxelGrid, albedo: Albedo, scale: f32, to_world: Mat4) -> Heterogeneous {
        let majorant = scale * density.max_value();
        let min_density = if density.zero_outside {
            0.0
        } else {
            density.data.iter().fold(f32::INFINITY, |m, &v| m.min(v))
        };
        Heterogeneous {
            min_density,
            majorants: MajorantGrid::new(&density, scale),
            density,
            albedo,
            scale,
            to_grid: to_world.inverse(),
            majorant,
        }
    }

    /// The part of the ray's `[0, d_max)` inside the grid's box, as ray parameters (the ray
    /// direction is unit, so parameters are distances), with the ray in grid space.
    #[inline]
    fn clip(&self, ray: &Ray, d_max: f32) -> Option<(f32, f32, Vec3, Vec3)> {
        let o = self.to_grid.transform_point3a(ray.o);
        let d = self.to_grid.transform_vector3a(ray.d);
        let inv = d.recip();
        let t0 = (Vec3::ZERO - o) * inv;
        let t1 = (Vec3::ONE - o) * inv;
        let near = t0.min(t1).max_element().max(0.0);
        let far = t0.max(t1).min_element().min(d_max);
        (near < far && self.majorant > 0.0).then_some((near, far, o, d))
    }

    /// The single-scattering albedo at the grid-space point `p`.
    #[inline]
    fn albedo_at(&self, p: Vec3) -> Vec3 {
        match &self.albedo {
            Albedo::Const(a) => *a,
            Albedo::Grid(g) => g.rgb(p),
            Albedo::Ratio(s) => {
                let d = self.density.scalar(p);
                if d > 0.0 {
                    (s.rgb(p) / d).min(Vec3::ONE)
                } else {
                    Vec3::ZERO
                }
            }
        }
    }

    #[inline]
    fn sigma_t(&self, p: Vec3) -> f32 {
        self.scale * self.density.scalar(p)
    }

    /// Delta tracking over `[0, d_max)` of the (unit-direction) ray.
    pub fn sample(&self, ray: &Ray, d_max: f32, sampler: &mut Sampler) -> Flight {
        self.sample_with(ray, d_max, &mut || sampler.next_1d())
    }

    /// [`Heterogeneous::sample`] with the uniform numbers from `u`.
    pub fn sample_with(&self, ray: &Ray, d_max: f32, u: &mut impl FnMut() -> f32) -> Flight {
        self.sample_with_in(ray, d_max, u, &RgbMode)
    }

    /// [`Heterogeneous::sample_with`] in the colour of `m`: the extinction is grey, so only
    /// the albedo at a collision depends on the mode (upsampled as a reflectance).
    pub fn sample_with_in<M: ColorMode>(
        &self,
        ray: &Ray,
        d_max: f32,
        u: &mut impl FnMut() -> f32,
        m: &M,
    ) -> Flight<M::C> {
        let Some((t0, t1, o, d)) = self.clip(ray, d_max) else {
            return Flight::THROUGH;
        };
        let mut flight = Flight::THROUGH;
        self.majorants.walk(o, d, t0, t1, |ta, tb, _, hi| {
            if hi <= 0.0 {
                return true;
            }
            let mut t = ta;
            loop {
                t -= (1.0 - u()).ln() / hi;
                if t >= tb {
                    return true;
                }
                let p = o + d * t;
                if u() * hi < self.sigma_t(p) {
                    let albedo = m.albedo(self.albedo_at(p));
                    flight = Flight::Scatter {
                        d: t,
                        weight: albedo,
                        ratio: M::C::ONE,
                        emit: M::C::ONE - albedo,
                    };
                    return false;
                }
            }
        });
        flight
    }

    /// σa = σt·(1 − albedo) at the world point `p` (0 outside the grid's box).
    pub fn sigma_a(&self, p: Vec3) -> Vec3 {
        self.sigma_a_in(p, &RgbMode)
    }

    /// [`Self::sigma_a`] in the colour of `m`.
    pub fn sigma_a_in<M: ColorMode>(&self, p: Vec3, m: &M) -> M::C {
        let q = self.to_grid.transform_point3a(p);
        if !grid::inside(q) {
            return M::C::ZERO;
        }
        let albedo = m.albedo(self.albedo_at(q));
        (M::C::ONE - albedo) * self.sigma_t(q)
    }

    /// σt at distance `t` along the (unit-direction) ray, for tests and quadrature.
    pub fn sigma_t_along(&self, ray: &Ray, t: f32) -> f32 {
        let o = self.to_grid.transform_point3a(ray.o);
        let d = self.to_grid.transform_vector3a(ray.d);
        let p = o + d * t;
        if grid::inside(p) {
            self.sigma_t(p)
        } else {
            0.0
        }
    }

    /// The transmittance along `ray` (unit direction) over `[0, d_max)` by `estimator`.
    pub fn transmittance(
        &self,
        ray: &Ray,
        d_max: f32,
        estimator: Estimator,
        sampler: &mut Sampler,
    ) -> Vec3 {
        Vec3::splat(self.estimate(ray, d_max, estimator, &mut || sampler.next_1d()))
    }

    /// [`Heterogeneous::transmittance`] with the uniform numbers from `u`.
    pub fn estimate(
        &self,
        ray: &Ray,
        d_max: f32,
        estimator: Estimator,
        u: &mut impl FnMut() -> f32,
    ) -> f32 {
        let Some((t0, t1, o, d)) = self.clip(ray, d_max) else {
            return 1.0;
        };
        let sigma = |t: f32| self.sigma_t(o + d * t);
        let (maj, len) = (self.majorant, t1 - t0);
        // The next tentative collision after `t` at rate `rate`.
        let step = |t: f32, rate: f32, u: &mut dyn FnMut() -> f32| t - (1.0 - u()).ln() / rate;
        match estimator {
            Estimator::DeltaTracking => {
                let mut tr = 1.0;
                self.majorants.walk(o, d, t0, t1, |ta, tb, _, hi| {
                    if hi <= 0.0 {
                        return true;
                    }
                    let mut t = ta;
                    loop {
                        t = step(t, hi, u);
                        if t >= tb {
                            break;
                        }
                        if u() * hi < sigma(t) {
                            tr = 0.0;
                            return false;
                        }
                    }
                    true
                });
                tr
            }
            // Ratio tracking is residual ratio tracking with a control of 0.
            Estimator::RatioTracking | Estimator::ResidualRatioTracking => {
                // Per cell: e^{−σc·Δt} with the control σc (the cell's smallest σt for the
                // residual tracker), times ratio tracking of σt − σc against the cell's
                // bound minus σc.
                let residual = estimator == Estimator::ResidualRatioTracking;
                let mut tr = 1.0f32;
                self.majorants.walk(o, d, t0, t1, |ta, tb, lo, hi| {
                    let control = if residual { lo } else { 0.0 };
                    tr *= (-control * (tb - ta)).exp();
                    let rate = hi - control;
                    if rate <= 0.0 {
                        return true;
                    }
                    let mut t = ta;
                    loop {
                        t = step(t, rate, u);
                        if t >= tb {
                            return true;
                        }
                        tr *= 1.0 - (sigma(t) - control) / rate;
                        if !roulette(&mut tr, u) {
                            tr = 0.0;
                            return false;
                        }
                    }
                });
                tr
            }
            Estimator::NextFlightRatioTracking => {
                let mut sum = (-maj * len).exp();
                let mut w = 1.0f32;
                let mut t = t0;
                loop {
                    t = step(t, maj, u);
                    if t >= t1 || w == 0.0 {
                        return sum;
                    }
                    w *= 1.0 - sigma(t) / maj;
                    sum += w * (-maj * (t1 - t)).exp();
                }
            }
            Estimator::PowerSeriesCmf => {
                // τc = σ̄·d; each factor (σ̄ − σ(x))·d at a uniform point estimates τc − τ.
                let lambda = (maj - self.scale * self.min_density) * len;
                power_series(maj * len, lambda, u, &mut |u| {
                    (maj - sigma(t0 + u() * len)) * len
                })
            }
            Estimator::UnbiasedRayMarching => {
                let steps = ((maj * len).ceil() as usize).clamp(1, 256);
                let h = len / steps as f32;
                let march = |u: &mut dyn FnMut() -> f32| {
                    let off = u();
                    (0..steps)
                        .map(|j| sigma(t0 + (j as f32 + off) * h))
                        .sum::<f32>()
                        * h
                };
                let control = march(u);
                power_series(control, 1.0, u, &mut |u| control - march(u))
            }
        }
    }
}

/// Russian roulette on a small ratio-tracking weight (unbiased; keeps long rays cheap):
/// `false` when the estimate is terminated (it is then 0).
#[inline]
fn roulette(tr: &mut f32, u: &mut impl FnMut() -> f32) -> bool {
    if *tr < 0.1 {
        const Q: f32 = 0.75;
        if u() < Q {
            return false;
        }
        *tr /= 1.0 - Q;
    }
    true
}

/// The smallest order k at which the Poisson(λ) cumulative mass reaches `p`.
fn cmf_order(lambda: f32, p: f32) -> u32 {
    let mut term = (-lambda).exp();
    let mut cmf = term;
    let mut k = 0;
    while cmf < p && k < 64 {
        k += 1;
        term *= lambda / k as f32;
        cmf += term;
    }
    k
}

/// e^{−τc} Σₖ Πᵢ₌₁ᵏ Yᵢ / k! with `factor` drawing independent Yᵢ of mean τc − τ: every term
/// up to the 90 % point of the Poisson(λ) cumulative mass (λ bounds |τc − τ|), then each
/// further term with probability min(λ/k, 0.9), its weight divided by the probability of
/// reaching it. Unbiased for e^{−τ}.
fn power_series(
    tau_c: f32,
    lambda: f32,
    u: &mut impl FnMut() -> f32,
    factor: &mut impl FnMut(&mut dyn FnMut() -> f32) -> f32,
) -> f32 {
    let k0 = cmf_order(lambda, 0.9);
    let (mut term, mut sum, mut reach) = (1.0f32, 1.0f32, 1.0f32);
    for k in 1..=1024u32 {
        if k > k0 {
            let q = (lambda / k as f32).min(0.9);
            if q <= 0.0 || u() >= q {
                break;
            }
            reach *= q;
        }
        term *= factor(u) / k as f32;
        sum += term / reach;
    }
    (-tau_c).exp() * sum
}

#[cfg(test)]
mod tests {
    use super::*;

    /// pbrt-v4's `rgbgrid` interpolates σa and σs apart: with σt = σa + σs per voxel and the
    /// albedo σs(x)/σt(x), σa(x) = scale·σa-grid(x) exactly, also where σt varies.
    #[test]
    fn a_ratio_albedo_gives_the_interpolated_absorption() {
        let grid = |data: Vec<f32>, channels| VoxelGrid {
            res: [3, 2, 1],
            channels,
            data,
            trilinear: true,
            zero_outside: true,
        };
        let sa: Vec<f32> = (0..6).flat_map(|i| [0.5 + i as f32, 1.0, 0.0]).collect();
        let ss: Vec<f32> = (0..6)
            .flat_map(|i| [1.0, 0.5 + i as f32, 1.5 + i as f32])
            .collect();
        let density: Vec<f32> = (0..6).map(|i| 1.5 + i as f32).collect();
        let (sa, ss) = (grid(sa, 3), grid(ss, 3));
        let m = Heterogeneous::new(grid(density, 1), Albedo::Ratio(ss), 2.0, Mat4::IDENTITY);
        for k in 0..200 {
            let p = Vec3::new(
                (k as f32 * 0.618).fract(),
                (k as f32 * 0.314).fract(),
                (k as f32 * 0.271).fract(),
            );
            let want = sa.rgb(p) * 2.0;
            assert!(
                m.sigma_a(p)
                    .abs_diff_eq(want, 1e-4 * want.max_element().max(1.0)),
                "{p}: {} vs {want}",
                m.sigma_a(p)
            );
        }
    }
}
