//! `penumbra render` on CS-E5520 OBJ+MTL scenes, with and without the camera/light flags.

use std::path::{Path, PathBuf};
use std::process::Command;

fn penumbra() -> Command {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("penumbra-objcli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn render(scene: &Path, out: &Path, extra: &[&str]) -> std::process::Output {
    penumbra()
        .args([
            "render",
            "--res",
            "32x32",
            "--spp",
            "4",
            "--threads",
            "2",
            "-q",
            "-o",
        ])
        .arg(out)
        .arg(scene)
        .args(extra)
        .output()
        .unwrap()
}

#[test]
fn aalto_scenes_render_without_flags() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes/aalto/cornell");
    if !dir.is_dir() {
        eprintln!("skipped: {} is absent", dir.display());
        return;
    }
    let tmp = temp_dir("aalto");
    for f in ["cornell.obj", "cornell_chesterfield.obj"] {
        let out = tmp.join(f).with_extension("pfm");
        let o = render(&dir.join(f), &out, &[]);
        assert!(
            o.status.success(),
            "{f}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let bytes = std::fs::read(&out).unwrap();
        // PFM: header then 32·32·3 floats; the image must not be black.
        let data = &bytes[bytes.len() - 32 * 32 * 12..];
        let sum: f32 = data
            .chunks_exact(4)
            .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
            .sum();
        assert!(sum.is_finite() && sum > 0.0, "{f}: black image");
    }
}

#[test]
fn camera_and_light_flags() {
    let tmp = temp_dir("flags");
    let obj = tmp.join("floor.obj");
    std::fs::write(
        &obj,
        "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nv -1 2 -1\nv 1 2 -1\nf 1 3 2\nf 1 4 3\nf 1 2 6\nf 1 6 5\n",
    )
    .unwrap();
    let out = tmp.join("a.pfm");
    // No emitter: the default light, with a warning.
    let o = render(&obj, &out, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("no emitter"));
    let o = render(
        &obj,
        &out,
        &[
            "--look-from",
            "0,1,4",
            "--look-at",
            "0,0.5,0",
            "--up",
            "0,1,0",
            "--fov",
            "60",
            "--area-light",
            "0,1.9,0;0,-1,0;0.5;8,8,8",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    for bad in [
        ["--area-light", "0,1,0;0,0,0;0.5;8"],
        ["--area-light", "0,1,0;0,-1,0;-1;8"],
        ["--look-from", "0,nan,0"],
        ["--fov", "200"],
    ] {
        let o = render(&obj, &out, &bad);
        assert_eq!(o.status.code(), Some(2), "{bad:?}");
    }
}
