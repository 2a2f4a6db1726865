//! Spheres under a non-uniform transformation are ellipsoids (CENG795 `hw2/ellipsoids.json`):
//! each ellipsoid's silhouette through the pixel centres equals the analytic one, pixel for
//! pixel, and an emissive ellipsoid's light sampling has the density it claims.

use build::{BuildOptions, build};
use glam::{DMat4, DVec3};
use render::math::{Mat4, PVec3, Vec2, Vec3};
use render::shapes::Ellipsoid;
use scene::{Document, LoadOptions, Shape};

/// The ray through a pixel centre against the unit sphere of `frame` (sphere centre, radius
/// and the shape's transformation), in f64: `Some(disc)` when it hits beyond the ray's start
/// (disc = the normalised discriminant, how far from grazing the ray is).
fn analytic_hit(frame: &DMat4, o: DVec3, d: DVec3) -> Option<f64> {
    let inv = frame.inverse();
    let (o, d) = (inv.transform_point3(o), inv.transform_vector3(d));
    let (a, b, c) = (d.dot(d), 2.0 * o.dot(d), o.dot(o) - 1.0);
    let disc = b * b - 4.0 * a * c;
    let t1 = (-b + disc.max(0.0).sqrt()) / (2.0 * a);
    (disc >= 0.0 && t1 > 0.0).then_some(disc / (b * b).max(1e-30))
}

#[test]
fn ellipsoid_silhouettes_are_pixel_exact() {
    let Some(path) = scene::testing::shared_dir("scenes/ceng795/json/hw2/ellipsoids.json") else {
        return;
    };
    let Ok(Document::Scene(desc)) = scene::load(&path, &LoadOptions::default()) else {
        panic!("ellipsoids.json loads");
    };
    let mut tested = 0;
    for (k, s) in desc.shapes.iter().enumerate() {
        let Shape::Sphere { center, radius } = s.shape else {
            continue;
        };
        if scene::is_similarity(&s.to_world) {
            continue;
        }
        // This shape alone, at 1/4 resolution.
        let mut one = (*desc).clone();
        one.shapes = vec![one.shapes[k].clone()];
        let opts = BuildOptions {
            resolution: Some((200, 200)),
            ..Default::default()
        };
        let scene = build(&one, &opts).unwrap().scene;
        let frame =
            (s.to_world * Mat4::from_translation(center) * Mat4::from_scale(PVec3::splat(radius)))
                .as_dmat4();
        let (mut inside, mut mismatches) = (0, 0);
        for y in 0..200 {
            for x in 0..200 {
                let cr = scene
                    .camera
                    .generate_ray(Vec2::new(x as f32 + 0.5, y as f32 + 0.5), Vec2::ZERO);
                let o = PVec3::from(cr.ray.o).as_dvec3();
                let d = PVec3::from(cr.ray.d).as_dvec3();
                let ours = scene.hit(&cr.ray, cr.t_max).is_some();
                match analytic_hit(&frame, o, d) {
                    // Rays within 1e-6 (relative discriminant) of grazing may go either way.
                    Some(disc) if disc < 1e-6 => {}
                    Some(_) => {
                        inside += 1;
                        mismatches += usize::from(!ours);
                    }
                    None => mismatches += usize::from(ours),
                }
            }
        }
        assert_eq!(
            mismatches, 0,
            "shape {k}: {mismatches} pixels differ ({inside} inside)"
        );
        assert!(inside > 500, "shape {k}: only {inside} pixels inside");
        tested += 1;
    }
    assert!(tested >= 3, "only {tested} ellipsoids in the scene");
}

/// An emissive ellipsoid samples points uniformly on its object sphere; the world area density
/// is 1 / (4π · area scale). Its integral over the surface (the mean of 1 / density over
/// uniform points, i.e. the area) must equal the numerically integrated area, and the area of
/// a sphere-like frame must be 4πr².
#[test]
fn ellipsoid_area_and_density_agree() {
    let sphere = Ellipsoid::new(Mat4::from_scale(PVec3::splat(2.0))).unwrap();
    let exact = 4.0 * std::f32::consts::PI * 4.0;
    assert!((sphere.area / exact - 1.0).abs() < 1e-4, "{}", sphere.area);
    // A prolate spheroid a = 3, b = c = 1: A = 2πb² (1 + a/(b e) asin e), e = √(1 − b²/a²).
    let e =
        Ellipsoid::new(Mat4::from_rotation_z(0.3) * Mat4::from_scale(PVec3::new(3.0, 1.0, 1.0)))
            .unwrap();
    let ecc = (1.0f64 - 1.0 / 9.0).sqrt();
    let prolate = 2.0 * std::f64::consts::PI * (1.0 + 3.0 / ecc * ecc.asin());
    assert!(
        (e.area as f64 / prolate - 1.0).abs() < 1e-4,
        "{} vs {prolate}",
        e.area
    );
    // Normals: orthogonal to the surface's tangents.
    let dir = Vec3::new(0.3, -0.5, 0.8).normalize();
    let n = e.normal(dir);
    let t = e
        .to_world
        .transform_vector3a(dir.cross(Vec3::Z).normalize());
    assert!(n.dot(t).abs() < 1e-5);
}
