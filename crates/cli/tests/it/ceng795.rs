//! CENG795 scenes through the command line and the renderer: every shared scene loads and
//! renders (tiny size, 1 spp), the white furnaces give 1, the brute-force / NEE / MIS Cornell
//! boxes converge to the same image, and Russian roulette leaves the mean unchanged (on our own
//! `scenes/ceng795/cornell_phong.json`). Tests of shared scenes are skipped with a notice when
//! ../shared/scenes/ceng795 is absent.
//!
//! Significance: the statistical checks use α = 0.01 overall, Šidák-corrected over the
//! [`TESTS`] tests of this file (2 furnaces; brute vs NEE, MIS vs NEE and Russian roulette on vs
//! off, each a block t-test and an image-mean t-test); seeds are fixed.

use std::path::{Path, PathBuf};
use std::process::Command;

use build::BuildOptions;
use build::render_desc;
use render::compare::{CompareOptions, Reference, TestImages, compare_with};
use render::film::Image;
use render::image_io::read_image;
use render::stats::{sidak, t_test};
use scene::{Document, LoadOptions, SceneDesc};
use statrs::distribution::{ContinuousCDF, StudentsT};

fn shared() -> Option<PathBuf> {
    scene::testing::shared_dir("scenes/ceng795")
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("penumbra-ceng795-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn scenes(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            scenes(&p, out);
        } else if matches!(p.extension().and_then(|e| e.to_str()), Some("json" | "xml")) {
            out.push(p);
        }
    }
}

/// Render `scene` to `out` at `res`×`res` with `spp` samples; returns stderr on failure.
fn render(scene: &Path, out: &Path, res: u32, spp: u32, seed: u64) -> Result<(), String> {
    let o = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("render")
        .arg(scene)
        .arg("-o")
        .arg(out)
        .args(["--res", &format!("{res}x{res}"), "--spp", &spp.to_string()])
        .args(["--seed", &seed.to_string(), "--threads", "2", "-q"])
        .output()
        .unwrap();
    if o.status.success() {
        Ok(())
    } else {
        Err(String::from_utf8_lossy(&o.stderr).into_owned())
    }
}

/// Statistical tests in this file (see the module docs).
const TESTS: usize = 8;

fn level() -> f64 {
    sidak(0.01, TESTS)
}

#[test]
fn every_shared_scene_renders_tiny() {
    let Some(dir) = shared() else { return };
    let mut files = Vec::new();
    scenes(&dir, &mut files);
    files.sort();
    let tmp = temp_dir("all");
    let mut rendered = 0;
    for (i, f) in files.iter().enumerate() {
        let out = tmp.join(format!("{i}.exr"));
        match render(f, &out, 8, 1, 1) {
            Ok(()) => {
                let img = read_image(&out).unwrap();
                assert!(
                    img.pixels
                        .iter()
                        .all(|p| p.is_finite() && p.min_element() >= 0.0),
                    "{}: negative or non-finite pixels",
                    f.display()
                );
                rendered += 1;
            }
            // The shared data lacks one PLY file (hw1/akif_uslu/trex_smooth_ply/mesh_3.ply);
            // anything else is a failure.
            Err(e) => assert!(e.contains("cannot load PLY file"), "{}: {e}", f.display()),
        }
    }
    eprintln!("{rendered} of {} CENG795 scenes rendered", files.len());
    assert!(rendered + 1 >= files.len());
    std::fs::remove_dir_all(&tmp).ok();
}

fn mean_var(v: &[f64]) -> (f64, f64) {
    let n = v.len() as f64;
    let m = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - m) * (x - m)).sum::<f64>() / (n - 1.0);
    (m, var)
}

#[test]
fn furnaces_give_one() {
    let Some(dir) = shared() else { return };
    let tmp = temp_dir("furnace");
    for name in ["furnace", "furnace_nee_mis"] {
        let out = tmp.join(format!("{name}.exr"));
        render(
            &dir.join(format!("json/tests/{name}.json")),
            &out,
            16,
            16,
            7,
        )
        .unwrap();
        let img = read_image(&out).unwrap();
        let v: Vec<f64> = img.pixels.iter().map(|p| p.x as f64).collect();
        let (m, var) = mean_var(&v);
        if var < 1e-12 {
            assert!((m - 1.0).abs() < 1e-4, "{name}: mean {m}");
        } else {
            let p = t_test(m, var, v.len() as u64, 1.0);
            assert!(p > level(), "{name}: mean {m}, var {var}, p = {p}");
        }
    }
    std::fs::remove_dir_all(&tmp).ok();
}

fn load(path: &Path) -> SceneDesc {
    match scene::load(path, &LoadOptions::default()) {
        Ok(Document::Scene(s)) => *s,
        Ok(_) => panic!("{}: not a scene", path.display()),
        Err(e) => panic!("{e}"),
    }
}

/// `k` independent renders of `desc` (its own integrator) at `res`×`res` with `spp` samples
/// each, seeds `seed`, `seed + 1`, ...
fn batches(desc: &SceneDesc, res: u32, spp: u32, k: u64, seed: u64) -> Vec<Image> {
    (seed..seed + k)
        .map(|seed| {
            let out = render_desc(
                desc,
                &BuildOptions {
                    spp: Some(spp),
                    seed: Some(seed),
                    resolution: Some((res, res)),
                    ..Default::default()
                },
            )
            .unwrap();
            assert_eq!(out.film.nonfinite_count(), 0);
            out.film.develop()
        })
        .collect()
}

/// Mean over pixels and channels.
fn image_mean(img: &Image) -> f64 {
    img.pixels
        .iter()
        .map(|p| (p.x + p.y + p.z) as f64)
        .sum::<f64>()
        / (3 * img.pixels.len()) as f64
}

/// Two tests of "`test` and `reference` (independent batches) converge to the same image":
/// the block t-test of `render::compare` (8×8 blocks, Šidák over the block-channels at the
/// file's per-test level) and Welch's t-test of the per-batch image means, which has the power
/// to see a uniform bias of a fraction of a percent. Batch means, not per-sample second
/// moments, carry the variance: a few rare bright paths (glossy reflections of the light)
/// make per-sample estimates too small. Returns whether both pass and a description.
fn same_image(reference: &[Image], test: &[Image]) -> (bool, String) {
    let cmp = compare_with(
        &Reference::from_batches(reference).unwrap(),
        &TestImages::Batches(test.to_vec()),
        &CompareOptions {
            alpha: level(),
            reference_batches: reference.len() as u32,
            ..CompareOptions::default()
        },
    )
    .unwrap();
    let (mr, vr) = mean_var(&reference.iter().map(image_mean).collect::<Vec<_>>());
    let (mt, vt) = mean_var(&test.iter().map(image_mean).collect::<Vec<_>>());
    let (kr, kt) = (reference.len() as f64, test.len() as f64);
    let (sr, st) = (vr / kr, vt / kt);
    let se = (sr + st).sqrt();
    let t = (mt - mr) / se;
    let dof = (sr + st).powi(2) / (sr * sr / (kr - 1.0) + st * st / (kt - 1.0));
    let p = StudentsT::new(0.0, 1.0, dof).map_or(0.0, |d| 2.0 * d.cdf(-t.abs()));
    let text = format!(
        "block test: {cmp}; image mean {mt:.5} vs {mr:.5} (ratio {:.4}, diff {:+.2e} ± {se:.2e}, \
         t = {t:+.2}, dof {dof:.1}, p = {p:.3}, level {:.2e})",
        mt / mr,
        mt - mr,
        level()
    );
    (cmp.passed && p >= level(), text)
}

/// The brute-force, NEE and MIS Cornell boxes (json/tests) converge to the same image.
/// Reference: NEE, 32 batches of 16 spp at 16×16. Brute force gets 16 batches of 256 spp (its
/// variance per sample is about 17 times NEE's), MIS 16 of 16. The image-mean test then has a
/// standard error of about 0.25 % of the mean, so a uniform bias of 1.5 % is found with near
/// certainty. (Long renders with the release build at 32×32, independent seeds, 32768
/// brute-force and 16384 NEE/MIS spp: brute/NEE = 1.0000 ± 0.0004, MIS/NEE = 0.9999 ± 0.0002,
/// no 8×8 block off by more than 3.1 standard errors.)
#[test]
fn cornell_brute_nee_mis_agree() {
    let Some(dir) = shared() else { return };
    let scene = |name: &str| load(&dir.join(format!("json/tests/cornell_{name}.json")));
    let nee = batches(&scene("nee"), 16, 16, 32, 1100);
    let mut failures = Vec::new();
    for (name, spp, seed) in [("brute", 256, 1200), ("mis", 16, 1300)] {
        let test = batches(&scene(name), 16, spp, 16, seed);
        let (ok, text) = same_image(&nee, &test);
        eprintln!("{name} vs nee: {text}");
        if !ok {
            failures.push(format!("{name} vs nee: {text}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Our own CENG795 scene, with the renderer parameters and recursion depth replaced.
fn phong_box(params: &str, max_depth: u32) -> SceneDesc {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/ceng795/cornell_phong.json");
    let text = std::fs::read_to_string(&src).unwrap();
    let from = "ImportanceSampling NextEventEstimation MIS_BALANCE";
    assert!(text.contains(from) && text.contains(r#""MaxRecursionDepth": "6""#));
    let text = text.replace(from, params).replace(
        r#""MaxRecursionDepth": "6""#,
        &format!(r#""MaxRecursionDepth": "{max_depth}""#),
    );
    static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let tmp = temp_dir("phong");
    let file = tmp.join(format!("box-{n}.json"));
    std::fs::write(&file, text).unwrap();
    let desc = load(&file);
    std::fs::remove_file(&file).ok();
    desc
}

/// Our example scene loads as written (path tracer with NEE and balance MIS, tone map, the
/// Phong-family materials) and renders a plausible image.
#[test]
fn own_example_scene_loads_and_renders() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/ceng795/cornell_phong.json");
    let desc = load(&src);
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    let s = &desc.sensors[0];
    assert!(s.film.tonemap.is_some());
    let Some(scene::IntegratorDesc::Path(p)) = &s.integrator else {
        panic!("path tracer expected")
    };
    assert!(p.nee && p.mis == scene::MisHeuristic::Balance && p.max_depth == 7);
    let m = image_mean(&batches(&desc, 16, 4, 1, 1)[0]);
    assert!(m > 0.01 && m < 10.0, "image mean {m}");
}

/// Russian roulette (from the first bounce) leaves the mean unchanged: the CENG795 path tracer
/// with `RussianRoulette` against the same without it, on our closed Cornell box with a glossy
/// and a metallic sphere. The same test must reject a render that stops after 3 bounces
/// instead of 6 (MaxRecursionDepth 3): it lacks about 5 % of the image mean (0.255 vs 0.270
/// here, t ≈ −8), less than a roulette that forgets to divide by its survival probability
/// would lose (paths survive each white-wall bounce with probability ≈ 0.7). Measured with
/// the test build at 32×32 and 4096 spp each: on/off = 1.0009 ± 0.0017.
#[test]
fn russian_roulette_leaves_the_mean_unchanged() {
    let params = "ImportanceSampling NextEventEstimation";
    let off = batches(&phong_box(params, 6), 16, 32, 32, 2100);
    let rr = format!("{params} RussianRoulette");
    let on = batches(&phong_box(&rr, 6), 16, 96, 16, 2200);
    let (ok, text) = same_image(&off, &on);
    eprintln!("roulette on vs off: {text}");
    assert!(ok, "roulette on vs off: {text}");
    let short = batches(&phong_box(params, 3), 16, 64, 16, 2300);
    let (ok, text) = same_image(&off, &short);
    eprintln!("depth 3 vs 6 (must fail): {text}");
    assert!(!ok, "a missing bounce was not detected: {text}");
}

/// Scenes without a `Tonemap` hold radiance in 0–255 display units: their PNG is
/// clamp(round(L), 0, 255) per channel of the EXR (no gamma), no PNG is more than 5 %
/// saturated (with 1.0 as white, hw1's Cornell box was white walls and solid red and blue),
/// and the box seen through its front wall from behind the image plane is not black.
#[test]
fn display_unit_scenes_write_rounded_pngs() {
    let Some(dir) = shared() else { return };
    let mut files = Vec::new();
    scenes(&dir, &mut files);
    files.sort();
    let tmp = temp_dir("display");
    let mut checked = 0;
    let mut report = Vec::new();
    for (i, f) in files.iter().enumerate() {
        let Ok(Document::Scene(desc)) = scene::load(f, &LoadOptions::default()) else {
            continue; // the scene with a missing PLY (see every_shared_scene_renders_tiny)
        };
        let Some(sensor) = desc.sensors.first() else {
            continue;
        };
        if !matches!(sensor.film.tonemap, Some(scene::Tonemap::DisplayUnits)) {
            continue;
        }
        // A tenth of the resolution keeps the aspect (and any off-axis window) of the scene.
        let (w, h) = (
            (sensor.film.width / 10).max(8),
            (sensor.film.height / 10).max(8),
        );
        let (png, exr) = (tmp.join(format!("{i}.png")), tmp.join(format!("{i}.exr")));
        let o = Command::new(env!("CARGO_BIN_EXE_penumbra"))
            .arg("render")
            .arg(f)
            .args(["--res", &format!("{w}x{h}"), "--spp", "4", "-q", "-o"])
            .arg(&png)
            .arg("-o")
            .arg(&exr)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{}: {}",
            f.display(),
            String::from_utf8_lossy(&o.stderr)
        );
        let radiance = read_image(&exr).unwrap();
        let bytes = render::image_io::read_image_with(&png, render::image_io::Decode::Raw).unwrap();
        // Saturated where the radiance is not: what 1.0-as-white did. Pixels whose radiance
        // exceeds 255 (bright highlights, hw1's fully lit red and blue walls) are counted
        // apart: the EXR says they are saturated.
        let (mut saturated, mut bright) = (0, 0);
        for (l, b) in radiance.pixels.iter().zip(&bytes.pixels) {
            for c in 0..3 {
                let expected = l[c].clamp(0.0, 255.0).round();
                let got = (b[c] * 255.0).round();
                assert!(
                    (got - expected).abs() <= 1.0,
                    "{}: PNG {got} for radiance {}",
                    f.display(),
                    l[c]
                );
            }
            let clipped = (0..3).any(|c| b[c] >= 1.0 && l[c] < 254.5);
            saturated += usize::from(clipped);
            bright += usize::from(l.max_element() >= 254.5);
        }
        let share = saturated as f64 / bytes.pixels.len() as f64;
        let bright = bright as f64 / bytes.pixels.len() as f64;
        let mean = radiance
            .pixels
            .iter()
            .map(|p| p.element_sum() as f64)
            .sum::<f64>()
            / (3 * radiance.pixels.len()) as f64;
        report.push(format!(
            "{}: mean {mean:.1}, {:.1} % saturated below 255, {:.1} % at or above 255",
            f.strip_prefix(&dir).unwrap_or(f).display(),
            100.0 * share,
            100.0 * bright
        ));
        assert!(
            share <= 0.05,
            "{}: {:.1} % of pixels saturated",
            f.display(),
            100.0 * share
        );
        if f.ends_with("hw3/cornellbox_boxes_dynamic.json") {
            assert!(mean > 10.0, "{}: black (mean {mean})", f.display());
        }
        checked += 1;
    }
    eprintln!("{}", report.join("\n"));
    assert!(checked >= 20, "only {checked} display-unit scenes");
    std::fs::remove_dir_all(&tmp).ok();
}

/// A one-pixel CENG795 scene looking straight down at a plane lit by a point light at the eye,
/// with a material of type `kind` (plus `extra` keys) of diffuse reflectance 0.3.
fn plane_scene(kind: &str, extra: &str) -> SceneDesc {
    let text = format!(
        r#"{{"Scene": {{
  "BackgroundColor": "0 0 0",
  "Cameras": {{"Camera": {{"_id": "1", "Position": "0 0 5", "Gaze": "0 0 -1", "Up": "0 1 0",
    "NearPlane": "-0.01 0.01 -0.01 0.01", "NearDistance": "1", "ImageResolution": "1 1",
    "ImageName": "p.png"}}}},
  "Lights": {{"PointLight": {{"_id": "1", "Position": "0 0 5", "Intensity": "1000 1000 1000"}}}},
  "Materials": {{"Material": {{"_id": "1", "_type": "{kind}", "AmbientReflectance": "0 0 0",
    "DiffuseReflectance": "0.3 0.3 0.3", "SpecularReflectance": "0 0 0",
    "MirrorReflectance": "0.5 0.5 0.5", "RefractionIndex": "1.5"{extra}}}}},
  "VertexData": {{"_data": "0 0 0"}},
  "Objects": {{"Plane": {{"_id": "1", "Material": "1", "Point": "1", "Normal": "0 0 1"}}}}
}}}}"#
    );
    let tmp = temp_dir("plane");
    let file = tmp.join(format!("{kind}.json"));
    std::fs::write(&file, text).unwrap();
    let desc = load(&file);
    std::fs::remove_dir_all(&tmp).ok();
    desc
}

/// Mirror, conductor and dielectric materials keep the course's diffuse lobe beside their
/// ideal one: the plane reads kd·I·cos θ / d² = 0.3 · 1000 / 25 = 12 (the ideal lobe sees the
/// black background), whichever lobe each sample chose. Dropping the lobes gives 0. Nothing
/// about these materials is warned about any more, rough or not.
#[test]
fn course_materials_keep_their_phong_lobes() {
    for kind in ["mirror", "conductor", "dielectric"] {
        for extra in ["", r#", "Roughness": "0.2", "AbsorptionIndex": "2""#] {
            let desc = plane_scene(kind, extra);
            assert!(desc.warnings.is_empty(), "{kind}: {:?}", desc.warnings);
            let img = &batches(&desc, 1, 16, 1, 5)[0];
            let v = img.pixels[0];
            assert!((v.x - 12.0).abs() < 1e-3 * 12.0, "{kind}{extra}: {v}");
        }
    }
}

/// `SampleClamp` on a path-tracing camera is the path tracer's sample clamp.
#[test]
fn sample_clamp_reaches_the_path_tracer() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/ceng795/cornell_phong.json");
    let text = std::fs::read_to_string(&src).unwrap();
    let from = r#""RendererParams""#;
    assert!(text.contains(from));
    let text = text.replacen(from, &format!(r#""SampleClamp": "10", {from}"#), 1);
    let tmp = temp_dir("clamp");
    let file = tmp.join("clamp.json");
    std::fs::write(&file, text).unwrap();
    let desc = load(&file);
    std::fs::remove_dir_all(&tmp).ok();
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    let Some(scene::IntegratorDesc::Path(p)) = &desc.sensors[0].integrator else {
        panic!("path tracer expected")
    };
    assert_eq!(p.clamp, Some(10.0));
}
