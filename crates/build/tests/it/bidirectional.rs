//! Light tracing (`ptracer`, `render::integrators::ptracer`) and bidirectional path tracing
//! (`bdpt`, `render::integrators::bdpt`), against Mitsuba 3's references by the shared rule
//! (16 batches × 32 spp, block t-test at α = 0.01 Šidák-corrected; skipped without
//! `../shared`):
//! - `bdpt` on all five RGB references, the media references and both spectral ones;
//! - `ptracer` on `mitsuba-cbox` (RGB and spectral) and `lights` (point, spot, directional
//!   and area lights). The other references show surfaces through delta or near-delta
//!   reflections (glass, mirrors, smooth plastic, `veach-plates`' α = 0.005 plate), which no
//!   light path can reach through a pinhole: light tracing is not expected to pass them;
//! - neither image depends on the thread count.

use std::path::Path;

use build::{BuildOptions, render_desc, render_seeds};
use render::compare::{TestImages, compare, load_reference};
use render::film::Image;
use render::render::RenderOptions;
use scene::{IntegratorDesc, RenderMode, SceneDesc};

fn load(file: &Path, defines: &[(&str, &str)]) -> SceneDesc {
    crate::references::load_scene(file, defines)
}

/// The scene's path length (its path tracer's).
fn max_depth(desc: &SceneDesc) -> i32 {
    match &desc.integrator {
        IntegratorDesc::Path(p) => p.max_depth,
        IntegratorDesc::VolPath { max_depth, .. } => *max_depth,
        _ => -1,
    }
}

/// The light tracer with the scene's own path length.
fn ptracer(desc: &SceneDesc) -> IntegratorDesc {
    IntegratorDesc::Ptracer {
        max_depth: max_depth(desc),
        hide_emitters: false,
    }
}

/// BDPT with the scene's own path length.
fn bdpt(desc: &SceneDesc) -> IntegratorDesc {
    IntegratorDesc::Bdpt {
        max_depth: max_depth(desc),
        visualize_strategies: false,
        visualize_weights: false,
    }
}

type Choice = fn(&SceneDesc) -> IntegratorDesc;

/// `integrator`'s images of `desc` at 32 spp, one per seed of `seeds`.
fn render_batches(
    desc: &SceneDesc,
    integrator: Choice,
    seeds: std::ops::Range<u64>,
    mode: RenderMode,
) -> Vec<Image> {
    let opts = BuildOptions {
        spp: Some(32),
        mode,
        integrator: Some(integrator(desc)),
        ..Default::default()
    };
    render_seeds(desc, &opts, seeds)
        .expect("scene builds")
        .into_iter()
        .map(|out| {
            assert_eq!(out.film.nonfinite_count(), 0, "NaN/Inf samples or splats");
            out.film.develop()
        })
        .collect()
}

/// 16 batches of 32 spp of `integrator` against the reference `name`.
fn check(integrator: Choice, name: &str, scene_rel: &str, res: bool, mode: RenderMode) {
    let Some(shared) = scene::testing::shared_dir("references").map(|r| r.join("..")) else {
        return;
    };
    let defines: &[(&str, &str)] = if res { &[("res", "128")] } else { &[] };
    let desc = load(&shared.join(scene_rel), defines);
    let reference = load_reference(&shared.join("references").join(name)).expect("reference");
    let batches = render_batches(&desc, integrator, 0..16, mode);
    let result = compare(&reference, &TestImages::Batches(batches)).expect("comparable");
    let label = format!("{:?}", integrator(&desc));
    println!("{label} {name}: {result}");
    assert!(result.passed, "{label} {name}: {result}");
}

const CBOX: &str = "scenes/standard/mitsuba-cbox/cbox-rgb.xml";
const RGB: RenderMode = RenderMode::Rgb;

#[test]
fn bdpt_mitsuba_cbox() {
    check(bdpt, "mitsuba-cbox", CBOX, true, RGB);
}

/// Glass, a mirror, rough gold and the caustics they make.
#[test]
fn bdpt_cbox_specular() {
    check(
        bdpt,
        "cbox-specular",
        "references/scenes/cbox-specular.xml",
        false,
        RGB,
    );
}

/// Sphere lights of four sizes over glossy plates (one of α = 0.005).
#[test]
fn bdpt_veach_plates() {
    check(
        bdpt,
        "veach-plates",
        "references/scenes/veach-plates.xml",
        false,
        RGB,
    );
}

/// Point, spot, directional and a BSDF-less one-sided disk light.
#[test]
fn bdpt_lights() {
    check(bdpt, "lights", "references/scenes/lights.xml", false, RGB);
}

/// The environment as a light (light subpaths start on the disk across the scene, their
/// densities per unit solid angle at infinity) and a thin lens.
#[test]
fn bdpt_envmap_materials() {
    let scene = "references/scenes/envmap-materials.xml";
    check(bdpt, "envmap-materials", scene, false, RGB);
}

/// Media behind a null boundary (HG g = 0.7) and inside a glass cube (coloured σt): medium
/// vertices on both subpaths, transmittance on every connection, hero-channel MIS. (With
/// pbrt's convention for the densities after a specular bounce, 0 read as 1, the light
/// reaching the green wall through the cube had a heavy tail, and these 16 batches failed
/// at one block, p = 1.3e-6; it took 48 to pass. With the discrete measure, p_min = 2.3e-3.)
#[test]
fn bdpt_media_homogeneous() {
    let scene = "references/scenes/media-homogeneous.xml";
    check(bdpt, "media-homogeneous", scene, false, RGB);
}

/// A density grid lit by the sun and the sky through it (free flights and transmittance
/// by delta and ratio tracking, drawing from the sample stream).
#[test]
fn bdpt_media_heterogeneous() {
    let scene = "references/scenes/media-heterogeneous.xml";
    check(bdpt, "media-heterogeneous", scene, false, RGB);
}

/// Camera, spot light and surfaces inside one fog: subpaths start in a medium.
#[test]
fn bdpt_media_fog() {
    check(
        bdpt,
        "media-fog",
        "references/scenes/media-fog.xml",
        false,
        RGB,
    );
}

/// Spectral mode: both subpaths share the camera sample's wavelengths.
#[test]
fn bdpt_mitsuba_cbox_spectral() {
    check(
        bdpt,
        "mitsuba-cbox-spectral",
        CBOX,
        true,
        RenderMode::Spectral,
    );
}

/// A black-body emitter, a D65 sky, measured conductors, a narrow-band reflectance and BK7
/// glass, in spectral mode, against our path tracer (32 × 512 spp, committed: `make_own_references`; the comparison counts the
/// reference's own noise, and this one leaves p_min 6.8e-5 against the threshold 1.3e-5)
/// rather than Mitsuba's
/// reference: on the narrow-band green wall our spectral renders, the path tracer's and
/// BDPT's alike, read the red channel lower than Mitsuba's (mean over the wall's pixels at
/// 4096–8192 spp: BDPT 0.0235, path 0.0241, Mitsuba 0.0279, against a green of about 3.5).
/// That channel is a small difference of large XYZ terms; ours matches the analytic value
/// for that wall under D65 and under a 3000 K black body alone, so the gap comes from the
/// light the rest of the scene sends there (the upsampled RGB floor, a metamer of
/// Mitsuba's, is a candidate), not from BDPT. BDPT's noise resolves it: against Mitsuba's
/// reference 2 of 3 seed sets of 16 × 32 spp failed there (p_min 3e-7, 9e-6); against the
/// path tracer four sets passed (p_min 1.0e-4 to 7.5e-3). `bdpt_mitsuba_cbox_spectral`
/// holds BDPT's spectral mode to Mitsuba.
#[test]
fn bdpt_spectral_materials() {
    check_spectral_against_own("spectral-materials", 32);
}

#[test]
fn ptracer_mitsuba_cbox() {
    check(ptracer, "mitsuba-cbox", CBOX, true, RGB);
}

/// Spectral mode: every light path carries its own wavelengths.
#[test]
fn ptracer_mitsuba_cbox_spectral() {
    check(
        ptracer,
        "mitsuba-cbox-spectral",
        CBOX,
        true,
        RenderMode::Spectral,
    );
}

/// The disk has no BSDF, so light from the others must stop at it (a photon walking
/// through such a surface once made its shadow 11 % too bright).
#[test]
fn ptracer_lights() {
    check(
        ptracer,
        "lights",
        "references/scenes/lights.xml",
        false,
        RGB,
    );
}

/// `integrator` on `desc` in `mode` at `spp` with `threads` threads.
fn render_threads(
    desc: &SceneDesc,
    integrator: IntegratorDesc,
    mode: RenderMode,
    spp: u32,
    threads: usize,
) -> Image {
    let opts = BuildOptions {
        spp: Some(spp),
        seed: Some(5),
        mode,
        integrator: Some(integrator),
        ..Default::default()
    };
    let built = build::build(desc, &opts).expect("builds");
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let ropts = RenderOptions {
        spp,
        ..Default::default()
    };
    pool.install(|| {
        render::render::render(
            &built.scene,
            &built.integrator,
            &ropts,
            &render::render::Silent,
        )
    })
    .film
    .develop()
}

#[test]
fn same_image_for_one_and_two_threads() {
    let mlt = |multiplexed| IntegratorDesc::Mlt {
        max_depth: 4,
        bootstrap: 2000,
        chains: 100,
        large_step: 0.3,
        sigma: 0.01,
        direct_samples: 16,
        multiplexed,
    };
    // Surfaces only, and media (a null-bounded smoke sphere, a glass cube holding a medium).
    for scene in ["cornell-box.xml", "media/smoky-box.xml"] {
        let desc = load(&ours(scene), &[("res", "24")]);
        for integrator in [ptracer(&desc), bdpt(&desc), mlt(true), mlt(false)] {
            for mode in [RGB, RenderMode::Spectral] {
                let a = render_threads(&desc, integrator.clone(), mode, 3, 1);
                let b = render_threads(&desc, integrator.clone(), mode, 3, 2);
                let label = format!("{scene} {integrator:?} {mode:?}");
                assert!(a.pixels.iter().any(|p| p.x > 0.0), "{label}");
                assert_eq!(a.pixels, b.pixels, "{label}");
            }
        }
    }
}

/// A minimal Mitsuba scene of `version` (an 8 × 8 film, a glowing sphere) with
/// `integrator` (its XML element), built.
fn built_with(version: &str, integrator: &str) -> build::Built {
    let xml = format!(
        r#"<scene version="{version}">
             {integrator}
             <sensor type="perspective">
               <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
             </sensor>
             <shape type="sphere"><emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
           </scene>"#
    );
    let desc = scene::load_xml_text("integrator.xml", &xml).expect("loads");
    build::build(&desc, &BuildOptions::default()).expect("builds")
}

/// Mitsuba 3's `ptracer` parameters (and Mitsuba 0.6's names): max_depth and hide_emitters
/// reach the integrator; rr_depth and samples_per_pass are read.
#[test]
fn mitsuba_ptracer_parameters() {
    use render::integrators::Integrator;
    for (version, params) in [
        (
            "3.0.0",
            r#"<integer name="max_depth" value="5"/><boolean name="hide_emitters" value="true"/>
               <integer name="rr_depth" value="3"/><integer name="samples_per_pass" value="4"/>"#,
        ),
        (
            "0.6.0",
            r#"<integer name="maxDepth" value="5"/><boolean name="hideEmitters" value="true"/>
               <integer name="rrDepth" value="3"/><integer name="granularity" value="1000"/>
               <boolean name="bruteForce" value="false"/>"#,
        ),
    ] {
        let built = built_with(
            version,
            &format!(r#"<integrator type="ptracer">{params}</integrator>"#),
        );
        let Integrator::Ptracer(cfg) = built.integrator else {
            panic!("{:?}", built.integrator)
        };
        assert_eq!(cfg.max_depth, 5, "{version}");
        assert!(cfg.hide_emitters, "{version}");
    }
}

/// Mitsuba 0.6's `pssmlt` parameters reach the MLT (`directSamples` included, and our
/// `multiplexed`); an unset `maxDepth` is pbrt's default of 6 edges, `directSamples`
/// Mitsuba's 16, and the chains multiplexed.
#[test]
fn mitsuba_pssmlt_parameters() {
    use render::integrators::Integrator;
    for (params, want) in [
        (
            r#"<integer name="maxDepth" value="7"/><float name="pLarge" value="0.5"/>
               <integer name="luminanceSamples" value="5000"/><integer name="directSamples" value="-1"/>
               <float name="sigma" value="0.02"/><integer name="chains" value="64"/>
               <boolean name="twoStage" value="false"/><integer name="rrDepth" value="3"/>
               <boolean name="multiplexed" value="false"/>"#,
            (7, 0.5, 5000, -1, 0.02, 64, false),
        ),
        ("", (6, 0.3, 100_000, 16, 0.01, 1000, true)),
    ] {
        let built = built_with(
            "0.6.0",
            &format!(r#"<integrator type="pssmlt">{params}</integrator>"#),
        );
        let Integrator::Mlt(c) = built.integrator else {
            panic!("{:?}", built.integrator)
        };
        let got = (
            c.max_depth,
            c.large_step,
            c.bootstrap,
            c.direct_samples,
            c.sigma,
            c.chains,
            c.multiplexed,
        );
        assert_eq!(got, want);
    }
}

/// MLT (multiplexed over BDPT's strategies, the chains doing every depth: direct samples
/// −1) on Mitsuba's Cornell box at 128²: the relMSE against the reference falls tenfold from
/// 64 to 2048 mutations per pixel (measured 2.31e-2 → 7.00e-4, 33-fold: a 32-fold count
/// keeps a threefold margin), and at 2048 the image mean is within 1 % of the reference in
/// every channel (measured +0.09/+0.03/+0.13 %; at 4096, which took twice the time,
/// +0.29/+0.37/+0.38 %). Chains are correlated, so the mean's error at a given mutation
/// count is larger than BDPT's at as many samples.
#[test]
fn mlt_converges_on_mitsuba_cbox() {
    check_mlt_convergence("mlt", true, |_| -1, (64, 2048), 0.1, RGB);
}

/// Kelemen's MLT (a state a whole BDPT sample) on Mitsuba's Cornell box at 128², with the
/// paths of one and two edges apart, so that the chains' `min_edges` bound is exercised
/// (counted twice, the direct light would make the image far too bright), at as many BDPT
/// samples per pixel as mutations (at a fixed 16 their noise holds the relMSE near 4e-3
/// whatever the mutations): the relMSE against the reference falls from 16 to 256
/// mutations per pixel (measured 6.59e-3 → 3.76e-4), and at 256 the image mean is within
/// 1 % of the reference in every channel (measured +0.04/+0.09/+0.08 %); about 20 s.
#[test]
fn kelemen_mlt_converges_on_mitsuba_cbox() {
    check_mlt_convergence("kelemen", false, |spp| spp as i32, (16, 256), 0.2, RGB);
}

/// The same in spectral mode against `mitsuba-cbox-spectral`, from 16 to 128 mutations per
/// pixel: the wavelengths are primary sample dimensions of the chains like any other
/// (measured 7.05e-3 → 9.06e-4, below the 0.2 factor with a 1.5-fold margin; mean
/// +0.25/+0.00/−0.48 %; at 256, twice the time: 4.40e-4, +0.20/+0.08/+0.31 %).
#[test]
fn kelemen_mlt_converges_on_mitsuba_cbox_spectral() {
    let spectral = RenderMode::Spectral;
    check_mlt_convergence("kelemen", false, |spp| spp as i32, (16, 128), 0.2, spectral);
}

/// MLT on Mitsuba's Cornell box at 128² in `mode`, seed 0 (`multiplexed` or Kelemen's,
/// `direct` the direct samples at a mutation count), at `lo` and `hi` mutations per pixel:
/// the relMSE against the reference (`mitsuba-cbox` or `mitsuba-cbox-spectral`) at `hi` is
/// below `factor` times that at `lo`, and the image mean at `hi` is within 1 % of the
/// reference in every channel.
fn check_mlt_convergence(
    label: &str,
    multiplexed: bool,
    direct: fn(u32) -> i32,
    (lo, hi): (u32, u32),
    factor: f64,
    mode: RenderMode,
) {
    let Some(shared) = scene::testing::shared_dir("references").map(|r| r.join("..")) else {
        return;
    };
    let desc = load(&shared.join(CBOX), &[("res", "128")]);
    let name = match mode {
        RenderMode::Rgb => "mitsuba-cbox",
        RenderMode::Spectral => "mitsuba-cbox-spectral",
    };
    let reference = load_reference(&shared.join("references").join(name)).expect("reference");
    let render = |spp| {
        let mlt = IntegratorDesc::Mlt {
            max_depth: max_depth(&desc),
            bootstrap: 100_000,
            chains: 1000,
            large_step: 0.3,
            sigma: 0.01,
            direct_samples: direct(spp),
            multiplexed,
        };
        let opts = BuildOptions {
            spp: Some(spp),
            seed: Some(0),
            mode,
            integrator: Some(mlt),
            ..Default::default()
        };
        render_desc(&desc, &opts).expect("builds").film.develop()
    };
    let e_lo = render::compare::rel_mse(&render(lo), &reference.mean).unwrap();
    let img = render(hi);
    let e_hi = render::compare::rel_mse(&img, &reference.mean).unwrap();
    println!("{label} {name} relMSE: {lo} mutations/pixel {e_lo:.3e}, {hi} {e_hi:.3e}");
    assert!(e_hi < factor * e_lo, "{label}: relMSE {e_lo} → {e_hi}");
    let (a, b) = (mean_rgb(&img), mean_rgb(&reference.mean));
    let ratio: Vec<f64> = (0..3).map(|c| a[c] / b[c]).collect();
    println!("{label} {name} mean ÷ reference at {hi}: {ratio:.4?}");
    for (c, r) in ratio.iter().enumerate() {
        assert!((r - 1.0).abs() < 0.01, "{label} channel {c}: {r}");
    }
}

/// The sum over an image's pixels, per channel.
fn mean_rgb(img: &Image) -> [f64; 3] {
    let mut m = [0.0f64; 3];
    for p in &img.pixels {
        for (c, v) in m.iter_mut().zip([p.x, p.y, p.z]) {
            *c += v as f64;
        }
    }
    m
}

/// BDPT with per-strategy images on `scenes/cornell-box.xml` (all diffuse, one area light)
/// at `res`², box filter, paths of at most 4 edges; the image and the strategy images by
/// name.
fn strategy_render(
    visualize_weights: bool,
    res: u32,
    spp: u32,
    seed: u64,
) -> (Image, Vec<(String, Image)>) {
    let mut desc = load(&ours("cornell-box.xml"), &[("res", &res.to_string())]);
    for s in &mut desc.sensors {
        s.film.filter = scene::FilterDesc::Box { radius: 0.5 };
    }
    let opts = BuildOptions {
        spp: Some(spp),
        seed: Some(seed),
        integrator: Some(IntegratorDesc::Bdpt {
            max_depth: 4,
            visualize_strategies: !visualize_weights,
            visualize_weights,
        }),
        ..Default::default()
    };
    let out = render_desc(&desc, &opts).expect("scene builds");
    let extra = out
        .extra
        .iter()
        .map(|(name, film)| (name.clone(), film.develop()))
        .collect();
    (out.film.develop(), extra)
}

/// pbrt-v4's `visualizeweights`: one image per strategy of paths up to 4 edges (13 of
/// them, (1, 1) left out), named `bdpt_dDD_sSS_tTT`, and their sum is the image (box
/// filter: every contribution lands in its own pixel; up to float rounding).
#[test]
fn weighted_strategy_images_sum_to_the_image() {
    let (image, parts) = strategy_render(true, 24, 8, 3);
    let names: Vec<&str> = parts.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names.len(), 13, "{names:?}");
    assert!(names.contains(&"bdpt_d00_s00_t02") && names.contains(&"bdpt_d03_s04_t01"));
    assert!(!names.contains(&"bdpt_d00_s01_t01"));
    let mut sum = vec![render::math::Vec3::ZERO; image.pixels.len()];
    for (name, part) in &parts {
        assert!(part.pixels.iter().any(|p| p.x > 0.0), "{name} is black");
        for (s, p) in sum.iter_mut().zip(&part.pixels) {
            *s += *p;
        }
    }
    for (i, (s, p)) in sum.iter().zip(&image.pixels).enumerate() {
        let err = (*s - *p).abs().max_element();
        assert!(
            err <= 1e-4 * (1.0 + p.max_element()),
            "pixel {i}: sum {s} image {p}"
        );
    }
}

/// pbrt-v4's `visualizestrategies`: each strategy's unweighted estimate. In a diffuse box
/// lit by an area light every strategy samples every path, so the images of one depth
/// estimate the same image: each strategy of depths 1 and 2 against the one that samples
/// a light point (s = 1), by the z statistic of the per-pixel differences, 15 tests
/// (5 pairs × RGB) at α = 0.01 Šidák-corrected.
#[test]
fn unweighted_strategy_images_of_one_depth_agree() {
    let (_, parts) = strategy_render(false, 32, 256, 7);
    let img = |name: &str| -> Vec<[f32; 3]> {
        let (_, i) = parts.iter().find(|(n, _)| n == name).expect(name);
        i.pixels.iter().map(|p| p.to_array()).collect()
    };
    // Šidák: 1 − 0.99^(1/15) = 6.70e-4 per test, two-sided normal quantile 3.40.
    let z_crit = 3.40;
    for (depth, others) in [
        (1, &[(0, 3), (2, 1)][..]),
        (2, &[(0, 4), (2, 2), (3, 1)][..]),
    ] {
        let light = img(&format!("bdpt_d{depth:02}_s01_t{:02}", depth + 1));
        for &(s, t) in others {
            let name = format!("bdpt_d{depth:02}_s{s:02}_t{t:02}");
            let z = scene::testing::z_of_mean_difference(&img(&name), &light);
            println!("{name} vs s = 1: z = {z:.2?} (|z| < {z_crit:.2})");
            assert!(z.iter().all(|z| z.abs() < z_crit), "{name}: z = {z:?}");
        }
    }
}

/// Mitsuba 0.6's `bdpt` parameters and pbrt-v4's per-strategy image switches (as Mitsuba
/// property names) reach the integrator; `visualizeWeights` wins over
/// `visualizeStrategies`, as in pbrt-v4.
#[test]
fn mitsuba_bdpt_parameters() {
    use render::integrators::Integrator;
    use render::integrators::bdpt::StrategyImages;
    for (params, expected) in [
        ("", None),
        (
            r#"<boolean name="visualizeStrategies" value="true"/>"#,
            Some(StrategyImages::Unweighted),
        ),
        (
            r#"<boolean name="visualizeStrategies" value="true"/>
               <boolean name="visualizeWeights" value="true"/>"#,
            Some(StrategyImages::Weighted),
        ),
    ] {
        let built = built_with(
            "0.6.0",
            &format!(
                r#"<integrator type="bdpt"><integer name="maxDepth" value="4"/>
                     <boolean name="lightImage" value="true"/>{params}</integrator>"#
            ),
        );
        let Integrator::Bdpt(cfg) = built.integrator else {
            panic!("{:?}", built.integrator)
        };
        assert_eq!(cfg.max_depth, 4);
        assert_eq!(cfg.strategy_images, expected, "{params}");
    }
}

/// A scene with an own reference: name, scene file, defines, reference spp per batch.
type OwnReference = (
    &'static str,
    std::path::PathBuf,
    &'static [(&'static str, &'static str)],
    u32,
);

/// The spectral scenes whose BDPT renders are checked against our own unidirectional
/// integrator (see each test): name, scene, defines, reference spp per batch.
fn own_reference_scenes() -> Vec<OwnReference> {
    let mut v = vec![
        ("bk7-prism", ours("dispersion/bk7-prism.xml"), &[][..], 256),
        (
            "tinted-glass",
            ours("dispersion/tinted-glass.xml"),
            &[("res", "48")][..],
            2048,
        ),
    ];
    if let Some(refs) = scene::testing::shared_dir("references") {
        v.push((
            "spectral-materials",
            refs.join("scenes/spectral-materials.xml"),
            &[][..],
            512,
        ));
    }
    v
}

/// Where the committed own references live: `scenes/own-refs/NAME{.exr,.stderr.exr}`.
fn own_reference(name: &str) -> std::path::PathBuf {
    ours("own-refs").join(name)
}

/// `count` batches of `spp` of `desc` in spectral mode with `integrator`, seeds from `seed0`.
fn spectral_batches(
    desc: &SceneDesc,
    integrator: &IntegratorDesc,
    seed0: u64,
    count: u64,
    spp: u32,
) -> Vec<Image> {
    let opts = BuildOptions {
        spp: Some(spp),
        mode: RenderMode::Spectral,
        integrator: Some(integrator.clone()),
        ..Default::default()
    };
    render_seeds(desc, &opts, seed0..seed0 + count)
        .expect("builds")
        .into_iter()
        .map(|out| {
            assert_eq!(out.film.nonfinite_count(), 0, "{integrator:?}");
            out.film.develop()
        })
        .collect()
}

/// Writes the references of [`own_reference_scenes`]: 32 batches (seeds 1000–1031, as the
/// shared references) of the scene's own integrator in spectral mode, mean and standard error
/// of the mean. Rendered once and committed, so that the suite does not render them on every
/// run (issue 36); rerun after a change that should move them:
/// `cargo test --release -p penumbra-build --test it make_own_references -- --ignored`.
#[test]
#[ignore = "writes scenes/own-refs/; run by hand"]
fn make_own_references() {
    use render::compare::Reference;
    use render::image_io::write_image;
    for (name, file, defines, spp) in own_reference_scenes() {
        let desc = load(&file, defines);
        let r = Reference::from_batches(&spectral_batches(&desc, &desc.integrator, 1000, 32, spp))
            .unwrap();
        let prefix = own_reference(name);
        std::fs::create_dir_all(prefix.parent().unwrap()).unwrap();
        write_image(&prefix.with_extension("exr"), &r.mean).unwrap();
        write_image(&prefix.with_extension("stderr.exr"), &r.stderr).unwrap();
        println!("wrote {} ({spp} spp × 32)", prefix.display());
    }
}

/// BDPT (16 batches of `spp`, seeds 300–315) in spectral mode against the committed
/// reference `name` of the scene's own integrator ([`make_own_references`]) by the block
/// t-test (α = 0.01 Šidák-corrected inside).
fn check_spectral_against_own(name: &str, spp: u32) {
    use render::compare::compare;
    let Some((_, file, defines, _)) = own_reference_scenes().into_iter().find(|s| s.0 == name)
    else {
        return; // needs ../shared, absent (said by shared_dir)
    };
    let desc = load(&file, defines);
    let reference = load_reference(&own_reference(name)).expect("a committed reference");
    let bdpt_batches = TestImages::Batches(spectral_batches(&desc, &bdpt(&desc), 300, 16, spp));
    let result = compare(&reference, &bdpt_batches).unwrap();
    println!("bdpt {name} (spectral): {result}");
    assert!(result.passed, "bdpt {name} (spectral): {result}");
}

/// `scenes/<file>`.
fn ours(file: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(file)
}

/// Spectral BDPT through a smooth dispersive interface: a collimated beam through a BK7
/// prism spreads into a spectrum across the film (`scenes/dispersion/bk7-prism.xml`), seen
/// through two delta refractions (s = 0), whose camera subpath keeps its hero wavelength
/// only. Against the path tracer (32 × 256 spp, committed); 16 × 64 spp. Measured p_min 6.7e-3;
/// counting every wavelength after the termination (the secondaries' light taking the hero's
/// way through the glass, which smears the spectrum) fails it at p_min 1e-55.
#[test]
fn bdpt_spectral_prism_matches_path() {
    check_spectral_against_own("bk7-prism", 64);
}

/// Spectral BDPT with a dispersive sphere holding a chromatic medium
/// (`scenes/dispersion/tinted-glass.xml`: SF11, its caustic on the floor): subpaths that
/// terminate their secondaries on their own, medium vertices on both, hero-only strategies
/// beside full ones. Against `volpath` (32 × 2048 spp, committed; p_min 1.4e-3 against the threshold
/// 9.3e-5), 48². At 32 spp per batch the
/// hero-only paths around the sphere's rim and in the caustic are so skewed that `volpath`'s
/// own batches failed against a 16384-spp `volpath` image in 2 of 3 seed sets; at 256 BDPT
/// passed 3 of 3 (p_min 1.8e-3 to 4.2e-2 against 65536 spp), at 0.55× `volpath`'s relMSE.
#[test]
fn bdpt_spectral_tinted_glass_matches_volpath() {
    check_spectral_against_own("tinted-glass", 256);
}
