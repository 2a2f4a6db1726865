//! Renders every scene of `../shared/references/` and compares it with Mitsuba 3's reference
//! by the rule of `../shared/references/README.md`: K = 16 independent batches of 16 spp
//! (seeds 0–15) must pass the block t-test (α = 0.01, Šidák-corrected over block-channels),
//! and the relMSE of their 256-spp mean must be at most 1.5× Mitsuba's at 256 spp.
//!
//! Why 16 × 16 rather than the README's minimum of 8 × 32: with K = 8 the per-block variance
//! is estimated from 7 degrees of freedom, and over 768 block-channels one of them now and then
//! gets a badly underestimated variance. We met exactly that on `lights` with seeds 0–7: one
//! block whose 8 batch means spread 4× less than the per-pixel variances imply, t = 10 — while
//! seeds 20–27 and 28–35 pass, and a 512-spp render agrees with the reference at that block.
//! Sixteen batches make the variance estimate robust at the same total cost.
//!
//! Skipped, with a notice, when `../shared/references` is absent.

use std::path::{Path, PathBuf};

use render::build::{BuildOptions, build};
use render::compare::{TestImages, compare, load_reference};
use render::film::Image;
use render::integrators::Integrator;
use render::render::{RenderOptions, Silent, render};
use scene::{Document, LoadOptions};

const BATCHES: u64 = 16;
const SPP: u32 = 16;

fn shared() -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared");
    if p.join("references").is_dir() {
        Some(p)
    } else {
        eprintln!(
            "notice: {} is absent; reference comparisons skipped",
            p.display()
        );
        None
    }
}

fn render_batches(scene_file: &Path, defines: &[(&str, &str)]) -> Vec<Image> {
    let opts = LoadOptions {
        defines: defines
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
    };
    let Document::Scene(desc) = scene::load(scene_file, &opts).expect("scene loads") else {
        panic!("not a scene")
    };
    (0..BATCHES)
        .map(|seed| {
            let scene = build(
                &desc,
                &BuildOptions {
                    spp: Some(SPP),
                    seed: Some(seed),
                    ..Default::default()
                },
            )
            .expect("scene builds");
            let integrator = Integrator::from_desc(&scene.integrator).unwrap();
            let out = render(
                &scene,
                &integrator,
                &RenderOptions {
                    spp: SPP,
                    ..Default::default()
                },
                &Silent,
            );
            assert_eq!(out.film.nonfinite_count(), 0, "NaN/Inf samples");
            out.film.develop()
        })
        .collect()
}

fn check(name: &str, scene_rel: &str, defines: &[(&str, &str)], mitsuba_rel_mse: f64) {
    let Some(shared) = shared() else { return };
    let refs = shared.join("references");
    let scene_file = if scene_rel.starts_with("../") {
        refs.join(scene_rel)
    } else {
        refs.join("scenes").join(scene_rel)
    };
    let reference = load_reference(&refs.join(name)).expect("reference loads");
    let batches = render_batches(&scene_file, defines);
    let result = compare(&reference, &TestImages::Batches(batches)).expect("comparable");
    println!("{name}: {result}");
    println!(
        "{name}: relMSE {:.3e} at {} spp vs Mitsuba {mitsuba_rel_mse:.3e} (ratio {:.2})",
        result.rel_mse,
        BATCHES * SPP as u64,
        result.rel_mse / mitsuba_rel_mse
    );
    assert!(result.passed, "{name}: block t-test fails: {result}");
    assert!(
        result.rel_mse <= 1.5 * mitsuba_rel_mse,
        "{name}: relMSE {} > 1.5 × Mitsuba's {mitsuba_rel_mse}",
        result.rel_mse
    );
}

#[test]
fn mitsuba_cbox() {
    check(
        "mitsuba-cbox",
        "../scenes/standard/mitsuba-cbox/cbox-rgb.xml",
        &[("res", "128")],
        0.00053,
    );
}

#[test]
fn cbox_specular() {
    check("cbox-specular", "cbox-specular.xml", &[], 0.0102);
}

#[test]
fn veach_plates() {
    check("veach-plates", "veach-plates.xml", &[], 0.00049);
}

#[test]
fn lights() {
    check("lights", "lights.xml", &[], 0.0027);
}

#[test]
fn envmap_materials() {
    check("envmap-materials", "envmap-materials.xml", &[], 0.0114);
}
