//! CENG795 loader tests on the shared course scenes (skipped with a notice when absent).

use std::path::{Path, PathBuf};

use scene::{Document, Emitter, IntegratorDesc, LoadOptions, Material, Projection, Shape};

fn shared() -> Option<PathBuf> {
    scene::testing::shared_dir("scenes/ceng795")
}

fn scenes(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(rd) = std::fs::read_dir(dir) else {
        return;
    };
    for e in rd.flatten() {
        let p = e.path();
        if p.is_dir() {
            scenes(&p, out);
        } else if matches!(p.extension().and_then(|e| e.to_str()), Some("json" | "xml")) {
            out.push(p);
        }
    }
}

fn load(p: &Path) -> scene::Result<scene::SceneDesc> {
    match scene::load(p, &LoadOptions::default())? {
        Document::Scene(s) => Ok(*s),
        Document::Test(_) => panic!("{}: not a scene", p.display()),
    }
}

#[test]
fn every_shared_scene_loads_or_fails_cleanly() {
    let Some(dir) = shared() else { return };
    let mut files = Vec::new();
    scenes(&dir, &mut files);
    files.sort();
    assert!(files.len() > 30);
    let mut failures = Vec::new();
    for f in &files {
        match load(f) {
            Ok(s) => {
                assert!(!s.sensors.is_empty(), "{}", f.display());
                assert!(!s.shapes.is_empty(), "{}", f.display());
            }
            // Only missing external files are acceptable failures.
            Err(e) => failures.push(e.to_string()),
        }
    }
    for e in &failures {
        eprintln!("{e}");
        assert!(e.contains("cannot"), "unexpected load error: {e}");
    }
}

#[test]
fn furnace_scene_is_translated() {
    let Some(dir) = shared() else { return };
    let s = load(&dir.join("json/tests/furnace.json")).unwrap();
    assert_eq!(s.shapes.len(), 2);
    let light = s.shapes.iter().find(|s| s.emission.is_some()).unwrap();
    let Shape::Mesh(m) = &light.shape else {
        panic!("light mesh expected")
    };
    assert_eq!(m.indices.len(), 12);
    assert_eq!(m.positions.len(), 8);
    let sphere = s.shapes.iter().find(|s| s.emission.is_none()).unwrap();
    assert!(
        matches!(sphere.shape, Shape::Sphere { radius, center } if radius == 0.8 && center.z == -0.5)
    );
    let mat = s.material(sphere.material.unwrap());
    assert!(matches!(
        mat.material,
        Material::PhongFamily {
            normalized: true,
            ..
        }
    ));
    let sensor = &s.sensors[0];
    assert_eq!((sensor.film.width, sensor.sampler.spp), (64, 144));
    assert!(matches!(sensor.camera.projection, Projection::Perspective { fov, .. } if fov == 60.0));
    let Some(IntegratorDesc::Path(p)) = &sensor.integrator else {
        panic!("path tracer expected")
    };
    assert!(!p.nee);
    // Looks along -z from z = 1.5; +x of the camera is the image's left, i.e. world -x.
    let m = sensor.camera.to_world;
    assert!((m.z_axis.truncate() - scene::Vec3::NEG_Z).length() < 1e-6);
    assert!((m.x_axis.truncate() - scene::Vec3::NEG_X).length() < 1e-6);
}

#[test]
fn xml_scene_with_tonemap_and_lights() {
    let Some(dir) = shared() else { return };
    let s = load(&dir.join("xml/cornellbox_jaroslav_diffuse_area.xml")).unwrap();
    let t = s.sensors[0].film.tonemap.as_ref().expect("tone map");
    assert_eq!(
        *t,
        scene::Tonemap::Photographic {
            key: 0.18,
            burn_percent: 1.0,
            saturation: 1.0,
            gamma: 2.2
        }
    );
    let Some(IntegratorDesc::Path(p)) = &s.sensors[0].integrator else {
        panic!("path tracer expected")
    };
    assert!(p.nee);
    let s = load(&dir.join("xml/cube_directional.xml")).unwrap();
    assert!(
        s.emitters
            .iter()
            .any(|e| matches!(e.emitter, Emitter::Directional { .. }))
    );
}

#[test]
fn errors_name_the_path_or_line() {
    let dir = std::env::temp_dir().join(format!("ceng795-test-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let j = dir.join("bad.json");
    std::fs::write(
        &j,
        r#"{"Scene":{"VertexData":"0 0 0 1 0 0 0 1 0","Materials":{"Material":{"_id":"1"}},
        "Cameras":{"Camera":{"Position":"0 0 1","Gaze":"0 0 -1","Up":"0 1 0","NearPlane":"-1 1 -1 1","ImageResolution":"4 4"}},
        "Objects":{"Mesh":[{"Material":"1","Faces":{"_data":"1 2 3"}},{"Material":"1","Faces":{"_data":"1 2 7"}}]}}}"#,
    )
    .unwrap();
    let e = load(&j).unwrap_err().to_string();
    assert!(e.contains("Scene.Objects.Mesh[1].Faces"), "{e}");
    assert!(e.contains("vertex id 7"), "{e}");
    let x = dir.join("bad.xml");
    std::fs::write(
        &x,
        "<Scene>\n<VertexData>0 0 0</VertexData>\n<Objects>\n<Sphere id=\"1\">\n<Center>1</Center>\n<Radius>x</Radius>\n</Sphere>\n</Objects>\n</Scene>\n",
    )
    .unwrap();
    let e = load(&x).unwrap_err().to_string();
    assert!(e.contains("bad.xml:6"), "{e}");
    // A missing PLY file (as hw1/akif_uslu/trex_smooth.json's mesh_3.ply in the shared data):
    // the error names the object's JSON path and the file.
    let p = dir.join("ply.json");
    std::fs::write(
        &p,
        r#"{"Scene":{"Materials":{"Material":{"_id":"1"}},
        "Cameras":{"Camera":{"Position":"0 0 1","Gaze":"0 0 -1","Up":"0 1 0","NearPlane":"-1 1 -1 1","ImageResolution":"4 4"}},
        "Objects":{"Mesh":[{"Material":"1","Faces":{"_plyFile":"meshes/absent.ply"}}]}}}"#,
    )
    .unwrap();
    let e = load(&p).unwrap_err().to_string();
    assert!(e.contains("Scene.Objects.Mesh[0].Faces._plyFile"), "{e}");
    assert!(e.contains("meshes/absent.ply"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

/// A course spot light keeps the course's falloff profile (and its full cone angles halved).
#[test]
fn spot_lights_use_the_course_falloff() {
    let dir = std::env::temp_dir().join(format!("penumbra-ceng-spot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("spot.json");
    std::fs::write(
        &file,
        r#"{"Scene": {"Cameras": {"Camera": {"_id": "1", "Position": "0 0 10",
          "Gaze": "0 0 -1", "Up": "0 1 0", "NearPlane": "-1 1 -1 1", "NearDistance": "1",
          "ImageResolution": "4 4", "ImageName": "x.png"}},
          "Lights": {"SpotLight": {"_id": "1", "Position": "0 5 0", "Direction": "0 -1 0",
            "Intensity": "100 100 100", "CoverageAngle": "60", "FalloffAngle": "20"}},
          "Materials": {"Material": {"_id": "1", "DiffuseReflectance": "1 1 1"}}}}"#,
    )
    .unwrap();
    let Ok(Document::Scene(d)) = scene::load(&file, &LoadOptions::default()) else {
        panic!("loads")
    };
    let spot = d
        .emitters
        .iter()
        .find_map(|e| match e.emitter {
            Emitter::Spot {
                cutoff_angle,
                beam_width,
                falloff,
                ..
            } => Some((cutoff_angle, beam_width, falloff)),
            _ => None,
        })
        .expect("a spot light");
    assert_eq!(spot, (30.0, 10.0, scene::SpotFalloff::Cosine4));
}

#[test]
fn motion_blur_and_instances_of_the_dynamic_cornell_box() {
    let Some(dir) = shared() else { return };
    let s = load(&dir.join("json/hw3/cornellbox_boxes_dynamic.json")).unwrap();
    // The MeshInstance moves by "0 0 4" over the shutter; nothing else moves.
    let moving: Vec<_> = s.shapes.iter().filter(|sh| sh.motion.is_some()).collect();
    assert_eq!(moving.len(), 1);
    assert_eq!(moving[0].motion, Some(glam::Vec3::new(0.0, 0.0, 4.0)));
    // It shares the base mesh (so the renderer instances it).
    let meshes: Vec<_> = s
        .shapes
        .iter()
        .filter_map(|sh| match &sh.shape {
            Shape::Mesh(m) if m.triangle_count() == 12 => Some(m.clone()),
            _ => None,
        })
        .collect();
    assert_eq!(meshes.len(), 2);
    assert!(std::sync::Arc::ptr_eq(&meshes[0], &meshes[1]));
    assert!(
        s.warnings.iter().all(|w| !w.message.contains("MotionBlur")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn a_ply_used_twice_is_read_once() {
    let dir = std::env::temp_dir().join(format!("ceng795-ply-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let ply = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
               property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
               end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    std::fs::write(dir.join("t.ply"), ply).unwrap();
    let mesh = |id: u32, mode: &str| {
        format!(
            r#"{{ "_id": "{id}", "_shadingMode": "{mode}", "Faces": {{ "_plyFile": "t.ply" }} }}"#
        )
    };
    let json = format!(
        r#"{{ "Scene": {{ "Cameras": {{ "Camera": {{ "_id": "1", "Position": "0 0 5",
        "Gaze": "0 0 -1", "Up": "0 1 0", "NearPlane": "-1 1 -1 1", "NearDistance": "1",
        "ImageResolution": "8 8", "ImageName": "a.png" }} }},
        "Materials": {{ "Material": {{ "_id": "1", "DiffuseReflectance": "1 1 1" }} }},
        "Objects": {{ "Mesh": [{}, {}, {}] }} }} }}"#,
        mesh(1, "flat"),
        mesh(2, "flat"),
        mesh(3, "smooth")
    );
    std::fs::write(dir.join("s.json"), json).unwrap();
    let s = load(&dir.join("s.json")).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
    let m: Vec<_> = s
        .shapes
        .iter()
        .map(|sh| match &sh.shape {
            Shape::Mesh(m) => m.clone(),
            _ => panic!("mesh expected"),
        })
        .collect();
    assert!(
        std::sync::Arc::ptr_eq(&m[0], &m[1]),
        "same file and mode: shared"
    );
    assert!(
        !std::sync::Arc::ptr_eq(&m[0], &m[2]),
        "smooth shading: its own mesh"
    );
    assert!(m[0].normals.is_empty() && !m[2].normals.is_empty());
}
