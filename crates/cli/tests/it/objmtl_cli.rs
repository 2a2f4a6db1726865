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

/// `map_Ke` is an emission texture: a quad emitting a black-and-white texture shows both,
/// where a constant `Ke` quad is uniform.
#[test]
fn map_ke_textures_the_emission() {
    let dir = temp_dir("map-ke");
    // Left half black, right half white (wide enough that bilinear filtering only blends
    // them near the middle).
    let mut tex = render::film::Image::new(16, 2);
    for (i, p) in tex.pixels.iter_mut().enumerate() {
        if i % 16 >= 8 {
            *p = render::math::Vec3::splat(1.0);
        }
    }
    render::image_io::write_image(&dir.join("glow.png"), &tex).unwrap();
    let obj = "mtllib quad.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n\
               vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl glow\nf 1/1 2/2 3/3 4/4\n";
    std::fs::write(dir.join("quad.obj"), obj).unwrap();
    let lit = |mtl: &str, name: &str| {
        std::fs::write(dir.join("quad.mtl"), mtl).unwrap();
        let out = dir.join(format!("{name}.exr"));
        let o = render(
            &dir.join("quad.obj"),
            &out,
            &[
                "--look-from",
                "0,0,3",
                "--look-at",
                "0,0,0",
                "--up",
                "0,1,0",
                "--fov",
                "40",
            ],
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let img = render::image_io::read_image(&out).unwrap();
        // The quad fills the middle of the image: its left and right thirds of the centre row.
        let row = img.height / 2;
        let px = |x: u32| img.pixels[(row * img.width + x) as usize].x;
        (px(img.width * 3 / 8), px(img.width * 5 / 8))
    };
    let (l, r) = lit("newmtl glow\nKd 0 0 0\nKe 1 1 1\n", "constant");
    assert!(l > 0.5 && (l - r).abs() < 0.05, "constant Ke: {l} {r}");
    let (l, r) = lit(
        "newmtl glow\nKd 0 0 0\nKe 1 1 1\nmap_Ke glow.png\n",
        "textured",
    );
    assert!(l < 0.05 && r > 0.5, "map_Ke: {l} {r}");
}
