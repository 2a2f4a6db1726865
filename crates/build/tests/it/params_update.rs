//! `build::params` and `build::build_cached` (Python's `scene.parameters()` and
//! `scene.update`): an edit through a parameter, built with the cache of the unedited scene,
//! renders the image of the scene file edited the same way and loaded afresh, bit for bit;
//! material and light edits keep the acceleration structure, a shape's move rebuilds it.

use build::params::{self, Value};
use build::{BuildCache, BuildOptions, Built, Changed, build, build_cached};
use render::render::{RenderOptions, Silent, render};
use scene::SceneDesc;

fn repo_file(rel: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel)
}

/// The scene of `text`, written beside the repo's scene it was read from (so that its
/// relative references still resolve).
fn load_text(text: &str, name: &str) -> SceneDesc {
    let dir = std::env::temp_dir().join(format!("penumbra-params-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("scene.xml");
    std::fs::write(&path, text).unwrap();
    let scene::Document::Scene(desc) = scene::load(&path, &Default::default()).unwrap() else {
        panic!("a scene")
    };
    let _ = std::fs::remove_dir_all(&dir);
    *desc
}

fn opts() -> BuildOptions {
    BuildOptions {
        spp: Some(4),
        seed: Some(7),
        ..Default::default()
    }
}

fn image(built: Built) -> Vec<[u32; 3]> {
    let out = render(
        &built.scene,
        &built.integrator,
        &RenderOptions {
            spp: built.spp,
            ..Default::default()
        },
        &Silent,
    );
    out.film
        .develop()
        .pixels
        .iter()
        .map(|p| [p.x.to_bits(), p.y.to_bits(), p.z.to_bits()])
        .collect()
}

const BOX: &str = "scenes/mitsuba/legacy_box.xml";

#[test]
fn parameters_name_materials_lights_shapes_and_sensors() {
    let desc = load_text(&std::fs::read_to_string(repo_file(BOX)).unwrap(), "names");
    let ps = params::parameters(&desc);
    let get = |k: &str| {
        ps.iter()
            .find(|p| p.key == k)
            .unwrap_or_else(|| panic!("{k} in {:?}", ps.iter().map(|p| &p.key).collect::<Vec<_>>()))
            .clone()
    };
    assert_eq!(get("shape_3.bsdf.alpha").value, Value::Float(0.2));
    assert_eq!(get("shape_3.bsdf.alpha").changes, Changed::Material);
    assert_eq!(
        get("shape_0.emitter.radiance").value,
        Value::Vec3([12.0, 11.0, 9.0])
    );
    assert_eq!(
        get("shape_2.bsdf.diffuse_reflectance").value,
        Value::Vec3([0.2, 0.4, 0.7])
    );
    assert_eq!(get("shape_1.to_world").changes, Changed::Geometry);
    assert_eq!(get("sensor_0.to_world").changes, Changed::Camera);
    // Declared spectra (the gold conductor's η and k) are not constants one can edit.
    assert!(ps.iter().all(|p| p.key != "shape_3.bsdf.eta"));
    let keys: std::collections::HashSet<_> = ps.iter().map(|p| &p.key).collect();
    assert_eq!(keys.len(), ps.len(), "keys are unique");
}

#[test]
fn set_refuses_unknown_keys_and_wrong_values() {
    let mut desc = load_text(&std::fs::read_to_string(repo_file(BOX)).unwrap(), "errors");
    let e = params::set(&mut desc, "shape_3.bsdf.roughness", Value::Float(0.1)).unwrap_err();
    assert!(matches!(e, params::ParamError::Unknown { .. }), "{e}");
    let e = params::set(&mut desc, "shape_3.bsdf.alpha", Value::Vec3([0.1; 3])).unwrap_err();
    assert!(matches!(e, params::ParamError::WrongType { .. }), "{e}");
    let e = params::set(&mut desc, "shape_3.bsdf.alpha", Value::Float(-1.0)).unwrap_err();
    assert!(matches!(e, params::ParamError::Invalid { .. }), "{e}");
    let e = params::set(
        &mut desc,
        "shape_0.emitter.radiance",
        Value::Float(f32::NAN),
    );
    assert!(
        matches!(e, Err(params::ParamError::Invalid { .. })),
        "{e:?}"
    );
    // A float for a colour is a grey.
    params::set(
        &mut desc,
        "shape_2.bsdf.diffuse_reflectance",
        Value::Float(0.5),
    )
    .unwrap();
}

/// Edits `desc` through `params::set`, rebuilds with `cache` (told what changed), and checks
/// the image against the fresh build of `reloaded`.
fn check_edit(
    desc: &mut SceneDesc,
    cache: &mut BuildCache,
    edits: &[(&str, Value)],
    reloaded: &SceneDesc,
) {
    for (k, v) in edits {
        let changed = params::set(desc, k, *v).unwrap();
        cache.invalidate(changed);
    }
    let cached = image(build_cached(desc, &opts(), cache).unwrap());
    let fresh = image(build(reloaded, &opts()).unwrap());
    assert!(
        cached == fresh,
        "edits {edits:?}: the image differs from a reload"
    );
}

#[test]
fn an_update_renders_the_reloaded_edited_file_bit_for_bit() {
    let text = std::fs::read_to_string(repo_file(BOX)).unwrap();
    let mut desc = load_text(&text, "orig");
    let mut cache = BuildCache::default();
    let before = image(build_cached(&desc, &opts(), &mut cache).unwrap());
    assert!(cache.has_geometry());

    // A material's roughness.
    let text = text.replace(
        r#"<float name="alpha" value="0.2"/>"#,
        r#"<float name="alpha" value="0.45"/>"#,
    );
    check_edit(
        &mut desc,
        &mut cache,
        &[("shape_3.bsdf.alpha", Value::Float(0.45))],
        &load_text(&text, "rough"),
    );
    assert!(cache.has_geometry(), "a material edit keeps the geometry");

    // A light's radiance.
    let text = text.replace(
        r#"<rgb name="radiance" value="12, 11, 9"/>"#,
        r#"<rgb name="radiance" value="6.5, 11, 3.25"/>"#,
    );
    check_edit(
        &mut desc,
        &mut cache,
        &[("shape_0.emitter.radiance", Value::Vec3([6.5, 11.0, 3.25]))],
        &load_text(&text, "light"),
    );
    assert!(cache.has_geometry(), "a light edit keeps the geometry");

    // A shape's move: the transform the edited file gives.
    let text = text.replace(
        r#"<translate x="0.45" y="0.25" z="0.2"/>"#,
        r#"<translate x="0.3" y="0.25" z="0.1"/>"#,
    );
    let moved = load_text(&text, "moved");
    let to_world = params::parameters(&moved)
        .into_iter()
        .find(|p| p.key == "shape_3.to_world")
        .unwrap()
        .value;
    assert_eq!(
        params::set(&mut desc, "shape_3.to_world", to_world),
        Ok(Changed::Geometry)
    );
    cache.invalidate(Changed::Geometry);
    assert!(!cache.has_geometry(), "a move drops the geometry");
    let cached = image(build_cached(&desc, &opts(), &mut cache).unwrap());
    assert!(cached == image(build(&moved, &opts()).unwrap()));
    assert!(cached != before);
}
