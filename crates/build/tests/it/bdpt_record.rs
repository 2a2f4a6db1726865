//! BDPT with a recorder (`Bdpt::record`, what `debug-paths` uses for `bdpt` and `mlt`) is the
//! rendered BDPT: for every camera sample the estimate and splats are those of `Bdpt::li` bit
//! for bit, the recorded strategies' values add up to them (t ≥ 2 to the estimate, t = 1 to
//! the splats, in order), and the recorded subpaths and joints are where they must be — the
//! camera subpath starts at the camera, the light subpath on an emitter, and each joint's
//! ends are vertices of the subpaths or the point sampled for s = 1 or t = 1.

use std::path::Path;

use build::{BuildOptions, build};
use render::integrators::Integrator;
use render::integrators::bdpt::{Bdpt, BdptSample, BdptVertexKind, Subpaths};
use render::math::{UVec2, Vec3};
use render::render::camera_sample;
use render::sampling::Sampler;
use render::world::Scene;
use scene::{Document, IntegratorDesc};

/// The scene at `rel` (from the repository root) built for BDPT with its own path length.
fn built(rel: &str, res: u32) -> build::Built {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel);
    let opts = scene::LoadOptions {
        defines: [("res".to_string(), res.to_string())].into_iter().collect(),
    };
    let Document::Scene(desc) = scene::load(&path, &opts).unwrap() else {
        panic!("not a scene")
    };
    let max_depth = match &desc.integrator {
        IntegratorDesc::Path(p) => p.max_depth,
        IntegratorDesc::VolPath { max_depth, .. } => *max_depth,
        _ => -1,
    };
    let opts = BuildOptions {
        integrator: Some(IntegratorDesc::Bdpt {
            max_depth,
            visualize_strategies: false,
            visualize_weights: false,
        }),
        ..Default::default()
    };
    build(&desc, &opts).unwrap()
}

/// How many connections of each kind were seen: s = 0, s = 1, t = 1, s and t ≥ 2.
#[derive(Default, Debug)]
struct Seen {
    s0: usize,
    s1: usize,
    t1: usize,
    inner: usize,
    medium: usize,
}

/// Records sample `index` of `pixel` and checks it against `li` and itself.
fn check_sample(
    scene: &Scene,
    bdpt: &Bdpt,
    pixel: UVec2,
    index: u32,
    seen: &mut Seen,
) -> BdptSample {
    let mut a = Sampler::new(scene.sampler.kind, 16, scene.sampler.seed);
    let mut b = a.clone();
    let (_, cray) = camera_sample(scene, &mut a, pixel, index);
    let mut splats = Vec::new();
    let l = bdpt.li(
        scene,
        &cray,
        &mut a,
        &mut Subpaths::default(),
        &mut splats,
        &mut (),
    );
    let (_, cray_b) = camera_sample(scene, &mut b, pixel, index);
    let rec = bdpt.record(scene, &cray_b, &mut b, &mut Subpaths::default());
    let at = format!("pixel {pixel} #{index}");
    assert_eq!(rec.li.to_array(), l.to_array(), "{at}");
    assert_eq!(rec.splats, splats, "{at}");

    // The record is faithful: its values make up the estimate and the splats.
    let mut sum = Vec3::ZERO;
    let mut recorded_splats = Vec::new();
    for c in &rec.connections {
        assert_ne!(c.value, Vec3::ZERO, "{at}: {c:?}");
        assert!(c.weight > 0.0 && c.weight <= 1.0, "{at}: {c:?}");
        if c.t == 1 {
            recorded_splats.push((c.p_film.expect("t = 1 splats"), c.value));
        } else {
            assert_eq!(c.p_film, None);
            sum += c.value;
        }
    }
    assert_eq!(sum.to_array(), l.to_array(), "{at}: t ≥ 2 values sum to li");
    assert_eq!(recorded_splats, splats, "{at}: t = 1 values are the splats");

    // The subpaths start at the camera and on an emitter.
    assert_eq!(rec.camera[0].kind, BdptVertexKind::Camera);
    assert_eq!(rec.camera[0].p, cray.lens, "{at}");
    assert!(
        rec.camera[1..]
            .iter()
            .all(|v| v.kind != BdptVertexKind::Camera)
    );
    if let Some(first) = rec.light.first() {
        let BdptVertexKind::Light { light } = first.kind else {
            panic!("{at}: light subpath starts at {first:?}")
        };
        assert!((light as usize) < scene.lights.len());
        assert!(
            rec.light[1..]
                .iter()
                .all(|v| matches!(v.kind, BdptVertexKind::Surface | BdptVertexKind::Medium))
        );
    }
    // Each joint's ends: subpath vertices, or the points sampled for s = 1 and t = 1.
    for c in &rec.connections {
        if c.t >= 2 {
            assert_eq!(c.from, rec.camera[c.t - 1], "{at}: {c:?}");
        } else {
            assert_eq!(c.from.kind, BdptVertexKind::Camera, "{at}: lens point");
            seen.t1 += 1;
        }
        match c.s {
            0 => {
                assert_eq!(c.to, None);
                seen.s0 += 1;
            }
            1 => {
                let to = c.to.expect("s = 1 joins a light point");
                assert!(
                    matches!(to.kind, BdptVertexKind::Light { .. }),
                    "{at}: {c:?}"
                );
                seen.s1 += 1;
            }
            s => {
                assert_eq!(c.to, Some(rec.light[s - 1]), "{at}: {c:?}");
                if c.t >= 2 {
                    seen.inner += 1;
                }
            }
        }
        let media = |v: &render::integrators::bdpt::BdptVertex| v.kind == BdptVertexKind::Medium;
        if media(&c.from) || c.to.as_ref().is_some_and(media) {
            seen.medium += 1;
        }
    }
    rec
}

#[test]
fn recorded_bdpt_samples_are_the_rendered_ones() {
    let b = built("scenes/cornell-box.xml", 32);
    let Integrator::Bdpt(cfg) = &b.integrator else {
        panic!("built for bdpt")
    };
    let scene = &b.scene;
    let bdpt = Bdpt::new(scene, cfg);
    let mut seen = Seen::default();
    // The light, the back wall, a box, the floor, a corner.
    for (x, y) in [(16, 1), (16, 10), (10, 20), (16, 28), (2, 2)] {
        for index in 0..16 {
            let rec = check_sample(scene, &bdpt, UVec2::new(x, y), index, &mut seen);
            // The camera at (0, 1, 3.8); the light a 0.46 × 0.38 rectangle at y = 1.98.
            assert!((rec.camera[0].p - Vec3::new(0.0, 1.0, 3.8)).length() < 1e-5);
            if let Some(l) = rec.light.first() {
                assert!((l.p.y - 1.98).abs() < 1e-5, "{l:?}");
                assert!(l.p.x.abs() <= 0.2301 && l.p.z.abs() <= 0.1901, "{l:?}");
            }
        }
    }
    assert!(
        seen.s0 > 0 && seen.s1 > 0 && seen.t1 > 0 && seen.inner > 0,
        "{seen:?}"
    );
}

#[test]
fn recorded_bdpt_samples_in_media() {
    let b = built("scenes/media/smoky-box.xml", 32);
    let Integrator::Bdpt(cfg) = &b.integrator else {
        panic!("built for bdpt")
    };
    let scene = &b.scene;
    let bdpt = Bdpt::new(scene, cfg);
    let mut seen = Seen::default();
    for (x, y) in [(8, 15), (10, 18), (16, 16), (25, 25)] {
        for index in 0..16 {
            check_sample(scene, &bdpt, UVec2::new(x, y), index, &mut seen);
        }
    }
    assert!(seen.medium > 0 && seen.t1 > 0 && seen.inner > 0, "{seen:?}");
}
