//! `penumbra debug-paths`: the PLY edge set and the JSON describe whole, connected paths that
//! start at the camera, and bad pixels are input errors.

use std::path::{Path, PathBuf};
use std::process::Command;

fn scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.xml")
}

fn out(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("penumbra-dbgpaths-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn run(args: &[&str], output: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("debug-paths")
        .arg(scene())
        .args(args)
        .arg("-o")
        .arg(output)
        .output()
        .unwrap()
}

#[test]
fn ply_edges_connect_vertices_of_one_path() {
    let o = out("p.ply");
    let r = run(&["--pixel", "128,140", "--count", "12"], &o);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let (verts, edges) = read_ply(&o);
    let (nv, ne) = (verts.len(), edges.len());
    // 12 paths, each starting with a camera vertex (event 0) at the camera position.
    let starts: Vec<&Vec<f64>> = verts.iter().filter(|v| v[10] == 0.0).collect();
    assert_eq!(starts.len(), 12);
    for s in starts {
        assert!((s[2] - 3.79).abs() < 1e-3, "camera at z = 3.79: {s:?}");
    }
    // Every edge joins consecutive vertices of the same path; a path of k vertices has k − 1.
    for e in &edges {
        let (a, b) = (e[0] as usize, e[1] as usize);
        assert_eq!(b, a + 1);
        assert_eq!(verts[a][11], verts[b][11], "edge across paths");
    }
    assert_eq!(ne, nv - 12);
    // The pixel looks at the back wall/boxes of a closed-at-the-back box: some path has a hit.
    assert!(verts.iter().any(|v| v[10] != 0.0 && v[10] != 5.0));
}

#[test]
fn json_and_errors() {
    let o = out("p.json");
    let r = run(&["--pixel", "10,10", "--count", "3"], &o);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let text = std::fs::read_to_string(&o).unwrap();
    assert!(text.starts_with("{\"paths\":["));
    assert_eq!(text.matches("\"vertices\"").count(), 3);
    assert_eq!(text.matches("\"event\":0").count(), 3);

    let bad = run(&["--pixel", "999,0"], &out("bad.ply"));
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("outside"));
    let bad = run(&["--pixel", "1,2"], &out("bad.txt"));
    assert_eq!(bad.status.code(), Some(2));
}

/// Volumetric paths are recorded: through the smoke sphere of the media example some vertex
/// is a medium collision (event 9, zero normal) and some a null crossing (event 10).
#[test]
fn volumetric_paths_record_medium_vertices() {
    let o = out("vol.json");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/media/smoky-box.xml");
    let r = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("debug-paths")
        .arg(scene)
        .args(["--pixel", "69,122", "--count", "8", "-o"])
        .arg(&o)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let text = std::fs::read_to_string(&o).unwrap();
    assert_eq!(text.matches("\"event\":0").count(), 8);
    assert!(text.contains("\"n\":[0,0,0],\"throughput\""));
    assert!(text.contains("\"event\":9"), "{text}");
    assert!(text.contains("\"event\":10"), "{text}");
}

/// The vertex rows and edge rows of a PLY written by debug-paths, as numbers.
fn read_ply(path: &Path) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let text = std::fs::read_to_string(path).unwrap();
    let (header, body) = text.split_once("end_header\n").unwrap();
    let count = |elem: &str| -> usize {
        header
            .lines()
            .find_map(|l| l.strip_prefix(&format!("element {elem} ")))
            .unwrap()
            .parse()
            .unwrap()
    };
    let rows: Vec<Vec<f64>> = body
        .lines()
        .map(|l| l.split(' ').map(|x| x.parse().unwrap()).collect())
        .collect();
    let nv = count("vertex");
    assert_eq!(rows.len(), nv + count("edge"));
    let (v, e) = rows.split_at(nv);
    (v.to_vec(), e.to_vec())
}

/// BDPT samples as a PLY (`--integrator bdpt` over the scene's `path`): every sample's camera
/// subpath starts at the camera and its light subpath on the ceiling light; segments join
/// consecutive vertices of one subpath; each connection joins camera vertex t − 1 (or a lens
/// point) and light vertex s − 1 (or a light point sampled on the light) of its own sample.
#[test]
fn bdpt_samples_as_ply() {
    let o = out("bdpt.ply");
    let r = run(
        &[
            "--pixel",
            "128,140",
            "--count",
            "12",
            "--integrator",
            "bdpt",
        ],
        &o,
    );
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    // Vertex: x y z nx ny nz β(3) pdf_fwd pdf_rev kind delta path subpath.
    // Edge: vertex1 vertex2 kind s t weight value(3) film_x film_y.
    let (verts, edges) = read_ply(&o);
    let on_light =
        |v: &[f64]| (v[1] - 1.98).abs() < 1e-4 && v[0].abs() <= 0.2301 && v[2].abs() <= 0.1901;
    let mut first_of = vec![[usize::MAX; 2]; 12];
    for (i, v) in verts.iter().enumerate() {
        let (path, subpath) = (v[13] as usize, v[14] as usize);
        if subpath < 2 && first_of[path][subpath] == usize::MAX {
            first_of[path][subpath] = i;
            if subpath == 0 {
                assert_eq!(v[11], 0.0, "camera subpath starts at the camera: {v:?}");
                assert!(
                    (v[2] - 3.8).abs() < 1e-4 && (v[1] - 1.0).abs() < 1e-4,
                    "{v:?}"
                );
            } else {
                assert_eq!(v[11], 1.0, "light subpath starts on an emitter: {v:?}");
                assert!(on_light(v), "{v:?}");
            }
        }
    }
    assert!(first_of.iter().all(|f| f[0] != usize::MAX), "{first_of:?}");
    let (mut s1, mut t1, mut inner) = (0, 0, 0);
    for e in &edges {
        let (a, b) = (&verts[e[0] as usize], &verts[e[1] as usize]);
        assert_eq!(a[13], b[13], "edge across samples: {e:?}");
        let path = a[13] as usize;
        if e[2] == 0.0 {
            assert_eq!(e[1], e[0] + 1.0, "{e:?}");
            assert!(
                a[14] == b[14] && a[14] < 2.0,
                "segment within a subpath: {e:?}"
            );
            assert_eq!((e[3], e[4]), (-1.0, -1.0));
            continue;
        }
        assert_eq!(e[2], 1.0);
        let (s, t) = (e[3] as usize, e[4] as usize);
        assert!(e[5] > 0.0 && e[5] <= 1.0, "weight {e:?}");
        assert!(e[6..9].iter().any(|&x| x > 0.0), "value {e:?}");
        if t >= 2 {
            assert_eq!(e[0] as usize, first_of[path][0] + t - 1, "{e:?}");
            assert_eq!(a[14], 0.0);
            assert_eq!((e[9], e[10]), (-1.0, -1.0));
        } else {
            assert_eq!((a[14], a[11]), (2.0, 0.0), "lens point: {e:?}");
            assert!((0.0..256.0).contains(&e[9]) && (0.0..256.0).contains(&e[10]));
            t1 += 1;
        }
        match s {
            0 => assert_eq!(e[1], e[0]),
            1 => {
                assert_eq!((b[14], b[11]), (2.0, 1.0), "light point: {e:?}");
                assert!(on_light(b), "{b:?}");
                s1 += 1;
            }
            _ => {
                assert_eq!(e[1] as usize, first_of[path][1] + s - 1, "{e:?}");
                inner += usize::from(t >= 2);
            }
        }
    }
    assert!(s1 > 0 && t1 > 0 && inner > 0, "{s1} {t1} {inner}");
}

/// BDPT samples as JSON, in media (`--integrator bdpt` over the scene's `volpath`): medium
/// vertices are recorded, each connection's ends are its subpaths' vertices (or the point it
/// sampled, given in full), and the t ≥ 2 values add up to the sample's estimate. `mlt`
/// records BDPT samples too; light tracing is refused.
#[test]
fn bdpt_samples_as_json() {
    let o = out("bdpt.json");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/media/smoky-box.xml");
    let r = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("debug-paths")
        .arg(&scene)
        .args([
            "--pixel",
            "69,122",
            "--count",
            "8",
            "--integrator",
            "bdpt",
            "-o",
        ])
        .arg(&o)
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&o).unwrap()).unwrap();
    let paths = doc["paths"].as_array().unwrap();
    assert_eq!(paths.len(), 8);
    let v3 = |v: &serde_json::Value| -> [f64; 3] {
        let a = v.as_array().unwrap();
        [0, 1, 2].map(|i| a[i].as_f64().unwrap())
    };
    let (mut medium, mut connections) = (0, 0);
    for p in paths {
        let (cam, light) = (
            p["camera"].as_array().unwrap(),
            p["light"].as_array().unwrap(),
        );
        assert_eq!(cam[0]["kind"], 0);
        if let Some(l) = light.first() {
            assert_eq!(l["kind"], 1);
            assert!(l["light"].is_u64());
        }
        medium += cam.iter().chain(light).filter(|v| v["kind"] == 3).count();
        let mut sum = [0.0; 3];
        for c in p["connections"].as_array().unwrap() {
            connections += 1;
            let (s, t) = (
                c["s"].as_u64().unwrap() as usize,
                c["t"].as_u64().unwrap() as usize,
            );
            let w = c["weight"].as_f64().unwrap();
            assert!(w > 0.0 && w <= 1.0, "{c}");
            if t >= 2 {
                assert_eq!(c["from"], cam[t - 1]["p"], "{c}");
                let v = v3(&c["value"]);
                (0..3).for_each(|i| sum[i] += v[i]);
            } else {
                assert_eq!(c["lens"]["kind"], 0, "{c}");
                assert_eq!(c["from"], c["lens"]["p"]);
                assert!(c["p_film"].is_array(), "{c}");
            }
            match s {
                0 => assert!(c["to"].is_null()),
                1 => {
                    assert_eq!(c["light_point"]["kind"], 1, "{c}");
                    assert_eq!(c["to"], c["light_point"]["p"]);
                }
                _ => assert_eq!(c["to"], light[s - 1]["p"], "{c}"),
            }
        }
        let li = v3(&p["li"]);
        for i in 0..3 {
            assert!(
                (sum[i] - li[i]).abs() <= 1e-5 * li[i].max(1e-3),
                "{sum:?} {li:?}"
            );
        }
    }
    assert!(medium > 0 && connections > 0, "{medium} {connections}");

    let mlt = out("mlt.json");
    let r = run(
        &["--pixel", "128,140", "--count", "2", "--integrator", "mlt"],
        &mlt,
    );
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let text = std::fs::read_to_string(&mlt).unwrap();
    assert_eq!(text.matches("\"camera\":").count(), 2);
    let bad = run(
        &["--pixel", "1,2", "--integrator", "ptracer"],
        &out("bad.json"),
    );
    assert_eq!(bad.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&bad.stderr).contains("'ptracer'"));
}
