//! χ² goodness-of-fit of the media's sampling routines against their densities: the phase
//! functions' directions (isotropic; Henyey–Greenstein for g ∈ {−0.9, −0.5, 0, 0.5, 0.9}, with
//! a tilted `wo`) and a homogeneous medium's free-flight distances (each hero channel). α =
//! 0.01, Šidák-corrected over the cases of each test; fixed seeds.

use render::math::{Vec2, Vec3};
use render::media::{Flight, Homogeneous, Phase};
use render::stats::{Chi2Config, chi2_test, chi2_test_2d, sidak};

fn cfg(seed: u64, significance: f64) -> Chi2Config {
    Chi2Config {
        res: 16,
        sample_count: 300_000,
        min_exp_frequency: 5.0,
        significance,
        seed,
    }
}

#[test]
fn phase_function_sampling_matches_its_density() {
    let wo = Vec3::new(0.3, -0.4, 0.866).normalize();
    let mut phases = vec![Phase::Isotropic];
    phases.extend([-0.9f32, -0.5, 0.0, 0.5, 0.9].map(|g| Phase::HenyeyGreenstein { g }));
    let a = sidak(0.01, phases.len());
    let failed: Vec<String> = phases
        .iter()
        .enumerate()
        .filter_map(|(i, phase)| {
            let r = chi2_test(
                |u, _| Some(phase.sample(wo, u).0),
                |wi| phase.eval(wo, wi),
                &cfg(40 + i as u64, a),
            );
            (!r.passed).then(|| format!("{phase:?}: {}", r.message))
        })
        .collect();
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

/// Distances sampled with each hero channel follow σt,h·e^{−σt,h·t} on [0, d_max), and the
/// mass e^{−σt,h·d_max} of "pass" is spread uniformly over [d_max, d_max + 1) by an
/// independent uniform. The 2D test's second coordinate is a dummy uniform so that the
/// generic 2D χ² can be used.
#[test]
fn free_flight_distances_match_their_density() {
    let m = Homogeneous::new(Vec3::new(0.5, 1.5, 4.0), Vec3::splat(0.7));
    let d_max = 1.0f32;
    let a = sidak(0.01, 3);
    for hero in 0..3 {
        let s = m.sigma_t[hero];
        let r = chi2_test_2d(
            |u, v| {
                let x = match m.sample(d_max, u.x, hero) {
                    Flight::Scatter { d, .. } => d,
                    Flight::Pass { .. } => d_max + v,
                };
                Some(Vec2::new(x, u.y))
            },
            |p| {
                if p.x < d_max {
                    s * (-s * p.x).exp()
                } else if p.x < d_max + 1.0 {
                    // The pass mass spread over [d_max, d_max + 1).
                    (-s * d_max).exp()
                } else {
                    0.0
                }
            },
            Vec2::ZERO,
            Vec2::new(d_max + 1.0, 1.0),
            &cfg(60 + hero as u64, a),
        );
        assert!(r.passed, "hero {hero}: {}", r.message);
    }
}
