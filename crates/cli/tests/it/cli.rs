//! Command-line tests: exit codes, diagnostics, output files.

use std::path::{Path, PathBuf};
use std::process::Command;

fn penumbra() -> Command {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
}

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("penumbra-cli-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Every malformed input gives exit code 2, a `file:line[:col]: message` diagnostic naming
/// the file, and no panic.
#[test]
fn malformed_inputs_fail_cleanly() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/malformed");
    let mut cases: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("tests/malformed exists")
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "xml"))
        .collect();
    cases.sort();
    assert!(cases.len() >= 10, "only {} malformed cases", cases.len());
    for case in &cases {
        let out = penumbra().arg("info").arg(case).output().unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(
            out.status.code(),
            Some(2),
            "{}: exit {:?}\n{stderr}",
            case.display(),
            out.status
        );
        assert!(
            !stderr.contains("panicked"),
            "{}: panic\n{stderr}",
            case.display()
        );
        let line = stderr
            .lines()
            .find(|l| l.starts_with("error: "))
            .unwrap_or_default();
        let msg = line.trim_start_matches("error: ");
        // The diagnostic names a file of the case (the scene or the mesh it points to) and,
        // for text formats, a line and column.
        let (file, rest) = msg.split_once(": ").unwrap_or(("", ""));
        let file_part = file.split(':').next().unwrap_or_default();
        assert!(
            Path::new(file_part).starts_with(&dir) || file_part.contains("malformed"),
            "{}: diagnostic does not name the file: {line}",
            case.display()
        );
        assert!(
            !rest.is_empty(),
            "{}: empty message: {line}",
            case.display()
        );
        let is_text = !file_part.ends_with(".ply");
        if is_text && file_part.ends_with(".xml") {
            let pos: Vec<&str> = file.split(':').skip(1).collect();
            assert!(
                pos.len() == 2 && pos.iter().all(|p| p.parse::<u32>().is_ok_and(|n| n > 0)),
                "{}: no line:col in {line}",
                case.display()
            );
        }
    }
}

#[test]
fn unknown_file_type_and_missing_file_exit_2() {
    let out = penumbra()
        .args(["info", "no-such-scene.xml"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let out = penumbra().args(["info", "scene.unknown"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn renders_the_example_scene_to_png_and_exr() {
    let dir = temp_dir("example");
    let png = dir.join("cbox.png");
    let exr = dir.join("cbox.exr");
    let out = penumbra()
        .arg("render")
        .arg(repo_root().join("scenes/cornell-box.xml"))
        .args([
            "--integrator",
            "ao:2",
            "--spp",
            "2",
            "--res",
            "32x32",
            "-q",
            "-o",
        ])
        .arg(&png)
        .arg("-o")
        .arg(&exr)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(png.is_file() && exr.is_file());
    // No temporary files left behind.
    let leftovers: Vec<_> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "{leftovers:?}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn unwritable_output_fails_before_rendering() {
    let out = penumbra()
        .arg("render")
        .arg(repo_root().join("scenes/cornell-box.xml"))
        .args(["-o", "/no/such/folder/out.png"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("does not exist"), "{stderr}");
}

#[test]
fn same_seed_same_image_for_any_thread_count() {
    let dir = temp_dir("determinism");
    let mut images = Vec::new();
    for threads in ["1", "2", "3"] {
        let out_path = dir.join(format!("t{threads}.pfm"));
        let out = penumbra()
            .arg("render")
            .arg(repo_root().join("scenes/cornell-box.xml"))
            .args([
                "--integrator",
                "ao:4",
                "--spp",
                "3",
                "--res",
                "24x20",
                "-q",
                "--threads",
                threads,
            ])
            .arg("-o")
            .arg(&out_path)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        images.push(std::fs::read(&out_path).unwrap());
    }
    assert!(images.windows(2).all(|w| w[0] == w[1]));
    std::fs::remove_dir_all(&dir).ok();
}

/// Texture and environment-map files are found when the scene is named by a relative path
/// from another folder (they were joined to the scene's folder twice).
#[test]
fn textures_of_a_scene_named_relatively_are_found() {
    let dir = temp_dir("relative");
    let scenes = dir.join("scenes");
    std::fs::create_dir_all(scenes.join("tex")).unwrap();
    image::RgbImage::from_pixel(4, 4, image::Rgb([200, 100, 50]))
        .save(scenes.join("tex/a.png"))
        .unwrap();
    std::fs::write(
        scenes.join("s.xml"),
        r#"<scene version="3.0.0">
  <sensor type="perspective"><float name="fov" value="30"/>
    <transform name="to_world"><lookat origin="0,0,5" target="0,0,0" up="0,1,0"/></transform>
    <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
  </sensor>
  <emitter type="envmap"><string name="filename" value="tex/a.png"/></emitter>
  <shape type="sphere"><bsdf type="diffuse">
    <texture type="bitmap" name="reflectance"><string name="filename" value="tex/a.png"/></texture>
  </bsdf></shape>
</scene>"#,
    )
    .unwrap();
    let o = penumbra()
        .current_dir(&dir)
        .args([
            "render",
            "scenes/s.xml",
            "--spp",
            "1",
            "-q",
            "-o",
            "out.exr",
        ])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(dir.join("out.exr").is_file());
    std::fs::remove_dir_all(&dir).ok();
}

/// `--integrator bdpt:weights` writes one EXR per strategy beside the first output
/// (pbrt-v4's names); without a finite max depth it is refused before rendering.
#[test]
fn bdpt_writes_per_strategy_images() {
    let dir = temp_dir("strategies");
    let png = dir.join("box.png");
    let run = |extra: &[&str]| {
        penumbra()
            .arg("render")
            .arg(repo_root().join("scenes/cornell-box.xml"))
            .args([
                "--integrator",
                "bdpt:weights",
                "--spp",
                "1",
                "--res",
                "16x16",
                "-q",
            ])
            .args(extra)
            .arg("-o")
            .arg(&png)
            .output()
            .unwrap()
    };
    let out = run(&["--max-depth", "-1"]);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("finite max depth"), "{stderr}");
    let out = run(&["--max-depth", "3"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    // Paths of 1 to 3 edges: 1 + 3 + 4 strategies.
    assert_eq!(names.len(), 1 + 8, "{names:?}");
    assert!(
        names.contains(&"box_bdpt_d00_s00_t02.exr".to_string()),
        "{names:?}"
    );
    assert!(
        names.contains(&"box_bdpt_d02_s03_t01.exr".to_string()),
        "{names:?}"
    );
    std::fs::remove_dir_all(&dir).ok();
    let out = penumbra()
        .arg("render")
        .arg(repo_root().join("scenes/cornell-box.xml"))
        .args(["--integrator", "bdpt:weight", "-o", "x.png"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("'strategies'"), "{stderr}");
}

/// `--integrator path` and `volpath` switch any scene back to unidirectional path tracing;
/// `path` on a scene with media says that it ignores them.
#[test]
fn integrator_path_and_volpath_are_selectable() {
    let dir = temp_dir("path-volpath");
    let run = |scene: &str, integrator: &str| {
        penumbra()
            .arg("render")
            .arg(repo_root().join(scene))
            .args([
                "--integrator",
                integrator,
                "--spp",
                "1",
                "--res",
                "8x8",
                "-o",
            ])
            .arg(dir.join(format!("{integrator}.exr")))
            .output()
            .unwrap()
    };
    let out = run("scenes/cornell-box.xml", "volpath");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let out = run("scenes/media/smoky-box.xml", "path");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("ignores participating media"), "{stderr}");
    std::fs::remove_dir_all(&dir).ok();
}

/// pbrt-v4 scenes through the command line: `info` describes one, `render` renders it, and a
/// malformed one exits with 2 and a `file:line:col` diagnostic.
#[test]
fn pbrt_scenes_run_and_malformed_ones_fail_cleanly() {
    let scene = repo_root().join("scenes/pbrt/cbox-specular.pbrt");
    let out = penumbra().arg("info").arg(&scene).output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        stdout.contains("sphere") && stdout.contains("128"),
        "{stdout}"
    );
    let dir = temp_dir("pbrt");
    let exr = dir.join("cbox.exr");
    let out = penumbra()
        .arg("render")
        .arg(&scene)
        .args(["--res", "16x16", "--spp", "2", "-q", "-o"])
        .arg(&exr)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(exr.is_file());
    let bad = dir.join("bad.pbrt");
    std::fs::write(&bad, "WorldBegin\nShape \"sphere\" \"float radius\" [ 1\n").unwrap();
    let out = penumbra().arg("info").arg(&bad).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("bad.pbrt:2:31: "), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}
