//! Mitsuba 0.6 files (issue 38): references of `scenes/mitsuba/` rewritten in Mitsuba 0.6
//! syntax (`scenes/mitsuba/v06/`) render the image Mitsuba 3 renders of their Mitsuba 3 form
//! (which Mitsuba 3 cannot load in 0.6 syntax): the rule of `repo_references.rs` against
//! `scenes/mitsuba/refs/NAME`.

use scene::{Document, LoadOptions, RenderMode};

use crate::references::{SPP, check_against, render_desc_batches};
use crate::repo_references::mitsuba_scenes;

/// Renders `v06/NAME.xml` as 16 × 32 spp against `refs/NAME`; the scene may warn only with
/// a message containing one of `allowed`.
fn check_v06(name: &str, allowed: &[&str]) {
    let dir = mitsuba_scenes();
    let path = dir.join("v06").join(format!("{name}.xml"));
    let Document::Scene(desc) = scene::load(&path, &LoadOptions::default()).expect("loads") else {
        panic!("not a scene")
    };
    for w in &desc.warnings {
        assert!(
            allowed.iter().any(|a| w.message.contains(a)),
            "{name}: unexpected warning {w:?}"
        );
    }
    let meta = dir.join("refs").join(format!("{name}.json"));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&meta).expect("reference metadata"))
            .expect("valid JSON");
    let rel_mse = v["relmse_256spp"].as_f64().expect("relmse_256spp");
    let batches = render_desc_batches(&desc, SPP, RenderMode::Rgb);
    check_against(&dir.join("refs").join(name), name, batches, rel_mse, SPP);
}

/// `lanczos.xml` in 0.6 syntax: `maxDepth`, `toWorld`, `sampleCount`, a `<spectrum>`
/// radiance, the checkerboard's `uscale`/`vscale`, hdrfilm's `banner` and `pixelFormat`.
#[test]
fn lanczos_v06() {
    check_v06("lanczos", &[]);
}

/// `legacy_box.xml` in 0.6 syntax: `flipNormals`, `diffuseReflectance`, `intIOR`, a
/// `<spectrum>` reflectance, `ldsampler` (Mitsuba 0.6's low-discrepancy sampler: padded
/// scrambled (0,2)-sequences, which our `sobol` is), hdrfilm's `fileFormat` and `banner`.
#[test]
fn legacy_box_v06() {
    check_v06("legacy_box", &[]);
}
