//! Instancing at scale (issue 17): a CENG795 scene with 10,000 instances of one
//! 100k-triangle PLY (10⁹ instanced triangles), loaded and built in well under 3 s and 1 GB.
//!
//! Run with `cargo bench -p penumbra-render --bench instances`. The PLY and the JSON scene
//! are generated in a temporary folder (removed afterwards). Prints the load and build times,
//! the peak resident memory of the load + build (`VmHWM` of /proc/self/status, reset through
//! /proc/self/clear_refs after generating the input where the kernel allows it), the time of
//! a small render, and the accelerator's memory.

use std::fmt::Write as _;
use std::time::Instant;

use build::{BuildOptions, build};
use render::render::{RenderOptions, Silent, render};
use scene::formats::ply::write_ply;
use scene::{Document, LoadOptions, TriMesh, Vec3};

/// An `n`×`n`-vertex bumpy height field over [-1,1]², two triangles per cell.
fn bumpy_grid(n: u32) -> TriMesh {
    let mut m = TriMesh::default();
    for j in 0..n {
        for i in 0..n {
            let (u, v) = (i as f32 / (n - 1) as f32, j as f32 / (n - 1) as f32);
            let h = 0.15 * (19.0 * u).sin() * (13.0 * v).cos();
            m.positions.push(Vec3::new(2.0 * u - 1.0, h, 2.0 * v - 1.0));
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i;
            m.indices.push([a, a + n + 1, a + 1]);
            m.indices.push([a, a + n, a + n + 1]);
        }
    }
    m
}

/// Small deterministic hash → [0, 1).
fn rnd(i: u64) -> f32 {
    let mut x = i.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    x ^= x >> 31;
    x = x.wrapping_mul(0xBF58_476D_1CE4_E5B9);
    x ^= x >> 29;
    (x >> 40) as f32 / (1u64 << 24) as f32
}

/// Peak resident set size (kB) so far, from /proc/self/status.
fn peak_rss_kb() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn current_rss_kb() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = s.lines().find(|l| l.starts_with("VmRSS:"))?;
    line.split_whitespace().nth(1)?.parse().ok()
}

fn scene_json(instances: u32) -> String {
    let side = (instances as f32).sqrt().ceil() as u32;
    let mut tr = String::new();
    let mut rot = String::new();
    let mut sc = String::new();
    let mut objs = String::new();
    for k in 0..instances {
        let (i, j) = (k % side, k / side);
        let id = k + 1;
        let sep = if k == 0 { "" } else { ",\n" };
        let (x, z) = (3.0 * i as f32, -3.0 * j as f32);
        write!(tr, r#"{sep}{{ "_id": "{id}", "_data": "{x} 0 {z}" }}"#).unwrap();
        let angle = 360.0 * rnd(3 * k as u64);
        write!(rot, r#"{sep}{{ "_id": "{id}", "_data": "{angle} 0 1 0" }}"#).unwrap();
        let (a, b) = (
            0.6 + 0.8 * rnd(3 * k as u64 + 1),
            0.6 + 0.8 * rnd(3 * k as u64 + 2),
        );
        write!(sc, r#"{sep}{{ "_id": "{id}", "_data": "{a} {b} {a}" }}"#).unwrap();
        if k > 0 {
            let sep = if k == 1 { "" } else { ",\n" };
            write!(
                objs,
                r#"{sep}{{ "_id": "{}", "_baseMeshId": "1", "_resetTransform": "true", "Transformations": "s{id} r{id} t{id}" }}"#,
                id + 1
            )
            .unwrap();
        }
    }
    let c = 1.5 * side as f32;
    format!(
        r#"{{ "Scene": {{
  "MaxRecursionDepth": "2",
  "BackgroundColor": "0 0 0",
  "Cameras": {{ "Camera": {{ "_id": "1", "Position": "{c} 40 20", "Gaze": "0 -0.6 -1",
    "Up": "0 1 0", "NearPlane": "-1 1 -1 1", "NearDistance": "1.5",
    "ImageResolution": "128 128", "NumSamples": "1", "ImageName": "instances.png" }} }},
  "Lights": {{ "PointLight": {{ "_id": "1", "Position": "{c} 200 0", "Intensity": "1e7 1e7 1e7" }} }},
  "Materials": {{ "Material": {{ "_id": "1", "AmbientReflectance": "0 0 0",
    "DiffuseReflectance": "0.6 0.6 0.6", "SpecularReflectance": "0 0 0" }} }},
  "Transformations": {{
    "Translation": [{tr}],
    "Rotation": [{rot}],
    "Scaling": [{sc}] }},
  "VertexData": {{ "_data": "0 0 0", "_type": "xyz" }},
  "Objects": {{
    "Mesh": {{ "_id": "1", "Material": "1", "Transformations": "s1 r1 t1",
      "Faces": {{ "_plyFile": "bumpy.ply" }} }},
    "MeshInstance": [{objs}]
  }}
}} }}"#
    )
}

fn main() {
    let instances = 10_000u32;
    let dir = std::env::temp_dir().join(format!("penumbra-bench-instances-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temporary folder");
    let path = dir.join("instances.json");
    let triangles = {
        let mesh = bumpy_grid(225);
        write_ply(&dir.join("bumpy.ply"), &mesh).expect("write the PLY");
        std::fs::write(&path, scene_json(instances)).expect("write the scene");
        mesh.triangle_count()
    };
    // Start the peak count here: the generated input is not part of the measurement.
    let reset = std::fs::write("/proc/self/clear_refs", "5").is_ok();
    let rss0 = current_rss_kb();

    let t0 = Instant::now();
    let desc = match scene::load(&path, &LoadOptions::default()).expect("load") {
        Document::Scene(s) => *s,
        Document::Test(_) => unreachable!(),
    };
    let t_load = t0.elapsed();
    let t1 = Instant::now();
    let build::Built {
        scene, integrator, ..
    } = build(&desc, &BuildOptions::default()).expect("build");
    let t_build = t1.elapsed();
    let peak = peak_rss_kb();
    let total = t0.elapsed();

    let (protos, accel_bytes) = scene.accel.instancing_stats();
    println!(
        "{} shapes ({} instances of a {} triangle PLY, {:.2e} instanced triangles), {} prototype(s)",
        desc.shapes.len(),
        instances,
        triangles,
        scene.triangle_count as f64,
        protos
    );
    println!(
        "load {:.3} s + build {:.3} s = {:.3} s (limit 3 s)",
        t_load.as_secs_f64(),
        t_build.as_secs_f64(),
        total.as_secs_f64()
    );
    match (peak, reset) {
        (Some(p), true) => println!(
            "peak RSS during load + build: {:.1} MB (limit 1 GB; {:.1} MB resident before)",
            p as f64 / 1024.0,
            rss0.unwrap_or(0) as f64 / 1024.0
        ),
        (Some(p), false) => println!(
            "peak RSS of the process (input generation included; clear_refs unavailable): {:.1} MB (limit 1 GB)",
            p as f64 / 1024.0
        ),
        _ => println!("peak RSS: /proc/self/status unavailable"),
    }
    println!(
        "bottom-level trees + instances + top level: {:.1} MB",
        accel_bytes as f64 / 1.0e6
    );
    let t2 = Instant::now();
    let out = render(
        &scene,
        &integrator,
        &RenderOptions {
            spp: 4,
            ..Default::default()
        },
        &Silent,
    );
    let img = out.film.develop();
    let lit = img.pixels.iter().filter(|p| p.max_element() > 0.0).count();
    println!(
        "render 128x128 at 4 spp: {:.3} s ({lit} of {} pixels lit)",
        t2.elapsed().as_secs_f64(),
        img.pixels.len()
    );
    let _ = std::fs::remove_dir_all(&dir);
}
