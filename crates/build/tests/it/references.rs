//! Renders every scene of `../shared/references/` and compares it with Mitsuba 3's reference
//! by the rule of `../shared/references/README.md`:
//! - bias: K = 16 independent batches of 32 spp (seeds 0–15) must pass the block t-test
//!   (α = 0.01, Šidák-corrected over block-channels);
//! - noise parity: the relMSE of the mean of the first 8 batches (256 spp) must be at most
//!   1.5× Mitsuba's relMSE at 256 spp.
//!
//! Why 16 × 32 rather than the README's minimum of 8 × 32: with K = 8 a block's variance is
//! estimated from 7 degrees of freedom and, over 768 block-channels, one of them now and then
//! is badly underestimated; and caustic paths (cbox-specular) make batch means of few samples
//! skewed, which the t-test does not model. Both happened to us: `lights` with seeds 0–7 had
//! one block whose batch means spread 4× less than the per-pixel variances imply (t = 10,
//! while seeds 20–35 pass and a 512-spp render agrees with the reference there), and
//! `cbox-specular` with 16 × 16 spp failed on the skew of its caustics. More and larger
//! batches make the test both more robust and more powerful against real bias.
//!
//! Skipped, with a notice, when `../shared/references` is absent.

use std::path::{Path, PathBuf};

use build::BuildOptions;
use render::compare::{TestImages, compare, load_reference, rel_mse};
use render::film::Image;
use scene::{Document, LoadOptions, RenderMode};

const BATCHES: u64 = 16;
/// Samples per pixel of one batch (envmap-materials uses more: see its test).
pub(crate) const SPP: u32 = 32;
/// The noise-parity figure is taken at 256 spp (the first 256 / batch-spp batches).
const PARITY_SPP: u32 = 256;

pub(crate) fn shared() -> Option<PathBuf> {
    scene::testing::shared_dir("references").map(|r| r.join(".."))
}

fn render_batches(
    scene_file: &Path,
    defines: &[(&str, &str)],
    spp: u32,
    mode: RenderMode,
) -> Vec<Image> {
    render_desc_batches(&load_scene(scene_file, defines), spp, mode)
}

/// The scene of `file` with the `-D` parameters `defines` (panics unless it is a scene).
pub(crate) fn load_scene(file: &Path, defines: &[(&str, &str)]) -> scene::SceneDesc {
    let opts = LoadOptions {
        defines: defines
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
    };
    let Document::Scene(desc) = scene::load(file, &opts).expect("scene loads") else {
        panic!("not a scene")
    };
    *desc
}

pub(crate) fn render_desc_batches(
    desc: &scene::SceneDesc,
    spp: u32,
    mode: RenderMode,
) -> Vec<Image> {
    let opts = BuildOptions {
        spp: Some(spp),
        mode,
        ..Default::default()
    };
    render_opts_batches(desc, &opts, 0..BATCHES)
}

/// One image per seed of `seeds`, the scene built once with `opts` (no NaN/Inf samples).
pub(crate) fn render_opts_batches(
    desc: &scene::SceneDesc,
    opts: &BuildOptions,
    seeds: std::ops::Range<u64>,
) -> Vec<Image> {
    build::render_seeds(desc, opts, seeds)
        .expect("scene builds")
        .into_iter()
        .map(|out| {
            assert_eq!(out.film.nonfinite_count(), 0, "NaN/Inf samples");
            out.film.develop()
        })
        .collect()
}

fn mean_image(images: &[Image]) -> Image {
    let mut m = Image::new(images[0].width, images[0].height);
    for img in images {
        for (a, b) in m.pixels.iter_mut().zip(&img.pixels) {
            *a += *b / images.len() as f32;
        }
    }
    m
}

fn check(name: &str, scene_rel: &str, defines: &[(&str, &str)], mitsuba_rel_mse: f64) {
    check_with(name, scene_rel, defines, mitsuba_rel_mse, SPP)
}

fn check_with(
    name: &str,
    scene_rel: &str,
    defines: &[(&str, &str)],
    mitsuba_rel_mse: f64,
    spp: u32,
) {
    let Some(shared) = shared() else { return };
    let refs = shared.join("references");
    let scene_file = if scene_rel.starts_with("../") {
        refs.join(scene_rel)
    } else {
        refs.join("scenes").join(scene_rel)
    };
    check_file(
        name,
        &scene_file,
        defines,
        mitsuba_rel_mse,
        spp,
        RenderMode::Rgb,
    )
}

/// [`check_with`] for a scene file anywhere (the reference is still `references/<name>`).
pub(crate) fn check_file(
    name: &str,
    scene_file: &Path,
    defines: &[(&str, &str)],
    mitsuba_rel_mse: f64,
    spp: u32,
    mode: RenderMode,
) {
    let Some(shared) = shared() else { return };
    let batches = render_batches(scene_file, defines, spp, mode);
    check_batches(&shared, name, batches, mitsuba_rel_mse, spp)
}

/// [`check_file`] for a scene already loaded (and perhaps adjusted by the caller).
pub(crate) fn check_desc(
    name: &str,
    desc: &scene::SceneDesc,
    mitsuba_rel_mse: f64,
    spp: u32,
    mode: RenderMode,
) {
    let Some(shared) = shared() else { return };
    let batches = render_desc_batches(desc, spp, mode);
    check_batches(&shared, name, batches, mitsuba_rel_mse, spp)
}

fn check_batches(shared: &Path, name: &str, batches: Vec<Image>, mitsuba_rel_mse: f64, spp: u32) {
    let prefix = shared.join("references").join(name);
    check_against(&prefix, name, batches, mitsuba_rel_mse, spp)
}

/// The block t-test and noise parity of `batches` against the reference at `prefix`
/// (`prefix.exr` and `prefix.stderr.exr`).
pub(crate) fn check_against(
    prefix: &Path,
    name: &str,
    batches: Vec<Image>,
    mitsuba_rel_mse: f64,
    spp: u32,
) {
    let reference = load_reference(prefix).expect("reference loads");
    let parity = mean_image(&batches[..(PARITY_SPP / spp) as usize]);
    let rel_mse = rel_mse(&parity, &reference.mean).expect("same size");
    let result = compare(&reference, &TestImages::Batches(batches)).expect("comparable");
    println!("{name}: {result}");
    println!(
        "{name}: relMSE {rel_mse:.3e} at {} spp vs Mitsuba {mitsuba_rel_mse:.3e} (ratio {:.2})",
        PARITY_SPP,
        rel_mse / mitsuba_rel_mse
    );
    assert!(result.passed, "{name}: block t-test fails: {result}");
    assert!(
        rel_mse <= 1.5 * mitsuba_rel_mse,
        "{name}: relMSE {rel_mse} > 1.5 × Mitsuba's {mitsuba_rel_mse}"
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

/// The same Cornell box in spectral mode against Mitsuba's `llvm_ad_spectral`: the RGB
/// reflectances upsampled (Jakob–Hanika), the light an RGB illuminant spectrum. 1–3 % from
/// the RGB reference, so an RGB render fails it.
#[test]
fn mitsuba_cbox_spectral() {
    let Some(shared) = shared() else { return };
    let scene = shared.join("scenes/standard/mitsuba-cbox/cbox-rgb.xml");
    check_file(
        "mitsuba-cbox-spectral",
        &scene,
        &[("res", "128")],
        0.00064,
        SPP,
        RenderMode::Spectral,
    );
}

/// Materials whose appearance depends on the spectrum, against Mitsuba's `llvm_ad_spectral`:
/// a 3000 K black-body area light and a `d65` sky (declared spectra, sampled as declared),
/// measured Cu and Au conductors, a narrow-band tabulated reflectance, an upsampled RGB
/// floor and BK7 glass (Mitsuba's constant 1.5046).
#[test]
fn spectral_materials() {
    let Some(shared) = shared() else { return };
    let scene = shared.join("references/scenes/spectral-materials.xml");
    check_file(
        "spectral-materials",
        &scene,
        &[],
        0.216,
        SPP,
        RenderMode::Spectral,
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

/// Batches of 128 spp here (16 × 128; the README allows any K ≥ 8 of equal spp). The floor
/// in the contact shadow of the rough-plastic sphere (block x 24–32, y 64–72) is lit mostly by
/// rare sun paths: its 32-spp batch means have skewness ≈ 3, and the t-test is not calibrated
/// there for *either* renderer. Measured on that block alone, 40 independent sets of
/// 16 × 32 spp: our grand mean / reference = 1.004 ± 0.009, Mitsuba 3 (scalar_rgb) 1.008 ±
/// 0.010 — no bias — but the block fails the image's Šidák level in 5/40 of our sets and
/// 2/40 of Mitsuba's own. With 128-spp batches the skewness drops to ≈ 2.3, the t statistics
/// have sd 1.35 instead of ≈ 2, and 0/30 sets fail (smallest p 9e-4).
#[test]
fn envmap_materials() {
    check_with("envmap-materials", "envmap-materials.xml", &[], 0.0114, 128);
}

/// `volpath` through a null-bounded HG medium and a glass cube with a coloured, absorbing
/// interior.
#[test]
fn media_homogeneous() {
    check("media-homogeneous", "media-homogeneous.xml", &[], 0.0244);
}

/// A 64³ density grid (`plume-density.vol`) under sun and sky: delta and ratio tracking.
#[test]
fn media_heterogeneous() {
    check(
        "media-heterogeneous",
        "media-heterogeneous.xml",
        &[],
        0.0019,
    );
}

/// The same scene with the grid read from `plume.vdb` (the same values as OpenVDB grids, whose
/// transform puts voxel centres where the `.vol`'s are): the scene is copied with the
/// `filename` swapped, and checked against the same reference.
#[test]
fn media_heterogeneous_vdb() {
    let Some(shared) = shared() else { return };
    let scenes = shared.join("references/scenes");
    let xml = std::fs::read_to_string(scenes.join("media-heterogeneous.xml")).expect("scene");
    let vdb = scenes.join("plume.vdb");
    let swapped = xml.replace(
        r#"value="plume-density.vol""#,
        &format!(r#"value="{}""#, vdb.display()),
    );
    assert_ne!(swapped, xml, "the scene names plume-density.vol");
    let dir = std::env::temp_dir().join(format!("penumbra-refs-vdb-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("a temporary folder");
    let scene_file = dir.join("media-heterogeneous-vdb.xml");
    std::fs::write(&scene_file, swapped).expect("write the scene");
    check_file(
        "media-heterogeneous",
        &scene_file,
        &[],
        0.0019,
        SPP,
        RenderMode::Rgb,
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Camera, spot light and surfaces inside one fog: sensor and exterior media, and the spot
/// light's 1/r² singularity in the medium (equiangular sampling keeps its variance finite).
#[test]
fn media_fog() {
    check("media-fog", "media-fog.xml", &[], 0.165);
}
