//! Issue 39: `render --denoise`, `penumbra denoise` and `render --display-server`, end to end
//! through the binary.
//!
//! The denoising tests need Open Image Denoise (`pip install pyoidn`): without it they print a
//! notice and pass, except under `CI=true`, where `.ci/run` installs it and its absence fails.

use std::net::TcpListener;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use render::compare::{load_reference, rel_mse};
use render::display::mock::Viewer;
use render::film::Image;
use render::image_io::read_image;

fn penumbra() -> Command {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("penumbra-denoise-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel)
}

fn run(cmd: &mut Command) -> Output {
    let o = cmd.output().expect("penumbra runs");
    assert!(
        o.status.success(),
        "{cmd:?} failed: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// Whether the denoiser library can be loaded (see the module docs).
fn have_oidn() -> bool {
    match render::denoise::Oidn::load() {
        Ok(_) => true,
        Err(e) => {
            let ci = std::env::var("CI").is_ok_and(|v| v == "true" || v == "1");
            assert!(!ci, "{e} (CI installs pyoidn)");
            eprintln!("skipping: {e}");
            false
        }
    }
}

/// The noisy (box-filtered, `--keep-noisy`) and denoised images of one render.
fn noisy_and_denoised(scene: &Path, args: &[&str], dir: &Path) -> (Image, Image) {
    let (noisy, den) = (dir.join("noisy.exr"), dir.join("den.exr"));
    run(penumbra()
        .arg("render")
        .arg(scene)
        .args(args)
        .args(["--denoise", "-q", "--keep-noisy"])
        .arg(&noisy)
        .arg("-o")
        .arg(&den));
    (read_image(&noisy).unwrap(), read_image(&den).unwrap())
}

/// Acceptance 1: relMSE against Mitsuba's references, noisy and denoised, on the two box-
/// filtered Cornell boxes (so the noisy image is also the plain render).
///
/// relMSE is an expectation over renders, so mitsuba-cbox's ratio is the pooled one over
/// seeds: at 16 spp, seeds 0–9 gave 8.1, 7.6, 8.7, 9.9, 9.7, 9.3, 7.2, 8.6, 10.0 and 10.3×
/// (8.8× pooled; 8.8× over the six tested here). What is left there is the luminaire's
/// edges, whose coverage at 16 samples of the independent sampler is noise that no auxiliary
/// image shows (the pixels along it are ~80 % of the denoised error), hence the spread
/// between seeds. bench-cbox at 4 spp: about 118×. Asserted: 8× pooled (the acceptance
/// line), 7× at each seed, 8× on bench-cbox.
#[test]
fn denoising_lowers_rel_mse() {
    let Some(shared) = scene::testing::shared_dir("references") else {
        return;
    };
    if !have_oidn() {
        return;
    }
    let dir = temp_dir("relmse");
    // bench-cbox's reference has no stderr image: the mean alone.
    let bench = read_image(&shared.join("bench-cbox.exr")).unwrap();
    let (n, d) = noisy_and_denoised(
        &shared.join("scenes/bench-cbox.xml"),
        &["--spp", "4", "--seed", "0"],
        &dir,
    );
    let (rn, rd) = (rel_mse(&n, &bench).unwrap(), rel_mse(&d, &bench).unwrap());
    println!(
        "bench-cbox 4 spp: relMSE {rn:.3e} → {rd:.3e} ({:.1}×)",
        rn / rd
    );
    assert!(rn / rd >= 8.0, "bench-cbox: only {:.1}×", rn / rd);

    let cbox = load_reference(&shared.join("mitsuba-cbox")).unwrap();
    let scene = shared.join("../scenes/standard/mitsuba-cbox/cbox-rgb.xml");
    let (mut sn, mut sd) = (0.0, 0.0);
    for seed in ["0", "1", "2", "3", "4", "5"] {
        let (n, d) = noisy_and_denoised(
            &scene,
            &["-D", "res=128", "--spp", "16", "--seed", seed],
            &dir,
        );
        let (rn, rd) = (
            rel_mse(&n, &cbox.mean).unwrap(),
            rel_mse(&d, &cbox.mean).unwrap(),
        );
        println!(
            "mitsuba-cbox 16 spp seed {seed}: relMSE {rn:.3e} → {rd:.3e} ({:.2}×)",
            rn / rd
        );
        assert!(
            rn / rd >= 7.0,
            "mitsuba-cbox seed {seed}: only {:.2}×",
            rn / rd
        );
        sn += rn;
        sd += rd;
    }
    println!("mitsuba-cbox pooled: {:.2}×", sn / sd);
    assert!(sn / sd >= 8.0, "mitsuba-cbox pooled: only {:.2}×", sn / sd);
}

/// Per row of `img`, the x where the profile crosses halfway between the row's dark and
/// bright levels (its values at x = 4 and x = width − 4; linear between pixels), and the
/// 20–80 % rise width (10–90 % reads the plateaus' residual noise: up to 2 pixels apart on
/// the dim bottom rows while the edge itself is in place).
fn edge_profile(img: &Image) -> Vec<(f32, f32)> {
    (0..img.height)
        .map(|y| {
            let row: Vec<f32> = (0..img.width).map(|x| img.get(x, y).y).collect();
            let (lo, hi) = (row[4], row[row.len() - 4]);
            let cross = |f: f32| {
                let v = lo + f * (hi - lo);
                let i = row.windows(2).position(|w| w[0] < v && w[1] >= v);
                i.map_or(f32::NAN, |i| {
                    i as f32 + (v - row[i]) / (row[i + 1] - row[i])
                })
            };
            (cross(0.5), cross(0.8) - cross(0.2))
        })
        .collect()
}

/// Acceptance 1, edges: a dark and a white wall meeting on a slanted line, 16 spp without
/// next-event estimation (very noisy), the scene's gaussian filter. Per row, the denoised
/// edge's 50 % crossing and its 20–80 % width are within 1 pixel of a 4096-spp render's
/// (measured: within 0.23 and 0.56 pixels).
#[test]
fn denoising_keeps_edges() {
    if !have_oidn() {
        return;
    }
    let dir = temp_dir("edge");
    let scene = repo("scenes/denoise/edge.xml");
    let reference = dir.join("ref.exr");
    run(penumbra()
        .arg("render")
        .arg(&scene)
        .args(["--spp", "4096", "-q", "-o"])
        .arg(&reference));
    let r = read_image(&reference).unwrap();
    let (_, d) = noisy_and_denoised(&scene, &["--spp", "16", "--nee", "off"], &dir);
    let (lo, hi) = (r.get(4, 32).y, r.get(60, 32).y);
    assert!(hi > 5.0 * lo, "a high-contrast edge ({lo} / {hi})");
    let (pr, pd) = (edge_profile(&r), edge_profile(&d));
    // Rows away from the film's top and bottom (the walls' own shading varies there).
    for y in 8..56 {
        let ((xr, wr), (xd, wd)) = (pr[y], pd[y]);
        assert!(
            (xr - xd).abs() <= 1.0 && (wr - wd).abs() <= 1.0,
            "row {y}: reference edge at {xr:.2} (width {wr:.2}), denoised at {xd:.2} (width {wd:.2})"
        );
    }
}

/// Acceptance 2: `penumbra denoise` on the noisy image and its auxiliary images gives the
/// bytes `render --denoise` wrote (a gaussian-filtered scene: `--filter gaussian` too).
#[test]
fn denoise_command_matches_render() {
    if !have_oidn() {
        return;
    }
    let dir = temp_dir("cmd");
    let scene = repo("scenes/denoise/edge.xml");
    noisy_and_denoised(&scene, &["--spp", "8", "--nee", "off"], &dir);
    let again = dir.join("again.exr");
    run(penumbra()
        .arg("denoise")
        .arg(dir.join("noisy.exr"))
        .arg("--albedo")
        .arg(dir.join("noisy_albedo.exr"))
        .arg("--normal")
        .arg(dir.join("noisy_normal.exr"))
        .args(["--filter", "gaussian", "-o"])
        .arg(&again));
    assert_eq!(
        std::fs::read(dir.join("den.exr")).unwrap(),
        std::fs::read(&again).unwrap(),
        "the same pixels"
    );
}

/// Acceptance 4: without the library (PENUMBRA_OIDN pointing nowhere) `--denoise` says how to
/// get it and exits 2; rendering without it works.
#[test]
fn denoise_without_library_says_how() {
    let dir = temp_dir("nolib");
    let out = dir.join("o.exr");
    let o = penumbra()
        .env(
            "PENUMBRA_OIDN",
            dir.join("missing/libOpenImageDenoise.so.2"),
        )
        .arg("render")
        .arg(repo("scenes/denoise/edge.xml"))
        .args(["--spp", "1", "--denoise", "-q", "-o"])
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("pip install pyoidn"), "{err}");
    assert!(!out.exists(), "nothing rendered");
    run(penumbra()
        .env("PENUMBRA_OIDN", dir.join("missing"))
        .arg("render")
        .arg(repo("scenes/denoise/edge.xml"))
        .args(["--spp", "1", "-q", "-o"])
        .arg(&out));
}

/// Acceptance 3: a mock tev receives a well-formed CreateImage and UpdateImage packets that
/// reassemble into exactly the image written to the EXR.
#[test]
fn live_view_shows_exactly_the_final_image() {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let viewer = Viewer::serve(listener, None);
    let dir = temp_dir("tev");
    let out = dir.join("live.exr");
    run(penumbra()
        .arg("render")
        .arg(repo("scenes/denoise/edge.xml"))
        .args([
            "--res",
            "150x130",
            "--spp",
            "8",
            "-q",
            "--display-server",
            &addr,
            "-o",
        ])
        .arg(&out));
    let v = viewer.join().unwrap();
    let img = read_image(&out).unwrap();
    assert_eq!(v.name, "live.exr");
    assert_eq!(v.size, (150, 130));
    assert_eq!(v.channels, ["R", "G", "B"]);
    for y in 0..img.height {
        for x in 0..img.width {
            let p = img.get(x, y);
            for (c, want) in [p.x, p.y, p.z].into_iter().enumerate() {
                assert_eq!(v.get(x, y, c).to_bits(), want.to_bits(), "pixel ({x}, {y})");
            }
        }
    }
}

/// Acceptance 3: tev quitting half-way (after its first packets) costs a warning, not the
/// render.
#[test]
fn live_view_losing_tev_is_a_warning() {
    let listener = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = listener.local_addr().unwrap().to_string();
    let viewer = Viewer::serve(listener, Some(2));
    let dir = temp_dir("tev-quit");
    let out = dir.join("o.exr");
    // Several passes (about a second each) on one thread.
    let o = run(penumbra()
        .arg("render")
        .arg(repo("scenes/denoise/edge.xml"))
        .args(["--res", "256x256", "--spp", "128", "--threads", "1"])
        .args(["--nee", "off", "--display-server", &addr, "-o"])
        .arg(&out));
    let v = viewer.join().unwrap();
    assert_eq!(v.created, 1);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("warning: live view"), "{err}");
    assert!(out.exists());
}
