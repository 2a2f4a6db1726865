//! Light selection by power and by the light BVH on the many-light demo scene
//! (`scenes/many-lights.xml`: 460 emitting triangles, one light each under these strategies).
//!
//! - `pmf_matches_sampling`: for receivers found by tracing camera-like rays into the scene
//!   (points on walls, objects and emitters, with their normals), every light returned by
//!   `Scene::sample_light` carries exactly `Scene::light_pmf` of it; the pmf sums to at most 1
//!   (exactly 1 for power, 1 minus the chance of no light for the BVH); and the frequencies of
//!   200 000 choices follow the pmf (χ², cells with fewer than 5 expected choices pooled, with
//!   "no light" as one more cell). α = 0.01, Šidák-corrected over all receivers; fixed seeds.
//! - `strategies_converge_to_the_same_image`: uniform, power and BVH selection render the
//!   same image: 16 independent batches of the uniform render make the reference (mean and
//!   standard error), and 16 batches of each other strategy pass `render::compare`'s block
//!   t-test (α = 0.01, Šidák-corrected over block-channels) against it.
//! - `bvh_beats_power_where_light_is_local`: on the outdoor demo
//!   (`scenes/many-lights-plaza.xml`, 784 emitting triangles in 196 lanterns) the light BVH's
//!   per-pixel relative variance, at equal spp (96², 64 spp, direct light), is less than a
//!   third of power selection's (measured ratio 5.0; no timing involved). Lower resolutions
//!   show less difference: pixels that partly cover a lantern are noisy under any strategy.

use std::path::PathBuf;

use build::render_desc;
use build::{BuildOptions, build};
use glam::Vec3;
use render::compare::{CompareOptions, Reference, TestImages, compare_with};
use render::film::Image;
use render::geometry::Ray;
use render::lights::Receiver;
use render::stats::{Pcg32, sidak};
use render::world::Scene;
use scene::{Document, LightSelection, LoadOptions, SceneDesc};
use statrs::distribution::{ChiSquared, ContinuousCDF};

fn demo(defines: &[(&str, &str)]) -> SceneDesc {
    load_scene("many-lights.xml", defines)
}

fn load_scene(name: &str, defines: &[(&str, &str)]) -> SceneDesc {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name);
    let opts = LoadOptions {
        defines: defines
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
    };
    let Document::Scene(desc) = scene::load(&path, &opts).expect("scene loads") else {
        panic!("not a scene")
    };
    *desc
}

fn built(desc: &SceneDesc, sel: LightSelection) -> Scene {
    build(
        desc,
        &BuildOptions {
            light_selection: Some(sel),
            ..Default::default()
        },
    )
    .expect("scene builds")
    .scene
}

/// Receivers on the scene's surfaces: hits of rays from random points in the room.
fn receivers(scene: &Scene, n: usize, seed: u64) -> Vec<Receiver> {
    let mut rng = Pcg32::new(seed, 7);
    let mut out = Vec::new();
    while out.len() < n {
        let o = Vec3::new(
            rng.next_f32() * 7.0 - 3.5,
            rng.next_f32() * 2.6 + 0.2,
            rng.next_f32() * 7.0 - 3.5,
        );
        let d = Vec3::new(
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
            rng.next_f32() - 0.5,
        )
        .normalize();
        if let Some(si) = scene.intersect(&Ray::new(o.into(), d.into()), f32::INFINITY) {
            out.push(Receiver::from(&si));
        }
    }
    out
}

#[test]
fn pmf_matches_sampling() {
    let desc = demo(&[]);
    const RECEIVERS: usize = 6;
    const SAMPLES: usize = 200_000;
    let alpha = sidak(0.01, 2 * RECEIVERS);
    for sel in [LightSelection::Power, LightSelection::Bvh] {
        let scene = built(&desc, sel);
        let n = scene.lights.len();
        assert_eq!(n, 460, "one light per emitting triangle");
        if let render::lights::select::LightSampler::Bvh(bvh) = &scene.light_sampler {
            println!(
                "light BVH: {} 4-wide nodes, {} levels",
                bvh.node_count(),
                bvh.depth()
            );
        }
        for (k, r) in receivers(&scene, RECEIVERS, 3).iter().enumerate() {
            let pmf: Vec<f64> = (0..n as u32)
                .map(|i| scene.light_pmf(r, i) as f64)
                .collect();
            let sum: f64 = pmf.iter().sum();
            match sel {
                LightSelection::Power => assert!((sum - 1.0).abs() < 1e-4, "Σ pmf = {sum}"),
                _ => assert!(sum <= 1.0 + 1e-4 && sum > 0.5, "Σ pmf = {sum}"),
            }
            let mut counts = vec![0u64; n + 1];
            let mut rng = Pcg32::new(11 + k as u64, 5);
            for _ in 0..SAMPLES {
                match scene.sample_light(rng.next_f32(), r) {
                    Some((i, _, p)) => {
                        assert_eq!(p, scene.light_pmf(r, i), "{sel:?}: light {i}");
                        counts[i as usize] += 1;
                    }
                    None => counts[n] += 1,
                }
            }
            // χ² with pooling of cells expecting fewer than 5 choices.
            let mut expected: Vec<f64> = pmf.iter().map(|p| p * SAMPLES as f64).collect();
            expected.push((1.0 - sum).max(0.0) * SAMPLES as f64);
            let mut order: Vec<usize> = (0..=n).collect();
            order.sort_by(|&a, &b| expected[a].total_cmp(&expected[b]));
            let (mut chi2, mut dof, mut pool_e, mut pool_o) = (0.0, 0i64, 0.0, 0.0);
            for &i in &order {
                let (e, o) = (expected[i], counts[i] as f64);
                if e == 0.0 {
                    assert_eq!(o, 0.0, "{sel:?}: light {i} has pmf 0 but was chosen");
                    continue;
                }
                if pool_e + e < 5.0 {
                    pool_e += e;
                    pool_o += o;
                    continue;
                }
                let (e, o) = (e + pool_e, o + pool_o);
                (pool_e, pool_o) = (0.0, 0.0);
                chi2 += (o - e) * (o - e) / e;
                dof += 1;
            }
            dof -= 1;
            let p = 1.0 - ChiSquared::new(dof.max(1) as f64).unwrap().cdf(chi2);
            println!(
                "{sel:?} receiver {k}: Σ pmf = {sum:.6}, chi2 = {chi2:.1}, dof = {dof}, p = {p:.3}"
            );
            assert!(
                p >= alpha,
                "{sel:?} receiver {k}: chi2 = {chi2}, dof = {dof}, p = {p}"
            );
        }
    }
}

const BATCHES: u64 = 16;

fn batches(desc: &SceneDesc, sel: LightSelection, spp: u32) -> Vec<Image> {
    (0..BATCHES)
        .map(|seed| {
            let out = render_desc(
                desc,
                &BuildOptions {
                    spp: Some(spp),
                    seed: Some(1000 * sel as u64 + seed),
                    light_selection: Some(sel),
                    ..Default::default()
                },
            )
            .expect("scene builds");
            assert_eq!(out.film.nonfinite_count(), 0, "NaN/Inf samples");
            out.film.develop()
        })
        .collect()
}

fn reference(images: &[Image]) -> Reference {
    Reference::from_batches(images).unwrap()
}

#[test]
fn strategies_converge_to_the_same_image() {
    let desc = demo(&[("res", "32"), ("max_depth", "3")]);
    let reference = reference(&batches(&desc, LightSelection::Uniform, 16));
    let opts = CompareOptions {
        reference_batches: BATCHES as u32,
        ..Default::default()
    };
    for sel in [LightSelection::Power, LightSelection::Bvh] {
        let test = TestImages::Batches(batches(&desc, sel, 8));
        let result = compare_with(&reference, &test, &opts).expect("comparable");
        println!("{sel:?} vs uniform: {result}");
        assert!(result.passed, "{sel:?} differs from uniform: {result}");
    }
}

#[test]
fn bvh_beats_power_where_light_is_local() {
    let desc = load_scene(
        "many-lights-plaza.xml",
        &[("res", "96"), ("max_depth", "2")],
    );
    // Mean over pixels of the squared standard error relative to the pixel's value (as relMSE).
    let rel_variance = |sel: LightSelection| {
        let out = render_desc(
            &desc,
            &BuildOptions {
                spp: Some(64),
                seed: Some(11),
                light_selection: Some(sel),
                ..Default::default()
            },
        )
        .expect("scene builds");
        let (img, se) = (out.film.develop(), out.film.develop_stderr());
        let n = img.pixels.len() as f64;
        img.pixels
            .iter()
            .zip(&se.pixels)
            .map(|(m, s)| {
                let (m, s) = (m.element_sum() as f64 / 3.0, s.element_sum() as f64 / 3.0);
                s * s / (m * m + 0.01)
            })
            .sum::<f64>()
            / n
    };
    let (power, bvh) = (
        rel_variance(LightSelection::Power),
        rel_variance(LightSelection::Bvh),
    );
    println!(
        "plaza, 64 spp: relative variance power {power:.3e}, bvh {bvh:.3e} (ratio {:.2})",
        power / bvh
    );
    assert!(bvh * 3.0 < power, "power {power}, bvh {bvh}");
}
