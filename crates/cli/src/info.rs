//! `penumbra info`: what was loaded.

use std::collections::BTreeMap;
use std::path::Path;

use glam::Vec3;
use scene::{Document, Projection, SceneDesc, Shape, TestKind};

use crate::Failure;

fn count<'a>(names: impl Iterator<Item = &'a str>) -> String {
    let mut m: BTreeMap<&str, usize> = BTreeMap::new();
    for n in names {
        *m.entry(n).or_default() += 1;
    }
    if m.is_empty() {
        return "none".into();
    }
    m.iter()
        .map(|(k, v)| format!("{v} {k}"))
        .collect::<Vec<_>>()
        .join(", ")
}

/// World-space bounds of the bounded shapes.
fn bounds(desc: &SceneDesc) -> Option<(Vec3, Vec3)> {
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    let mut grow = |p: Vec3| {
        lo = lo.min(p);
        hi = hi.max(p);
    };
    for s in &desc.shapes {
        let m = s.to_world;
        match &s.shape {
            Shape::Mesh(mesh) => mesh
                .positions
                .iter()
                .for_each(|p| grow(m.transform_point3(*p))),
            Shape::Sphere { center, radius } => {
                let c = m.transform_point3(*center);
                let r = m.transform_vector3(Vec3::new(*radius, 0.0, 0.0)).length();
                grow(c - Vec3::splat(r));
                grow(c + Vec3::splat(r));
            }
            Shape::Rectangle | Shape::Disk | Shape::Cube => {
                let z = if matches!(s.shape, Shape::Cube) {
                    [-1.0, 1.0]
                } else {
                    [0.0, 0.0]
                };
                for x in [-1.0, 1.0] {
                    for y in [-1.0, 1.0] {
                        for z in z {
                            grow(m.transform_point3(Vec3::new(x, y, z)));
                        }
                    }
                }
            }
            Shape::InfinitePlane { .. } => {}
        }
    }
    (lo.x <= hi.x).then_some((lo, hi))
}

fn print_scene(desc: &SceneDesc, indent: &str) {
    let tris: usize = desc
        .shapes
        .iter()
        .map(|s| match &s.shape {
            Shape::Mesh(m) => m.triangle_count(),
            _ => 0,
        })
        .sum();
    println!(
        "{indent}shapes:     {} ({}), {} triangles in meshes",
        desc.shapes.len(),
        count(desc.shapes.iter().map(|s| s.shape.kind_name())),
        tris
    );
    println!(
        "{indent}materials:  {} ({})",
        desc.materials.len(),
        count(desc.materials.iter().map(|m| m.material.kind_name()))
    );
    println!("{indent}textures:   {}", desc.textures.len());
    let area = desc.shapes.iter().filter(|s| s.emission.is_some()).count();
    println!(
        "{indent}emitters:   {} area, {}",
        area,
        count(desc.emitters.iter().map(|e| e.emitter.kind_name()))
    );
    match bounds(desc) {
        Some((lo, hi)) => println!("{indent}bounds:     {lo} .. {hi}"),
        None => println!("{indent}bounds:     empty"),
    }
    for (i, s) in desc.sensors.iter().enumerate() {
        let cam = &s.camera;
        let kind = match cam.projection {
            Projection::Perspective { fov, fov_axis } => {
                format!("perspective, fov {fov}° ({fov_axis:?})")
            }
            Projection::ThinLens {
                fov,
                fov_axis,
                aperture_radius,
                focus_distance,
            } => format!(
                "thin lens, fov {fov}° ({fov_axis:?}), aperture {aperture_radius}, focus {focus_distance}"
            ),
            Projection::Orthographic => "orthographic".into(),
        };
        println!(
            "{indent}sensor {i}:   {kind}, at {}, {}x{}{}, {:?} {} spp, filter {:?}",
            cam.to_world.w_axis.truncate(),
            s.film.width,
            s.film.height,
            s.film
                .crop
                .map(|c| format!(
                    " (crop {}x{} at {},{})",
                    c.width, c.height, c.offset_x, c.offset_y
                ))
                .unwrap_or_default(),
            s.sampler.kind,
            s.sampler.spp,
            s.film.filter,
        );
        // A sensor's own integrator (CENG795 cameras) replaces the scene's.
        if let Some(integrator) = &s.integrator {
            println!("{indent}  integrator: {integrator:?}");
        }
    }
    println!("{indent}integrator: {:?}", desc.integrator);
    for w in &desc.warnings {
        println!("{indent}{w}");
    }
}

pub fn print(path: &Path, doc: &Document) -> Result<(), Failure> {
    println!("{}", path.display());
    match doc {
        Document::Scene(desc) => print_scene(desc, "  "),
        Document::Test(t) => match &t.kind {
            TestKind::TTest {
                references,
                scenes,
                bsdfs,
                angles,
                ..
            } => {
                println!(
                    "  t-test: {} reference value(s), {} scene(s), {} bsdf(s), {} angle(s)",
                    references.len(),
                    scenes.len(),
                    bsdfs.len(),
                    angles.len()
                );
                for (i, s) in scenes.iter().enumerate() {
                    println!("  scene {i}:");
                    print_scene(s, "    ");
                }
            }
            TestKind::Chi2Test { bsdfs, .. } => {
                println!("  chi2 test: {} bsdf(s)", bsdfs.len());
            }
        },
    }
    Ok(())
}
