//! CENG795 homework 4: texture maps on objects and the background. Every decal mode has a
//! test here that fails when the mode is ignored; the nearest-mode image test goes through the
//! command line and compares the PNG with the texture byte for byte.
//!
//! The scenes are built per test: a square of side 8 at z = 0 facing a camera on the +z axis,
//! lit by a directional light along −z of radiance E = 100 (display units, no tone map), with
//! the course's default shading (f = kd + ks cosᵖα / cos θi, so a surface facing the light
//! reads kd·E·cos θ). Everything here is deterministic: the Whitted tracer with only delta
//! lights draws no random number that changes a pixel.

use std::path::{Path, PathBuf};
use std::process::Command;

use build::BuildOptions;
use build::render_desc;
use render::math::Vec3;
use scene::{Document, LoadOptions, SceneDesc};

const E: f32 = 100.0;

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("penumbra-tex-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Write an RGB8 PNG of `w`×`h` texels given by `f(i, j)`.
fn write_png(path: &Path, w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 3]) {
    let img = image::RgbImage::from_fn(w, h, |i, j| image::Rgb(f(i, j)));
    img.save(path).unwrap();
}

struct Setup<'a> {
    /// `Textures` JSON body (`Images` + `TextureMap`s), or empty.
    textures: &'a str,
    /// The square's `Textures` list, or empty.
    object_textures: &'a str,
    /// Image resolution (the near plane is ±0.4 × ±0.4·h/w at distance 1 from z = 10: the
    /// image spans x ∈ [−4, 4] exactly).
    res: (u32, u32),
    /// Material keys after the diffuse one.
    material: &'a str,
    /// Offset of the camera and the square in x and y (to move the world point the centre
    /// pixel sees, for solid textures).
    shift: (f32, f32),
    /// Scale of the near plane: 1 shows the square exactly, small values a spot around the
    /// centre.
    zoom: f32,
    /// The square's z (0: in view; above 10: behind the camera).
    square_z: f32,
}

impl Default for Setup<'_> {
    /// The untextured square filling a 9×9 image.
    fn default() -> Self {
        Setup {
            textures: "",
            object_textures: "",
            res: (9, 9),
            material: "",
            shift: (0.0, 0.0),
            zoom: 1.0,
            square_z: 0.0,
        }
    }
}

fn scene_json(s: &Setup) -> String {
    let (w, h) = s.res;
    let half_x = 0.4 * s.zoom;
    let half_y = half_x * h as f32 / w as f32;
    let (dx, dy) = s.shift;
    let ys = 4.0 * h as f32 / w as f32;
    // uv: texel (i, j) of a w×h texture under pixel (i, j) with the course's addressing
    // (texel i at u = i/w, so the square spans u from −½/w to 1 − ½/w).
    let (u0, u1) = (-0.5 / w as f32, 1.0 - 0.5 / w as f32);
    let (v0, v1) = (-0.5 / h as f32, 1.0 - 0.5 / h as f32);
    let objects_textures = if s.object_textures.is_empty() {
        String::new()
    } else {
        format!(r#", "Textures": "{}""#, s.object_textures)
    };
    let textures = if s.textures.is_empty() {
        String::new()
    } else {
        format!(r#""Textures": {{ {} }},"#, s.textures)
    };
    format!(
        r#"{{"Scene": {{
  "BackgroundColor": "0 0 0",
  "Cameras": {{"Camera": {{"_id": "1", "Position": "{dx} {dy} 10", "Gaze": "0 0 -1", "Up": "0 1 0",
    "NearPlane": "-{half_x} {half_x} -{half_y} {half_y}", "NearDistance": "1",
    "ImageResolution": "{w} {h}", "ImageName": "t.png"}}}},
  "Lights": {{"DirectionalLight": {{"_id": "1", "Direction": "0 0 -1", "Radiance": "{E} {E} {E}"}}}},
  "Materials": {{"Material": {{"_id": "1", "AmbientReflectance": "0 0 0",
    "DiffuseReflectance": "0.1 0.2 0.3", "SpecularReflectance": "0 0 0"{material}}}}},
  {textures}
  "VertexData": {{"_data": "{xa} {yb} {z}  {xb} {yb} {z}  {xb} {ya} {z}  {xa} {ya} {z}"}},
  "TexCoordData": {{"_data": "{u0} {v1}  {u1} {v1}  {u1} {v0}  {u0} {v0}"}},
  "Objects": {{"Mesh": {{"_id": "1", "Material": "1", "Faces": {{"_data": "1 2 3 1 3 4"}}{objects_textures}}}}}
}}}}"#,
        material = s.material,
        z = s.square_z,
        xa = -4.0 + dx,
        xb = 4.0 + dx,
        ya = ys + dy,
        yb = -ys + dy,
    )
}

fn load_in(dir: &Path, s: &Setup) -> SceneDesc {
    let file = dir.join("scene.json");
    std::fs::write(&file, scene_json(s)).unwrap();
    match scene::load(&file, &LoadOptions::default()) {
        Ok(Document::Scene(d)) => {
            assert!(d.warnings.is_empty(), "{:?}", d.warnings);
            *d
        }
        Ok(_) => panic!("not a scene"),
        Err(e) => panic!("{e}"),
    }
}

/// The radiance of pixel (x, y) of a 1-spp render.
fn render_pixels(desc: &SceneDesc) -> render::film::Image {
    let out = render_desc(
        desc,
        &BuildOptions {
            spp: Some(1),
            seed: Some(3),
            ..Default::default()
        },
    )
    .unwrap();
    out.film.develop()
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol
}

/// Acceptance: an image-textured square at 1 spp shows the texture's pixels through the
/// camera, nearest mode, exactly: the PNG `penumbra render` writes equals the texture.
#[test]
fn nearest_image_texture_reproduces_its_texels() {
    let dir = temp_dir("nearest");
    let (w, h) = (8, 6);
    let texel = |i: u32, j: u32| [(i * 30 + 10) as u8, (j * 40 + 5) as u8, ((i + j) * 7) as u8];
    write_png(&dir.join("tex.png"), w, h, texel);
    let textures = r#""Images": {"Image": {"_id": "1", "_data": "tex.png"}},
        "TextureMap": {"_id": "1", "_type": "image", "ImageId": "1", "DecalMode": "replace_all",
                       "Interpolation": "nearest"}"#;
    let file = dir.join("scene.json");
    let setup = Setup {
        textures,
        object_textures: "1",
        res: (w, h),
        ..Setup::default()
    };
    std::fs::write(&file, scene_json(&setup)).unwrap();
    let out = dir.join("out.png");
    let o = Command::new(env!("CARGO_BIN_EXE_penumbra"))
        .arg("render")
        .arg(&file)
        .arg("-o")
        .arg(&out)
        .args(["--spp", "1", "--filter", "box", "-q"])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let png = image::open(&out).unwrap().to_rgb8();
    assert_eq!(png.dimensions(), (w, h));
    for j in 0..h {
        for i in 0..w {
            assert_eq!(png.get_pixel(i, j).0, texel(i, j), "pixel ({i}, {j})");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// A uniform image texture of colour `c` (0–255), map 1 with `decal` and `extra` keys.
fn uniform_texture(dir: &Path, c: [u8; 3], decal: &str, extra: &str) -> String {
    write_png(&dir.join("u.png"), 4, 4, |_, _| c);
    format!(
        r#""Images": {{"Image": {{"_id": "1", "_data": "u.png"}}}},
        "TextureMap": {{"_id": "1", "_type": "image", "ImageId": "1", "DecalMode": "{decal}"{extra}}}"#
    )
}

fn centre(img: &render::film::Image) -> Vec3 {
    img.get(img.width / 2, img.height / 2)
}

/// The shading decals: kd replaced, kd blended, ks replaced, everything replaced. Each reads
/// its analytic value at the centre; ignoring the mode gives kd·E = (10, 20, 30).
#[test]
fn shading_decals_change_what_they_name() {
    let dir = temp_dir("shading");
    let plain = kd_e();
    let t = Vec3::new(200.0, 100.0, 50.0) / 255.0;
    let cases: [(&str, &str, &str, Vec3); 5] = [
        ("replace_kd", "", "", t * E),
        ("blend_kd", "", "", (t + Vec3::new(0.1, 0.2, 0.3)) * 0.5 * E),
        // ks = t, Blinn–Phong at α = 0 (light, eye and normal aligned at the centre).
        ("replace_ks", "", r#", "PhongExponent": "1""#, plain + t * E),
        // Pasted as it is, in display units: the texel itself.
        ("replace_all", "", "", t * 255.0),
        // A normalizer of 510 halves the texture's value.
        ("replace_kd", r#", "Normalizer": "510""#, "", t * 0.5 * E),
    ];
    for (decal, extra, material, want) in cases {
        let textures = uniform_texture(&dir, [200, 100, 50], decal, extra);
        let setup = Setup {
            textures: &textures,
            object_textures: "1",
            material,
            ..Setup::default()
        };
        let got = centre(&render_pixels(&load_in(&dir, &setup)));
        assert!(close(got, want, 0.05), "{decal}{extra}: {got} vs {want}");
        assert!(!close(got, plain, 1.0), "{decal} had no effect");
    }
    std::fs::remove_dir_all(&dir).ok();
}

fn kd_e() -> Vec3 {
    Vec3::new(0.1, 0.2, 0.3) * E
}

/// `replace_background`: escaping camera rays show the texture spread over the image, texel
/// (i, j) on pixel (i, j).
#[test]
fn background_texture_fills_the_image() {
    let dir = temp_dir("background");
    let (w, h) = (6, 4);
    let texel = |i: u32, j: u32| [(i * 40) as u8, (j * 60 + 3) as u8, 77];
    write_png(&dir.join("bg.png"), w, h, texel);
    let textures = r#""Images": {"Image": {"_id": "1", "_data": "bg.png"}},
        "TextureMap": {"_id": "1", "_type": "image", "ImageId": "1",
                       "DecalMode": "replace_background", "Interpolation": "nearest"}"#;
    // No object lists the map: only background (the square is behind the camera).
    let setup = Setup {
        textures,
        res: (w, h),
        square_z: 20.0,
        ..Setup::default()
    };
    let img = render_pixels(&load_in(&dir, &setup));
    for j in 0..h {
        for i in 0..w {
            let c = texel(i, j);
            let want = Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32);
            let got = img.get(i, j);
            assert!(close(got, want, 1e-3), "({i}, {j}): {got} vs {want}");
        }
    }
    std::fs::remove_dir_all(&dir).ok();
}

/// `replace_normal`: a uniform normal map tilting the normal to (0.6, 0, 0.8) in the tangent
/// frame dims the square to kd·E·n′z; quantised to 8 bits, n′ = normalize(2c/255 − 1).
#[test]
fn normal_map_tilts_the_normal() {
    let dir = temp_dir("normal");
    let c = [204u8, 128, 230];
    let textures = uniform_texture(&dir, c, "replace_normal", "");
    let setup = Setup {
        textures: &textures,
        object_textures: "1",
        ..Setup::default()
    };
    let got = centre(&render_pixels(&load_in(&dir, &setup)));
    let n =
        (Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32) * (2.0 / 255.0) - Vec3::ONE).normalize();
    let want = kd_e() * n.z;
    assert!(close(got, want, 0.05), "{got} vs {want}");
    std::fs::remove_dir_all(&dir).ok();
}

/// `bump_normal` from an image: a ramp rising by 10/255 per texel along u, with a bump
/// factor of 19.125, tilts the normal by atan(0.75): the square reads kd·E·0.8.
#[test]
fn image_bump_map_tilts_the_normal() {
    let dir = temp_dir("bump");
    write_png(&dir.join("ramp.png"), 32, 4, |i, _| {
        let v = (i * 10) as u8;
        [v, v, v]
    });
    let textures = r#""Images": {"Image": {"_id": "1", "_data": "ramp.png"}},
        "TextureMap": {"_id": "1", "_type": "image", "ImageId": "1", "DecalMode": "bump_normal",
                       "Interpolation": "bilinear", "BumpFactor": "19.125"}"#;
    let setup = Setup {
        textures,
        object_textures: "1",
        ..Setup::default()
    };
    let got = centre(&render_pixels(&load_in(&dir, &setup)));
    let want = kd_e() * 0.8;
    assert!(close(got, want, 0.05), "{got} vs {want}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Perlin noise as kd (both conversions) and as a bump map, and the solid checkerboard, at
/// points worked out by hand: the camera, zoomed onto a spot, sees the world point
/// (0.5, 0, 0)·(1/scale), where the noise is 0.25 (see the render crate's unit test).
#[test]
fn solid_textures_at_known_points() {
    let dir = temp_dir("solid");
    let perlin = |conv: &str, decal: &str, extra: &str| {
        format!(
            r#""TextureMap": {{"_id": "1", "_type": "perlin", "DecalMode": "{decal}",
                "NoiseConversion": "{conv}", "NoiseScale": "2"{extra}}}"#
        )
    };
    let run = |textures: &str, shift: (f32, f32), zoom: f32| {
        let setup = Setup {
            textures,
            object_textures: "1",
            shift,
            zoom,
            ..Setup::default()
        };
        render_pixels(&load_in(&dir, &setup))
    };
    // Scale 2: the point 0.25 along x is noise coordinate 0.5.
    let linear = centre(&run(&perlin("linear", "replace_kd", ""), (0.25, 0.0), 1e-4));
    assert!(close(linear, Vec3::splat(0.625 * E), 0.05), "{linear}");
    let absval = centre(&run(&perlin("absval", "replace_kd", ""), (0.25, 0.0), 1e-4));
    assert!(close(absval, Vec3::splat(0.25 * E), 0.05), "{absval}");
    // Bumped by the noise: the image is no longer the flat kd·E everywhere.
    let bumped = run(
        &perlin("linear", "bump_normal", r#", "BumpFactor": "3""#),
        (0.3, 0.2),
        1.0,
    );
    let flat = kd_e();
    let changed = bumped
        .pixels
        .iter()
        .filter(|p| !close(**p, flat, 0.5))
        .count();
    assert!(
        changed > bumped.pixels.len() / 2,
        "{changed} pixels changed"
    );
    assert!(
        bumped
            .pixels
            .iter()
            .all(|p| p.max_element() <= flat.max_element() + 1e-3)
    );
    // Checkerboard cells of side 1/scale = 0.5: the centre (−0.3, 0.1, 0) + offset 0.05 is
    // in cell (−1, 0, 0), of odd parity: black; + 0.35 in cell (0, 0, 0): white.
    let checker = |offset: &str| {
        format!(
            r#""TextureMap": {{"_id": "1", "_type": "checkerboard", "DecalMode": "replace_kd",
                "BlackColor": "0 0 255", "WhiteColor": "255 255 255", "Scale": "2",
                "Offset": "{offset}"}}"#
        )
    };
    let black = centre(&run(&checker("0.05"), (-0.3, 0.1), 1e-4));
    assert!(close(black, Vec3::new(0.0, 0.0, E), 0.05), "{black}");
    let white = centre(&run(&checker("0.35"), (-0.3, 0.1), 1e-4));
    assert!(close(white, Vec3::splat(E), 0.05), "{white}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Spheres take the course's uv: θ = acos(y/r), φ = atan2(z, x), u = (π − φ)/2π, v = θ/π.
/// A camera on +z zoomed onto the sphere's front point (0, 0, r) sees u = ¼, v = ½: texel
/// (2, 2) of an 8×4 texture (nearest texel (round(u·8), round(v·4))); other views likewise.
#[test]
fn spheres_use_the_course_uv() {
    let dir = temp_dir("sphere");
    let texel = |i: u32, j: u32| [(i * 30) as u8, (j * 60) as u8, 9];
    write_png(&dir.join("s.png"), 8, 4, texel);
    let scene = |pos: &str, gaze: &str, up: &str| {
        format!(
            r#"{{"Scene": {{
  "Cameras": {{"Camera": {{"_id": "1", "Position": "{pos}", "Gaze": "{gaze}", "Up": "{up}",
    "NearPlane": "-1e-4 1e-4 -1e-4 1e-4", "NearDistance": "1", "ImageResolution": "3 3",
    "ImageName": "s.png"}}}},
  "Materials": {{"Material": {{"_id": "1", "DiffuseReflectance": "1 1 1"}}}},
  "Textures": {{"Images": {{"Image": {{"_id": "1", "_data": "s.png"}}}},
    "TextureMap": {{"_id": "1", "_type": "image", "ImageId": "1", "DecalMode": "replace_all",
      "Interpolation": "nearest"}}}},
  "VertexData": {{"_data": "1 2 3"}},
  "Objects": {{"Sphere": {{"_id": "1", "Material": "1", "Center": "1", "Radius": "2", "Textures": "1"}}}}
}}}}"#
        )
    };
    let file = dir.join("sphere.json");
    for (pos, gaze, up, want) in [
        ("1 2 10", "0 0 -1", "0 1 0", texel(2, 2)),
        // From +x: φ = 0, u = ½; from −z: φ = −π/2, u = ¾.
        ("11 2 3", "-1 0 0", "0 1 0", texel(4, 2)),
        ("1 2 -7", "0 0 1", "0 1 0", texel(6, 2)),
        // 45° above the front: θ = π/4, v = ¼ (row 1).
        ("1 9.0710678 10.0710678", "0 -1 -1", "0 1 -1", texel(2, 1)),
    ] {
        std::fs::write(&file, scene(pos, gaze, up)).unwrap();
        let Ok(Document::Scene(desc)) = scene::load(&file, &LoadOptions::default()) else {
            panic!("loads")
        };
        let got = centre(&render_pixels(&desc));
        let want = Vec3::new(want[0] as f32, want[1] as f32, want[2] as f32);
        assert!(close(got, want, 1e-3), "camera at {pos}: {got} vs {want}");
    }
    std::fs::remove_dir_all(&dir).ok();
}
