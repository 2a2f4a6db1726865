//! Camera rays are exact: depth images of analytic scenes equal the analytically computed
//! distances within 1e-4 relative.

use build::{BuildOptions, build};
use glam::{DVec3, Mat4, Vec3};
use render::math::Vec2;
use render::render::{RenderOptions, Silent, render};
use scene::{
    Camera, FilterDesc, FovAxis, IntegratorDesc, Projection, SamplerDesc, SamplerKind, SceneDesc,
    Sensor, Shape, ShapeDesc,
};

fn shape(shape: Shape, to_world: Mat4) -> ShapeDesc {
    ShapeDesc {
        media: Default::default(),
        motion: None,
        shape,
        to_world,
        material: None,
        emission: None,
        flip_normals: false,
        name: None,
        loc: Default::default(),
    }
}

fn scene_with(camera: Camera, shapes: Vec<ShapeDesc>, w: u32, h: u32) -> SceneDesc {
    SceneDesc {
        shapes,
        sensors: vec![Sensor {
            medium: None,
            camera,
            film: scene::Film {
                width: w,
                height: h,
                crop: None,
                filter: FilterDesc::Box { radius: 0.5 },
                output: None,
                tonemap: None,
            },
            sampler: SamplerDesc {
                kind: SamplerKind::Independent,
                spp: 4,
                seed: 7,
            },
            integrator: None,
            name: None,
            loc: Default::default(),
        }],
        integrator: IntegratorDesc::Depth,
        ..Default::default()
    }
}

/// Mitsuba's look-at matrix (camera +z towards the target, +x = up × dir).
fn look_at(origin: Vec3, target: Vec3, up: Vec3) -> Mat4 {
    let dir = (target - origin).normalize();
    let left = up.cross(dir).normalize();
    let new_up = dir.cross(left);
    Mat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        origin.extend(1.0),
    )
}

/// Ray through the centre of pixel (i, j), computed in f64 straight from the definition of
/// the field of view, independent of the renderer's camera code.
fn reference_ray(
    origin: DVec3,
    m: &Mat4,
    fov_x_deg: f64,
    w: u32,
    h: u32,
    i: u32,
    j: u32,
) -> (DVec3, DVec3) {
    let tan = (0.5 * fov_x_deg).to_radians().tan();
    let aspect = w as f64 / h as f64;
    let sx = (i as f64 + 0.5) / w as f64;
    let sy = (j as f64 + 0.5) / h as f64;
    let x = -(2.0 * sx - 1.0) * tan;
    let y = -(2.0 * sy - 1.0) * tan / aspect;
    let cols = |c: glam::Vec4| DVec3::new(c.x as f64, c.y as f64, c.z as f64);
    let d = cols(m.x_axis) * x + cols(m.y_axis) * y + cols(m.z_axis);
    (origin, d.normalize())
}

fn sphere_hit(o: DVec3, d: DVec3, c: DVec3, r: f64) -> Option<f64> {
    let oc = o - c;
    let b = oc.dot(d);
    let disc = b * b - (oc.length_squared() - r * r);
    (disc >= 0.0).then(|| -b - disc.sqrt()).filter(|t| *t > 0.0)
}

fn plane_hit(o: DVec3, d: DVec3, p: DVec3, n: DVec3) -> Option<f64> {
    let t = (p - o).dot(n) / d.dot(n);
    (t > 0.0).then_some(t)
}

#[test]
fn perspective_depth_matches_analytic_distances() {
    let (w, h) = (48u32, 32u32);
    let origin = Vec3::new(0.3, 1.2, 6.0);
    let m = look_at(origin, Vec3::new(0.0, 0.5, 0.0), Vec3::Y);
    let fov = 50.0f32;
    let camera = Camera {
        projection: Projection::Perspective {
            fov,
            fov_axis: FovAxis::X,
        },
        to_world: m,
        near_clip: 0.0,
        far_clip: 1e5,
    };
    let center = Vec3::new(0.2, 0.8, 0.1);
    let radius = 1.1;
    let shapes = vec![
        shape(Shape::Sphere { center, radius }, Mat4::IDENTITY),
        // An infinite floor at y = -0.5.
        shape(
            Shape::InfinitePlane {
                point: Vec3::new(0.0, -0.5, 0.0),
                normal: Vec3::Y,
            },
            Mat4::IDENTITY,
        ),
    ];
    let desc = scene_with(camera, shapes, w, h);
    let scene = build(&desc, &BuildOptions::default()).unwrap().scene;
    let mut checked = 0;
    for j in 0..h {
        for i in 0..w {
            let (o, d) = reference_ray(origin.as_dvec3(), &m, fov as f64, w, h, i, j);
            let expect = [
                sphere_hit(o, d, center.as_dvec3(), radius as f64),
                plane_hit(o, d, DVec3::new(0.0, -0.5, 0.0), DVec3::Y),
            ]
            .into_iter()
            .flatten()
            .fold(f64::INFINITY, f64::min);
            let cray = scene
                .camera
                .generate_ray(Vec2::new(i as f32 + 0.5, j as f32 + 0.5), Vec2::ZERO);
            let got = scene.intersect(&cray.ray, cray.t_max).map(|si| si.t as f64);
            match got {
                Some(t) => {
                    assert!(
                        expect.is_finite(),
                        "pixel ({i},{j}): hit at {t}, expected a miss"
                    );
                    let rel = (t - expect).abs() / expect;
                    assert!(
                        rel < 1e-4,
                        "pixel ({i},{j}): depth {t} vs {expect} (rel {rel:e})"
                    );
                    checked += 1;
                }
                None => assert!(
                    !expect.is_finite(),
                    "pixel ({i},{j}): missed, expected {expect}"
                ),
            }
        }
    }
    assert!(checked > (w * h / 2) as usize);
}

#[test]
fn orthographic_depth_image_of_a_facing_plane_is_exact() {
    // An orthographic camera looking down -z at a plane 5 units away: every sample of every
    // pixel has depth 5, so the rendered depth image is 5 everywhere, whatever the sampler.
    let camera = Camera {
        projection: Projection::Orthographic,
        to_world: look_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO, Vec3::Y)
            * Mat4::from_scale(Vec3::new(2.0, 2.0, 1.0)),
        near_clip: 0.0,
        far_clip: 100.0,
    };
    let plane = shape(Shape::Rectangle, Mat4::from_scale(Vec3::splat(10.0)));
    let desc = scene_with(camera, vec![plane], 16, 12);
    let build::Built {
        scene, integrator, ..
    } = build(&desc, &BuildOptions::default()).unwrap();
    let out = render(
        &scene,
        &integrator,
        &RenderOptions {
            spp: 4,
            ..Default::default()
        },
        &Silent,
    );
    let img = out.film.develop();
    for p in &img.pixels {
        assert!(((p.x as f64) - 5.0).abs() / 5.0 < 1e-4, "{p}");
    }
}
