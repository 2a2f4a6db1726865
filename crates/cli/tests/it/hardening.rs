//! Hostile inputs (issue 18): each must end in exit 2 with a located diagnostic, never an
//! abort, a panic or unbounded memory.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn penumbra() -> Command {
    Command::new(env!("CARGO_BIN_EXE_penumbra"))
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("penumbra-hard-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Exit 2, no panic, and an `error: FILE:LINE:COL: …` line naming `file` whose message
/// contains `needle`.
fn assert_located_failure(out: &Output, file: &Path, needle: &str) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(2),
        "exit {:?}\n{stderr}",
        out.status
    );
    assert!(!stderr.contains("panicked"), "panic\n{stderr}");
    let line = stderr
        .lines()
        .find(|l| l.starts_with("error: "))
        .unwrap_or_else(|| panic!("no error line\n{stderr}"));
    let rest = line
        .trim_start_matches("error: ")
        .strip_prefix(&*file.to_string_lossy())
        .unwrap_or_else(|| panic!("diagnostic does not start with the file: {line}"));
    let mut parts = rest.splitn(4, ':');
    assert_eq!(parts.next(), Some(""), "{line}");
    for what in ["line", "column"] {
        let n = parts.next().unwrap_or_default();
        assert!(
            n.parse::<u32>().is_ok_and(|n| n > 0),
            "no {what} number: {line}"
        );
    }
    assert!(line.contains(needle), "expected '{needle}' in: {line}");
}

/// `open` nested `n` deep inside `root`, closed again, written to `name`: `info` refuses it
/// with a located diagnostic about the nesting.
fn assert_deep_refused(name: &str, root: (&str, &str), open: &str, close: &str, n: usize) {
    let dir = temp_dir(name);
    let file = dir.join(name);
    let text = format!("{}{}{}{}", root.0, open.repeat(n), close.repeat(n), root.1);
    std::fs::write(&file, text).unwrap();
    let out = penumbra().arg("info").arg(&file).output().unwrap();
    assert_located_failure(&out, &file, "nested more than 256 deep");
}

/// A Mitsuba scene nested 10,000 shapes deep overflowed the stack (SIGABRT) before; a
/// CENG795 XML scene with 20,000 nested `<Objects>` did after 1.1 GB.
#[test]
fn deeply_nested_xml_is_refused() {
    assert_deep_refused(
        "mitsuba-deep.xml",
        ("<scene version=\"3.0.0\">", "</scene>"),
        "<shape type=\"sphere\">",
        "</shape>",
        10_000,
    );
    assert_deep_refused(
        "ceng-deep.xml",
        ("<Scene>", "</Scene>"),
        "<Objects>",
        "</Objects>",
        20_000,
    );
}

/// COLLADA nodes and CENG795 JSON already had limits (256 nodes, serde_json's 128 levels);
/// keep them.
#[test]
fn deeply_nested_collada_and_json_are_refused() {
    let dir = temp_dir("other-deep");
    let dae = dir.join("deep.dae");
    let n = 5_000;
    std::fs::write(
        &dae,
        format!(
            "<COLLADA><library_visual_scenes><visual_scene id=\"s\">{}{}</visual_scene>\
             </library_visual_scenes><scene><instance_visual_scene url=\"#s\"/></scene></COLLADA>",
            "<node>".repeat(n),
            "</node>".repeat(n)
        ),
    )
    .unwrap();
    let out = penumbra().arg("info").arg(&dae).output().unwrap();
    assert_located_failure(&out, &dae, "deep");

    let json = dir.join("deep.json");
    std::fs::write(
        &json,
        format!("{{\"Scene\": {}{}}}", "[".repeat(n), "]".repeat(n)),
    )
    .unwrap();
    let out = penumbra().arg("info").arg(&json).output().unwrap();
    assert_located_failure(&out, &json, "recursion limit");
}

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Exit 2 with a message containing every needle, and no panic.
fn assert_input_failure(out: &Output, needles: &[&str]) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(
        out.status.code(),
        Some(2),
        "exit {:?}\n{stderr}",
        out.status
    );
    assert!(!stderr.contains("panicked"), "panic\n{stderr}");
    for n in needles {
        assert!(stderr.contains(n), "expected '{n}' in\n{stderr}");
    }
}

/// A 16384² film needs ~70 GB of sums and tiles: refused before allocating (it aborted).
#[test]
fn a_film_beyond_the_memory_budget_is_refused() {
    let dir = temp_dir("film");
    let out = penumbra()
        .current_dir(repo_root())
        .args([
            "render",
            "scenes/cornell-box.xml",
            "--res",
            "16384x16384",
            "-q",
            "-o",
        ])
        .arg(dir.join("big.exr"))
        .output()
        .unwrap();
    assert_input_failure(&out, &["16384x16384 film", "GiB", "--memory-limit"]);
    assert!(!dir.join("big.exr").exists());
    // And the limit is the user's to set: 512 KiB refuses even a 64² film (≈ 0.8 MiB of
    // fixed-point sums).
    let out = penumbra()
        .current_dir(repo_root())
        .args([
            "render",
            "scenes/cornell-box.xml",
            "--res",
            "64x64",
            "--spp",
            "1",
        ])
        .args(["-q", "--memory-limit", "512K", "-o"])
        .arg(dir.join("small.exr"))
        .output()
        .unwrap();
    assert_input_failure(&out, &["64x64 film", "limit of 512.0 KiB"]);
}

#[test]
fn debug_paths_beyond_the_memory_budget_is_refused() {
    let dir = temp_dir("paths");
    let out = penumbra()
        .current_dir(repo_root())
        .args(["debug-paths", "scenes/cornell-box.xml", "--pixel", "10,10"])
        .args(["--count", "100000000", "-o"])
        .arg(dir.join("p.ply"))
        .output()
        .unwrap();
    assert_input_failure(&out, &["recording 100000000 paths", "GiB"]);
}

/// Devices and folders named as scene, mesh or texture files are refused at once (a
/// `/dev/zero` mesh was read until memory ran out).
#[cfg(unix)]
#[test]
fn non_regular_files_are_refused_at_once() {
    let dir = temp_dir("devzero");
    let ceng = dir.join("zero.json");
    std::fs::write(
        &ceng,
        r#"{"Scene": {"Cameras": {"Camera": {"_id": "1", "Position": "0 0 10",
            "Gaze": "0 0 -1", "Up": "0 1 0", "NearPlane": "-1 1 -1 1", "NearDistance": "1",
            "ImageResolution": "8 8", "ImageName": "x.png"}},
          "Materials": {"Material": {"_id": "1", "DiffuseReflectance": "1 1 1"}},
          "Objects": {"Mesh": {"_id": "1", "Material": "1",
            "Faces": {"_plyFile": "/dev/zero"}}}}}"#,
    )
    .unwrap();
    let mitsuba = dir.join("zero.xml");
    std::fs::write(
        &mitsuba,
        r#"<scene version="3.0.0"><shape type="ply"><string name="filename" value="/dev/zero"/></shape>
           <shape type="obj"><string name="filename" value="/dev/zero"/></shape></scene>"#,
    )
    .unwrap();
    for scene in [&ceng, &mitsuba] {
        let out = penumbra().arg("info").arg(scene).output().unwrap();
        assert_input_failure(&out, &["/dev/zero"]);
    }
    // The scene file itself.
    let out = penumbra().args(["info", "/dev/zero"]).output().unwrap();
    assert_input_failure(&out, &["not a regular file"]);
    let out = penumbra().arg("info").arg(&dir).output().unwrap();
    assert_input_failure(&out, &[]);
}

/// `compare`: below the calibrated batch count it refuses and says why; images that cannot
/// be compared are bad input (2), a rejection is 1.
#[test]
fn compare_refuses_too_few_batches_and_mismatched_images() {
    let dir = temp_dir("compare");
    let render = |res: &str, spp: &str, seed: &str, out: &Path, stderr: Option<&Path>| {
        let mut c = penumbra();
        c.current_dir(repo_root())
            .args([
                "render",
                "scenes/cornell-box.xml",
                "--res",
                res,
                "--spp",
                spp,
            ])
            .args(["--seed", seed, "-q", "-o"])
            .arg(out);
        if let Some(s) = stderr {
            c.arg("--stderr").arg(s);
        }
        let o = c.output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    let reference = dir.join("ref.exr");
    render(
        "16x16",
        "64",
        "1000",
        &reference,
        Some(&dir.join("ref.stderr.exr")),
    );
    let batches: Vec<PathBuf> = (0..8).map(|k| dir.join(format!("b{k}.exr"))).collect();
    for (k, b) in batches.iter().enumerate() {
        render("16x16", "4", &k.to_string(), b, None);
    }
    let out = penumbra()
        .arg("compare")
        .arg(&reference)
        .args(&batches)
        .output()
        .unwrap();
    assert_input_failure(&out, &["8 test image(s)", "at least 16", "--min-batches"]);
    // Lowered knowingly, it runs the comparison (pass or reject, never 2).
    let out = penumbra()
        .arg("compare")
        .arg(&reference)
        .args(&batches)
        .args(["--min-batches", "8"])
        .output()
        .unwrap();
    assert!(matches!(out.status.code(), Some(0 | 1)), "{out:?}");
    // A different size is bad input.
    let small = dir.join("small.exr");
    render("8x8", "4", "0", &small, Some(&dir.join("small.stderr.exr")));
    let out = penumbra()
        .arg("compare")
        .arg(&reference)
        .arg(&small)
        .arg("--stderr")
        .arg(dir.join("small.stderr.exr"))
        .output()
        .unwrap();
    assert_input_failure(&out, &[]);
}

/// One Ctrl-C finishes the pass, writes the image and exits 130, so a script can tell an
/// interrupted render from a finished one.
#[cfg(unix)]
#[test]
fn an_interrupted_render_writes_its_image_and_exits_130() {
    use std::io::{BufRead, BufReader};
    use std::process::Stdio;
    let dir = temp_dir("sigint");
    let out_file = dir.join("int.exr");
    let mut child = penumbra()
        .current_dir(repo_root())
        .args([
            "render",
            "scenes/cornell-box.xml",
            "--res",
            "32x32",
            "--spp",
            "100000000",
        ])
        .arg("-o")
        .arg(&out_file)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until rendering has started (the build line), then interrupt.
    let mut stderr = BufReader::new(child.stderr.take().unwrap());
    let mut seen = String::new();
    let mut line = String::new();
    while stderr.read_line(&mut line).unwrap() > 0 {
        seen.push_str(&line);
        if line.starts_with("built the scene") {
            break;
        }
        line.clear();
    }
    std::thread::sleep(std::time::Duration::from_millis(500));
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let mut rest = String::new();
    std::io::Read::read_to_string(&mut stderr, &mut rest).unwrap();
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130), "{seen}{rest}");
    assert!(rest.contains("interrupted after"), "{rest}");
    assert!(
        out_file.is_file(),
        "the image of the finished passes is written"
    );
}

/// A CENG795 `ImageName` must not write outside the scene's folder (`-o` may).
#[test]
fn a_scene_cannot_write_outside_its_folder() {
    let dir = temp_dir("imagename");
    for name in [
        "../escape.png",
        "/tmp/penumbra-escape.png",
        "sub/../../x.png",
    ] {
        let scene = dir.join("s.json");
        std::fs::write(
            &scene,
            format!(
                r#"{{"Scene": {{"Cameras": {{"Camera": {{"_id": "1", "Position": "0 0 10",
                "Gaze": "0 0 -1", "Up": "0 1 0", "NearPlane": "-1 1 -1 1", "NearDistance": "1",
                "ImageResolution": "4 4", "ImageName": "{name}"}}}},
                "Materials": {{"Material": {{"_id": "1", "DiffuseReflectance": "1 1 1"}}}},
                "VertexData": {{"_data": "0 0 0"}},
                "Objects": {{"Sphere": {{"_id": "1", "Material": "1", "Center": "1",
                "Radius": "1"}}}}}}}}"#
            ),
        )
        .unwrap();
        let out = penumbra()
            .arg("render")
            .arg(&scene)
            .arg("-q")
            .output()
            .unwrap();
        assert_input_failure(&out, &["outside the scene's folder", "-o FILE"]);
        // With -o the user decides.
        let out = penumbra()
            .arg("render")
            .arg(&scene)
            .args(["-q", "-o"])
            .arg(dir.join("mine.png"))
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    assert!(!dir.parent().unwrap().join("escape.png").exists());
}

#[test]
fn usage_errors_say_what_is_wrong() {
    let dir = temp_dir("usage");
    let out = penumbra()
        .current_dir(repo_root())
        .args(["render", "scenes/cornell-box.xml", "-q", "-o"])
        .arg(&dir)
        .output()
        .unwrap();
    assert_input_failure(&out, &["is a folder", "image.exr"]);
    let out = penumbra()
        .current_dir(repo_root())
        .args(["render", "scenes/cornell-box.xml", "--spp", "0", "-o"])
        .arg(dir.join("x.exr"))
        .output()
        .unwrap();
    assert_input_failure(&out, &["--spp"]);
}

/// A depth AOV as PNG is scaled by the farthest hit (it was solid white); EXR keeps metres.
#[test]
fn a_depth_png_is_normalised() {
    let dir = temp_dir("depth");
    let (png, exr) = (dir.join("d.png"), dir.join("d.exr"));
    let out = penumbra()
        .current_dir(repo_root())
        .args(["render", "scenes/cornell-box.xml", "--integrator", "depth"])
        .args(["--res", "32x32", "--spp", "1", "-q", "-o"])
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
    let png = render::image_io::read_image_with(&png, render::image_io::Decode::Srgb).unwrap();
    let exr = render::image_io::read_image(&exr).unwrap();
    let max = |i: &render::film::Image| i.pixels.iter().map(|p| p.x).fold(0.0f32, f32::max);
    assert!(max(&exr) > 2.0, "the EXR keeps distances: {}", max(&exr));
    assert!((max(&png) - 1.0).abs() < 0.01, "{}", max(&png));
    let white = png.pixels.iter().filter(|p| p.x > 0.99).count();
    assert!(
        white < png.pixels.len() / 10,
        "{white} of {} pixels white",
        png.pixels.len()
    );
}

/// Exit 1: the comparison ran and rejects (16 batches of the albedo AOV against a path-traced
/// reference); exit 3: an output that cannot be written (a file inside /proc, whose folder
/// exists, so the check before rendering passes and the write fails).
#[test]
fn a_rejected_comparison_exits_1_and_an_unwritable_output_3() {
    let dir = temp_dir("exit13");
    let render = |extra: &[&str], seed: usize, out: &Path, stderr: Option<&Path>| {
        let mut c = penumbra();
        c.current_dir(repo_root())
            .args(["render", "scenes/cornell-box.xml", "--res", "16x16"])
            .args(["--seed", &seed.to_string(), "-q", "-o"])
            .arg(out)
            .args(extra);
        if let Some(s) = stderr {
            c.arg("--stderr").arg(s);
        }
        let o = c.output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    let reference = dir.join("ref.exr");
    render(
        &["--spp", "64"],
        1000,
        &reference,
        Some(&dir.join("ref.stderr.exr")),
    );
    // The test side: 16 batches of 4 spp of the albedo AOV (a different image).
    let batches: Vec<PathBuf> = (0..16).map(|k| dir.join(format!("b{k}.exr"))).collect();
    for (k, b) in batches.iter().enumerate() {
        render(&["--integrator", "albedo", "--spp", "4"], k, b, None);
    }
    let out = penumbra()
        .arg("compare")
        .arg(&reference)
        .args(&batches)
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(1),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    let out = penumbra()
        .current_dir(repo_root())
        .args([
            "render",
            "scenes/cornell-box.xml",
            "--res",
            "8x8",
            "--spp",
            "1",
            "-q",
        ])
        .args(["-o", "/proc/penumbra-cannot-write.exr"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{stderr}");
    assert!(
        stderr.contains("/proc/penumbra-cannot-write.exr"),
        "{stderr}"
    );
}

/// Medium grids that cannot be used (issue 20): a truncated `.vol` or `.vdb`, a grid name the
/// file lacks, a negative value, a NaN: exit 2, the scene's line and column, the grid file,
/// the byte offset where the file is at fault, and what is wrong.
#[test]
fn unreadable_medium_grids_exit_2_with_the_file_and_offset() {
    let dir = temp_dir("grids");
    let data = repo_root().join("crates/render/tests/data");
    let small = std::fs::read(data.join("small.vdb")).unwrap();
    std::fs::write(dir.join("small.vdb"), &small).unwrap();
    std::fs::write(dir.join("cut.vdb"), &small[..5000]).unwrap();
    let vol = |values: &[f32]| {
        let mut b = b"VOL\x03".to_vec();
        for v in [1i32, 2, 1, 1, 1] {
            b.extend(v.to_le_bytes());
        }
        for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
            b.extend(v.to_le_bytes());
        }
        for v in values {
            b.extend(v.to_le_bytes());
        }
        b
    };
    std::fs::write(dir.join("cut.vol"), &vol(&[0.5, 0.5])[..52]).unwrap();
    std::fs::write(dir.join("nan.vol"), vol(&[0.5, f32::NAN])).unwrap();
    let scene = dir.join("grid.xml");
    std::fs::write(
        &scene,
        r#"<scene version="3.0.0">
    <default name="grid" value="density"/>
    <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
    <shape type="cube">
        <bsdf type="null"/>
        <medium type="heterogeneous" name="interior">
            <volume type="gridvolume" name="sigma_t">
                <string name="filename" value="$file"/>
                <string name="grid_name" value="$grid"/>
            </volume>
        </medium>
    </shape>
</scene>"#,
    )
    .unwrap();
    let cases: &[(&str, &str, &[&str])] = &[
        (
            "cut.vol",
            "density",
            &["cut.vol (byte 52)", "truncated data"],
        ),
        ("nan.vol", "density", &["nan.vol (byte 52)", "NaN"]),
        (
            "cut.vdb",
            "density",
            &["cut.vdb (byte ", "past the end of the file"],
        ),
        (
            "small.vdb",
            "smoke",
            &["no grid named 'smoke'", "'density', 'fog_bg'"],
        ),
        (
            "small.vdb",
            "negative",
            &["grid 'negative'", "is -1", "≥ 0"],
        ),
        ("small.vdb", "color", &["not a float grid"]),
    ];
    for (file, grid, needles) in cases {
        let out = penumbra()
            .arg("render")
            .arg(&scene)
            .args(["-D", &format!("file={file}"), "-D", &format!("grid={grid}")])
            .args(["--spp", "1", "-o"])
            .arg(dir.join("out.exr"))
            .output()
            .unwrap();
        assert_located_failure(&out, &scene, needles[0]);
        assert_input_failure(&out, needles);
    }
}
