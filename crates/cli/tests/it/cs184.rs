//! CS184 compatibility: the COLLADA example against its Mitsuba twin, hemisphere against light
//! sampling, adaptive against uniform sampling (block t-tests of `render::compare` at the
//! documented 1 % family-wise level, fixed seeds), and the `penumbra cs184` command line.

use std::path::{Path, PathBuf};
use std::process::Command;

use build::{BuildOptions, build};
use render::adaptive::AdaptiveSettings;
use render::compare::{Reference, TestImages, compare};
use render::film::Image;
use render::render::{RenderOptions, Silent, render, render_adaptive};
use scene::formats::collada::cs184_path;
use scene::{Document, IntegratorDesc, LoadOptions, SceneDesc};

const RES: (u32, u32) = (32, 24);

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn load(rel: &str) -> SceneDesc {
    let Document::Scene(d) = scene::load(&root().join(rel), &LoadOptions::default()).unwrap()
    else {
        panic!("not a scene")
    };
    *d
}

fn integrator(hemisphere: bool) -> IntegratorDesc {
    IntegratorDesc::Path(cs184_path(2, 1, hemisphere))
}

fn render_one(desc: &SceneDesc, integ: &IntegratorDesc, spp: u32, seed: u64) -> Image {
    let build::Built {
        scene, integrator, ..
    } = build(
        desc,
        &BuildOptions {
            spp: Some(spp),
            seed: Some(seed),
            resolution: Some(RES),
            integrator: Some(integ.clone()),
            ..Default::default()
        },
    )
    .unwrap();
    let opts = RenderOptions {
        spp,
        ..Default::default()
    };
    let out = render(&scene, &integrator, &opts, &Silent);
    assert_eq!(out.film.nonfinite_count(), 0);
    out.film.develop()
}

fn reference(batches: &[Image]) -> Reference {
    Reference::from_batches(batches).unwrap()
}

fn batches(desc: &SceneDesc, integ: &IntegratorDesc, k: u64, spp: u32, seed0: u64) -> Vec<Image> {
    (0..k)
        .map(|s| render_one(desc, integ, spp, seed0 + s))
        .collect()
}

#[test]
fn collada_example_matches_its_mitsuba_twin() {
    let dae = load("scenes/cs184/floor_sphere.dae");
    let xml = load("scenes/cs184/floor_sphere.xml");
    let integ = integrator(false);
    let reference = reference(&batches(&xml, &integ, 16, 16, 100));
    let test = batches(&dae, &integ, 16, 16, 200);
    let r = compare(&reference, &TestImages::Batches(test)).unwrap();
    println!("twin: {r}");
    assert!(r.passed, "{r}");
    // A real difference would be seen: moving the light is rejected.
    let mut moved = dae.clone();
    for s in &mut moved.shapes {
        if s.emission.is_some() {
            s.to_world = glam::Mat4::from_translation(glam::Vec3::new(0.4, 0.0, 0.0)) * s.to_world;
        }
    }
    let bad = batches(&moved, &integ, 16, 16, 300);
    assert!(
        !compare(&reference, &TestImages::Batches(bad))
            .unwrap()
            .passed
    );
}

#[test]
fn hemisphere_and_light_sampling_converge_to_the_same_image() {
    let dae = load("scenes/cs184/floor_sphere.dae");
    let reference = reference(&batches(&dae, &integrator(false), 16, 16, 400));
    let test = batches(&dae, &integrator(true), 16, 64, 500);
    let r = compare(&reference, &TestImages::Batches(test)).unwrap();
    println!("hemisphere: {r}");
    assert!(r.passed, "{r}");
}

#[test]
fn adaptive_sampling_reaches_the_same_mean() {
    let dae = load("scenes/cs184/floor_sphere.dae");
    let integ = integrator(false);
    let reference = reference(&batches(&dae, &integ, 16, 32, 600));
    let settings = AdaptiveSettings {
        batch: 8,
        tolerance: 0.1,
    };
    let mut total = 0u64;
    let test: Vec<Image> = (0..16)
        .map(|s| {
            let build::Built {
                scene, integrator, ..
            } = build(
                &dae,
                &BuildOptions {
                    spp: Some(64),
                    seed: Some(700 + s),
                    resolution: Some(RES),
                    integrator: Some(integ.clone()),
                    ..Default::default()
                },
            )
            .unwrap();
            let opts = RenderOptions {
                spp: 64,
                ..Default::default()
            };
            let out = render_adaptive(&scene, &integrator, &opts, &settings, &Silent).unwrap();
            assert!(out.samples.iter().all(|&n| (1..=64).contains(&n)));
            total += out.total_samples;
            out.film.develop()
        })
        .collect();
    let mean_spp = total as f64 / (16.0 * (RES.0 * RES.1) as f64);
    println!("adaptive: {mean_spp:.1} spp on average (cap 64)");
    // Background pixels (black) stop after one batch: fewer samples than the cap.
    assert!(mean_spp < 64.0);
    let r = compare(&reference, &TestImages::Batches(test)).unwrap();
    println!("adaptive: {r}");
    assert!(r.passed, "{r}");
}

/// The adaptive driver gives the same image, bit for bit, and the same sample counts on 1 and
/// 3 worker threads (tiles run in parallel; a pixel's k-th sample does not depend on the
/// thread that takes it). With tile size 8 a 32×24 image has 12 tiles to share.
#[test]
fn adaptive_sampling_is_deterministic_across_thread_counts() {
    let dae = load("scenes/cs184/floor_sphere.dae");
    let build::Built {
        scene,
        integrator: integ,
        ..
    } = build(
        &dae,
        &BuildOptions {
            spp: Some(32),
            seed: Some(5),
            resolution: Some(RES),
            integrator: Some(integrator(false)),
            ..Default::default()
        },
    )
    .unwrap();
    let settings = AdaptiveSettings {
        batch: 4,
        tolerance: 0.2,
    };
    let opts = RenderOptions {
        spp: 32,
        tile_size: 8,
        ..Default::default()
    };
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        let out = pool
            .install(|| render_adaptive(&scene, &integ, &opts, &settings, &Silent))
            .unwrap();
        (out.film.develop(), out.samples, out.total_samples)
    };
    let (a, na, ta) = run(1);
    let (b, nb, tb) = run(3);
    // Every pixel stopped exactly where the course's one-pixel loop stops: sample k of the
    // pixel is sample k of the uniform driver, the rule is checked after every `batch`.
    let sampler0 = render::sampling::Sampler::new(scene.sampler.kind, 32, scene.sampler.seed);
    for y in 0..RES.1 {
        for x in 0..RES.0 {
            let pixel = render::math::UVec2::new(x, y);
            let mut sampler = sampler0.clone();
            let (mut s1, mut s2, mut n) = (0f64, 0f64, 0u32);
            while n < 32 {
                sampler.start_pixel_sample(pixel, n);
                let p_film = pixel.as_vec2() + sampler.next_2d();
                let u_lens = sampler.next_2d();
                let cray = scene.camera.generate_ray(p_film, u_lens);
                let l = render::render::li(&scene, &integ, &cray, &mut sampler).unwrap();
                let v = render::adaptive::illuminance(l);
                if v.is_finite() {
                    s1 += v;
                    s2 += v * v;
                }
                n += 1;
                if n.is_multiple_of(4) && settings.converged(n, s1, s2) {
                    break;
                }
            }
            assert_eq!(na[(y * RES.0 + x) as usize], n, "pixel ({x}, {y})");
        }
    }
    // Some pixels stop early and some reach the cap: the stopping rule was exercised.
    assert!(na.iter().any(|&n| n < 32) && na.contains(&32), "{na:?}");
    assert_eq!(na, nb);
    assert_eq!(ta, tb);
    assert!(
        a.pixels.iter().zip(&b.pixels).all(|(p, q)| p
            .to_array()
            .iter()
            .zip(q.to_array())
            .all(|(x, y)| x.to_bits() == y.to_bits())),
        "images differ between 1 and 3 threads"
    );
}

fn penumbra(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .args(args)
        .output()
        .unwrap()
}

#[test]
fn command_line_flags() {
    let dir = std::env::temp_dir().join(format!("penumbra-cs184-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = root().join("scenes/cs184/floor_sphere.dae");
    let scene = scene.to_str().unwrap();
    let out = dir.join("img.png");
    let o = out.to_str().unwrap();
    let run = penumbra(&[
        "cs184", "-t", "1", "-s", "4", "-l", "2", "-m", "3", "-r", "24", "16", "-a", "4", "0.2",
        "-p", "4", "2", "8", "8", "-b", "0.05", "-d", "4", "-q", "-f", o, scene,
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(out.is_file());
    assert!(dir.join("img_rate.png").is_file());
    let h = penumbra(&[
        "cs184", "-H", "-s", "2", "-r", "16", "12", "-q", "-f", o, scene,
    ]);
    assert!(h.status.success(), "{}", String::from_utf8_lossy(&h.stderr));
    // -e with a synthesized EXR environment map, and --stderr.
    let env = dir.join("env.exr");
    let mut map = Image::new(8, 4);
    map.set(2, 1, render::math::Vec3::splat(50.0));
    render::image_io::write_image(&env, &map).unwrap();
    let se = dir.join("img_se.exr");
    let e = penumbra(&[
        "cs184",
        "-e",
        env.to_str().unwrap(),
        "-s",
        "2",
        "-r",
        "16",
        "12",
        "-q",
        "--stderr",
        se.to_str().unwrap(),
        "-f",
        o,
        scene,
    ]);
    assert!(e.status.success(), "{}", String::from_utf8_lossy(&e.stderr));
    assert!(se.is_file());
    // Bad input: exit code 2 and a message, never a panic.
    for bad in [
        &["cs184", "-e", "/nonexistent/sky.exr", "-f", o, scene][..],
        &[
            "cs184", "-p", "20", "0", "8", "8", "-r", "24", "16", "-f", o, scene,
        ][..],
        &["cs184", "-a", "1", "0.1", "-f", o, scene][..],
        &["cs184", "-s", "0", "-f", o, scene][..],
        &["cs184", "-c", "/nonexistent/camera.txt", "-f", o, scene][..],
    ] {
        let r = penumbra(bad);
        assert_eq!(
            r.status.code(),
            Some(2),
            "{bad:?}: {}",
            String::from_utf8_lossy(&r.stderr)
        );
    }
    let r = penumbra(&[
        "render",
        "--adaptive",
        "0.2,4",
        "--spp",
        "8",
        "--res",
        "16x12",
        "-q",
        "-o",
        o,
        scene,
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(dir.join("img_rate.png").is_file());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every `.dae` of `../shared/scenes/cs184` renders through the course's command line with its
/// own camera: exit 0, a finite image with some light in it (40×30, 2 spp: a smoke test; the
/// timings at full size are in the issue notes).
#[test]
fn every_shared_dae_renders_with_its_own_camera() {
    let Some(shared) = scene::testing::shared_dir("scenes/cs184") else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("penumbra-cs184-all-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut files: Vec<PathBuf> = ["sky", "meshedit"]
        .iter()
        .filter_map(|sub| std::fs::read_dir(shared.join(sub)).ok())
        .flat_map(|rd| rd.flatten().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "dae"))
        .collect();
    files.sort();
    assert!(files.len() >= 8, "{files:?}");
    for f in &files {
        let out = dir.join(format!("{}.exr", f.file_stem().unwrap().to_string_lossy()));
        let run = penumbra(&[
            "cs184",
            "-t",
            "2",
            "-s",
            "2",
            "-m",
            "3",
            "-r",
            "40",
            "30",
            "-q",
            "-f",
            out.to_str().unwrap(),
            f.to_str().unwrap(),
        ]);
        assert!(
            run.status.success(),
            "{}: {}",
            f.display(),
            String::from_utf8_lossy(&run.stderr)
        );
        let img = render::image_io::read_image(&out).unwrap();
        assert!(img.pixels.iter().all(|p| p.is_finite()), "{}", f.display());
        let mean = img.pixels.iter().map(|p| p.element_sum()).sum::<f32>();
        assert!(mean > 0.0, "{}: black image", f.display());
    }
}

/// CS184's `-o 0` (isAccumBounces off) keeps only light of exactly the m-th bounce: the
/// images of bounces 0, 1 and 2 add up to the accumulated image of depth 2 (block t-test),
/// (if `-o 0` were ignored the sum would be three times it), and each bounce carries light.
#[test]
fn single_bounce_images_add_up_to_the_accumulated_one() {
    let dae = load("scenes/cs184/floor_sphere.dae");
    let accumulated = reference(&batches(&dae, &integrator(false), 16, 16, 700));
    let bounce = |m: u32| {
        let mut p = cs184_path(2, 1, false);
        p.only_depth = Some(m + 1);
        IntegratorDesc::Path(p)
    };
    let parts: Vec<Vec<Image>> = (0..3)
        .map(|m| batches(&dae, &bounce(m), 16, 16, 800 + 100 * m as u64))
        .collect();
    let sums: Vec<Image> = (0..16)
        .map(|k| {
            let mut s = parts[0][k].clone();
            for part in &parts[1..] {
                for (a, b) in s.pixels.iter_mut().zip(&part[k].pixels) {
                    *a += *b;
                }
            }
            s
        })
        .collect();
    let r = compare(&accumulated, &TestImages::Batches(sums)).unwrap();
    println!("bounce sum: {r}");
    assert!(r.passed, "{r}");
    let mean = |i: &Image| i.pixels.iter().map(|p| p.element_sum() as f64).sum::<f64>();
    let total: f64 = mean(&parts[0][0]) + mean(&parts[1][0]) + mean(&parts[2][0]);
    for (m, part) in parts.iter().enumerate() {
        let share = mean(&part[0]) / total;
        assert!(
            share > 1e-3 && share < 0.99,
            "bounce {m}: {share} of the light"
        );
    }
}
