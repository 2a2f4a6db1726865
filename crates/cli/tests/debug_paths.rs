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
    let text = std::fs::read_to_string(&o).unwrap();
    let (header, body) = text.split_once("end_header\n").unwrap();
    let count = |elem: &str| -> usize {
        header
            .lines()
            .find_map(|l| l.strip_prefix(&format!("element {elem} ")))
            .unwrap()
            .parse()
            .unwrap()
    };
    let (nv, ne) = (count("vertex"), count("edge"));
    let lines: Vec<&str> = body.lines().collect();
    assert_eq!(lines.len(), nv + ne);
    let verts: Vec<Vec<f64>> = lines[..nv]
        .iter()
        .map(|l| l.split(' ').map(|x| x.parse().unwrap()).collect())
        .collect();
    // 12 paths, each starting with a camera vertex (event 0) at the camera position.
    let starts: Vec<&Vec<f64>> = verts.iter().filter(|v| v[10] == 0.0).collect();
    assert_eq!(starts.len(), 12);
    for s in starts {
        assert!((s[2] - 3.79).abs() < 1e-3, "camera at z = 3.79: {s:?}");
    }
    // Every edge joins consecutive vertices of the same path; a path of k vertices has k − 1.
    for l in &lines[nv..] {
        let (a, b) = l.split_once(' ').unwrap();
        let (a, b): (usize, usize) = (a.parse().unwrap(), b.parse().unwrap());
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
