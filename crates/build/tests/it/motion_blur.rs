//! Motion blur (issue 17): a black sphere and a black square (a mesh) moving across a
//! constant white environment, seen by an orthographic camera. A camera sample's value is 0
//! when its ray hits a shape at the sample's time and 1 otherwise, so a pixel's expected
//! value is 1 − c, with c the fraction of (pixel area × shutter) in which the ray is covered.
//! For one ray c is an interval length in time, computed analytically; over the pixel it is
//! integrated by a 48×48 midpoint rule (error far below the test's noise).
//!
//! Test: every partially covered pixel's mean of n = 2048 samples is z-tested against the
//! Bernoulli mean 1 − c (variance c(1 − c)/n), at a family-wise α = 1e-4 with Bonferroni over
//! the tested pixels. Fixed seed.

use build::{BuildOptions, build};
use glam::{Mat4, Vec3};
use render::math::Vec2;
use render::render::{RenderOptions, Silent, render};
use scene::{
    Camera, ColorParam, Emitter, EmitterDesc, FilterDesc, IntegratorDesc, Material, MaterialDesc,
    MaterialId, PathDesc, Projection, SamplerDesc, SamplerKind, SceneDesc, Sensor, Shape,
    ShapeDesc,
};
use statrs::distribution::{ContinuousCDF, Normal};

const SPHERE_C: Vec3 = Vec3::new(-2.0, 1.2, 0.0);
const SPHERE_R: f32 = 0.9;
const SPHERE_V: Vec3 = Vec3::new(2.5, 0.0, 0.0);
/// The square [-1,1]² scaled by `SQUARE_H` around `SQUARE_C`, facing the camera.
const SQUARE_C: Vec3 = Vec3::new(1.0, -1.3, 0.0);
const SQUARE_H: f32 = 0.8;
const SQUARE_V: Vec3 = Vec3::new(-1.7, 0.3, 0.0);

fn shape(shape: Shape, to_world: Mat4, motion: Vec3) -> ShapeDesc {
    ShapeDesc {
        media: Default::default(),
        shape,
        to_world,
        material: Some(MaterialId(0)),
        emission: None,
        flip_normals: false,
        motion: Some(motion),
        name: None,
        loc: Default::default(),
    }
}

fn scene_desc(w: u32, h: u32, spp: u32) -> SceneDesc {
    SceneDesc {
        shapes: vec![
            shape(
                Shape::Sphere {
                    center: SPHERE_C,
                    radius: SPHERE_R,
                },
                Mat4::IDENTITY,
                SPHERE_V,
            ),
            shape(
                Shape::Rectangle,
                Mat4::from_translation(SQUARE_C) * Mat4::from_scale(Vec3::splat(SQUARE_H)),
                SQUARE_V,
            ),
        ],
        materials: vec![MaterialDesc {
            material: Material::Diffuse {
                reflectance: ColorParam::Const(Vec3::ZERO),
            },
            ambient: Vec3::ZERO,
            name: None,
            loc: Default::default(),
        }],
        emitters: vec![EmitterDesc {
            name: None,
            medium: None,
            emitter: Emitter::Constant {
                radiance: Vec3::ONE.into(),
            },
            loc: Default::default(),
        }],
        sensors: vec![Sensor {
            medium: None,
            camera: Camera {
                projection: Projection::Orthographic,
                // Looking down −z from z = 10; the film spans [-4, 4] in x.
                // (Mitsuba's look-at: +x = up × direction.)
                to_world: Mat4::from_cols(
                    glam::Vec4::new(-1.0, 0.0, 0.0, 0.0),
                    glam::Vec4::new(0.0, 1.0, 0.0, 0.0),
                    glam::Vec4::new(0.0, 0.0, -1.0, 0.0),
                    glam::Vec4::new(0.0, 0.0, 10.0, 1.0),
                ) * Mat4::from_scale(Vec3::new(4.0, 4.0, 1.0)),
                near_clip: 0.0,
                far_clip: 100.0,
            },
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
                spp,
                seed: 17,
            },
            integrator: None,
            name: None,
            loc: Default::default(),
        }],
        integrator: IntegratorDesc::Path(PathDesc::default()),
        ..Default::default()
    }
}

/// Length of `{τ ∈ [0, 1] : |a − τ·v| ≤ h}` (`h < 0`: empty).
fn interval(a: f32, v: f32, h: f32) -> (f32, f32) {
    if h < 0.0 {
        return (1.0, 0.0);
    }
    if v == 0.0 {
        return if a.abs() <= h { (0.0, 1.0) } else { (1.0, 0.0) };
    }
    let (t0, t1) = ((a - h) / v, (a + h) / v);
    (t0.min(t1).max(0.0), t0.max(t1).min(1.0))
}

/// Fraction of the shutter during which the ray from `o` along −z hits a shape.
fn covered(o: Vec3) -> f32 {
    // Sphere: the centre-to-line distance in the xy plane is at most r.
    let dy = o.y - SPHERE_C.y;
    let s = interval(
        o.x - SPHERE_C.x,
        SPHERE_V.x,
        (SPHERE_R * SPHERE_R - dy * dy).max(-1.0).sqrt_or_neg(),
    );
    // Square: both coordinates within h of the moving centre.
    let qx = interval(o.x - SQUARE_C.x, SQUARE_V.x, SQUARE_H);
    let qy = interval(o.y - SQUARE_C.y, SQUARE_V.y, SQUARE_H);
    let q = (qx.0.max(qy.0), qx.1.min(qy.1));
    // The two never overlap on screen (different rows).
    (s.1 - s.0).max(0.0) + (q.1 - q.0).max(0.0)
}

trait SqrtOrNeg {
    fn sqrt_or_neg(self) -> f32;
}
impl SqrtOrNeg for f32 {
    /// √x, or −1 (no interval) for x < 0.
    fn sqrt_or_neg(self) -> f32 {
        if self < 0.0 { -1.0 } else { self.sqrt() }
    }
}

#[test]
fn time_averaged_coverage_matches_the_analytic_fraction() {
    let (w, h, spp) = (32u32, 32u32, 2048u32);
    let desc = scene_desc(w, h, spp);
    let build::Built {
        scene, integrator, ..
    } = build(&desc, &BuildOptions::default()).unwrap();
    assert!(scene.has_motion);
    let img = render(
        &scene,
        &integrator,
        &RenderOptions {
            spp,
            ..Default::default()
        },
        &Silent,
    )
    .film
    .develop();

    // Expected coverage per pixel: midpoint rule over the pixel, rays from the camera itself.
    let g = 48;
    let mut tested = Vec::new();
    for j in 0..h {
        for i in 0..w {
            let mut c = 0.0f64;
            for a in 0..g {
                for b in 0..g {
                    let p = Vec2::new(
                        i as f32 + (a as f32 + 0.5) / g as f32,
                        j as f32 + (b as f32 + 0.5) / g as f32,
                    );
                    let ray = scene.camera.generate_ray(p, Vec2::ZERO).ray;
                    c += covered(ray.o.into()) as f64;
                }
            }
            let c = c / (g * g) as f64;
            let got = img.pixels[(j * w + i) as usize].x as f64;
            if c > 0.02 && c < 0.98 {
                tested.push((i, j, c, got));
            } else if c == 0.0 {
                assert_eq!(got, 1.0, "pixel ({i}, {j}) is never covered");
            }
        }
    }
    assert!(tested.len() >= 40, "only {} partial pixels", tested.len());
    let alpha = 1e-4 / tested.len() as f64;
    let z_max = Normal::new(0.0, 1.0)
        .unwrap()
        .inverse_cdf(1.0 - alpha / 2.0);
    let mut worst = 0.0f64;
    for &(i, j, c, got) in &tested {
        let sd = (c * (1.0 - c) / spp as f64).sqrt();
        let z = (got - (1.0 - c)) / sd;
        worst = worst.max(z.abs());
        assert!(
            z.abs() < z_max,
            "pixel ({i}, {j}): {got} vs expected {} (coverage {c}), z = {z:.2} > {z_max:.2}",
            1.0 - c
        );
    }
    println!(
        "{} partially covered pixels, worst |z| = {worst:.2} (Bonferroni bound {z_max:.2})",
        tested.len()
    );
}

#[test]
fn static_scenes_draw_no_time() {
    let mut desc = scene_desc(8, 8, 4);
    for s in &mut desc.shapes {
        s.motion = None;
    }
    assert!(
        !build(&desc, &BuildOptions::default())
            .unwrap()
            .scene
            .has_motion
    );
    for s in &mut desc.shapes {
        s.motion = Some(Vec3::ZERO);
    }
    assert!(
        !build(&desc, &BuildOptions::default())
            .unwrap()
            .scene
            .has_motion
    );
}
