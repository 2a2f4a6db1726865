//! The `comp30019` command on the course's scenes with the original command lines, malformed
//! scene lines, render layers, and a COMP30019 ↔ Mitsuba XML equivalence test.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use render::build::{BuildOptions, build};
use render::compare::{Reference, TestImages, compare};
use render::film::Image;
use render::integrators::Integrator;
use render::layers::render_layers;
use render::render::render_desc;
use scene::{Document, IntegratorDesc, LoadOptions, PathDesc, SceneDesc};

fn penumbra() -> Command {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
}

fn ours(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes/comp30019")
        .join(name)
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("penumbra-c3-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn run_ok(cwd: &Path, args: &[&str]) -> f64 {
    let t = Instant::now();
    let out = penumbra()
        .current_dir(cwd)
        .arg("comp30019")
        .args(args)
        .arg("--quiet")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "comp30019 {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    t.elapsed().as_secs_f64()
}

/// Every course scene with the grading stages' command lines, at 32×32, from the course
/// project root (model paths in the scenes are relative to it).
#[test]
fn course_scenes_render_with_original_command_lines() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes/comp30019");
    if !root.join("tests").is_dir() {
        println!("skipped: {} is absent", root.display());
        return;
    }
    let out = temp_dir("course");
    let mut scenes: Vec<String> = std::fs::read_dir(root.join("tests"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "txt"))
        .map(|p| p.file_name().unwrap().to_string_lossy().into_owned())
        .collect();
    scenes.sort();
    assert!(!scenes.is_empty());
    for s in &scenes {
        let png = out.join(s.replace(".txt", ".png"));
        let f = format!("tests/{s}");
        let secs = run_ok(
            &root,
            &[
                "-f",
                &f,
                "-o",
                png.to_str().unwrap(),
                "-w",
                "32",
                "-h",
                "32",
            ],
        );
        println!("{s}: {secs:.3} s (32x32, Whitted, 1 spp, 1 thread)");
        assert!(png.is_file());
    }
    let png = out.join("stage.png");
    let png = png.to_str().unwrap();
    let stages: [&[&str]; 6] = [
        &["-x", "3"],
        &["-l", "-q", "2"],
        &[
            "--cam-pos",
            "0,2,-0.5",
            "--cam-axis",
            "1,0,0",
            "--cam-angle",
            "45",
        ],
        &[
            "--aperture-radius",
            "0.06",
            "--focal-length",
            "1.5",
            "-x",
            "2",
        ],
        &["-s", "-g", "--post", "-m"],
        &["--prog", "--scale", "0.5", "-d", "3", "-c"],
    ];
    for flags in stages {
        let mut args = vec![
            "-f",
            "tests/sample_scene_2.txt",
            "-o",
            png,
            "-w",
            "32",
            "-h",
            "32",
        ];
        args.extend_from_slice(flags);
        let secs = run_ok(&root, &args);
        println!("sample_scene_2 {flags:?}: {secs:.3} s");
    }
    assert!(out.join("stage_refraction.png").is_file(), "-s layers");
}

/// Malformed scene lines: exit code 2 and a `file:line:col:` diagnostic, no panic.
#[test]
fn malformed_lines_fail_cleanly() {
    let dir = temp_dir("malformed");
    let cases = [
        (
            "Material \"m\" Diffuse (1, 1) 1\n",
            ":1:",
            "Material \"id\" TYPE",
        ),
        (
            "Sphere \"s\" (0, 0, 1) 1 \"m\"\nMaterial \"m\" Diffuse (1,1,1) 1\n",
            ":1:",
            "line 2",
        ),
        ("\nFoo \"x\"\n", ":2:1:", "PointLight"),
        ("Material \"m\" Shiny (1,1,1) 1\n", ":1:", "Glossy"),
        (
            "PointLight \"l\" (0, 0) (1, 1, 1)\n",
            ":1:",
            "PointLight \"id\"",
        ),
        (
            "Material \"m\" Diffuse (1,1,1) 1\nTriangle \"t\" (0,0,0) (1,0,0) \"m\"\n",
            ":2:",
            "v2",
        ),
    ];
    for (i, (text, loc, needle)) in cases.iter().enumerate() {
        let f = dir.join(format!("case{i}.txt"));
        std::fs::write(&f, text).unwrap();
        let out = penumbra()
            .args(["comp30019", "-f", f.to_str().unwrap(), "-o"])
            .arg(dir.join("x.png"))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "case {i}: {stderr}");
        assert!(
            stderr.contains(&format!("case{i}.txt{loc}")) && stderr.contains(needle),
            "case {i}: {stderr}"
        );
        assert!(!stderr.contains("panicked"), "case {i}: {stderr}");
    }
}

fn load(path: &Path) -> SceneDesc {
    match scene::load(path, &LoadOptions::default()).unwrap() {
        Document::Scene(s) => *s,
        Document::Test(_) => panic!("not a scene"),
    }
}

/// The layer films sum to the beauty film (same samples, linear splats).
#[test]
fn layers_sum_to_beauty() {
    let desc = load(&ours("showcase.txt"));
    let scene = build(
        &desc,
        &BuildOptions {
            spp: Some(4),
            resolution: Some((24, 24)),
            integrator: Some(IntegratorDesc::Path(PathDesc::default())),
            ..Default::default()
        },
    )
    .unwrap();
    let Integrator::Path(cfg) = Integrator::from_desc(&scene.integrator).unwrap() else {
        panic!("path integrator expected")
    };
    let films = render_layers(&scene, &cfg, 4, 8);
    let beauty = films.beauty.develop();
    let layers: Vec<Image> = films.layers.iter().map(|f| f.develop()).collect();
    let mut nonzero = [false; 5];
    for (i, b) in beauty.pixels.iter().enumerate() {
        let sum: glam::Vec3A = layers.iter().map(|l| l.pixels[i]).sum();
        let tol = 1e-4 * (1.0 + b.abs().max_element());
        assert!(
            (sum - *b).abs().max_element() <= tol,
            "pixel {i}: layers sum {sum} vs beauty {b}"
        );
        for (k, l) in layers.iter().enumerate() {
            nonzero[k] |= l.pixels[i] != glam::Vec3::ZERO.into();
        }
    }
    // The showcase has visible emitters, direct and indirect light, mirrors and glass.
    assert_eq!(nonzero, [true; 5], "every layer receives something");
}

const W: u32 = 24;

fn batches(desc: &SceneDesc, k: u64, spp: u32) -> Vec<Image> {
    (0..k)
        .map(|seed| {
            let opts = BuildOptions {
                spp: Some(spp),
                seed: Some(1000 + seed),
                resolution: Some((W, W)),
                integrator: Some(IntegratorDesc::Path(PathDesc::default())),
                ..Default::default()
            };
            render_desc(desc, &opts).unwrap().film.develop()
        })
        .collect()
}

/// equivalence.txt and equivalence.xml describe the same scene: renders of the two with the
/// path tracer pass the block t-test (`render::compare`, Šidák-corrected level α = 0.01 over
/// all block-channels). The XML side is the reference: its mean and the standard error of
/// the mean from 16 independent batches; the .txt side gives 8 batches.
#[test]
fn txt_and_mitsuba_xml_agree() {
    let txt = load(&ours("equivalence.txt"));
    let xml = load(&ours("equivalence.xml"));
    let refs = batches(&xml, 16, 16);
    let reference = Reference::from_batches(&refs).unwrap();
    let test = batches(&txt, 8, 16);
    let result = compare(&reference, &TestImages::Batches(test)).unwrap();
    println!("equivalence: {result}");
    assert!(result.passed, "{result}");
    // Not vacuous: the image is not black.
    assert!(
        result.mean_ratio.iter().all(|r| (r - 1.0).abs() < 0.05),
        "{result}"
    );
}
