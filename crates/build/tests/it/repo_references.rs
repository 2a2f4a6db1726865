//! Scenes of `scenes/mitsuba/` against the Mitsuba 3 references committed beside them
//! (`scenes/mitsuba/refs/`, made by `scenes/mitsuba/make_reference.py`: 32 batches, the
//! command and Mitsuba's relMSE at 256 spp in `NAME.json`), by the rule of `references.rs`:
//! 16 × 32 spp pass the block t-test (α = 0.01, Šidák-corrected) and the relMSE at 256 spp
//! is at most 1.5× Mitsuba's. The references live in the repository, so these tests never
//! skip.

use std::path::{Path, PathBuf};

use scene::{Document, LoadOptions, RenderMode};

use crate::references::{SPP, check_against, render_desc_batches};

/// `scenes/mitsuba/`.
pub(crate) fn mitsuba_scenes() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/mitsuba")
}

/// What `make_reference.py` recorded of a reference.
struct RefMeta {
    scene: PathBuf,
    defines: Vec<(String, String)>,
    spectral: bool,
    rel_mse_256: f64,
}

fn meta(name: &str) -> RefMeta {
    let dir = mitsuba_scenes();
    let path = dir.join("refs").join(format!("{name}.json"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    let v: serde_json::Value = serde_json::from_str(&text).expect("valid JSON");
    let defines = v["defines"]
        .as_object()
        .map(|m| {
            m.iter()
                .map(|(k, v)| (k.clone(), v.as_str().expect("string define").to_string()))
                .collect()
        })
        .unwrap_or_default();
    RefMeta {
        scene: dir.join(v["scene"].as_str().expect("scene path")),
        defines,
        spectral: v["variant"]
            .as_str()
            .is_some_and(|s| s.contains("spectral")),
        rel_mse_256: v["relmse_256spp"].as_f64().expect("relmse_256spp"),
    }
}

/// Renders the reference's scene (with its defines, in its variant's mode) as 16 × 32 spp
/// and checks it against `scenes/mitsuba/refs/NAME`.
pub(crate) fn check_repo_reference(name: &str) {
    check_repo_reference_with(name, None, SPP)
}

/// [`check_repo_reference`] with another scene file than the reference's own (with the
/// reference's defines and mode: e.g. the scene rewritten in pbrt-v4 syntax) and batches of
/// `spp` samples.
pub(crate) fn check_repo_reference_with(name: &str, scene_file: Option<&Path>, spp: u32) {
    let m = meta(name);
    let opts = LoadOptions {
        defines: m.defines.clone(),
    };
    let scene_file = scene_file.unwrap_or(&m.scene);
    let Document::Scene(desc) = scene::load(scene_file, &opts).expect("scene loads") else {
        panic!("not a scene")
    };
    assert!(
        desc.warnings.is_empty(),
        "{name}: the scene loads with warnings: {:?}",
        desc.warnings
    );
    let mode = if m.spectral {
        RenderMode::Spectral
    } else {
        RenderMode::Rgb
    };
    let batches = render_desc_batches(&desc, spp, mode);
    let prefix = mitsuba_scenes().join("refs").join(name);
    check_against(&prefix, name, batches, m.rel_mse_256, spp)
}

/// Mitsuba's `lanczos` filter (2 lobes): its negative lobes ring at the checkerboard's edges.
#[test]
fn lanczos_filter() {
    check_repo_reference("lanczos");
}

/// Mitsuba's `multijitter` sampler: a checkerboard and a sphere, every pixel across edges.
/// The sampler changes the noise, not the image: the test is that stratified draws stay
/// unbiased in every dimension the paths use (its stratification is `sampling_stats.rs`'s).
#[test]
fn multijitter_sampler() {
    check_repo_reference("multijitter");
}
