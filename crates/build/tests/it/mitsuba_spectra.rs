//! Mitsuba 3's `regular` and `irregular` spectrum plugins (issue 38) on
//! `scenes/mitsuba/spectra.xml`: diffuse and conductor reflectances, an area light's and the
//! sky's radiance.

use crate::repo_references::{check_repo_reference, mitsuba_scenes};

/// Spectral mode against Mitsuba 3.9.1's `llvm_ad_spectral` render of the same file.
#[test]
fn spectra_spectral() {
    check_repo_reference("spectra_spectral");
}

/// RGB mode: Mitsuba 3.9.1's RGB variants refuse to evaluate the two plugins, but convert
/// the same spectra written as inline `wavelength:value` lists (`spectra_inline.xml`,
/// generated from `spectra.xml`); `spectra.xml` in RGB renders that file's RGB reference.
#[test]
fn spectra_rgb_as_inline_lists() {
    let dir = mitsuba_scenes();
    let scene::Document::Scene(desc) =
        scene::load(&dir.join("spectra.xml"), &Default::default()).unwrap()
    else {
        panic!("not a scene")
    };
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    let meta: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.join("refs/spectra_inline.json")).unwrap(),
    )
    .unwrap();
    let batches = crate::references::render_desc_batches(
        &desc,
        crate::references::SPP,
        scene::RenderMode::Rgb,
    );
    crate::references::check_against(
        &dir.join("refs/spectra_inline"),
        "spectra (RGB, as inline lists)",
        batches,
        meta["relmse_256spp"].as_f64().unwrap(),
        crate::references::SPP,
    );
}
