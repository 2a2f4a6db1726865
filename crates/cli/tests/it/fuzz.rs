//! Structure-aware fuzzing of every loader on stable Rust (issue 18).
//!
//! Targets: Mitsuba/Nori XML, COMP30019 text, CENG795 JSON and XML, OBJ+MTL scenes, COLLADA,
//! pbrt-v4,
//! PLY (ASCII and binary), OBJ meshes, image textures (PNG, EXR) and medium grids (Mitsuba
//! `.vol`, OpenVDB `.vdb`). Seeds are the files of each kind under `scenes/` and
//! `../shared/scenes` (up to 256 KiB; generated ones where there are none, and for grids the
//! fixtures of `crates/render/tests/data`) and mutations are drawn from a fixed-seed
//! SplitMix64 stream:
//! - text formats: a number replaced by an edge value (NaN, ±inf, 1e39, 2³², −1, 0, …), a
//!   token replaced by another token of the file, a line duplicated, deleted or moved, a line
//!   of another seed of the same format spliced in, the text truncated;
//! - every format: bytes flipped, inserted, deleted or duplicated.
//!
//! Each target runs in a child process (this test binary again, `PENUMBRA_FUZZ_CHILD=target`)
//! under `ulimit -v` (2 GiB of address space, so any allocation near 1 GB or more fails) and
//! a watchdog: the child writes each input to `current.*` before loading it, so a panic, an
//! abort (stack overflow, failed allocation) or a hang (no new input for 20 s) leaves the
//! input behind, and the parent copies it to `target/fuzz-findings/` and fails the test.
//!
//! `cargo test` runs a bounded slice ([`DEFAULT_ITERATIONS`] inputs per target, fixed seed).
//! `PENUMBRA_FUZZ_ITERATIONS=N` (0 = without bound, until interrupted) and
//! `PENUMBRA_FUZZ_SEED=S` change that; `PENUMBRA_FUZZ_TARGETS=mitsuba,ply-binary` picks
//! targets. Run `cargo test --release -p penumbra --test fuzz -- --nocapture` to see the
//! counts.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

/// Inputs per target in the bounded mode (`cargo test`).
const DEFAULT_ITERATIONS: u64 = 2000;
/// Seeds larger than this are skipped (mutating them is slow and adds little).
const MAX_SEED_BYTES: u64 = 256 * 1024;
/// Address-space limit of the child, in KiB.
const MEMORY_LIMIT_KIB: u64 = 2 * 1024 * 1024;
/// An input that takes longer than this is a hang.
const HANG: Duration = Duration::from_secs(20);

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    /// A scene file, loaded with `scene::load`.
    Scene,
    Ply,
    Obj,
    Image,
    /// A medium grid, read with `VoxelGrid::read_vol` or `read_vdb`.
    Grid,
}

struct Target {
    name: &'static str,
    kind: Kind,
    /// Extensions of its seed files (the first is the one inputs are written with).
    extensions: &'static [&'static str],
    /// Text-aware mutations apply.
    text: bool,
    /// Keeps only seeds for which this holds (e.g. CENG795 vs Mitsuba XML).
    accept: fn(&Path, &[u8]) -> bool,
}

fn any(_: &Path, _: &[u8]) -> bool {
    true
}
fn ceng_xml(_: &Path, b: &[u8]) -> bool {
    head(b).contains("<Scene")
}
fn not_ceng_xml(p: &Path, b: &[u8]) -> bool {
    !ceng_xml(p, b) && (head(b).contains("<scene") || head(b).contains("<test"))
}
fn ascii_ply(_: &Path, b: &[u8]) -> bool {
    head(b).contains("format ascii")
}
fn binary_ply(_: &Path, b: &[u8]) -> bool {
    head(b).contains("format binary")
}
fn head(b: &[u8]) -> String {
    String::from_utf8_lossy(&b[..b.len().min(512)]).into_owned()
}

const TARGETS: &[Target] = &[
    Target {
        name: "mitsuba",
        kind: Kind::Scene,
        extensions: &["xml"],
        text: true,
        accept: not_ceng_xml,
    },
    Target {
        name: "comp30019",
        kind: Kind::Scene,
        extensions: &["txt"],
        text: true,
        accept: any,
    },
    Target {
        name: "ceng795-json",
        kind: Kind::Scene,
        extensions: &["json"],
        text: true,
        accept: any,
    },
    Target {
        name: "ceng795-xml",
        kind: Kind::Scene,
        extensions: &["xml"],
        text: true,
        accept: ceng_xml,
    },
    Target {
        name: "objmtl",
        kind: Kind::Scene,
        extensions: &["obj"],
        text: true,
        accept: any,
    },
    Target {
        name: "collada",
        kind: Kind::Scene,
        extensions: &["dae"],
        text: true,
        accept: any,
    },
    Target {
        name: "pbrt",
        kind: Kind::Scene,
        extensions: &["pbrt"],
        text: true,
        accept: any,
    },
    Target {
        name: "ply-ascii",
        kind: Kind::Ply,
        extensions: &["ply"],
        text: true,
        accept: ascii_ply,
    },
    Target {
        name: "ply-binary",
        kind: Kind::Ply,
        extensions: &["ply"],
        text: false,
        accept: binary_ply,
    },
    Target {
        name: "obj",
        kind: Kind::Obj,
        extensions: &["obj"],
        text: true,
        accept: any,
    },
    Target {
        name: "images",
        kind: Kind::Image,
        extensions: &["png", "exr"],
        text: false,
        accept: any,
    },
    Target {
        name: "vol",
        kind: Kind::Grid,
        extensions: &["vol"],
        text: false,
        accept: any,
    },
    Target {
        name: "vdb",
        kind: Kind::Grid,
        extensions: &["vdb"],
        text: false,
        accept: any,
    },
];

// ---------------------------------------------------------------------------------------------
// Randomness and mutations

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: usize) -> usize {
        if n == 0 {
            0
        } else {
            (self.next() % n as u64) as usize
        }
    }
}

const EDGE_NUMBERS: &[&str] = &[
    "0",
    "-0",
    "-1",
    "1",
    "0.5",
    "nan",
    "NaN",
    "inf",
    "-inf",
    "1e39",
    "-1e39",
    "3.4e38",
    "1e-45",
    "4294967295",
    "4294967296",
    "2147483647",
    "-2147483648",
    "18446744073709551616",
    "99999999999",
    "1e308",
    "",
    "1.5.3",
    "0x10",
    "+",
    "-",
    ".",
];

/// Byte ranges of the tokens of `text` (runs between delimiters).
fn tokens(text: &[u8]) -> Vec<(usize, usize)> {
    let delim = |c: u8| c.is_ascii_whitespace() || b"<>=\"',:;()[]{}/".contains(&c);
    let mut out = Vec::new();
    let mut i = 0;
    while i < text.len() {
        if delim(text[i]) {
            i += 1;
            continue;
        }
        let s = i;
        while i < text.len() && !delim(text[i]) {
            i += 1;
        }
        out.push((s, i));
    }
    out
}

fn lines(text: &[u8]) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut s = 0;
    for (i, &c) in text.iter().enumerate() {
        if c == b'\n' {
            out.push((s, i + 1));
            s = i + 1;
        }
    }
    if s < text.len() {
        out.push((s, text.len()));
    }
    out
}

fn mutate(rng: &mut Rng, seed: &[u8], others: &[Vec<u8>], text: bool) -> Vec<u8> {
    let mut v = seed.to_vec();
    for _ in 0..1 + rng.below(4) {
        let choice = if text {
            rng.below(10)
        } else {
            6 + rng.below(4)
        };
        match choice {
            0 | 1 => {
                // A number (or any token) replaced by an edge value.
                let toks = tokens(&v);
                let numeric: Vec<_> = toks
                    .iter()
                    .filter(|&&(s, e)| v[s..e].iter().any(u8::is_ascii_digit))
                    .copied()
                    .collect();
                let pool = if numeric.is_empty() { &toks } else { &numeric };
                if let Some(&(s, e)) = pool.get(rng.below(pool.len())) {
                    let new = EDGE_NUMBERS[rng.below(EDGE_NUMBERS.len())].as_bytes();
                    v.splice(s..e, new.iter().copied());
                }
            }
            2 => {
                // A token replaced by another token of the file (names, ids, tags).
                let toks = tokens(&v);
                if toks.len() >= 2 {
                    let (s, e) = toks[rng.below(toks.len())];
                    let (a, b) = toks[rng.below(toks.len())];
                    let new = v[a..b].to_vec();
                    v.splice(s..e, new);
                }
            }
            3 | 4 => {
                // A line duplicated (in place or elsewhere), deleted or moved.
                let ls = lines(&v);
                if !ls.is_empty() {
                    let (s, e) = ls[rng.below(ls.len())];
                    let line = v[s..e].to_vec();
                    match rng.below(3) {
                        0 => {
                            v.splice(s..s, line);
                        }
                        1 => {
                            v.drain(s..e);
                        }
                        _ => {
                            v.drain(s..e);
                            let ls = lines(&v);
                            let at = ls.get(rng.below(ls.len())).map_or(0, |l| l.0);
                            v.splice(at..at, line);
                        }
                    }
                }
            }
            5 => {
                // A line of another seed of the same format spliced in, or a truncation.
                if rng.below(2) == 0 && !others.is_empty() {
                    let o = &others[rng.below(others.len())];
                    let ls = lines(o);
                    if let Some(&(s, e)) = ls.get(rng.below(ls.len())) {
                        let at = lines(&v).get(rng.below(lines(&v).len())).map_or(0, |l| l.0);
                        v.splice(at..at, o[s..e].iter().copied());
                    }
                } else {
                    let n = rng.below(v.len() + 1);
                    v.truncate(n);
                }
            }
            6 => {
                if !v.is_empty() {
                    let i = rng.below(v.len());
                    v[i] ^= 1 << rng.below(8);
                }
            }
            7 => {
                let i = rng.below(v.len() + 1);
                let b = [0u8, 0xff, 0x7f, 0x80, b'\n', b'<', b'"', rng.next() as u8][rng.below(8)];
                v.insert(i, b);
            }
            8 => {
                if !v.is_empty() {
                    let s = rng.below(v.len());
                    let e = (s + 1 + rng.below(64)).min(v.len());
                    v.drain(s..e);
                }
            }
            _ => {
                if !v.is_empty() {
                    let s = rng.below(v.len());
                    let e = (s + 1 + rng.below(64)).min(v.len());
                    let chunk = v[s..e].to_vec();
                    let at = rng.below(v.len() + 1);
                    v.splice(at..at, chunk);
                }
            }
        }
    }
    v
}

// ---------------------------------------------------------------------------------------------
// Seeds

fn repo_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<_> = entries.flatten().map(|e| e.path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            walk(&p, out);
        } else if p.is_file() {
            out.push(p);
        }
    }
}

/// Generated seeds for kinds the scene folders may lack (binary PLY, images).
fn generated_seeds(t: &Target, dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    match t.name {
        "ply-binary" | "ply-ascii" => {
            let mut m = scene::TriMesh::default();
            for (x, y) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
                m.positions.push(scene::Vec3::new(x, y, 0.0));
                m.normals.push(scene::Vec3::Z);
                m.uvs.push(scene::Vec2::new(x, y));
            }
            m.indices = vec![[0, 1, 2], [1, 3, 2]];
            let p = dir.join("generated.ply");
            scene::formats::ply::write_ply(&p, &m).expect("write a seed");
            if t.name == "ply-binary" {
                out.push(p);
            } else {
                let ascii = dir.join("generated-ascii.ply");
                std::fs::write(
                    &ascii,
                    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
                     property float z\nelement face 2\nproperty list uchar int vertex_indices\n\
                     end_header\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n3 1 3 2\n",
                )
                .expect("write a seed");
                out.push(ascii);
            }
        }
        "pbrt" => {
            // Directives the shared scenes do not use: objects, media, textures, lights,
            // shapes made into triangles, pbrt-v3 materials, Attribute, Import.
            let p = dir.join("generated.pbrt");
            std::fs::write(&p, GENERATED_PBRT).expect("write a seed");
            std::fs::write(
                dir.join("generated-import.pbrt"),
                "Translate 1 0 0\nShape \"sphere\"\n",
            )
            .expect("write a seed");
            out.push(p);
        }
        "vol" => {
            // 3×2×2 voxels of one channel and 2×2×1 of three (the two layouts read_vol takes).
            for (name, res, channels) in [("one", [3i32, 2, 2], 1i32), ("rgb", [2, 2, 1], 3)] {
                let mut b = b"VOL\x03".to_vec();
                for v in [1, res[0], res[1], res[2], channels] {
                    b.extend(v.to_le_bytes());
                }
                for v in [0.0f32, 0.0, 0.0, 1.0, 1.0, 1.0] {
                    b.extend(v.to_le_bytes());
                }
                let n = res.iter().product::<i32>() * channels;
                for i in 0..n {
                    b.extend((0.1 * i as f32).to_le_bytes());
                }
                let p = dir.join(format!("generated-{name}.vol"));
                std::fs::write(&p, b).expect("write a seed");
                out.push(p);
            }
        }
        "vdb" => {
            // Written by OpenVDB (crates/render/tests/data/make_vdb.py): several grids, a
            // tile, transforms vdb-rs reads and one it does not, a half-float grid.
            for name in ["tiny.vdb", "small.vdb"] {
                out.push(repo_root().join("crates/render/tests/data").join(name));
            }
        }
        "images" => {
            let mut img = render::film::Image::new(5, 3);
            for (i, p) in img.pixels.iter_mut().enumerate() {
                *p = render::math::Vec3::new(i as f32 * 0.1, 0.5, 2.0);
            }
            for ext in ["png", "exr"] {
                let p = dir.join(format!("generated.{ext}"));
                render::image_io::write_image(&p, &img).expect("write a seed");
                out.push(p);
            }
        }
        _ => {}
    }
    out
}

const GENERATED_PBRT: &str = r#"Option "integer seed" 3
LookAt 0 1 -5  0 1 0  0 1 0
Camera "perspective" "float fov" 45 "float lensradius" 0.01 "float focaldistance" 5
Film "rgb" "integer xresolution" 32 "integer yresolution" 24 "float cropwindow" [0 1 0.25 0.75]
Sampler "stratified" "integer xsamples" 2 "integer ysamples" 2
PixelFilter "mitchell" "float xradius" 2 "float yradius" 2
Integrator "sppm" "integer maxdepth" 4 "float radius" 0.1
ColorSpace "srgb"
WorldBegin
Attribute "shape" "float radius" 0.5
MakeNamedMedium "fog" "string type" "homogeneous" "spectrum sigma_a" [400 0.1 700 0.2] "rgb sigma_s" [1 1 1] "float g" -0.3
Texture "checks" "spectrum" "checkerboard" "float uscale" 4 "float vscale" 4 "rgb tex1" [1 0 0] "rgb tex2" [0 0 1]
Texture "half" "float" "scale" "float tex" 0.5 "float scale" 0.5
Texture "blend" "spectrum" "mix" "texture tex1" "checks" "rgb tex2" [0 1 0] "float amount" 0.25
MakeNamedMaterial "a" "string type" "diffuse" "texture reflectance" "blend"
MakeNamedMaterial "b" "string type" "coatedconductor" "float interface.roughness" 0.1 "spectrum conductor.eta" "metal-Ag-eta" "spectrum conductor.k" "metal-Ag-k"
MakeNamedMaterial "m" "string type" "mix" "string materials" ["a" "b"] "texture amount" "half"
LightSource "spot" "point3 from" [0 4 0] "point3 to" [0 0 0] "blackbody I" 3000 "float power" 100
LightSource "distant" "point3 from" [1 1 1] "point3 to" [0 0 0] "float illuminance" 2
LightSource "infinite" "spectrum L" "stdillum-D65" "float scale" 0.1
AttributeBegin
  MediumInterface "fog" ""
  Material "interface"
  Shape "sphere" "float radius" 2
AttributeEnd
ObjectBegin "thing"
  NamedMaterial "m"
  Shape "cylinder" "float zmin" 0 "float zmax" 1 "float phimax" 270
  Shape "disk" "float innerradius" 0.2 "float alpha" 0.5
ObjectEnd
AttributeBegin
  ActiveTransform EndTime
  Translate 0 0.1 0
  ActiveTransform All
  ObjectInstance "thing"
AttributeEnd
TransformBegin
  ReverseOrientation
  AreaLightSource "diffuse" "blackbody L" 6500 "float power" 10 "bool twosided" true
  Shape "bilinearmesh" "point3 P" [0 0 0 1 0 0 0 1 0 1 1 0.5] "integer indices" [0 1 2 3]
TransformEnd
CoordinateSystem "here"
Material "plastic" "color Kd" [0.5 0.2 0.1] "float roughness" 0.05
Shape "loopsubdiv" "integer levels" 2 "point3 P" [1 1 1 -1 -1 1 -1 1 -1 1 -1 -1] "integer indices" [0 1 2 0 3 1 0 2 3 1 3 2]
CoordSysTransform "camera"
Material "dielectric" "spectrum eta" "glass-F11" "float roughness" 0.2
Shape "trianglemesh" "point3 P" [0 0 0 1 0 0 0 1 0] "normal N" [0 0 1 0 0 1 0 0 1] "point2 uv" [0 0 1 0 0 1]
Import "generated-import.pbrt"
"#;

fn seeds(t: &Target, gen_dir: &Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    walk(&repo_root().join("scenes"), &mut files);
    let shared = repo_root().join("../shared/scenes");
    if shared.is_dir() {
        walk(&shared, &mut files);
    }
    let mut out: Vec<PathBuf> = files
        .into_iter()
        .filter(|p| {
            let ext = p
                .extension()
                .and_then(|e| e.to_str())
                .map(str::to_ascii_lowercase)
                .unwrap_or_default();
            t.extensions.contains(&ext.as_str())
                && std::fs::metadata(p).is_ok_and(|m| m.len() <= MAX_SEED_BYTES)
                && std::fs::read(p).is_ok_and(|b| (t.accept)(p, &b))
        })
        .collect();
    out.extend(generated_seeds(t, gen_dir));
    out
}

// ---------------------------------------------------------------------------------------------
// The child: load inputs until the count is reached

/// Load one input the way its target is loaded in use; errors are fine, panics are findings.
fn load(kind: Kind, path: &Path, bytes: &[u8]) {
    match kind {
        Kind::Scene => {
            let _ = scene::load(path, &scene::LoadOptions::default());
        }
        Kind::Ply => {
            let _ = scene::formats::ply::parse_ply(bytes, path);
        }
        Kind::Obj => {
            let _ = scene::formats::obj::parse_obj(&String::from_utf8_lossy(bytes), path);
        }
        Kind::Image => {
            let _ = render::image_io::read_image_alpha(path, render::image_io::Decode::Srgb);
        }
        Kind::Grid => {
            use render::media::grid::VoxelGrid;
            if path.extension().is_some_and(|e| e == "vdb") {
                // The grids of the seeds, and one that none has. read_vdb turns a panic of
                // vdb-rs into an error, but its bounds walk is meant to leave vdb-rs nothing
                // to fail on: such an error is a finding too.
                for name in ["density", "fog_bg", "rotated", "half", "color", "missing"] {
                    if let Err(e) = VoxelGrid::read_vdb(path, name, true)
                        && e.message.contains("(vdb-rs) failed")
                    {
                        panic!("the preflight let through a file vdb-rs fails on: {e}");
                    }
                }
            } else {
                let _ = VoxelGrid::read_vol(path, true);
            }
        }
    }
}

/// A folder beside which the input's relative references (meshes, textures, includes) still
/// resolve: symbolic links to everything in the seed's folder.
fn mirror_folder(seed: &Path, work: &Path, index: usize) -> PathBuf {
    let dir = work.join(format!("seed-{index}"));
    std::fs::create_dir_all(&dir).expect("work folder");
    #[cfg(unix)]
    if let Some(parent) = seed.parent()
        && let Ok(entries) = std::fs::read_dir(parent)
    {
        for e in entries.flatten() {
            if e.path() != seed {
                let _ = std::os::unix::fs::symlink(e.path(), dir.join(e.file_name()));
            }
        }
    }
    dir
}

fn run_child(t: &Target, work: &Path, iterations: u64, seed: u64) {
    let gen_dir = work.join("generated");
    std::fs::create_dir_all(&gen_dir).expect("work folder");
    let seeds = seeds(t, &gen_dir);
    assert!(!seeds.is_empty(), "{}: no seed files", t.name);
    let contents: Vec<Vec<u8>> = seeds.iter().map(|p| std::fs::read(p).unwrap()).collect();
    let dirs: Vec<PathBuf> = seeds
        .iter()
        .enumerate()
        .map(|(i, p)| mirror_folder(p, work, i))
        .collect();
    // Panics are findings: the parent reads the current input.
    let mut rng = Rng(seed
        ^ t.name
            .bytes()
            .fold(0u64, |h, b| h.wrapping_mul(31) ^ b as u64));
    let start = Instant::now();
    let mut n = 0u64;
    while iterations == 0 || n < iterations {
        let i = rng.below(seeds.len());
        let input = mutate(&mut rng, &contents[i], &contents, t.text);
        let name = seeds[i].file_name().expect("a file name");
        let path = dirs[i].join(name);
        std::fs::write(&path, &input).expect("write the input");
        // The watchdog's record: which input is being loaded.
        std::fs::write(work.join("current"), path.to_string_lossy().as_bytes())
            .expect("write the record");
        load(t.kind, &path, &input);
        n += 1;
    }
    println!(
        "fuzz {}: {n} inputs from {} seeds in {:.1} s",
        t.name,
        seeds.len(),
        start.elapsed().as_secs_f64()
    );
}

/// Runs only as the child (`PENUMBRA_FUZZ_CHILD` set); a no-op in a normal test run.
#[test]
fn fuzz_child() {
    let Ok(name) = std::env::var("PENUMBRA_FUZZ_CHILD") else {
        return;
    };
    let t = TARGETS
        .iter()
        .find(|t| t.name == name)
        .expect("a known target");
    let work = PathBuf::from(std::env::var("PENUMBRA_FUZZ_WORK").expect("work folder"));
    let iterations = std::env::var("PENUMBRA_FUZZ_ITERATIONS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(DEFAULT_ITERATIONS);
    let seed = std::env::var("PENUMBRA_FUZZ_SEED")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1);
    run_child(t, &work, iterations, seed);
}

// ---------------------------------------------------------------------------------------------
// The parent: one child per target, watched

#[cfg(unix)]
#[test]
fn every_loader_survives_mutated_inputs() {
    if std::env::var("PENUMBRA_FUZZ_CHILD").is_ok() {
        return;
    }
    let wanted: Option<Vec<String>> = std::env::var("PENUMBRA_FUZZ_TARGETS")
        .ok()
        .map(|s| s.split(',').map(str::to_string).collect());
    let findings_dir = repo_root().join("target/fuzz-findings");
    let exe = std::env::current_exe().expect("the test binary");
    // The child test's full name in this binary (its module path without the crate's name).
    let child_test = match module_path!().split_once("::") {
        Some((_, module)) => format!("{module}::fuzz_child"),
        None => "fuzz_child".to_string(),
    };
    let mut findings = Vec::new();
    for t in TARGETS {
        if wanted
            .as_ref()
            .is_some_and(|w| !w.iter().any(|n| n == t.name))
        {
            continue;
        }
        let work =
            std::env::temp_dir().join(format!("penumbra-fuzz-{}-{}", std::process::id(), t.name));
        let _ = std::fs::remove_dir_all(&work);
        std::fs::create_dir_all(&work).unwrap();
        let mut child = Command::new("sh")
            .arg("-c")
            .arg(format!(
                "ulimit -v {MEMORY_LIMIT_KIB} && exec \"$0\" {child_test} --exact --nocapture --test-threads 1"
            ))
            .arg(&exe)
            .env("PENUMBRA_FUZZ_CHILD", t.name)
            .env("PENUMBRA_FUZZ_WORK", &work)
            .env("RUST_BACKTRACE", "0")
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .expect("start the child");
        // Watch: a new input at least every HANG, else it is stuck.
        let record = work.join("current");
        let mut last = (String::new(), Instant::now());
        let status = loop {
            if let Some(s) = child.try_wait().expect("wait for the child") {
                break Some(s);
            }
            let now = std::fs::read_to_string(&record).unwrap_or_default();
            let modified = std::fs::metadata(&record).and_then(|m| m.modified()).ok();
            let key = format!("{now}{modified:?}");
            if key != last.0 {
                last = (key, Instant::now());
            } else if last.1.elapsed() > HANG {
                let _ = child.kill();
                let _ = child.wait();
                break None;
            }
            std::thread::sleep(Duration::from_millis(50));
        };
        let output = child.wait_with_output().expect("child output");
        let stdout = String::from_utf8_lossy(&output.stdout);
        let tag = format!("fuzz {}:", t.name);
        let report = stdout.find(&tag);
        if let Some(i) = report {
            eprintln!("{}", stdout[i..].lines().next().unwrap_or_default());
        }
        let ok = status.is_some_and(|s| s.success());
        // A child that ran no test (its name not found) exits with success having fuzzed
        // nothing.
        if ok && report.is_none() {
            findings.push(format!(
                "{}: the child ({child_test}) reported no run",
                t.name
            ));
        }
        if !ok {
            let input = PathBuf::from(std::fs::read_to_string(&record).unwrap_or_default());
            std::fs::create_dir_all(&findings_dir).unwrap();
            let ext = input
                .extension()
                .and_then(|e| e.to_str())
                .unwrap_or("bin")
                .to_string();
            let saved = findings_dir.join(format!("{}-{}.{ext}", t.name, std::process::id()));
            let _ = std::fs::copy(&input, &saved);
            let why = match status {
                None => "hang".to_string(),
                Some(s) => format!("{s}"),
            };
            let stderr = String::from_utf8_lossy(&output.stderr);
            let lines: Vec<&str> = stderr.lines().collect();
            let tail = lines[lines.len().saturating_sub(15)..].join("\n");
            findings.push(format!(
                "{}: {why} on the input saved as {}\n{tail}",
                t.name,
                saved.display()
            ));
        }
        let _ = std::fs::remove_dir_all(&work);
    }
    assert!(findings.is_empty(), "findings:\n{}", findings.join("\n\n"));
}
