//! CS-E5520 OBJ+MTL scenes: MTL parsing, material mapping, malformed input.

use std::path::{Path, PathBuf};

use scene::formats::objmtl::{self, parse_mtl};
use scene::{
    ColorParam, Document, IntegratorDesc, LoadOptions, Material, RussianRoulette, SamplerKind,
    SceneDesc, Shape,
};

fn tmpdir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("penumbra-objmtl-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn load(dir: &Path, obj: &str, mtl: &str) -> scene::Result<SceneDesc> {
    std::fs::write(dir.join("s.obj"), obj).unwrap();
    std::fs::write(dir.join("s.mtl"), mtl).unwrap();
    match scene::load(&dir.join("s.obj"), &LoadOptions::default())? {
        Document::Scene(s) => Ok(*s),
        Document::Test(_) => panic!("not a scene"),
    }
}

const QUAD: &str = "mtllib s.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
usemtl wall
f 1/1 2/2 3/3
usemtl lamp
f 1/1 3/3 4/4
";

#[test]
fn parses_keys_tabs_and_trailing_comments() {
    let mut w = Vec::new();
    let mtls = parse_mtl(
        "newmtl a\n\tKd 0.1 0.2 0.3 red wall\n\tKs 0.5\n\tNs 3200 grey wall\n\tKe 1 2 3\n\
         \tNi 1.33\n\td 0.5\n\tillum 7\n\tmap_Kd -bm 1 tex\\d.png\nnewmtl b\nTr 0.25 # comment\n",
        Path::new("/x/y.mtl"),
        &mut w,
    );
    assert!(w.is_empty(), "{w:?}");
    assert_eq!(mtls.len(), 2);
    let a = &mtls[0];
    assert_eq!(a.kd, scene::Vec3::new(0.1, 0.2, 0.3));
    assert_eq!(a.ks, scene::Vec3::splat(0.5));
    assert_eq!(a.ns, 3200.0);
    assert_eq!(a.ke, scene::Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(a.ni, Some(1.33));
    assert_eq!(a.d, 0.5);
    assert_eq!(a.illum, Some(7));
    assert_eq!(a.map_kd.as_deref(), Some(Path::new("/x/tex/d.png")));
    assert!(a.is_transparent());
    assert_eq!(mtls[1].d, 0.75);
}

#[test]
fn malformed_mtl_values_warn() {
    let mut w = Vec::new();
    let mtls = parse_mtl(
        "Kd 1 1 1\nnewmtl a\nKd nan 0 0\nNs inf\nKs 1 2\nfoo 3\nillum 2.5\n",
        Path::new("m.mtl"),
        &mut w,
    );
    assert_eq!(mtls.len(), 1);
    assert_eq!(w.len(), 6, "{w:?}");
    assert_eq!(mtls[0].kd, scene::Vec3::splat(0.8));
    assert_eq!(mtls[0].ns, 0.0);
}

#[test]
fn maps_materials_and_splits_emitters() {
    let dir = tmpdir("map");
    let s = load(
        &dir,
        QUAD,
        "newmtl wall\nKd 0.5 0.5 0.5\nKs 0.2 0.2 0.2\nNs 98\nnewmtl lamp\nKd 0 0 0\nKe 4 4 4\n",
    )
    .unwrap();
    assert_eq!(s.shapes.len(), 2, "one mesh per material, no default light");
    let wall = &s.shapes[0];
    assert!(wall.emission.is_none());
    match &s.material(wall.material.unwrap()).material {
        Material::RoughPlastic { alpha, .. } => {
            assert!((alpha - (2.0f32 / 100.0).sqrt()).abs() < 1e-6)
        }
        m => panic!("expected rough plastic, got {}", m.kind_name()),
    }
    let lamp = &s.shapes[1];
    let e = lamp.emission.as_ref().expect("Ke makes an emitter");
    assert_eq!(e.radiance, ColorParam::Const(scene::Vec3::splat(4.0)));
    assert!(matches!(
        s.material(lamp.material.unwrap()).material,
        Material::Diffuse { .. }
    ));
    let Shape::Mesh(m) = &lamp.shape else {
        panic!()
    };
    assert_eq!(m.indices.len(), 1);
    assert_eq!(m.positions.len(), 3);
    assert_eq!(m.uvs.len(), 3);
    // Course conventions.
    assert_eq!(s.sensors[0].sampler.kind, SamplerKind::Sobol);
    let IntegratorDesc::Path(p) = &s.integrator else {
        panic!()
    };
    assert!(matches!(p.rr, RussianRoulette::Fixed { q, .. } if q == 0.2));
}

#[test]
fn no_emitter_gets_the_default_light() {
    let dir = tmpdir("nolight");
    let s = load(
        &dir,
        QUAD,
        "newmtl wall\nKd 0.5 0.5 0.5\nnewmtl lamp\nd 0.5\nillum 7\nNi 1.33\n",
    )
    .unwrap();
    assert!(matches!(
        s.material(s.shapes[1].material.unwrap()).material,
        Material::Dielectric { int_ior, .. } if int_ior == 1.33
    ));
    let light = s.shapes.last().unwrap();
    assert_eq!(light.name.as_deref(), Some(objmtl::DEFAULT_LIGHT_NAME));
    assert!(light.emission.is_some());
    assert!(s.warnings.iter().any(|w| w.message.contains("no emitter")));
}

#[test]
fn dissolve_and_alpha_maps_are_cut_outs() {
    let dir = tmpdir("alpha");
    std::fs::write(dir.join("leaf.png"), b"").unwrap(); // existence is all the loader checks
    let s = load(
        &dir,
        QUAD,
        "newmtl wall\nKd 0.5 0.5 0.5\nd 0.25\nnewmtl lamp\nKd 0.2 0.2 0.2\nmap_d leaf.png\nKe 1 1 1\n",
    )
    .unwrap();
    let outer = |i: usize| &s.material(s.shapes[i].material.unwrap()).material;
    let Material::Mask { nested, opacity } = outer(0) else {
        panic!("d < 1 makes a cut-out, got {}", outer(0).kind_name())
    };
    assert_eq!(*opacity, scene::FloatParam::Const(0.25));
    assert!(matches!(
        s.material(*nested).material,
        Material::Diffuse { .. }
    ));
    let Material::Mask { opacity, .. } = outer(1) else {
        panic!("map_d makes a cut-out, got {}", outer(1).kind_name())
    };
    let scene::FloatParam::Texture(t) = opacity else {
        panic!("map_d is a texture")
    };
    assert!(matches!(
        &s.textures[t.0 as usize].texture,
        scene::Texture::Bitmap { raw: true, .. }
    ));
}

/// `disp` is a height bump map (Mitsuba 3's `bumpmap`, `-bm` its scale) on a material
/// without a normal map; under a normal map it is not applied, and one note says so.
#[test]
fn height_maps_bump_unless_a_normal_map_shades() {
    let dir = tmpdir("disp");
    for f in ["h.png", "n.png"] {
        std::fs::write(dir.join(f), b"").unwrap(); // existence is all the loader checks
    }
    let s = load(
        &dir,
        QUAD,
        "newmtl wall\nKd 0.5 0.5 0.5\ndisp -bm 0.25 h.png\n\
         newmtl lamp\nKd 0.2 0.2 0.2\nmap_bump n.png\ndisp h.png\nKe 1 1 1\n",
    )
    .unwrap();
    let outer = |i: usize| &s.material(s.shapes[i].material.unwrap()).material;
    let Material::HeightBump {
        nested,
        texture,
        scale,
        flip_invalid_normals: true,
        shadowing: true,
    } = outer(0)
    else {
        panic!("disp makes a bump map, got {}", outer(0).kind_name())
    };
    assert_eq!(*scale, 0.25);
    assert!(matches!(
        s.material(*nested).material,
        Material::Diffuse { .. }
    ));
    assert!(matches!(
        &s.textures[texture.0 as usize].texture,
        scene::Texture::Bitmap { raw: true, path, .. } if path.ends_with("h.png")
    ));
    assert!(
        matches!(outer(1), Material::NormalMap { nested, .. }
            if matches!(s.material(*nested).material, Material::RoughPlastic { .. } | Material::Diffuse { .. })),
        "a normal map shades alone, got {}",
        outer(1).kind_name()
    );
    let notes: Vec<_> = s
        .warnings
        .iter()
        .filter(|w| w.message.contains("height map"))
        .collect();
    assert_eq!(notes.len(), 1, "{:?}", s.warnings);
    assert!(notes[0].message.contains("'lamp'"), "{}", notes[0].message);
    assert!(
        !s.warnings
            .iter()
            .any(|w| w.message.contains("not supported"))
    );
}

#[test]
fn missing_texture_warns_once_and_falls_back() {
    let dir = tmpdir("tex");
    let s = load(
        &dir,
        QUAD,
        "newmtl wall\nKd 0.3 0.3 0.3\nmap_Kd nothere.png\nnewmtl lamp\nmap_Kd nothere.png\nKe 1 1 1\n",
    )
    .unwrap();
    let n = s
        .warnings
        .iter()
        .filter(|w| w.message.contains("nothere.png"))
        .count();
    assert_eq!(n, 1, "{:?}", s.warnings);
    assert!(s.textures.is_empty());
    assert!(matches!(
        &s.material(s.shapes[0].material.unwrap()).material,
        Material::Diffuse { reflectance: ColorParam::Const(c) } if *c == scene::Vec3::splat(0.3)
    ));
}

#[test]
fn malformed_obj_is_an_error_not_a_panic() {
    let dir = tmpdir("bad");
    for obj in [
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 7\n",
        "v 0 nan 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n",
        "v 0 0 0\n",
        "",
    ] {
        assert!(load(&dir, obj, "").is_err(), "{obj:?}");
    }
    // Unknown material and missing library: warnings only.
    std::fs::write(
        dir.join("u.obj"),
        "mtllib none.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl x\nf 1 2 3\n",
    )
    .unwrap();
    let Document::Scene(s) = scene::load(&dir.join("u.obj"), &LoadOptions::default()).unwrap()
    else {
        panic!()
    };
    assert!(s.shapes[0].material.is_none());
    assert!(s.warnings.len() >= 3, "{:?}", s.warnings);
}

#[test]
fn aalto_scenes_load() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/scenes/aalto/cornell");
    if !dir.is_dir() {
        eprintln!("skipped: {} is absent", dir.display());
        return;
    }
    for f in ["cornell.obj", "cornell_chesterfield.obj"] {
        let Document::Scene(s) = scene::load(&dir.join(f), &LoadOptions::default()).unwrap() else {
            panic!()
        };
        assert!(s.shapes.iter().any(|s| s.emission.is_some()), "{f}");
    }
}
