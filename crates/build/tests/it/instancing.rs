//! Instancing (issue 17): a scene whose mesh is placed several times (CENG795 `MeshInstance`
//! with `_resetTransform` true and false, rotations, non-uniform and mirroring scales) renders
//! the same through the two-level BVH as with every instance copied to world space
//! (`BuildOptions::flatten_instances`).
//!
//! - Exact: at 1 spp with the same seed both builds trace the same camera rays; depth and
//!   normals images agree within float tolerance (the instanced triangle test runs in object
//!   space, so barycentrics and t differ by rounding only).
//! - Statistical: path-traced images (K = 16 independent batches per side, different seeds)
//!   pass the block t-test of `render::compare` (8×8 blocks, Šidák-corrected family-wise
//!   α = 0.01, the shared references' test).

use std::path::PathBuf;

use build::{BuildOptions, Built, build};
use render::compare::{CompareOptions, Reference, TestImages, compare_with};
use render::film::Image;
use render::render::{RenderOptions, Silent, render};
use scene::{Document, IntegratorDesc, PathDesc};

/// An octahedron with smooth normals, placed four times: the base mesh (rotated), an instance
/// that keeps the base's transformation and adds a non-uniform scale, one that resets it
/// (rotation and non-uniform scale), and one that resets it with a mirroring scale. A floor
/// and an emitting quad (flattened: emitters are never instanced).
const SCENE: &str = r#"{
  "Scene": {
    "MaxRecursionDepth": "6",
    "BackgroundColor": "0 0 0",
    "Cameras": { "Camera": {
      "_id": "1", "Position": "0 3 9", "Gaze": "0 -0.3 -1", "Up": "0 1 0",
      "NearPlane": "-1 1 -1 1", "NearDistance": "1.6",
      "ImageResolution": "64 64", "NumSamples": "1", "ImageName": "inst.png" } },
    "Lights": { },
    "Materials": { "Material": [
      { "_id": "1", "AmbientReflectance": "0 0 0", "DiffuseReflectance": "0.7 0.5 0.3",
        "SpecularReflectance": "0 0 0" },
      { "_id": "2", "AmbientReflectance": "0 0 0", "DiffuseReflectance": "0.5 0.5 0.5",
        "SpecularReflectance": "0 0 0" },
      { "_id": "3", "AmbientReflectance": "0 0 0", "DiffuseReflectance": "0.2 0.6 0.8",
        "SpecularReflectance": "0 0 0" } ] },
    "Transformations": {
      "Translation": [
        { "_id": "1", "_data": "-2.2 0.2 0" }, { "_id": "2", "_data": "2.5 0 0" },
        { "_id": "3", "_data": "0.3 0.4 -1.5" }, { "_id": "4", "_data": "0 0.3 1.8" } ],
      "Scaling": [
        { "_id": "1", "_data": "0.6 1.4 0.8" }, { "_id": "2", "_data": "1.5 0.5 1" },
        { "_id": "3", "_data": "-0.9 1.1 0.7" } ],
      "Rotation": [
        { "_id": "1", "_data": "30 0 1 0" }, { "_id": "2", "_data": "-50 1 1 0" } ] },
    "VertexData": { "_type": "xyz", "_data":
      "1 0 0  -1 0 0  0 1 0  0 -1 0  0 0 1  0 0 -1  -8 -1 -8  8 -1 -8  8 -1 8  -8 -1 8  -1 4 -1  1 4 -1  1 4 1  -1 4 1" },
    "Objects": {
      "Mesh": [
        { "_id": "1", "Material": "1", "_shadingMode": "smooth", "Transformations": "r1 t1",
          "Faces": { "_type": "triangle", "_data":
            "1 3 5  5 3 2  2 3 6  6 3 1  5 4 1  2 4 5  6 4 2  1 4 6" } },
        { "_id": "2", "Material": "2",
          "Faces": { "_type": "triangle", "_data": "7 10 9  9 8 7" } } ],
      "LightMesh": { "_id": "3", "Material": "2", "Radiance": "4 4 4",
          "Faces": { "_type": "triangle", "_data": "11 12 13  13 14 11" } },
      "MeshInstance": [
        { "_id": "4", "_baseMeshId": "1", "_resetTransform": "false", "Material": "3",
          "Transformations": "s1 t2" },
        { "_id": "5", "_baseMeshId": "1", "_resetTransform": "true",
          "Transformations": "r2 s2 t3" },
        { "_id": "6", "_baseMeshId": "1", "_resetTransform": "true", "Material": "3",
          "Transformations": "s3 t4" } ]
    }
  }
}"#;

/// The same kind of scene through Mitsuba's `shapegroup` / `instance`.
const MITSUBA: &str = r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 3, 9" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="1"/></sampler>
        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="64"/>
            <rfilter type="box"/></film>
    </sensor>
    <shape type="shapegroup" id="g">
        <shape type="obj"><string name="filename" value="octa.obj"/>
            <transform name="to_world"><rotate x="1" angle="20"/></transform></shape>
        <shape type="sphere"><float name="radius" value="0.4"/>
            <point name="center" x="0" y="1.2" z="0"/></shape>
    </shape>
    <shape type="instance"><ref id="g"/>
        <transform name="to_world"><translate x="-2"/></transform></shape>
    <shape type="instance"><ref id="g"/>
        <transform name="to_world"><scale x="1.5" y="0.6" z="1"/><rotate y="1" angle="40"/>
            <translate x="1.5" z="-1"/></transform></shape>
    <shape type="instance"><ref id="g"/>
        <transform name="to_world"><scale x="-0.8" y="1.2" z="0.9"/><translate z="1.5" y="0.2"/></transform></shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="8"/><rotate x="1" angle="-90"/><translate y="-1"/></transform></shape>
    <emitter type="constant"/>
</scene>"#;

const OCTA_OBJ: &str = "v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n\
    vn 1 0 0\nvn -1 0 0\nvn 0 1 0\nvn 0 -1 0\nvn 0 0 1\nvn 0 0 -1\n\
    f 1//1 3//3 5//5\nf 5//5 3//3 2//2\nf 2//2 3//3 6//6\nf 6//6 3//3 1//1\n\
    f 5//5 4//4 1//1\nf 2//2 4//4 5//5\nf 6//6 4//4 2//2\nf 1//1 4//4 6//6\n";

fn load() -> scene::SceneDesc {
    load_files(&[("instances.json", SCENE)])
}

fn load_files(files: &[(&str, &str)]) -> scene::SceneDesc {
    // One directory per call: the tests run in parallel threads of one process.
    static CALLS: std::sync::atomic::AtomicU32 = std::sync::atomic::AtomicU32::new(0);
    let n = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("penumbra-instancing-{}-{n}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for (name, text) in files {
        std::fs::write(dir.join(name), text).unwrap();
    }
    let path: PathBuf = dir.join(files[0].0);
    let doc = scene::load(&path, &Default::default()).expect("scene loads");
    let _ = std::fs::remove_dir_all(&dir);
    match doc {
        Document::Scene(s) => *s,
        _ => panic!("not a scene"),
    }
}

fn build_with(
    desc: &scene::SceneDesc,
    flatten: bool,
    integrator: IntegratorDesc,
    seed: u64,
) -> Built {
    build(
        desc,
        &BuildOptions {
            integrator: Some(integrator),
            seed: Some(seed),
            flatten_instances: flatten,
            ..Default::default()
        },
    )
    .unwrap()
}

fn render_image(built: &Built, spp: u32) -> Image {
    render(
        &built.scene,
        &built.integrator,
        &RenderOptions {
            spp,
            ..Default::default()
        },
        &Silent,
    )
    .film
    .develop()
}

#[test]
fn the_scene_is_instanced() {
    let desc = load();
    let inst = build_with(&desc, false, IntegratorDesc::Depth, 1).scene;
    let flat = build_with(&desc, true, IntegratorDesc::Depth, 1).scene;
    // One prototype (the octahedron, used by four shapes), none when flattened.
    assert_eq!(inst.accel.instancing_stats().0, 1);
    assert_eq!(flat.accel.instancing_stats().0, 0);
    assert_eq!(inst.triangle_count, flat.triangle_count);
    let (lo_i, hi_i) = inst.bounds;
    let (lo_f, hi_f) = flat.bounds;
    // Instance boxes are padded and transformed boxes: they contain the exact bounds.
    assert!(lo_i.cmple(lo_f).all() && hi_i.cmpge(hi_f).all());
}

#[test]
fn depth_and_normals_equal_the_flattened_scene() {
    exact_check(&load());
}

#[test]
fn mitsuba_shapegroup_instances_equal_the_flattened_scene() {
    let desc = load_files(&[("scene.xml", MITSUBA), ("octa.obj", OCTA_OBJ)]);
    assert_eq!(desc.shapes.len(), 7);
    let inst = build_with(&desc, false, IntegratorDesc::Depth, 1).scene;
    assert_eq!(
        inst.accel.instancing_stats().0,
        1,
        "the octahedron is a prototype"
    );
    exact_check(&desc);
}

fn exact_check(desc: &scene::SceneDesc) {
    for (integrator, what) in [
        (IntegratorDesc::Depth, "depth"),
        (IntegratorDesc::Normals, "normals"),
    ] {
        let a = render_image(&build_with(desc, false, integrator.clone(), 5), 1);
        let b = render_image(&build_with(desc, true, integrator, 5), 1);
        let mut covered = 0;
        for (i, (p, q)) in a.pixels.iter().zip(&b.pixels).enumerate() {
            let d = (*p - *q).abs().max_element();
            let scale = p.abs().max_element().max(1.0);
            assert!(d <= 2e-4 * scale, "{what}: pixel {} differs: {p} vs {q}", i);
            covered += (q.abs().max_element() > 0.0) as u32;
        }
        // The scene covers most of the image (the floor), so this compared hits.
        assert!(covered > 64 * 64 / 2, "{what}: only {covered} pixels hit");
    }
}

#[test]
fn path_traced_images_agree_statistically() {
    let desc = load();
    let path = IntegratorDesc::Path(PathDesc::default());
    let batches = |flatten: bool, seed0: u64| -> Vec<Image> {
        (0..16)
            .map(|k| render_image(&build_with(&desc, flatten, path.clone(), seed0 + k), 16))
            .collect()
    };
    let reference = Reference::from_batches(&batches(true, 1000)).unwrap();
    let test = TestImages::Batches(batches(false, 2000));
    let c = compare_with(
        &reference,
        &test,
        &CompareOptions {
            block: 8,
            alpha: 0.01,
            reference_batches: 16,
        },
    )
    .unwrap();
    println!("instanced vs flattened: {c}");
    assert!(c.passed, "{c}");
    // The images are not black: the comparison has something to compare.
    assert!(c.mean_ratio.iter().all(|r| (r - 1.0).abs() < 0.05), "{c}");
}

/// Emitters are flattened, never instanced: light sampling works on world-space triangles.
/// A shapegroup holding an emitting mesh gives one area light per instance.
#[test]
fn emitting_instances_are_flattened() {
    let xml = r#"<scene version="3.0.0">
    <shape type="shapegroup" id="g">
        <shape type="obj"><string name="filename" value="octa.obj"/>
            <emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
    </shape>
    <shape type="instance"><ref id="g"/></shape>
    <shape type="instance"><ref id="g"/>
        <transform name="to_world"><translate x="3"/></transform></shape>
</scene>"#;
    let desc = load_files(&[("scene.xml", xml), ("octa.obj", OCTA_OBJ)]);
    let scene = build(&desc, &BuildOptions::default()).unwrap().scene;
    assert_eq!(scene.accel.instancing_stats().0, 0);
    assert_eq!(scene.lights.len(), 2);
}
