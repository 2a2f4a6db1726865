//! pbrt-v4 loader: directives, transforms and the camera frame, defaults, parameter types,
//! errors with their positions, the parse time of a large inline mesh, and the shared
//! Bitterli scenes.

use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::{Mat4, Vec3};
use scene::*;

/// Write `files` (name, content) into a fresh temporary folder; returns the first file's path.
fn write_scene(files: &[(&str, &[u8])]) -> PathBuf {
    static N: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!(
        "penumbra-pbrt-test-{}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, text) in files {
        let p = dir.join(name);
        std::fs::create_dir_all(p.parent().unwrap()).unwrap();
        std::fs::write(p, text).unwrap();
    }
    dir.join(files[0].0)
}

fn load_text(text: &str) -> Result<SceneDesc> {
    let path = write_scene(&[("scene.pbrt", text.as_bytes())]);
    match load(&path, &LoadOptions::default())? {
        Document::Scene(s) => Ok(*s),
        Document::Test(_) => panic!("a scene expected"),
    }
}

fn scene(text: &str) -> SceneDesc {
    load_text(text).unwrap_or_else(|e| panic!("{e}"))
}

fn error(text: &str) -> LoadError {
    match load_text(text) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => e,
    }
}

/// The material inside the `twosided` wrapper pbrt's two-sided BSDFs get.
fn base(s: &SceneDesc, id: MaterialId) -> &Material {
    match &s.material(id).material {
        Material::TwoSided { front, back: None } => &s.material(*front).material,
        m => m,
    }
}

fn warnings(s: &SceneDesc) -> Vec<String> {
    s.warnings.iter().map(|w| w.message.clone()).collect()
}

#[test]
fn bitterli_scenes_load_without_warnings() {
    for name in [
        "bitterli-cornell-box",
        "bitterli-veach-mis",
        "bitterli-coffee",
        "bitterli-water-caustic",
    ] {
        let Some(dir) = testing::shared_dir(&format!("scenes/standard/{name}")) else {
            return;
        };
        let path = dir.join("pbrt/scene-v4.pbrt");
        let t = std::time::Instant::now();
        let Document::Scene(s) =
            load(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"))
        else {
            panic!("a scene expected")
        };
        let tris: usize = s
            .shapes
            .iter()
            .map(|x| match &x.shape {
                Shape::Mesh(m) => m.indices.len(),
                _ => 0,
            })
            .sum();
        println!(
            "{name}: {} shapes, {tris} triangles, {} materials, {} textures, {} emitters, {:?}",
            s.shapes.len(),
            s.materials.len(),
            s.textures.len(),
            s.emitters.len(),
            t.elapsed()
        );
        for w in &s.warnings {
            println!("  {w}");
        }
        assert!(s.warnings.is_empty(), "{name}: {:?}", warnings(&s));
        assert!(!s.shapes.is_empty());
    }
}

const CAMERA: &str = r#"
Film "rgb" "integer xresolution" 64 "integer yresolution" 32
Camera "perspective" "float fov" 40
WorldBegin
"#;

#[test]
fn defaults_of_an_empty_world() {
    let s = scene("WorldBegin\n");
    let c = &s.sensors[0];
    assert_eq!((c.film.width, c.film.height), (1280, 720));
    assert!(matches!(
        c.camera.projection,
        Projection::Perspective { fov, fov_axis: FovAxis::Smaller } if fov == 90.0
    ));
    assert_eq!(c.sampler.spp, 16);
    assert!(matches!(
        c.film.filter,
        FilterDesc::Gaussian { stddev, radius } if stddev == 0.5 && radius == 1.5
    ));
    // volpath, maxdepth 5 bounces = 6 segments.
    assert!(matches!(
        s.integrator,
        IntegratorDesc::VolPath { max_depth: 6, .. }
    ));
    assert_eq!(s.light_selection, LightSelection::Bvh);
}

/// pbrt-v4's graphics state starts with a "diffuse" material (reflectance 0.5): an area
/// light given no Material reflects light as well as emitting it (the scene model's "no
/// material" would make it black, Mitsuba's rule for emitters).
#[test]
fn area_lights_without_a_material_reflect() {
    let s = scene(&format!(
        "{CAMERA}AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 1 1 1 ]\nShape \"sphere\"\nAttributeEnd\n"
    ));
    let shape = &s.shapes[0];
    assert!(shape.emission.is_some());
    let m = shape.material.expect("the default material");
    assert!(matches!(
        &s.materials[m.0 as usize].material,
        Material::Diffuse { reflectance } if *reflectance == ColorParam::constant(0.5)
    ));
}

/// pbrt's camera space has +x to the image's right; Mitsuba's (ours) to its left. `Scale -1
/// 1 1` before pbrt's LookAt is therefore the same camera as Mitsuba's `lookat`.
#[test]
fn the_camera_frame_is_pbrts_left_handed_one() {
    let (e, t, u) = (Vec3::new(1.0, 2.0, 3.0), Vec3::new(0.0, 1.0, 0.0), Vec3::Y);
    let mitsuba = scene::formats::common::look_at(e, t, u).unwrap();
    let s = scene("Scale -1 1 1\nLookAt 1 2 3  0 1 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n");
    assert!(s.sensors[0].camera.to_world.abs_diff_eq(mitsuba, 1e-5));
    // Without the flip the image is mirrored: our camera's x axis is reversed.
    let s = scene("LookAt 1 2 3  0 1 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n");
    let flipped = mitsuba * Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
    assert!(s.sensors[0].camera.to_world.abs_diff_eq(flipped, 1e-5));
}

/// What a full pbrt sphere's `to_world` starts with: a mirror in z that makes our sphere's
/// v (θ/π from +z) pbrt-v4's (1 − θ/π).
const SPHERE_UV: Mat4 = Mat4::from_diagonal(glam::Vec4::new(1.0, 1.0, -1.0, 1.0));

#[test]
fn transforms_compose_as_pbrt_and_matrices_are_column_major() {
    let s = scene(&format!(
        "{CAMERA}Translate 1 2 3\nRotate 90 0 0 1\nScale 2 2 2\nShape \"sphere\"\n\
         AttributeBegin\nTransform [1 0 0 0  0 1 0 0  0 0 1 0  5 6 7 1]\nShape \"sphere\"\nAttributeEnd\n\
         Shape \"sphere\" \"float radius\" 3\n"
    ));
    let m = s.shapes[0].to_world;
    let expect = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0))
        * Mat4::from_rotation_z(90f32.to_radians())
        * Mat4::from_scale(Vec3::splat(2.0))
        * SPHERE_UV;
    assert!(m.abs_diff_eq(expect, 1e-6));
    assert_eq!(
        s.shapes[1].to_world.w_axis.truncate(),
        Vec3::new(5.0, 6.0, 7.0)
    );
    // AttributeEnd restored the transform.
    assert!(s.shapes[2].to_world.abs_diff_eq(expect, 1e-6));
    assert!(matches!(s.shapes[2].shape, Shape::Sphere { radius, .. } if radius == 3.0));
}

#[test]
fn objects_are_instanced_onto_shared_meshes() {
    let s = scene(&format!(
        "{CAMERA}ObjectBegin \"tri\"\nTranslate 0 0 1\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0]\nObjectEnd\n\
         ObjectInstance \"tri\"\nTranslate 10 0 0\nObjectInstance \"tri\"\n"
    ));
    assert_eq!(s.shapes.len(), 2);
    let (Shape::Mesh(a), Shape::Mesh(b)) = (&s.shapes[0].shape, &s.shapes[1].shape) else {
        panic!("meshes expected")
    };
    assert!(std::sync::Arc::ptr_eq(a, b));
    assert_eq!(a.indices, vec![[0, 1, 2]]);
    assert_eq!(
        s.shapes[1].to_world.w_axis.truncate(),
        Vec3::new(10.0, 0.0, 1.0)
    );
}

#[test]
fn materials_map_with_pbrt_defaults() {
    let s = scene(&format!(
        "{CAMERA}Material \"conductor\"\nShape \"sphere\"\n\
         Material \"conductor\" \"float roughness\" 0.04 \"spectrum eta\" \"metal-Au-eta\" \"spectrum k\" \"metal-Au-k\"\nShape \"sphere\"\n\
         Material \"dielectric\" \"spectrum eta\" \"glass-BK7\"\nShape \"sphere\"\n\
         Material \"dielectric\" \"float eta\" 1.33 \"float roughness\" 0.01 \"bool remaproughness\" false\nShape \"sphere\"\n\
         Material \"coateddiffuse\"\nShape \"sphere\"\n\
         Material \"interface\"\nShape \"sphere\"\n"
    ));
    let mat = |i: usize| base(&s, s.shapes[i].material.unwrap());
    match mat(0) {
        Material::Conductor { eta, k, .. } => {
            let (e, kk) = scene::formats::mitsuba::ior::conductor("Cu").unwrap();
            assert_eq!((eta.rgb(), k.rgb()), (e, kk));
            assert!(
                matches!(eta.spectrum().unwrap().kind, SpectrumKind::Conductor { ref material, eta: true } if material == "Cu")
            );
        }
        m => panic!("{m:?}"),
    }
    match mat(1) {
        Material::RoughConductor {
            alpha_u,
            distribution,
            ..
        } => {
            assert_eq!(*distribution, MicrofacetDistribution::Ggx);
            // RoughnessToAlpha: √0.04.
            assert!(matches!(alpha_u, FloatParam::Const(a) if (a - 0.2).abs() < 1e-6));
        }
        m => panic!("{m:?}"),
    }
    match mat(2) {
        Material::Dielectric {
            int_ior,
            dispersion,
            ..
        } => {
            assert!((int_ior - 1.5168).abs() < 1e-3, "{int_ior}");
            assert!(dispersion.is_some());
        }
        m => panic!("{m:?}"),
    }
    assert!(
        matches!(mat(3), Material::RoughDielectric { int_ior, alpha_u: FloatParam::Const(a), .. } if *int_ior == 1.33 && *a == 0.01)
    );
    match mat(4) {
        Material::CoatedDiffuse {
            eta,
            thickness,
            max_depth,
            n_samples,
            reflectance,
            ..
        } => {
            assert_eq!((*eta, *max_depth, *n_samples), (1.5, 10, 1));
            assert_eq!(*thickness, FloatParam::Const(0.01));
            assert_eq!(*reflectance, ColorParam::constant(0.5));
        }
        m => panic!("{m:?}"),
    }
    assert!(matches!(mat(5), Material::Null));
    // pbrt's conductors and diffuse surfaces reflect on both sides; dielectrics by nature.
    let outer = |i: usize| &s.material(s.shapes[i].material.unwrap()).material;
    assert!(matches!(outer(0), Material::TwoSided { .. }));
    assert!(matches!(outer(2), Material::Dielectric { .. }));
    assert!(s.warnings.is_empty(), "{:?}", warnings(&s));
}

#[test]
fn lights_media_and_area_lights() {
    let s = scene(&format!(
        "{CAMERA}MakeNamedMedium \"fog\" \"string type\" \"homogeneous\" \"rgb sigma_a\" [1 1 1] \"rgb sigma_s\" [3 3 3] \"float scale\" 2 \"float g\" 0.5\n\
         LightSource \"point\" \"point3 from\" [1 2 3] \"rgb I\" [4 5 6] \"float scale\" 2\n\
         LightSource \"distant\" \"point3 from\" [0 1 0] \"point3 to\" [0 0 0] \"blackbody L\" 5500\n\
         LightSource \"infinite\" \"rgb L\" [0.1 0.2 0.3]\n\
         AttributeBegin\nMediumInterface \"fog\" \"\"\nAreaLightSource \"diffuse\" \"rgb L\" [1 2 3] \"bool twosided\" true\nReverseOrientation\nShape \"disk\" \"float radius\" 2\nAttributeEnd\n"
    ));
    let Emitter::Point {
        position,
        intensity,
    } = &s.emitters[0].emitter
    else {
        panic!()
    };
    assert_eq!(*position, Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(intensity.rgb(), Vec3::new(8.0, 10.0, 12.0));
    let Emitter::Directional {
        direction,
        irradiance,
    } = &s.emitters[1].emitter
    else {
        panic!()
    };
    assert!(direction.abs_diff_eq(-Vec3::Y, 1e-6));
    // A blackbody light has unit luminance in pbrt-v4.
    let y = irradiance.rgb().dot(Vec3::new(0.2126, 0.7152, 0.0722));
    assert!((y - 1.0).abs() < 0.02, "{y}");
    assert!(
        matches!(&s.emitters[2].emitter, Emitter::Constant { radiance } if radiance.rgb() == Vec3::new(0.1, 0.2, 0.3))
    );
    let d = &s.shapes[0];
    assert!(matches!(d.shape, Shape::Disk));
    assert!(d.flip_normals);
    assert_eq!(d.to_world.x_axis.x, 2.0);
    let e = d.emission.as_ref().unwrap();
    assert!(e.two_sided);
    assert_eq!(e.radiance, ColorParam::Const(Vec3::new(1.0, 2.0, 3.0)));
    // pbrt: MediumInterface "inside" "outside".
    assert_eq!(d.media.interior, Some(MediumId(0)));
    assert_eq!(d.media.exterior, None);
    let Medium::Homogeneous {
        sigma_t,
        albedo,
        scale,
    } = &s.media[0].medium
    else {
        panic!()
    };
    assert_eq!(
        (*sigma_t, *albedo, *scale),
        (Vec3::splat(4.0), Vec3::splat(0.75), 2.0)
    );
    assert_eq!(s.media[0].phase, PhaseDesc::HenyeyGreenstein { g: 0.5 });
}

#[test]
fn unused_parameters_are_reported_once() {
    let s = scene(&format!(
        "{CAMERA}Shape \"sphere\" \"float frobnicate\" 1\nShape \"sphere\" \"float frobnicate\" 2\n"
    ));
    let w = warnings(&s);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(w[0].contains("frobnicate"), "{w:?}");
    assert_eq!(s.warnings[0].loc.line, 5);
}

#[test]
fn pbrt_v3_materials_are_translated_with_a_notice() {
    let s = scene(&format!(
        "{CAMERA}Material \"matte\" \"color Kd\" [0.1 0.2 0.3]\nShape \"sphere\"\nMaterial \"glass\" \"float index\" 1.7\nShape \"sphere\"\n"
    ));
    let mat = |i: usize| base(&s, s.shapes[i].material.unwrap());
    assert!(
        matches!(mat(0), Material::Diffuse { reflectance: ColorParam::Const(c) } if *c == Vec3::new(0.1, 0.2, 0.3))
    );
    assert!(matches!(mat(1), Material::Dielectric { int_ior, .. } if *int_ior == 1.7));
    let w = warnings(&s);
    assert_eq!(w.len(), 3, "{w:?}");
}

#[test]
fn include_and_import_resolve_relative_to_the_including_file() {
    let main = write_scene(&[
        (
            "main.pbrt",
            b"WorldBegin\nInclude \"sub/a.pbrt\"\nImport \"sub/b.pbrt\"\nShape \"sphere\"\n",
        ),
        ("sub/a.pbrt", b"Shape \"sphere\" \"float radius\" 2\n"),
        (
            "sub/b.pbrt",
            b"Translate 1 0 0\nMakeNamedMaterial \"m\" \"string type\" \"diffuse\"\n",
        ),
    ]);
    let Document::Scene(s) = load(&main, &LoadOptions::default()).unwrap() else {
        panic!()
    };
    assert_eq!(s.shapes.len(), 2);
    // Import does not leak its graphics state.
    assert_eq!(s.shapes[1].to_world, SPHERE_UV);
}

/// `file:line:col` of an error, checked against the expected line and column.
fn at(e: &LoadError, line: u32, col: u32, words: &str) {
    assert_eq!((e.loc.line, e.loc.col), (line, col), "{e}");
    assert!(e.message.contains(words), "{e}");
    let shown = e.to_string();
    assert!(shown.contains(&format!(".pbrt:{line}:{col}: ")), "{shown}");
}

#[test]
fn malformed_input_is_reported_at_its_position() {
    at(
        &error("WorldBegin\nShape \"sphere\n"),
        2,
        7,
        "unterminated string",
    );
    at(
        &error("WorldBegin\n  Shpe \"sphere\"\n"),
        2,
        3,
        "unknown directive 'Shpe'",
    );
    at(
        &error("WorldBegin\nShape \"sphere\" \"rgb radius\" [1 2 3]\n"),
        2,
        16,
        "wrong type",
    );
    at(
        &error("WorldBegin\nShape \"sphere\" \"float radius\" [1.5.3]\n"),
        2,
        32,
        "expected a number",
    );
    at(
        &error("WorldBegin\nTranslate 1 nan 2\n"),
        2,
        13,
        "expected a number",
    );
    at(
        &error("WorldBegin\nAttributeEnd\n"),
        2,
        1,
        "without a matching begin",
    );
    at(
        &error("WorldBegin\nAttributeBegin\nShape \"sphere\"\n"),
        2,
        1,
        "never closed",
    );
    at(
        &error("WorldBegin\nTransformBegin\nAttributeEnd\n"),
        3,
        1,
        "does not match",
    );
    at(
        &error("WorldBegin\nInclude \"nowhere.pbrt\"\n"),
        2,
        9,
        "not found",
    );
    at(
        &error("WorldBegin\nShapé \"sphere\"\n"),
        2,
        1,
        "unknown directive 'Shapé'",
    );
    at(
        &error("WorldBegin\nShape \"sphere\" \"float radius\" [1\n"),
        2,
        31,
        "never closed",
    );
    at(
        &error("WorldBegin\nShape \"sphere\" \"flot radius\" 1\n"),
        2,
        16,
        "unknown parameter type",
    );
    at(
        &error("WorldBegin\nNamedMaterial \"m\"\n"),
        2,
        15,
        "unknown named material",
    );
    at(
        &error("WorldBegin\nMaterial \"hair\"\n"),
        2,
        1,
        "not supported",
    );
    at(
        &error(
            "WorldBegin\nShape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 3]\n",
        ),
        2,
        53,
        "outside",
    );
    at(&error("Shape \"sphere\"\n"), 1, 1, "only after WorldBegin");
    // Invalid UTF-8: the position of the first bad byte.
    let path = write_scene(&[("bad.pbrt", b"WorldBegin\n# \xff\n")]);
    let e = load(&path, &LoadOptions::default()).unwrap_err();
    assert_eq!((e.loc.line, e.loc.col), (2, 3), "{e}");
}

#[test]
fn import_cycles_and_nesting_depth_are_errors() {
    let main = write_scene(&[
        ("a.pbrt", b"WorldBegin\nImport \"b.pbrt\"\n"),
        ("b.pbrt", b"\n  Import \"a.pbrt\"\n"),
    ]);
    let e = load(&main, &LoadOptions::default()).unwrap_err();
    assert!(e.message.contains("cycle"), "{e}");
    assert!(e.loc.file.ends_with("b.pbrt"), "{e}");
    assert_eq!((e.loc.line, e.loc.col), (2, 10), "{e}");
    let deep = "AttributeBegin\n".repeat(5000);
    let e = error(&format!("WorldBegin\n{deep}"));
    assert!(e.message.contains("nested"), "{e}");
}

/// A 1M-triangle inline mesh parses correctly (and in linear time: the figure is printed).
#[test]
fn a_million_triangle_inline_mesh_parses() {
    use std::fmt::Write;
    let n = 708u32; // (n − 1)² · 2 ≈ 1.0M triangles
    let mut text = String::with_capacity(40 << 20);
    text.push_str("WorldBegin\nShape \"trianglemesh\"\n\"point3 P\" [");
    for j in 0..n {
        for i in 0..n {
            write!(text, " {} {} {}", i, j, (i * j) % 7).unwrap();
        }
    }
    text.push_str(" ]\n\"integer indices\" [");
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i;
            write!(
                text,
                " {} {} {} {} {} {}",
                a,
                a + 1,
                a + n + 1,
                a,
                a + n + 1,
                a + n
            )
            .unwrap();
        }
    }
    text.push_str(" ]\n");
    let path = write_scene(&[("big.pbrt", text.as_bytes())]);
    let t = std::time::Instant::now();
    let Document::Scene(s) = load(&path, &LoadOptions::default()).unwrap() else {
        panic!()
    };
    let secs = t.elapsed().as_secs_f64();
    let Shape::Mesh(m) = &s.shapes[0].shape else {
        panic!()
    };
    println!(
        "{} triangles, {:.1} MB of text parsed in {secs:.3} s",
        m.indices.len(),
        text.len() as f64 / 1e6
    );
    assert_eq!(m.indices.len(), 2 * (n as usize - 1).pow(2));
    assert_eq!(m.positions.len(), (n * n) as usize);
    assert_eq!(m.positions[n as usize + 3], Vec3::new(3.0, 1.0, 3.0));
    let last = m.indices.len() - 1;
    let a = (n - 2) * n + n - 2;
    assert_eq!(m.indices[last], [a, a + n + 1, a + n]);
}

#[test]
fn shapes_made_into_triangles_and_ply_meshes() {
    let mut m = TriMesh::default();
    for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
        m.positions.push(Vec3::new(x, y, 0.0));
    }
    m.indices = vec![[0, 1, 2], [0, 2, 3]];
    let dir = write_scene(&[("x.txt", b"")])
        .parent()
        .unwrap()
        .to_path_buf();
    scene::formats::ply::write_ply(&dir.join("quad.ply"), &m).unwrap();
    let raw = std::fs::read(dir.join("quad.ply")).unwrap();
    let mut gz = flate2_gzip(&raw);
    std::fs::write(dir.join("quad.ply.gz"), &mut gz).unwrap();
    let text = format!(
        "{CAMERA}Shape \"plymesh\" \"string filename\" \"quad.ply\"\n\
         Shape \"plymesh\" \"string filename\" \"quad.ply.gz\"\n\
         Shape \"plymesh\" \"string filename\" \"quad.ply\"\n\
         Shape \"cylinder\" \"float phimax\" 180\n\
         Shape \"disk\" \"float innerradius\" 0.5\n\
         Shape \"bilinearmesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 0]\n\
         Shape \"bilinearmesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 1]\n\
         Shape \"loopsubdiv\" \"integer levels\" 2 \"point3 P\" [1 1 1 -1 -1 1 -1 1 -1 1 -1 -1] \"integer indices\" [0 1 2 0 3 1 0 2 3 1 3 2]\n"
    );
    std::fs::write(dir.join("s.pbrt"), text).unwrap();
    let Document::Scene(s) = load(&dir.join("s.pbrt"), &LoadOptions::default()).unwrap() else {
        panic!()
    };
    let tris = |i: usize| match &s.shapes[i].shape {
        Shape::Mesh(m) => m.indices.len(),
        other => panic!("{other:?}"),
    };
    assert_eq!((tris(0), tris(1)), (2, 2));
    // The same file is read once and shared.
    let (Shape::Mesh(a), Shape::Mesh(b)) = (&s.shapes[0].shape, &s.shapes[2].shape) else {
        panic!()
    };
    assert!(std::sync::Arc::ptr_eq(a, b));
    assert_eq!(tris(3), 2 * 128);
    assert_eq!(tris(4), 2 * 256);
    assert_eq!(tris(5), 2, "a planar patch is two triangles");
    assert_eq!(tris(6), 2 * 64, "a curved one is a grid");
    assert_eq!(tris(7), 4 * 16);
    assert!(s.warnings.is_empty(), "{:?}", warnings(&s));
}

fn flate2_gzip(data: &[u8]) -> Vec<u8> {
    // A stored (uncompressed) gzip member: header, deflate blocks of ≤ 65535 bytes, CRC, size.
    let mut out = vec![0x1f, 0x8b, 8, 0, 0, 0, 0, 0, 0, 255];
    let chunks: Vec<&[u8]> = data.chunks(65535).collect();
    for (i, c) in chunks.iter().enumerate() {
        out.push(u8::from(i + 1 == chunks.len()));
        let n = c.len() as u16;
        out.extend(n.to_le_bytes());
        out.extend((!n).to_le_bytes());
        out.extend_from_slice(c);
    }
    let mut crc = 0xffff_ffffu32;
    for &b in data {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = if crc & 1 != 0 {
                (crc >> 1) ^ 0xedb8_8320
            } else {
                crc >> 1
            };
        }
    }
    out.extend((!crc).to_le_bytes());
    out.extend((data.len() as u32).to_le_bytes());
    out
}

#[test]
fn textures_spectra_and_environment_maps() {
    let dir = write_scene(&[("x.txt", b"")])
        .parent()
        .unwrap()
        .to_path_buf();
    std::fs::write(
        dir.join("img.pfm"),
        b"PF\n1 1\n-1\n\0\0\x80?\0\0\x80?\0\0\x80?",
    )
    .unwrap();
    std::fs::write(
        dir.join("refl.spd"),
        "# a flat spectrum\n400 0.5\n700 0.5\n",
    )
    .unwrap();
    let text = format!(
        "{CAMERA}Texture \"t\" \"spectrum\" \"imagemap\" \"string filename\" \"img.pfm\" \"float uscale\" 2 \"string encoding\" \"linear\"\n\
         Texture \"c\" \"spectrum\" \"checkerboard\" \"rgb tex1\" [1 0 0] \"rgb tex2\" [0 0 1]\n\
         Texture \"s\" \"spectrum\" \"scale\" \"texture tex\" \"t\" \"float scale\" 0.5\n\
         Material \"diffuse\" \"texture reflectance\" \"s\"\nShape \"sphere\"\n\
         Material \"diffuse\" \"spectrum reflectance\" \"refl.spd\"\nShape \"sphere\"\n\
         Material \"diffuse\" \"texture reflectance\" \"c\"\nShape \"sphere\"\n\
         Rotate 90 1 0 0\nLightSource \"infinite\" \"string filename\" \"img.pfm\" \"float scale\" 3\n"
    );
    std::fs::write(dir.join("s.pbrt"), text).unwrap();
    let Document::Scene(s) = load(&dir.join("s.pbrt"), &LoadOptions::default()).unwrap() else {
        panic!()
    };
    assert!(s.warnings.is_empty(), "{:?}", warnings(&s));
    let refl = |i: usize| match base(&s, s.shapes[i].material.unwrap()) {
        Material::Diffuse { reflectance } => reflectance.clone(),
        m => panic!("{m:?}"),
    };
    let ColorParam::Texture(t) = refl(0) else {
        panic!()
    };
    match &s.texture(t).texture {
        Texture::Affine {
            texture,
            scale,
            offset,
        } => {
            assert_eq!((*scale, *offset), (0.5, Vec3::ZERO));
            let Texture::Bitmap { raw, to_uv, .. } = texture.as_ref() else {
                panic!()
            };
            assert!(*raw);
            // pbrt looks up (u·2, 1 − v).
            let uv = *to_uv * Vec3::new(0.25, 0.25, 1.0);
            assert!((uv - Vec3::new(0.5, 0.75, 1.0)).length() < 1e-6, "{uv}");
        }
        t => panic!("{t:?}"),
    }
    let ColorParam::Spectrum(d) = refl(1) else {
        panic!()
    };
    assert!(
        (d.rgb - Vec3::splat(0.5)).abs().max_element() < 0.02,
        "{}",
        d.rgb
    );
    let ColorParam::Texture(t) = refl(2) else {
        panic!()
    };
    let Texture::Checkerboard { color0, to_uv, .. } = &s.texture(t).texture else {
        panic!()
    };
    assert_eq!(*color0, Vec3::X);
    assert_eq!(to_uv.x_axis.x, 0.5);
    let Emitter::EnvMap {
        scale,
        to_world,
        mapping,
        ..
    } = &s.emitters[0].emitter
    else {
        panic!()
    };
    assert_eq!((*scale, *mapping), (3.0, EnvMapping::EqualArea));
    assert!(to_world.abs_diff_eq(Mat4::from_rotation_x(90f32.to_radians()), 1e-6));
}

#[test]
fn pbrt_v3_mix_and_names_are_upgraded() {
    let s = scene(&format!(
        "{CAMERA}MakeNamedMaterial \"a\" \"string type\" \"matte\"\n\
         MakeNamedMaterial \"b\" \"string type\" \"mirror\"\n\
         Material \"mix\" \"string namedmaterial1\" \"a\" \"string namedmaterial2\" \"b\" \"float amount\" 0.25\n\
         AreaLightSource \"area\" \"color L\" [1 1 1]\nShape \"sphere\"\n"
    ));
    let Material::Mix { materials, amount } = &s.material(s.shapes[0].material.unwrap()).material
    else {
        panic!()
    };
    // pbrt-v3 weighs namedmaterial1 by amount; pbrt-v4 picks materials[1] with probability
    // amount: the order is swapped.
    assert_eq!(s.material(materials[0]).name.as_deref(), Some("b"));
    assert_eq!(s.material(materials[1]).name.as_deref(), Some("a"));
    assert_eq!(*amount, FloatParam::Const(0.25));
    assert!(s.shapes[0].emission.is_some());
    assert!(
        warnings(&s).iter().all(|w| w.contains("pbrt-v3")),
        "{:?}",
        warnings(&s)
    );
}

#[test]
fn screen_windows_lenses_and_crop() {
    let s = scene(
        "Film \"rgb\" \"integer xresolution\" 200 \"integer yresolution\" 100 \"float cropwindow\" [0.25 0.75 0 0.5]\n\
         Camera \"perspective\" \"float fov\" 90 \"float screenwindow\" [0 1 -0.5 0.5]\nWorldBegin\n",
    );
    let c = &s.sensors[0];
    let Projection::Window {
        left,
        right,
        bottom,
        top,
    } = c.camera.projection
    else {
        panic!()
    };
    assert!((left - 0.0).abs() < 1e-6 && (right - 1.0).abs() < 1e-6);
    assert!((bottom + 0.5).abs() < 1e-6 && (top - 0.5).abs() < 1e-6);
    assert_eq!(
        c.film.crop,
        Some(CropWindow {
            offset_x: 50,
            offset_y: 0,
            width: 100,
            height: 50
        })
    );
    let s = scene(
        "Camera \"perspective\" \"float lensradius\" 0.1 \"float focaldistance\" 4\nWorldBegin\n",
    );
    assert!(matches!(
        s.sensors[0].camera.projection,
        Projection::ThinLens { aperture_radius, focus_distance, fov_axis: FovAxis::Smaller, .. }
            if aperture_radius == 0.1 && focus_distance == 4.0
    ));
}

/// pbrt-v4's procedural and combining textures (a 2D checkerboard of textures too), MIP
/// filters, its spot falloff and the
/// coated materials' per-lookup roughness remapping reach the model as such.
#[test]
fn procedural_textures_filters_spots_and_coated_roughness() {
    let dir = write_scene(&[("x.txt", b"")])
        .parent()
        .unwrap()
        .to_path_buf();
    std::fs::write(
        dir.join("img.pfm"),
        b"PF\n1 1\n-1\n\0\0\x80?\0\0\x80?\0\0\x80?",
    )
    .unwrap();
    let text = format!(
        "{CAMERA}Texture \"i\" \"spectrum\" \"imagemap\" \"string filename\" \"img.pfm\" \"string filter\" \"trilinear\"\n\
         Texture \"e\" \"spectrum\" \"imagemap\" \"string filename\" \"img.pfm\" \"string filter\" \"ewa\"\n\
         Translate 1 2 3\n\
         Texture \"f\" \"float\" \"fbm\" \"integer octaves\" 4 \"float roughness\" 0.3\n\
         Texture \"p\" \"spectrum\" \"scale\" \"texture tex\" \"i\" \"texture scale\" \"f\"\n\
         Texture \"m\" \"spectrum\" \"mix\" \"texture tex1\" \"i\" \"texture tex2\" \"e\" \"texture amount\" \"f\"\n\
         Texture \"c3\" \"spectrum\" \"checkerboard\" \"integer dimension\" 3 \"texture tex1\" \"i\" \"rgb tex2\" [0 1 0]\n\
         Texture \"b\" \"spectrum\" \"bilerp\" \"rgb v00\" [1 0 0] \"rgb v11\" [0 0 1]\n\
         Texture \"c2\" \"spectrum\" \"checkerboard\" \"texture tex1\" \"i\" \"rgb tex2\" [0 0 1]\n\
         Texture \"d\" \"spectrum\" \"dots\" \"rgb inside\" [1 0 0] \"float uscale\" 4\n\
         Texture \"w\" \"float\" \"wrinkled\"\nTexture \"marble\" \"spectrum\" \"marble\" \"float scale\" 2\n\
         Material \"diffuse\" \"texture reflectance\" \"m\"\nShape \"sphere\"\n\
         Material \"diffuse\" \"texture reflectance\" \"c3\"\nShape \"sphere\"\n\
         Material \"diffuse\" \"texture reflectance\" \"b\"\nShape \"sphere\"\n\
         Material \"coateddiffuse\" \"texture roughness\" \"w\"\nShape \"sphere\"\n\
         Material \"coateddiffuse\" \"float roughness\" 0.04 \"bool remaproughness\" false \"texture reflectance\" \"marble\"\nShape \"sphere\"\n\
         Material \"diffuse\" \"texture reflectance\" \"p\"\nShape \"sphere\"\n\
         Material \"diffuse\" \"texture reflectance\" \"c2\"\nShape \"sphere\"\n\
         Material \"diffuse\" \"texture reflectance\" \"d\"\nShape \"sphere\"\n\
         LightSource \"spot\" \"float coneangle\" 30 \"float conedelta\" 10\n"
    );
    std::fs::write(dir.join("s.pbrt"), text).unwrap();
    let Document::Scene(s) = load(&dir.join("s.pbrt"), &LoadOptions::default()).unwrap() else {
        panic!()
    };
    assert!(s.warnings.is_empty(), "{:?}", warnings(&s));
    let refl = |i: usize| match base(&s, s.shapes[i].material.unwrap()) {
        Material::Diffuse {
            reflectance: ColorParam::Texture(t),
        } => s.texture(*t).texture.clone(),
        m => panic!("{m:?}"),
    };
    let Texture::Mix { a, b, amount } = refl(0) else {
        panic!("mix")
    };
    assert!(matches!(
        *a,
        Texture::Bitmap {
            filter: TextureFilter::Trilinear,
            mipmapped: true,
            ..
        }
    ));
    assert!(matches!(
        *b,
        Texture::Bitmap {
            filter: TextureFilter::Ewa,
            ..
        }
    ));
    let Texture::Noise {
        kind: NoiseKind::Fbm { octaves: 4, omega },
        to_texture,
    } = *amount
    else {
        panic!("fbm")
    };
    assert_eq!(omega, 0.3);
    // The texture space is the CTM's at the definition: world (1, 2, 3) is its origin.
    assert!(
        to_texture
            .transform_point3(Vec3::new(1.0, 2.0, 3.0))
            .length()
            < 1e-6
    );
    let Texture::Checker3D { a, b, .. } = refl(1) else {
        panic!("checker3d")
    };
    assert!(matches!(*a, Texture::Bitmap { .. }));
    assert!(matches!(*b, Texture::Constant(c) if c == Vec3::Y));
    let Texture::Bilerp { v00, v01, v11, .. } = refl(2) else {
        panic!("bilerp")
    };
    assert_eq!((v00, v01, v11), (Vec3::X, Vec3::ONE, Vec3::Z));
    match &s.material(s.shapes[3].material.unwrap()).material {
        Material::CoatedDiffuse {
            alpha_u: FloatParam::Texture(t),
            remap_roughness: true,
            ..
        } => assert!(matches!(
            s.texture(*t).texture,
            Texture::Noise {
                kind: NoiseKind::Wrinkled { .. },
                ..
            }
        )),
        m => panic!("{m:?}"),
    }
    match &s.material(s.shapes[4].material.unwrap()).material {
        Material::CoatedDiffuse {
            alpha_u: FloatParam::Const(a),
            remap_roughness: false,
            reflectance: ColorParam::Texture(t),
            ..
        } => {
            assert_eq!(*a, 0.04);
            assert!(matches!(
                s.texture(*t).texture,
                Texture::Noise {
                    kind: NoiseKind::Marble { scale: 2.0, .. },
                    ..
                }
            ));
        }
        m => panic!("{m:?}"),
    }
    assert!(matches!(refl(5), Texture::Product { .. }));
    let Texture::Mix { a, b, amount } = refl(6) else {
        panic!("a textured 2D checkerboard")
    };
    assert!(matches!(*a, Texture::Bitmap { .. }));
    assert!(matches!(*b, Texture::Constant(c) if c == Vec3::Z));
    assert!(
        matches!(*amount, Texture::Checkerboard { color0, color1, .. }
        if color0 == Vec3::ZERO && color1 == Vec3::ONE)
    );
    let Texture::Dots {
        inside,
        outside,
        to_uv,
    } = refl(7)
    else {
        panic!("dots")
    };
    assert!(matches!(*inside, Texture::Constant(c) if c == Vec3::X));
    assert!(matches!(*outside, Texture::Constant(c) if c == Vec3::ZERO));
    assert_eq!(to_uv.x_axis.x, 4.0);
    let Emitter::Spot {
        falloff,
        cutoff_angle,
        beam_width,
        ..
    } = &s.emitters[0].emitter
    else {
        panic!()
    };
    assert_eq!(
        (*falloff, *cutoff_angle, *beam_width),
        (SpotFalloff::SmoothStep, 30.0, 20.0)
    );
}

/// The inline grid of a volume description: (res, channels, data, to_world).
fn inline(v: &VolumeDesc) -> ([usize; 3], usize, Vec<f32>, Mat4) {
    match &v.format {
        VolumeFormat::Inline {
            res,
            channels,
            data,
        } => (*res, *channels, data.to_vec(), v.to_world),
        f => panic!("an inline grid expected, found {f:?}"),
    }
}

#[test]
fn grid_media_become_inline_grids_over_their_box() {
    let s = scene(&format!(
        "{CAMERA}Translate 1 0 0\n\
         MakeNamedMedium \"smoke\" \"string type\" \"uniformgrid\" \"integer nx\" 2 \"integer ny\" 1 \"integer nz\" 3\n\
         \"float density\" [0 1 2 3 4 5] \"point3 p0\" [0 -1 0] \"point3 p1\" [2 1 6]\n\
         \"rgb sigma_a\" [1 2 3] \"rgb sigma_s\" [3 2 1] \"float scale\" 0.5 \"float g\" -0.3 \"rgb Le\" [1 0.5 0.25]\n\
         MakeNamedMedium \"lit\" \"string type\" \"uniformgrid\" \"float density\" [2] \"rgb Le\" [1 1 1] \"float Lescale\" [3]\n\
         MakeNamedMedium \"rgb\" \"string type\" \"rgbgrid\" \"integer nx\" 2 \"point3 p1\" [1 1 2]\n\
         \"rgb sigma_a\" [1 1 1 0 1 2] \"rgb sigma_s\" [1 1 1 2 1 0] \"rgb Le\" [0 0 0 1 2 3] \"float Lescale\" 2 \"float scale\" 4\n"
    ));
    // uniformgrid: σt = (σa + σs)·scale·density, a constant albedo, the box p0–p1 placed by
    // the CTM.
    let Medium::Heterogeneous {
        sigma_t,
        albedo,
        scale,
    } = &s.media[0].medium
    else {
        panic!("{:?}", s.media[0].medium)
    };
    let (res, ch, data, to_world) = inline(sigma_t);
    assert_eq!(
        (res, ch, data),
        ([2, 1, 3], 1, vec![0.0, 1.0, 2.0, 3.0, 4.0, 5.0])
    );
    assert!(
        to_world
            .transform_point3(Vec3::ZERO)
            .abs_diff_eq(Vec3::new(1.0, -1.0, 0.0), 1e-6)
    );
    assert!(
        to_world
            .transform_point3(Vec3::ONE)
            .abs_diff_eq(Vec3::new(3.0, 1.0, 6.0), 1e-6)
    );
    assert_eq!(*scale, 2.0);
    assert!(
        matches!(albedo, VolumeParam::Const(a) if a.abs_diff_eq(Vec3::new(0.75, 0.5, 0.25), 1e-6))
    );
    assert_eq!(s.media[0].phase, PhaseDesc::HenyeyGreenstein { g: -0.3 });
    // Le without "Lescale": pbrt-v4's one-voxel scale grid, a tent over the box.
    let Some(MediumEmission::Radiance(VolumeParam::Grid(le))) = &s.media[0].emission else {
        panic!()
    };
    let (res, ch, data, _) = inline(le);
    assert_eq!((res, ch, data), ([1, 1, 1], 3, vec![1.0, 0.5, 0.25]));
    // With one: Le times each voxel's scale, on the density's lattice.
    let Some(MediumEmission::Radiance(VolumeParam::Grid(le))) = &s.media[1].emission else {
        panic!()
    };
    assert_eq!(inline(le).2, vec![3.0, 3.0, 3.0]);
    assert_eq!(s.media[1].phase, PhaseDesc::Isotropic);
    // rgbgrid: σt from σa + σs per voxel, the albedo σs/σt interpolated apart, Le per voxel.
    let Medium::Heterogeneous {
        sigma_t,
        albedo,
        scale,
    } = &s.media[2].medium
    else {
        panic!()
    };
    assert_eq!(inline(sigma_t).2, vec![2.0, 2.0]);
    assert_eq!(*scale, 4.0);
    let VolumeParam::SigmaSGrid(ss) = albedo else {
        panic!("{albedo:?}")
    };
    assert_eq!(inline(ss).2, vec![1.0, 1.0, 1.0, 2.0, 1.0, 0.0]);
    let Some(MediumEmission::Radiance(VolumeParam::Grid(le))) = &s.media[2].emission else {
        panic!()
    };
    assert_eq!(inline(le).2, vec![0.0, 0.0, 0.0, 2.0, 4.0, 6.0]);
    assert!(
        inline(le)
            .3
            .transform_point3(Vec3::ONE)
            .abs_diff_eq(Vec3::new(2.0, 1.0, 2.0), 1e-6)
    );

    // What our grid media cannot express is refused, saying why.
    for (params, want) in [
        ("\"float density\" [1 2]", "expected 1"),
        ("\"integer nx\" 2 \"float density\" [1 -2]", "≥ 0"),
        ("\"float density\" [1] \"rgb sigma_a\" [1 0 0]", "not grey"),
        (
            "\"float density\" [1] \"float temperature\" [1000]",
            "temperature",
        ),
        ("", "no \"density\""),
        (
            "\"float density\" [1] \"point3 p0\" [0 0 1] \"point3 p1\" [1 1 1]",
            "empty",
        ),
    ] {
        let e = error(&format!(
            "{CAMERA}MakeNamedMedium \"m\" \"string type\" \"uniformgrid\" {params}\n"
        ))
        .to_string();
        assert!(e.contains(want), "{params}: {e}");
    }
    for (params, want) in [
        ("\"rgb sigma_a\" [1 1 1]", "both"),
        (
            "\"rgb sigma_a\" [1 1 1] \"rgb sigma_s\" [1 2 1]",
            "not grey",
        ),
    ] {
        let e = error(&format!(
            "{CAMERA}MakeNamedMedium \"m\" \"string type\" \"rgbgrid\" {params}\n"
        ))
        .to_string();
        assert!(e.contains(want), "{params}: {e}");
    }
    let e = error(&format!(
        "{CAMERA}MakeNamedMedium \"m\" \"string type\" \"nanovdb\" \"string filename\" \"a.nvdb\"\n"
    ));
    assert!(e.to_string().contains("not supported"), "{e}");
}

#[test]
fn partial_spheres_are_tessellated_and_full_ones_take_pbrts_uv() {
    let s = scene(&format!(
        "{CAMERA}Shape \"sphere\" \"float radius\" 2 \"float zmin\" -1 \"float zmax\" 3 \"float phimax\" 90\n\
         Shape \"sphere\" \"float radius\" 2\n\
         AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\nShape \"sphere\"\nAttributeEnd\n"
    ));
    let Shape::Mesh(m) = &s.shapes[0].shape else {
        panic!("{:?}", s.shapes[0].shape)
    };
    // zmax is clamped to the radius; the quarter from z = −1 to the top pole.
    let area: f32 = m
        .indices
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            0.5 * (b - a).cross(c - a).length()
        })
        .sum();
    let want = std::f32::consts::FRAC_PI_2 * 2.0 * 3.0;
    assert!((area / want - 1.0).abs() < 2e-4, "{area} vs {want}");
    assert!(
        m.positions
            .iter()
            .all(|p| p.z >= -1.0 - 1e-5 && p.x >= -1e-5 && p.y >= -1e-5)
    );
    // u = φ/φmax, v from θmin (at zmin) to θmax.
    for (p, uv) in m.positions.iter().zip(&m.uvs) {
        let theta = (p.z / 2.0).clamp(-1.0, 1.0).acos();
        let t0 = (-0.5f32).acos();
        assert!((uv.y - (theta - t0) / (0.0 - t0)).abs() < 1e-3, "{p}: {uv}");
    }
    assert!(matches!(s.shapes[1].shape, Shape::Sphere { radius, .. } if radius == 2.0));
    assert_eq!(s.shapes[1].to_world, SPHERE_UV);
    // A sphere light keeps our frame (sampled by the cone it subtends).
    assert_eq!(s.shapes[2].to_world, Mat4::IDENTITY);
}

#[test]
fn goniometric_and_projection_lights_carry_pbrts_frames() {
    let path = write_scene(&[
        (
            "scene.pbrt",
            format!(
                "{CAMERA}AttributeBegin\nTranslate 1 2 3\nLightSource \"goniometric\" \"string filename\" \"g.pfm\" \"rgb I\" [1 2 3] \"float scale\" 2\nAttributeEnd\n\
                 LightSource \"projection\" \"string filename\" \"g.pfm\" \"float fov\" 30 \"float power\" 5\n"
            )
            .as_bytes(),
        ),
        ("g.pfm", b"PF\n1 1\n-1\n\0\0\x80\x3f\0\0\x80\x3f\0\0\x80\x3f"),
    ]);
    let Document::Scene(s) = load(&path, &LoadOptions::default()).unwrap() else {
        panic!()
    };
    let Emitter::ImagePoint {
        to_world,
        intensity,
        profile,
        power,
        ..
    } = &s.emitters[0].emitter
    else {
        panic!("{:?}", s.emitters[0].emitter)
    };
    // The light's y and z swapped, then placed by the CTM.
    assert_eq!(to_world.transform_vector3(Vec3::Z), Vec3::Y);
    assert_eq!(to_world.transform_vector3(Vec3::Y), Vec3::Z);
    assert_eq!(to_world.w_axis.truncate(), Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(*intensity, Vec3::new(2.0, 4.0, 6.0));
    assert_eq!((*profile, *power), (ImageProfile::Goniometric, None));
    let Emitter::ImagePoint {
        to_world,
        intensity,
        profile,
        power,
        ..
    } = &s.emitters[1].emitter
    else {
        panic!()
    };
    // The y flip.
    assert_eq!(to_world.transform_vector3(Vec3::Y), -Vec3::Y);
    assert_eq!(*intensity, Vec3::ONE);
    assert_eq!(
        (*profile, *power),
        (ImageProfile::Projection { fov: 30.0 }, Some(5.0))
    );
    let e = error(&format!(
        "{CAMERA}LightSource \"projection\" \"string filename\" \"missing.pfm\"\n"
    ));
    assert!(e.to_string().contains("not found"), "{e}");
}
