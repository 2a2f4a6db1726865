//! Records the rays a path tracer traces in Bitterli's *classroom* (Mitsuba form, under
//! `../shared/scenes/bench/classroom/`), for the accelerator benchmark of `penumbra-render`
//! (`crates/render/benches/accel.rs`), which cannot load scenes itself: the renderer does not
//! depend on the scene model.
//!
//! Run once: `cargo bench -p penumbra-build --bench record_rays`. Writes
//! `target/rays/classroom.rays` (never committed: it holds third-party geometry); without the
//! shared folder it prints a notice and writes nothing.
//!
//! The scene is loaded and built as `penumbra render` does it; the rays come from the built
//! scene's own camera, BSDFs and light sampling, with robust spawning, at 4 samples per pixel
//! of the scene's 640×360 film:
//! - `camera`: the camera rays (closest hit);
//! - `bounce`: from each camera hit that scatters, the ray of a BSDF sample (closest hit);
//! - `shadow`: from each camera hit that scatters, the shadow ray of a light sample
//!   (occlusion; the classroom's only emitter is a constant sky, so every shadow ray is
//!   unbounded).
//!
//! File format (little-endian), read by `crates/render/benches/accel.rs`:
//! `b"PNRAYS01"`, u32 mesh count, per mesh (u32 vertices, u32 triangles, f32 xyz per vertex,
//! u32 ×3 per triangle), u32 set count, per set (u32 name length, name, u8 kind: 0 closest
//! hit, 1 occlusion, u32 rays, f32 ×7 per ray: origin, direction, t_max).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use build::{BuildOptions, build};
use render::accel::AccelShape;
use render::bsdf::TransportMode;
use render::geometry::Ray;
use render::lights::Receiver;
use render::math::Vec2;
use render::spectral::lanes::RgbMode;
use render::world::Scene;
use scene::{Document, LoadOptions};

const SPP: u32 = 4;

/// A deterministic hash of `(i, k)` to [0, 1).
fn rnd(i: u64, k: u64) -> f32 {
    let mut x = i
        .wrapping_mul(0x9E37_79B9_7F4A_7C15)
        .wrapping_add(k.wrapping_mul(0xD1B5_4A32_D192_ED03));
    x ^= x >> 31;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x ^= x >> 29;
    x = x.wrapping_mul(0x94D0_49BB_1331_11EB);
    x ^= x >> 32;
    (x >> 40) as f32 / (1u64 << 24) as f32
}

/// The target directory this benchmark runs from (`target/release/deps/record_rays-…`).
fn target_dir() -> Option<PathBuf> {
    let exe = std::env::current_exe().ok()?;
    Some(exe.parent()?.parent()?.parent()?.to_path_buf())
}

struct Set {
    name: &'static str,
    occlusion: bool,
    rays: Vec<(Ray, f32)>,
}

fn record(scene: &Scene) -> Vec<Set> {
    let (w, h) = (scene.film.width, scene.film.height);
    let mut camera = Set {
        name: "camera",
        occlusion: false,
        rays: Vec::new(),
    };
    let mut bounce = Set {
        name: "bounce",
        occlusion: false,
        rays: Vec::new(),
    };
    let mut shadow = Set {
        name: "shadow",
        occlusion: true,
        rays: Vec::new(),
    };
    for y in 0..h {
        for x in 0..w {
            for s in 0..SPP {
                let i = ((u64::from(y) * u64::from(w) + u64::from(x)) << 8) | u64::from(s);
                let r = |k| rnd(i, k);
                let p_film = Vec2::new(x as f32 + r(0), y as f32 + r(1));
                let cray = scene.camera.generate_ray(p_film, Vec2::new(r(2), r(3)));
                camera.rays.push((cray.ray, cray.t_max));
                let Some(si) = scene.intersect(&cray.ray, cray.t_max) else {
                    continue;
                };
                let Some((bsdf, frame)) = scene.bsdf_at(&si) else {
                    continue;
                };
                let wo = frame.to_local(si.wo);
                if let Some(bs) =
                    bsdf.sample(wo, r(4), Vec2::new(r(5), r(6)), TransportMode::Radiance)
                {
                    bounce
                        .rays
                        .push((si.spawn_ray(frame.to_world(bs.wi)), f32::INFINITY));
                }
                let receiver = Receiver {
                    p: si.p,
                    n: si.shading.n,
                };
                if let Some((_, light, _)) = scene.sample_light(r(7), &receiver)
                    && let Some(ls) =
                        light.sample_li(scene, &receiver, Vec2::new(r(8), r(9)), &RgbMode)
                    && ls.pdf > 0.0
                {
                    shadow.rays.push(ls.target.ray_from(&si, ls.wi));
                }
            }
        }
    }
    vec![camera, bounce, shadow]
}

fn write(path: &Path, scene: &Scene, sets: &[Set]) -> std::io::Result<()> {
    let mut out = Vec::new();
    out.extend_from_slice(b"PNRAYS01");
    let u32s = |out: &mut Vec<u8>, v: u32| out.extend_from_slice(&v.to_le_bytes());
    let f32s = |out: &mut Vec<u8>, v: f32| out.extend_from_slice(&v.to_le_bytes());
    let meshes: Vec<_> = scene
        .shapes
        .iter()
        .filter_map(|s| match s.geom.accel_shape() {
            AccelShape::Triangles { positions, indices } => Some((positions, indices)),
            _ => None,
        })
        .collect();
    let others = scene.shapes.len() - meshes.len();
    if others > 0 {
        println!("{others} shapes that are not triangle meshes left out");
    }
    u32s(&mut out, meshes.len() as u32);
    for (p, i) in &meshes {
        u32s(&mut out, p.len() as u32);
        u32s(&mut out, i.len() as u32);
        for v in p.iter() {
            for c in v.to_array() {
                f32s(&mut out, c);
            }
        }
        for t in i.iter() {
            for c in t {
                u32s(&mut out, *c);
            }
        }
    }
    u32s(&mut out, sets.len() as u32);
    for s in sets {
        u32s(&mut out, s.name.len() as u32);
        out.extend_from_slice(s.name.as_bytes());
        out.push(u8::from(s.occlusion));
        u32s(&mut out, s.rays.len() as u32);
        for (r, t_max) in &s.rays {
            for c in r.o.to_array().into_iter().chain(r.d.to_array()) {
                f32s(&mut out, c);
            }
            f32s(&mut out, *t_max);
        }
    }
    if let Some(dir) = path.parent() {
        std::fs::create_dir_all(dir)?;
    }
    std::fs::File::create(path)?.write_all(&out)
}

fn main() {
    let Some(file) = base::testing::shared_dir("scenes/bench/classroom/scene.xml") else {
        return;
    };
    let Some(out) = target_dir().map(|t| t.join("rays/classroom.rays")) else {
        eprintln!("cannot tell the target directory; nothing recorded");
        return;
    };
    let desc = match scene::load(&file, &LoadOptions::default()).expect("load classroom") {
        Document::Scene(s) => *s,
        Document::Test(_) => unreachable!("a scene file"),
    };
    let built = build(&desc, &BuildOptions::default()).expect("build classroom");
    let scene = &built.scene;
    let sets = record(scene);
    write(&out, scene, &sets).expect("write the ray file");
    println!(
        "classroom: {} triangles; {} rays written to {}",
        scene.triangle_count,
        sets.iter()
            .map(|s| format!("{} {}", s.rays.len(), s.name))
            .collect::<Vec<_>>()
            .join(", "),
        out.display()
    );
}
