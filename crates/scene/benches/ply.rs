//! Binary PLY loading speed: a ~1M-triangle displaced grid, with and without normals and uvs.
//!
//! Run with `cargo bench -p penumbra-scene --bench ply`. Prints the best of 5 loads.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use scene::formats::ply::{read_ply, write_ply};
use scene::{TriMesh, Vec2, Vec3};

/// An `n`×`n`-vertex height field over [0,1]², two triangles per cell.
fn displaced_grid(n: u32, attributes: bool) -> TriMesh {
    let mut m = TriMesh::default();
    let h = |u: f32, v: f32| 0.05 * (20.0 * u).sin() * (17.0 * v).cos();
    for j in 0..n {
        for i in 0..n {
            let (u, v) = (i as f32 / (n - 1) as f32, j as f32 / (n - 1) as f32);
            m.positions.push(Vec3::new(u, v, h(u, v)));
            if attributes {
                let e = 1e-3;
                let du = (h(u + e, v) - h(u - e, v)) / (2.0 * e);
                let dv = (h(u, v + e) - h(u, v - e)) / (2.0 * e);
                m.normals.push(Vec3::new(-du, -dv, 1.0).normalize());
                m.uvs.push(Vec2::new(u, v));
            }
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i;
            m.indices.push([a, a + 1, a + n + 1]);
            m.indices.push([a, a + n + 1, a + n]);
        }
    }
    m
}

fn main() {
    let dir = std::env::temp_dir();
    for attributes in [false, true] {
        let mesh = displaced_grid(708, attributes);
        let path: PathBuf = dir.join(format!(
            "penumbra-bench-{}-{attributes}.ply",
            std::process::id()
        ));
        write_ply(&path, &mesh).expect("write the benchmark mesh");
        let bytes = std::fs::metadata(&path).expect("stat").len() as f64;
        let mut best = Duration::MAX;
        for _ in 0..5 {
            let t = Instant::now();
            let loaded = read_ply(&path).expect("read the benchmark mesh");
            best = best.min(t.elapsed());
            assert_eq!(loaded.triangle_count(), mesh.triangle_count());
        }
        let _ = std::fs::remove_file(&path);
        let mb = bytes / 1.0e6;
        let s = best.as_secs_f64();
        println!(
            "read_ply {:<22} {} triangles, {} vertices, {mb:.1} MB: {:.1} ms ({:.0} MB/s)",
            if attributes {
                "(positions+normals+uv)"
            } else {
                "(positions)"
            },
            mesh.triangle_count(),
            mesh.positions.len(),
            s * 1e3,
            mb / s
        );
    }
}
