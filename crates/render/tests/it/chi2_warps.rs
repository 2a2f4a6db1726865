//! χ² goodness-of-fit of each warp in `sampling/warp.rs` (and the microfacet normal samplers)
//! against its density. α = 0.01 Šidák-corrected over the cases of each test; fixed seeds.

use render::bsdf::{Microfacet, MicrofacetType};
use render::math::{INV_PI, Vec2, Vec3};
use render::sampling::warp;
use render::stats::{Chi2Config, chi2_test, chi2_test_2d, sidak};

fn cfg(seed: u64, significance: f64) -> Chi2Config {
    Chi2Config {
        res: 16,
        sample_count: 200_000,
        min_exp_frequency: 5.0,
        significance,
        seed,
    }
}

#[test]
fn sphere_warps() {
    let cos_maxes = [0.8f32, 0.0, -0.5];
    let n = 3 + cos_maxes.len();
    let a = sidak(0.01, n);
    let mut results = vec![
        (
            "cosine hemisphere".to_string(),
            chi2_test(
                |u, _| Some(warp::square_to_cosine_hemisphere(u)),
                warp::cosine_hemisphere_pdf,
                &cfg(1, a),
            ),
        ),
        (
            "uniform hemisphere".to_string(),
            chi2_test(
                |u, _| Some(warp::square_to_uniform_hemisphere(u)),
                warp::uniform_hemisphere_pdf,
                &cfg(2, a),
            ),
        ),
        (
            "uniform sphere".to_string(),
            chi2_test(
                |u, _| Some(warp::square_to_uniform_sphere(u)),
                |_| warp::uniform_sphere_pdf(),
                &cfg(3, a),
            ),
        ),
    ];
    for (i, &c) in cos_maxes.iter().enumerate() {
        results.push((
            format!("uniform cone cos_max={c}"),
            chi2_test(
                |u, _| Some(warp::square_to_uniform_cone(u, c)),
                |w| {
                    if w.z >= c {
                        warp::uniform_cone_pdf(c)
                    } else {
                        0.0
                    }
                },
                &cfg(10 + i as u64, a),
            ),
        ));
    }
    let failed: Vec<String> = results
        .iter()
        .filter(|(_, r)| !r.passed)
        .map(|(n, r)| format!("{n}: {}", r.message))
        .collect();
    assert!(failed.is_empty(), "{}", failed.join("\n"));
}

#[test]
fn planar_warps() {
    let a = sidak(0.01, 2);
    let disk = chi2_test_2d(
        |u, _| Some(warp::square_to_uniform_disk_concentric(u)),
        |p| {
            if p.length_squared() <= 1.0 {
                warp::uniform_disk_pdf()
            } else {
                0.0
            }
        },
        Vec2::splat(-1.0),
        Vec2::splat(1.0),
        &cfg(20, a),
    );
    assert!(disk.passed, "disk: {}", disk.message);
    let tri = chi2_test_2d(
        |u, _| Some(warp::square_to_uniform_triangle(u)),
        |b| {
            if b.x >= 0.0 && b.y >= 0.0 && b.x + b.y <= 1.0 {
                2.0
            } else {
                0.0
            }
        },
        Vec2::ZERO,
        Vec2::ONE,
        &cfg(21, a),
    );
    assert!(tri.passed, "triangle: {}", tri.message);
}

/// Visible-normal sampling (Heitz 2018 for GGX, Heitz–d'Eon / Jakob for Beckmann) against
/// D_wi(m) = G1(wi, m)·max(0, wi·m)·D(m)/cos θi, and Nori's all-normal Beckmann warp against
/// D(m) cos θm.
#[test]
fn microfacet_normal_warps() {
    let mut cases = Vec::new();
    for kind in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
        for (au, av) in [(0.05, 0.05), (0.3, 0.3), (0.8, 0.8), (0.15, 0.6)] {
            for theta in [0.0f32, 45.0, 85.0] {
                cases.push((kind, au, av, theta));
            }
        }
    }
    let a = sidak(0.01, cases.len() + 3);
    let mut failed = Vec::new();
    for (i, &(kind, au, av, theta)) in cases.iter().enumerate() {
        let d = Microfacet::new(kind, au, av);
        let t = theta.to_radians();
        let wi = Vec3::new(t.sin() * 0.6f32.cos(), t.sin() * 0.6f32.sin(), t.cos());
        let r = chi2_test(
            |u, _| Some(d.sample(wi, u).0),
            |m| d.pdf(wi, m),
            &cfg(100 + i as u64, a),
        );
        if !r.passed {
            failed.push(format!("{kind:?} ({au},{av}) θ={theta}: {}", r.message));
        }
    }
    for (i, alpha) in [0.1f32, 0.3, 0.6].into_iter().enumerate() {
        let d = Microfacet::isotropic(MicrofacetType::Beckmann, alpha);
        let r = chi2_test(
            |u, _| Some(d.sample_all(u)),
            |m| d.eval(m) * m.z.max(0.0),
            &cfg(200 + i as u64, a),
        );
        if !r.passed {
            failed.push(format!("beckmann all normals α={alpha}: {}", r.message));
        }
    }
    assert!(failed.is_empty(), "{}", failed.join("\n"));
    let _ = INV_PI;
}
