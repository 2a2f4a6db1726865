//! The transmittance estimators and free-flight sampling of grid media, against quadrature,
//! on the reference density grid `plume-density.vol` (64³, trilinear) in the unit cube with
//! σt = 8 · density.
//!
//! - Estimators: for each of the six and each of 16 fixed rays, the mean of 5·10⁵ estimates
//!   must equal e^{−τ}, τ from a 20,000-step midpoint rule over the ray's part inside the cube
//!   (z-test, α = 0.01 Šidák-corrected
//!   over 6 × 16 tests). The variance, time and variance × time of each estimator are printed
//!   (`cargo test --release --test transmittance -- --nocapture`); nothing is asserted about
//!   time.
//! - Free flights: delta tracking's distances along one ray follow σt(t)·e^{−τ(t)} on the
//!   segment with the mass e^{−τ} of passing spread over one more unit (χ², α = 0.01).
//!
//! Skipped with a notice when `../shared/references` is absent (fails under CI=true).

use std::time::Instant;

use rayon::prelude::*;
use render::geometry::Ray;
use render::math::{Mat4, Vec2, Vec3};
use render::media::grid::VoxelGrid;
use render::media::heterogeneous::Albedo;
use render::media::{Flight, Heterogeneous};
use render::stats::{Chi2Config, Pcg32, chi2_test_2d, sidak};

use base::TransmittanceEstimator;

const SCALE: f32 = 8.0;

fn medium() -> Option<Heterogeneous> {
    let refs = base::testing::shared_dir("references")?;
    let grid = VoxelGrid::read_vol(&refs.join("scenes/plume-density.vol"), true).unwrap();
    Some(Heterogeneous::new(
        grid,
        Albedo::Const(Vec3::ONE),
        SCALE,
        Mat4::IDENTITY,
    ))
}

/// 16 rays from points on a sphere around the cube towards points near its centre.
fn rays() -> Vec<Ray> {
    let mut rng = Pcg32::new(11, 3);
    (0..16)
        .map(|_| {
            let z = 2.0 * rng.next_f32() - 1.0;
            let phi = 2.0 * std::f32::consts::PI * rng.next_f32();
            let r = (1.0 - z * z).sqrt();
            let o = Vec3::splat(0.5) + 1.5 * Vec3::new(r * phi.cos(), r * phi.sin(), z);
            let target = Vec3::new(
                0.3 + 0.4 * rng.next_f32(),
                0.2 + 0.6 * rng.next_f32(),
                0.3 + 0.4 * rng.next_f32(),
            );
            Ray::new(o, (target - o).normalize())
        })
        .collect()
}

/// The part of the ray inside the unit cube (f64 slab test).
fn clip(ray: &Ray) -> (f64, f64) {
    let (mut near, mut far) = (0.0f64, f64::INFINITY);
    for k in 0..3 {
        let (o, d) = (ray.o[k] as f64, ray.d[k] as f64);
        let (a, b) = ((0.0 - o) / d, (1.0 - o) / d);
        near = near.max(a.min(b));
        far = far.min(a.max(b));
    }
    (near, far.max(near))
}

/// τ along the ray by the midpoint rule over the part inside the cube (σt jumps at the
/// faces: integrating across them would cost the rule its accuracy).
fn optical_depth(m: &Heterogeneous, ray: &Ray) -> f64 {
    let (t0, t1) = clip(ray);
    let n = 20_000;
    let h = (t1 - t0) / n as f64;
    (0..n)
        .map(|i| m.sigma_t_along(ray, (t0 + (i as f64 + 0.5) * h) as f32) as f64)
        .sum::<f64>()
        * h
}

#[test]
fn every_estimator_is_unbiased() {
    let Some(m) = medium() else { return };
    let rays = rays();
    let n = 500_000u64;
    let level = sidak(0.01, 6 * rays.len());
    let z_max = statrs_z(level);
    let mut failures = Vec::new();
    println!("estimator      mean variance   ns/estimate  variance × ns");
    for est in TransmittanceEstimator::ALL {
        let start = Instant::now();
        let mut var_sum = 0.0;
        for (r, ray) in rays.iter().enumerate() {
            let exact = (-optical_depth(&m, ray)).exp();
            // 16 chunks, each with its own stream, summed in order (deterministic).
            let chunks: Vec<(f64, f64)> = (0..16u64)
                .into_par_iter()
                .map(|c| {
                    let mut rng = Pcg32::new(1000 + r as u64, c + 16 * est as u64);
                    let mut u = || rng.next_f32();
                    let (mut s, mut s2) = (0.0f64, 0.0f64);
                    for _ in 0..n / 16 {
                        let x = m.estimate(ray, f32::INFINITY, est, &mut u) as f64;
                        s += x;
                        s2 += x * x;
                    }
                    (s, s2)
                })
                .collect();
            let (s, s2) = chunks
                .iter()
                .fold((0.0, 0.0), |(a, b), (c, d)| (a + c, b + d));
            let mean = s / n as f64;
            let var = (s2 / n as f64 - mean * mean).max(0.0);
            var_sum += var;
            let se = (var / n as f64).sqrt().max(1e-12);
            let z = (mean - exact) / se;
            if z.abs() > z_max {
                failures.push(format!(
                    "{} ray {r}: mean {mean:.6} vs {exact:.6} (z = {z:.2})",
                    est.name()
                ));
            }
        }
        let ns = start.elapsed().as_nanos() as f64 / (n as f64 * rays.len() as f64);
        let var = var_sum / rays.len() as f64;
        println!(
            "{:<14} {var:.3e}   {ns:8.1}     {:.3e}",
            est.name(),
            var * ns
        );
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// The two-sided standard-normal quantile for level `alpha`.
fn statrs_z(alpha: f64) -> f64 {
    use statrs::distribution::{ContinuousCDF, Normal};
    Normal::new(0.0, 1.0)
        .unwrap()
        .inverse_cdf(1.0 - alpha / 2.0)
}

#[test]
fn free_flights_follow_their_density() {
    let Some(m) = medium() else { return };
    let ray = rays()[3];
    // The cube's exit along the ray is before t = 4; τ(t) tabulated for the density.
    let t_end = 4.0f32;
    let n = 8192;
    let h = t_end / n as f32;
    let mut tau = vec![0.0f32; n + 1];
    for i in 0..n {
        tau[i + 1] = tau[i] + m.sigma_t_along(&ray, (i as f32 + 0.5) * h) * h;
    }
    let tau_at = |t: f32| {
        let x = (t / h).clamp(0.0, n as f32);
        let i = (x as usize).min(n - 1);
        tau[i] + (tau[i + 1] - tau[i]) * (x - i as f32)
    };
    let pass = (-tau[n]).exp();
    let mut rng_u = Pcg32::new(5, 5);
    let r = chi2_test_2d(
        |u, v| {
            let mut first = Some(u.x);
            let mut next = || first.take().unwrap_or_else(|| rng_u.next_f32());
            let x = match m.sample_with(&ray, f32::INFINITY, &mut next) {
                Flight::Scatter { d, .. } => d,
                Flight::Pass { .. } => t_end + v,
            };
            Some(Vec2::new(x, u.y))
        },
        |p| {
            if p.x < t_end {
                m.sigma_t_along(&ray, p.x) * (-tau_at(p.x)).exp()
            } else if p.x < t_end + 1.0 {
                pass
            } else {
                0.0
            }
        },
        Vec2::ZERO,
        Vec2::new(t_end + 1.0, 1.0),
        &Chi2Config {
            res: 40,
            sample_count: 400_000,
            min_exp_frequency: 5.0,
            significance: 0.01,
            seed: 9,
        },
    );
    assert!(r.passed, "{}", r.message);
}
