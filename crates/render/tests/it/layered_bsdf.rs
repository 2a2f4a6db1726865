//! pbrt-v4's stochastic layered BSDFs (`coateddiffuse`, `coatedconductor`) and
//! `diffusetransmission`:
//!
//! - white furnace: a lossless stack (smooth coating, white Lambertian base, no absorption)
//!   reflects everything, and a grey base reflects the closed form of a coated Lambertian
//!   surface, F + (1 − F)·ρ(1 − F̄ᵢ)/(1 − ρF̄ᵢ) (F̄ᵢ: the coating's hemispherical reflectance
//!   seen from inside) — by the mean sample weight and by integrating `eval`;
//! - reciprocity: f(wo, wi) = f(wi, wo) within noise (each estimate is a deterministic
//!   function of its directions, so independent estimates come from turning both directions
//!   about the normal, which an isotropic stack does not notice);
//! - sampling against `eval`: the weighted histogram of `sample` (Σ weight per cell / N)
//!   against `eval` integrated over each cell by Monte Carlo, as a χ² test with both variances;
//! - `diffusetransmission` sampled against its pdf, and its albedo R + T;
//! - `mix` picks its second material with probability `amount`.
//!
//! Every test has fixed seeds and significance α = 0.01, Šidák-corrected over its cases.

use render::bsdf::fresnel::fresnel_dielectric;
use render::bsdf::{
    Bsdf, DiffuseTransmission, Ggx, Layered, LayeredBase, LayeredInterface, TransportMode,
};
use render::materials::mix_picks_second;
use render::math::{Vec2, Vec3};
use render::stats::{MeanVar, Pcg32, sidak};
use statrs::distribution::{ChiSquared, ContinuousCDF, Normal};

const ALPHA: f64 = 0.01;

fn dir(theta_deg: f32, phi: f32) -> Vec3 {
    let t = theta_deg.to_radians();
    Vec3::new(t.sin() * phi.cos(), t.sin() * phi.sin(), t.cos())
}

fn mean3(c: Vec3) -> f64 {
    (c.x as f64 + c.y as f64 + c.z as f64) / 3.0
}

fn coated_diffuse(rho: f32, alpha: f32, thickness: f32, albedo: f32, depth: u32) -> Layered {
    Layered::new(
        LayeredInterface {
            distrib: Ggx::new(alpha, alpha),
            eta: 1.5,
        },
        LayeredBase::Diffuse(Vec3::splat(rho)),
        thickness,
        Vec3::splat(albedo),
        0.0,
        depth,
        1,
    )
}

fn gold(alpha: f32) -> LayeredBase<Vec3> {
    LayeredBase::Conductor {
        distrib: Ggx::new(alpha, alpha),
        eta: Vec3::new(0.143, 0.374, 1.442) / 1.5,
        k: Vec3::new(3.983, 2.385, 1.603) / 1.5,
    }
}

/// The mean sample weight (all lobes) from `wo` over `n` samples.
fn sampled_albedo(b: &Bsdf, wo: Vec3, n: u32, seed: u64) -> MeanVar {
    let mut rng = Pcg32::new(seed, 5);
    let mut mv = MeanVar::default();
    for _ in 0..n {
        let (u1, u2) = (rng.next_f32(), rng.next_vec2());
        mv.push(
            b.sample(wo, u1, u2, TransportMode::Radiance)
                .map_or(0.0, |s| mean3(s.weight)),
        );
    }
    mv
}

/// ∫ eval(wo, wi) dωi over the upper hemisphere by stratified uniform directions.
fn integrated_eval(b: &Bsdf, wo: Vec3, n_side: u32, seed: u64) -> MeanVar {
    let mut rng = Pcg32::new(seed, 9);
    let mut mv = MeanVar::default();
    for i in 0..n_side {
        for j in 0..n_side {
            let u = (Vec2::new(i as f32, j as f32) + rng.next_vec2()) / n_side as f32;
            let z = u.x;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * std::f32::consts::PI * u.y;
            let wi = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            mv.push(mean3(b.eval(wo, wi, TransportMode::Radiance)) * 2.0 * std::f64::consts::PI);
        }
    }
    mv
}

/// The coating's hemispherical reflectance for light inside it, ∫ F(μ) 2μ dμ.
fn internal_diffuse_fresnel(eta: f32) -> f64 {
    let n = 200_000;
    (0..n)
        .map(|i| {
            let mu = (i as f64 + 0.5) / n as f64;
            fresnel_dielectric(-(mu as f32), eta).0 as f64 * 2.0 * mu / n as f64
        })
        .sum()
}

#[test]
fn white_furnace_and_the_coated_lambertian_closed_form() {
    let f_int = internal_diffuse_fresnel(1.5);
    let angles = [0.0, 40.0, 75.0];
    let rhos = [1.0, 0.5];
    let cases = angles.len() * rhos.len() * 2;
    let alpha = sidak(ALPHA, cases);
    let mut worst = (1.0f64, String::new());
    for (a, &theta) in angles.iter().enumerate() {
        let wo = dir(theta, 0.3);
        let f = fresnel_dielectric(wo.z, 1.5).0 as f64;
        for &rho in &rhos {
            // No absorption in the slab (zero thickness), walks long enough to end.
            let b: Bsdf = coated_diffuse(rho, 0.0, 0.0, 0.0, 400).into();
            let r = rho as f64;
            let expect = f + (1.0 - f) * r * (1.0 - f_int) / (1.0 - r * f_int);
            let s = sampled_albedo(&b, wo, 200_000, 100 + a as u64);
            // A white base makes every weight 1 up to rounding: compare those to 1e-4.
            let p = if s.variance() < 1e-10 {
                if (s.mean - expect).abs() < 1e-4 {
                    1.0
                } else {
                    0.0
                }
            } else {
                s.t_test(expect)
            };
            let name = format!("θ={theta} ρ={rho} sampled {:.5} vs {expect:.5}", s.mean);
            assert!(p >= alpha, "{name}: p = {p:.2e}");
            if p < worst.0 {
                worst = (p, name);
            }
            // `eval` has no delta part: it integrates to the light through the slab.
            let e = integrated_eval(&b, wo, 300, 200 + a as u64);
            let p = e.t_test(expect - f);
            let name = format!("θ={theta} ρ={rho} eval {:.5} vs {:.5}", e.mean, expect - f);
            assert!(p >= alpha, "{name}: p = {p:.2e}");
            if p < worst.0 {
                worst = (p, name);
            }
        }
    }
    eprintln!("closed form: smallest p {:.3e} ({})", worst.0, worst.1);
}

#[test]
fn absorbing_and_rough_stacks_lose_energy_only() {
    let wo = dir(30.0, 0.0);
    let stacks: [(&str, Bsdf); 4] = [
        (
            "absorbing slab",
            coated_diffuse(1.0, 0.0, 0.5, 0.0, 100).into(),
        ),
        (
            "scattering slab",
            coated_diffuse(1.0, 0.2, 0.5, 0.8, 100).into(),
        ),
        (
            "rough coating",
            coated_diffuse(1.0, 0.5, 0.0, 0.0, 100).into(),
        ),
        (
            "coated conductor",
            Layered::new(
                LayeredInterface {
                    distrib: Ggx::new(0.2, 0.2),
                    eta: 1.5,
                },
                gold(0.3),
                0.01,
                Vec3::ZERO,
                0.0,
                10,
                1,
            )
            .into(),
        ),
    ];
    let alpha = sidak(ALPHA, stacks.len());
    for (i, (name, b)) in stacks.iter().enumerate() {
        let s = sampled_albedo(b, wo, 100_000, 300 + i as u64);
        // One-sided: the albedo must not exceed 1 (and must be clearly positive).
        let t = (s.mean - 1.0) / (s.variance() / s.n as f64).sqrt();
        let p = 1.0 - Normal::new(0.0, 1.0).unwrap().cdf(t);
        assert!(
            p >= alpha,
            "{name}: albedo {} above 1 (p = {p:.2e})",
            s.mean
        );
        assert!(s.mean > 0.05, "{name}: albedo {}", s.mean);
        assert!(
            s.mean < 0.995,
            "{name}: albedo {} (it should lose energy)",
            s.mean
        );
    }
}

#[test]
fn layered_bsdfs_are_reciprocal() {
    let stacks: [(&str, Layered); 3] = [
        ("coated diffuse, rough, scattering", {
            let mut b = coated_diffuse(0.7, 0.3, 0.1, 0.6, 10);
            b.g = 0.3;
            b.n_samples = 8;
            b
        }),
        ("coated diffuse, smooth", {
            let mut b = coated_diffuse(0.7, 0.0, 0.05, 0.0, 10);
            b.n_samples = 8;
            b
        }),
        (
            "coated conductor",
            Layered::new(
                LayeredInterface {
                    distrib: Ggx::new(0.25, 0.25),
                    eta: 1.5,
                },
                gold(0.3),
                0.05,
                Vec3::splat(0.5),
                -0.2,
                10,
                8,
            ),
        ),
    ];
    let pairs = [
        (dir(10.0, 0.0), dir(50.0, 2.0)),
        (dir(70.0, 1.0), dir(30.0, 4.0)),
        (dir(45.0, 0.5), dir(45.0, 2.5)),
    ];
    let cases = stacks.len() * pairs.len();
    let alpha = sidak(ALPHA, cases);
    let normal = Normal::new(0.0, 1.0).unwrap();
    for (name, layered) in &stacks {
        let b: Bsdf = layered.clone().into();
        for (wo, wi) in pairs {
            let (mut fwd, mut rev) = (MeanVar::default(), MeanVar::default());
            let turns = 400;
            for k in 0..turns {
                let phi = k as f32 * (std::f32::consts::TAU / turns as f32);
                let (s, c) = phi.sin_cos();
                let turn = |w: Vec3| Vec3::new(c * w.x - s * w.y, s * w.x + c * w.y, w.z);
                let (a, b2) = (turn(wo), turn(wi));
                fwd.push(mean3(b.eval(a, b2, TransportMode::Radiance)) / b2.z as f64);
                rev.push(mean3(b.eval(b2, a, TransportMode::Radiance)) / a.z as f64);
            }
            let se = (fwd.variance() / fwd.n as f64 + rev.variance() / rev.n as f64).sqrt();
            let z = (fwd.mean - rev.mean) / se;
            let p = 2.0 * normal.cdf(-z.abs());
            assert!(
                p >= alpha,
                "{name} {wo} {wi}: f = {:.5} vs reversed {:.5} (p = {p:.2e})",
                fwd.mean,
                rev.mean
            );
        }
    }
}

/// χ² of the weighted histogram of `sample` against `eval` integrated over each cell.
/// Cells are equal-solid-angle over the upper hemisphere: `nz` bands of cos θ × `nphi`.
fn sample_matches_eval(b: &Bsdf, wo: Vec3, seed: u64) -> (f64, usize) {
    let (nz, nphi) = (8usize, 16usize);
    let cells = nz * nphi;
    let n = 200_000u32;
    let mut rng = Pcg32::new(seed, 21);
    let (mut sum, mut sum2) = (vec![0f64; cells], vec![0f64; cells]);
    let cell_of = |w: Vec3| {
        let iz = ((w.z * nz as f32) as usize).min(nz - 1);
        let phi = w.y.atan2(w.x).rem_euclid(std::f32::consts::TAU);
        let ip = ((phi / std::f32::consts::TAU * nphi as f32) as usize).min(nphi - 1);
        iz * nphi + ip
    };
    for _ in 0..n {
        let (u1, u2) = (rng.next_f32(), rng.next_vec2());
        if let Some(s) = b.sample(wo, u1, u2, TransportMode::Radiance)
            && !s.delta
            && s.wi.z > 0.0
        {
            let w = mean3(s.weight);
            let c = cell_of(s.wi);
            sum[c] += w;
            sum2[c] += w * w;
        }
    }
    let area = 2.0 * std::f64::consts::PI / cells as f64;
    let m = 1024;
    let mut stat = 0.0;
    let mut dof = 0;
    for c in 0..cells {
        let (iz, ip) = (c / nphi, c % nphi);
        let mut e = MeanVar::default();
        for _ in 0..m {
            let u = rng.next_vec2();
            let z = (iz as f32 + u.x) / nz as f32;
            let phi = (ip as f32 + u.y) / nphi as f32 * std::f32::consts::TAU;
            let r = (1.0 - z * z).max(0.0).sqrt();
            let wi = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            e.push(mean3(b.eval(wo, wi, TransportMode::Radiance)) * area);
        }
        let obs = sum[c] / n as f64;
        let var_obs = (sum2[c] / n as f64 - obs * obs) / n as f64;
        let var_exp = e.variance() / m as f64;
        let var = var_obs + var_exp;
        if var > 0.0 && e.mean > 1e-6 {
            stat += (obs - e.mean).powi(2) / var;
            dof += 1;
        } else {
            assert!(obs < 1e-6, "cell {c}: sampled {obs} where eval is 0");
        }
    }
    let p = 1.0 - ChiSquared::new(dof as f64).unwrap().cdf(stat);
    (p, dof)
}

#[test]
fn layered_sampling_matches_integrated_eval() {
    let mut stacks: Vec<(&str, Bsdf)> = vec![
        (
            "coated diffuse rough",
            coated_diffuse(0.8, 0.3, 0.01, 0.0, 10).into(),
        ),
        ("coated diffuse scattering", {
            let mut b = coated_diffuse(0.5, 0.15, 0.2, 0.7, 10);
            b.g = 0.4;
            b.into()
        }),
        (
            "coated diffuse smooth",
            coated_diffuse(0.8, 0.0, 0.01, 0.0, 10).into(),
        ),
    ];
    stacks.push((
        "coated conductor",
        Layered::new(
            LayeredInterface {
                distrib: Ggx::new(0.2, 0.2),
                eta: 1.5,
            },
            gold(0.35),
            0.01,
            Vec3::ZERO,
            0.0,
            10,
            1,
        )
        .into(),
    ));
    let angles = [20.0, 65.0];
    let alpha = sidak(ALPHA, stacks.len() * angles.len());
    for (i, (name, b)) in stacks.iter().enumerate() {
        for (j, &theta) in angles.iter().enumerate() {
            let (p, dof) = sample_matches_eval(b, dir(theta, 0.4), (10 * i + j) as u64);
            assert!(p >= alpha, "{name} θ={theta}: p = {p:.2e} over {dof} cells");
        }
    }
}

#[test]
fn diffuse_transmission_samples_its_density_and_conserves_r_plus_t() {
    let b: Bsdf = DiffuseTransmission::new(
        Vec3::new(0.3, 0.2, 0.1),
        Vec3::new(0.5, 0.6, 0.2),
        (0.3, 0.6),
    )
    .into();
    for (k, wo) in [dir(30.0, 0.2), -dir(60.0, 1.0)].into_iter().enumerate() {
        let s = sampled_albedo(&b, wo, 50_000, 400 + k as u64);
        let expect = mean3(Vec3::new(0.8, 0.8, 0.3));
        assert!(
            s.t_test(expect) >= ALPHA / 2.0,
            "albedo {} vs {expect}",
            s.mean
        );
        // Every sample's weight is eval/pdf, its pdf what `pdf` says, and it lands on the
        // side its lobe says.
        let mut rng = Pcg32::new(7, k as u64);
        for _ in 0..1000 {
            let (u1, u2) = (rng.next_f32(), rng.next_vec2());
            let smp = b.sample(wo, u1, u2, TransportMode::Radiance).unwrap();
            let f = b.eval(wo, smp.wi, TransportMode::Radiance);
            let p = b.pdf(wo, smp.wi);
            assert!((smp.pdf - p).abs() <= 1e-5 * p);
            assert!((smp.weight - f / p).abs().max_element() <= 1e-4);
            assert_eq!(smp.transmission, smp.wi.z * wo.z < 0.0);
        }
    }
}

#[test]
fn mix_picks_the_second_material_with_probability_amount() {
    let mut rng = Pcg32::new(3, 3);
    let amounts = [0.1f32, 0.5, 0.85];
    let alpha = sidak(ALPHA, amounts.len());
    let normal = Normal::new(0.0, 1.0).unwrap();
    for a in amounts {
        let n = 100_000;
        let hits = (0..n)
            .filter(|_| {
                let p = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 10.0;
                let wo = dir(
                    rng.next_f32() * 90.0,
                    rng.next_f32() * std::f32::consts::TAU,
                );
                mix_picks_second(a, p, wo)
            })
            .count();
        let (m, sd) = (
            n as f64 * a as f64,
            (n as f64 * a as f64 * (1.0 - a as f64)).sqrt(),
        );
        let p = 2.0 * normal.cdf(-((hits as f64 - m) / sd).abs());
        assert!(p >= alpha, "amount {a}: {hits} of {n} (p = {p:.2e})");
    }
    assert!(!mix_picks_second(0.0, Vec3::ONE, Vec3::Z));
    assert!(mix_picks_second(1.0, Vec3::ONE, Vec3::Z));
    // The same vertex always sees the same material.
    let (p, wo) = (Vec3::new(0.3, 1.2, -4.0), dir(40.0, 1.0));
    assert_eq!(mix_picks_second(0.5, p, wo), mix_picks_second(0.5, p, wo));
}
