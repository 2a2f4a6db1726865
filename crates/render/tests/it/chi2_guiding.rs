//! χ² goodness-of-fit of path guiding's sampling (`sampling/sdtree.rs`,
//! `integrators/path/guided.rs`) against its density: the directional quadtree of an
//! SD-tree trained on a peaked, a two-lobed and a broad incident distribution, sampled over the
//! square and over the sphere, and the one-sample mixture of a BSDF and the quadtree that the
//! path tracer samples at a guided vertex, against the mixture density the tracer weighs with.
//! α = 0.01, Šidák-corrected over all cases; fixed seeds.

use render::bsdf::{Bsdf, Diffuse, RoughConductor, TransportMode};
use render::integrators::path::guided;
use render::math::{Frame, Vec2, Vec3};
use render::sampling::sdtree::{DTree, SdTree};
use render::spectral::lanes::Color;
use render::stats::{Chi2Config, Pcg32, chi2_test, chi2_test_2d, sidak};

fn cfg(seed: u64, significance: f64) -> Chi2Config {
    Chi2Config {
        res: 16,
        sample_count: 200_000,
        min_exp_frequency: 5.0,
        significance,
        seed,
    }
}

/// A quadtree learnt from `iterations` rounds of samples of `radiance` (uniform directions,
/// recorded as radiance over their density), refined between rounds as a render does.
fn learnt(radiance: impl Fn(Vec3) -> f32, iterations: u32, seed: u64) -> (SdTree, u32) {
    let mut t = SdTree::new(Vec3::ZERO, Vec3::ONE, 1e9, 64 << 20);
    let mut rng = Pcg32::new(seed, 7);
    for _ in 0..iterations {
        for _ in 0..100_000 {
            let u = Vec2::new(rng.next_f32(), rng.next_f32());
            let d = render::sampling::warp::square_to_uniform_sphere(u);
            let l = t.leaf(Vec3::splat(0.5));
            t.record(l, d, radiance(d) * 4.0 * std::f32::consts::PI);
        }
        t.refine();
    }
    let leaf = t.leaf(Vec3::splat(0.5));
    (t, leaf)
}

fn distributions() -> Vec<(&'static str, SdTree, u32)> {
    let peak = Vec3::new(0.3, -0.5, 0.81).normalize();
    let other = Vec3::new(-0.7, 0.2, -0.68).normalize();
    let mut out = Vec::new();
    let (t, l) = learnt(|d| d.dot(peak).max(0.0).powi(40) * 50.0 + 0.01, 4, 1);
    out.push(("peaked", t, l));
    let (t, l) = learnt(
        |d| d.dot(peak).max(0.0).powi(200) * 300.0 + d.dot(other).max(0.0).powi(10) * 5.0,
        5,
        2,
    );
    out.push(("two lobes", t, l));
    let (t, l) = learnt(|d| 1.0 + d.z.max(0.0), 3, 3);
    out.push(("broad", t, l));
    out
}

#[test]
fn chi2_quadtree_and_guided_mixture() {
    let dists = distributions();
    let bsdfs: Vec<(&str, Bsdf)> = vec![
        ("diffuse", Diffuse::new(Vec3::new(0.8, 0.5, 0.2)).into()),
        (
            "rough conductor",
            RoughConductor::new(
                render::bsdf::MicrofacetType::Ggx,
                0.3,
                0.3,
                Vec3::new(0.2, 0.9, 1.1),
                Vec3::new(3.9, 2.4, 2.2),
                Vec3::ONE,
            )
            .into(),
        ),
    ];
    let n = dists.len() * (2 + bsdfs.len());
    let a = sidak(0.01, n);
    let mut failures = Vec::new();
    let mut seed = 100;
    let report = |failures: &mut Vec<String>, name: String, r: render::stats::Chi2Result| {
        println!("{name}: p = {:.3e}", r.p_value);
        if !r.passed {
            failures.push(format!("{name}: {}", r.message));
        }
    };
    for (name, tree, leaf) in &dists {
        let g: &DTree = tree.guide(*leaf).expect("a learnt distribution");
        assert!(g.node_count() > 5, "{name}: the quadtree was refined");
        seed += 1;
        report(
            &mut failures,
            format!("{name} square ({} nodes)", g.node_count()),
            chi2_test_2d(
                |u, _| Some(g.sample_square(u).0),
                |p| g.pdf_square(p),
                Vec2::ZERO,
                Vec2::ONE,
                &Chi2Config {
                    res: 32,
                    ..cfg(seed, a)
                },
            ),
        );
        seed += 1;
        report(
            &mut failures,
            format!("{name} sphere"),
            chi2_test(|u, _| Some(g.sample(u).0), |d| g.pdf(d), &cfg(seed, a)),
        );
        let frame = Frame::from_normal(Vec3::new(0.2, 0.4, 0.89).normalize());
        let wo_world = Vec3::new(-0.3, 0.5, 0.8).normalize();
        let wo = frame.to_local(wo_world);
        for (bname, bsdf) in &bsdfs {
            seed += 1;
            let mut bad = 0u32;
            let r = chi2_test(
                |u2, u1| {
                    let s = guided::sample(bsdf, &frame, wo, g, u1, u2)?;
                    let (f, p) = bsdf.eval_pdf(wo, s.wi, TransportMode::Radiance);
                    let pm = guided::mixture_pdf(p, g, frame.to_world(s.wi));
                    if (pm - s.pdf).abs() > 2e-3 * pm
                        || (f / pm - s.weight).abs().max_element() > 2e-3 * (f / pm).max_element()
                    {
                        bad += 1;
                    }
                    Some(frame.to_world(s.wi))
                },
                // A guided direction where the BSDF is zero (below the surface) ends the path:
                // the density of the directions produced is the mixture's where f > 0.
                |d| {
                    let wi = frame.to_local(d);
                    if bsdf.eval(wo, wi, TransportMode::Radiance).is_black() {
                        0.0
                    } else {
                        guided::mixture_pdf(bsdf.pdf(wo, wi), g, d)
                    }
                },
                &cfg(seed, a),
            );
            // A direction's round trip through the square map (polynomial atan2) lands in the
            // neighbouring quadtree cell when it is within ~1e-6 of a cell edge: about 1 in
            // 10⁴–10⁵ samples, as the BSDF χ² tests tolerate for grazing half vectors.
            if bad > 20 {
                failures.push(format!("{name} × {bname}: {bad} pdf/weight mismatches"));
            }
            report(&mut failures, format!("{name} × {bname} mixture"), r);
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
