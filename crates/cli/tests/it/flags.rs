//! `render`'s light-transport and sampling flags for every format: `--max-depth`,
//! `--rr-depth`, `--sampler`, `--filter`, `--clamp`, `--nee`; `-D` outside Mitsuba XML.
//! Each test fails if its flag is ignored. Statistical checks use the block t-test of
//! `penumbra compare` (Šidák-corrected inside, α = 0.01) with fixed seeds.

use std::path::{Path, PathBuf};
use std::process::Command;

use render::film::Image;
use render::image_io::read_image;

fn penumbra() -> Command {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
}

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("penumbra-flags-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Render the example Cornell box at 24² with `flags`; returns the image and its stderr.
fn render(dir: &Path, name: &str, flags: &[&str]) -> (Image, Image) {
    let (out, se) = (
        dir.join(format!("{name}.exr")),
        dir.join(format!("{name}.se.exr")),
    );
    let o = penumbra()
        .current_dir(repo_root())
        .args([
            "render",
            "scenes/cornell-box.xml",
            "--res",
            "24x24",
            "-q",
            "-o",
        ])
        .arg(&out)
        .arg("--stderr")
        .arg(&se)
        .args(flags)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{flags:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    (read_image(&out).unwrap(), read_image(&se).unwrap())
}

fn mean(i: &Image) -> f64 {
    i.pixels.iter().map(|p| p.element_sum() as f64).sum::<f64>() / (3 * i.pixels.len()) as f64
}

fn mean_sq(i: &Image) -> f64 {
    i.pixels
        .iter()
        .map(|p| (p.x * p.x + p.y * p.y + p.z * p.z) as f64)
        .sum::<f64>()
        / (3 * i.pixels.len()) as f64
}

/// `penumbra compare` of `test` (+ its stderr image) against `reference`: exit code.
fn compare(dir: &Path, reference: &str, test: &str) -> i32 {
    let o = penumbra()
        .arg("compare")
        .arg(dir.join(format!("{reference}.exr")))
        .arg(dir.join(format!("{test}.exr")))
        .arg("--stderr")
        .arg(dir.join(format!("{test}.se.exr")))
        .output()
        .unwrap();
    o.status.code().unwrap_or(-1)
}

/// The reference a comparison reads: NAME.exr with NAME.stderr.exr beside it.
fn as_reference(dir: &Path, name: &str) {
    std::fs::copy(
        dir.join(format!("{name}.se.exr")),
        dir.join(format!("{name}.stderr.exr")),
    )
    .unwrap();
}

#[test]
fn max_depth_and_nee_are_applied() {
    let dir = temp_dir("depth-nee");
    let (d1, _) = render(&dir, "d1", &["--spp", "16", "--max-depth", "1"]);
    let (d3, _) = render(&dir, "d3", &["--spp", "16", "--max-depth", "3"]);
    // Depth 1 sees only the light itself; depth 3 adds direct and one bounce of indirect
    // (0.063 against 0.112).
    assert!(
        mean(&d3) > 1.5 * mean(&d1),
        "{} vs {}",
        mean(&d1),
        mean(&d3)
    );

    // NEE off is brute force: the same mean, more noise.
    render(&dir, "on", &["--spp", "256", "--seed", "1"]);
    as_reference(&dir, "on");
    let (_, se_on) = render(&dir, "on2", &["--spp", "64", "--seed", "2"]);
    let (_, se_off) = render(&dir, "off", &["--spp", "64", "--seed", "3", "--nee", "off"]);
    assert_eq!(
        compare(&dir, "on", "off"),
        0,
        "brute force converges to the same image"
    );
    assert!(
        mean_sq(&se_off) > 2.0 * mean_sq(&se_on),
        "brute force is noisier: {} vs {}",
        mean_sq(&se_off),
        mean_sq(&se_on)
    );
}

/// `--max-depth` reaches a scene's `volpath` too (it was refused as "another integrator").
#[test]
fn max_depth_applies_to_volpath() {
    let dir = temp_dir("volpath-depth");
    let mean_at = |depth: &str| {
        let out = dir.join(format!("v{depth}.exr"));
        let o = penumbra()
            .current_dir(repo_root())
            .args([
                "render",
                "scenes/media/smoky-box.xml",
                "--res",
                "24x24",
                "--spp",
                "8",
            ])
            .args(["-q", "--max-depth", depth, "-o"])
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        mean(&read_image(&out).unwrap())
    };
    // One edge: the light alone; three: direct light and a bounce.
    let (d1, d3) = (mean_at("1"), mean_at("3"));
    assert!(d3 > 1.5 * d1, "{d1} vs {d3}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn rr_depth_sampler_and_filter_are_applied() {
    let dir = temp_dir("rr");
    // Roulette from the first segment on leaves the mean unchanged (t-test); that the flag
    // reaches the path tracer's settings is `TransportArgs`'s unit test (in the Cornell box
    // Mitsuba's throughput roulette changes the noise by only ~3 %, too little to test here).
    render(&dir, "ref", &["--spp", "256", "--seed", "1"]);
    as_reference(&dir, "ref");
    render(
        &dir,
        "early",
        &["--spp", "64", "--seed", "3", "--rr-depth", "1"],
    );
    assert_eq!(
        compare(&dir, "ref", "early"),
        0,
        "roulette leaves the mean unchanged"
    );
    // Another sampler or filter gives another image from the same seed.
    let (a, _) = render(&dir, "ind", &["--spp", "4", "--sampler", "independent"]);
    let (b, _) = render(&dir, "sob", &["--spp", "4", "--sampler", "sobol"]);
    assert_ne!(a.pixels, b.pixels, "--sampler is applied");
    let (c, _) = render(&dir, "box", &["--spp", "4", "--filter", "box"]);
    let (d, _) = render(&dir, "mit", &["--spp", "4", "--filter", "mitchell"]);
    assert_ne!(c.pixels, d.pixels, "--filter is applied");
}

/// With a box filter a pixel averages its own samples, so clamped samples bound it.
#[test]
fn clamp_bounds_every_sample() {
    let dir = temp_dir("clamp");
    let (free, _) = render(&dir, "free", &["--spp", "8", "--filter", "box"]);
    let (clamped, _) = render(
        &dir,
        "clamped",
        &["--spp", "8", "--filter", "box", "--clamp", "0.2"],
    );
    let max = |i: &Image| {
        i.pixels
            .iter()
            .map(|p| p.max_element())
            .fold(0.0f32, f32::max)
    };
    assert!(
        max(&free) > 1.0,
        "the light is brighter than the clamp: {}",
        max(&free)
    );
    assert!(max(&clamped) <= 0.2 + 1e-5, "{}", max(&clamped));
    for bad in ["0", "-1", "nan"] {
        let o = penumbra()
            .current_dir(repo_root())
            .args([
                "render",
                "scenes/cornell-box.xml",
                "--clamp",
                bad,
                "-q",
                "-o",
            ])
            .arg(dir.join("x.exr"))
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "--clamp {bad}");
    }
}

/// `-D` only means something to Mitsuba XML: elsewhere it is an error, not ignored.
#[test]
fn defines_outside_mitsuba_xml_are_errors() {
    let o = penumbra()
        .current_dir(repo_root())
        .args(["info", "scenes/comp30019/showcase.txt", "-D", "spp=4"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("-D sets Mitsuba/Nori XML"), "{stderr}");
    let o = penumbra()
        .current_dir(repo_root())
        .args(["info", "scenes/cornell-box.xml", "-D", "spp=4"])
        .output()
        .unwrap();
    assert!(o.status.success());
}

/// `--mode` (and `-m` with Mitsuba variant names) selects the colour mode: every spelling of
/// spectral gives the same image, which is not the RGB one; `rgb` is the default; anything
/// else is a usage error naming what is accepted.
#[test]
fn mode_selects_rgb_or_spectral() {
    let dir = temp_dir("mode");
    let px = |i: &Image| i.pixels.clone();
    let seed = ["--spp", "4", "--seed", "1"];
    let with = |name: &str, extra: &[&str]| {
        let flags: Vec<&str> = seed.iter().chain(extra).copied().collect();
        render(&dir, name, &flags).0
    };
    let default = with("default", &[]);
    let rgb = with("rgb", &["--mode", "rgb"]);
    let llvm_rgb = with("llvm-rgb", &["-m", "llvm_ad_rgb"]);
    let spectral = with("spectral", &["--mode", "spectral"]);
    let scalar = with("scalar", &["-m", "scalar_spectral"]);
    let llvm = with("llvm", &["-m", "llvm_ad_spectral"]);
    assert_eq!(px(&default), px(&rgb));
    assert_eq!(px(&default), px(&llvm_rgb));
    assert_eq!(px(&spectral), px(&scalar));
    assert_eq!(px(&spectral), px(&llvm));
    assert_ne!(px(&spectral), px(&rgb));
    // Same scene, same light: the spectral image is the RGB one up to noise and the
    // upsampling's few percent.
    let (s, r) = (mean(&spectral), mean(&rgb));
    assert!((s / r - 1.0).abs() < 0.1, "spectral mean {s} vs RGB {r}");
    for bad in ["bogus", "llvm_ad_mono"] {
        let o = penumbra()
            .current_dir(repo_root())
            .args(["render", "scenes/cornell-box.xml", "-q", "--mode", bad])
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(2), "--mode {bad}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains("expected rgb, spectral"),
            "--mode {bad}: {err}"
        );
    }
}
