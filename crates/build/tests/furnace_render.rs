//! White furnace through the whole renderer: a sphere inside a uniform environment of
//! radiance 1, made of an energy-conserving material that does not absorb, must look exactly
//! like the environment (radiance 1 everywhere), whatever the number of bounces.
//!
//! Statistics: 24×24 pixels × 64 spp of the path tracer (unbounded depth, Russian roulette),
//! the image mean must be within 1% of 1, and a z-test of the mean against 1 (standard error
//! from the per-pixel sample variances) must not reject at α = 0.001 per material.

use build::{BuildOptions, build};
use glam::{Mat4, Vec3};
use render::compare::image_mean;
use render::render::{RenderOptions, Silent, render};
use scene::{
    Camera, ColorParam, Emitter, EmitterDesc, FilterDesc, FovAxis, IntegratorDesc, Material,
    MaterialDesc, Projection, SamplerDesc, SamplerKind, SceneDesc, Sensor, Shape, ShapeDesc,
};

fn furnace(material: Material) -> (f64, f64) {
    furnace_with_fov(material, 30.0)
}

fn furnace_with_fov(material: Material, fov: f32) -> (f64, f64) {
    let mut desc = SceneDesc {
        integrator: IntegratorDesc::Path(scene::PathDesc::default()),
        ..Default::default()
    };
    let id = desc.add_material(MaterialDesc {
        material,
        ambient: Default::default(),
        name: None,
        loc: Default::default(),
    });
    desc.shapes.push(ShapeDesc {
        media: Default::default(),
        motion: None,
        shape: Shape::Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
        },
        to_world: Mat4::IDENTITY,
        material: Some(id),
        emission: None,
        flip_normals: false,
        name: None,
        loc: Default::default(),
    });
    desc.emitters.push(EmitterDesc {
        medium: None,
        emitter: Emitter::Constant {
            radiance: Vec3::ONE,
        },
        loc: Default::default(),
    });
    desc.sensors.push(Sensor {
        medium: None,
        camera: Camera {
            projection: Projection::Perspective {
                fov,
                fov_axis: FovAxis::X,
            },
            to_world: scene::formats::mitsuba::look_at(
                Vec3::new(0.0, 0.0, 4.0),
                Vec3::ZERO,
                Vec3::Y,
            )
            .unwrap(),
            near_clip: 0.0,
            far_clip: 100.0,
        },
        film: scene::Film {
            width: 24,
            height: 24,
            crop: None,
            filter: FilterDesc::Box { radius: 0.5 },
            output: None,
            tonemap: None,
        },
        sampler: SamplerDesc {
            kind: SamplerKind::Independent,
            spp: 64,
            seed: 3,
        },
        integrator: None,
        name: None,
        loc: Default::default(),
    });
    let build::Built { scene, integrator } = build(&desc, &BuildOptions::default()).unwrap();
    let out = render(
        &scene,
        &integrator,
        &RenderOptions {
            spp: 64,
            ..Default::default()
        },
        &Silent,
    );
    assert_eq!(out.film.nonfinite_count(), 0);
    image_mean(&out.film.develop(), &out.film.develop_stderr())
}

fn check(name: &str, m: Material) {
    let (mean, se) = furnace(m);
    let z = (mean - 1.0) / se.max(1e-9);
    println!("{name}: mean {mean:.5} ± {se:.5} (z = {z:.2})");
    assert!((mean - 1.0).abs() < 0.01, "{name}: furnace mean {mean}");
    // Two-sided z-test at α = 0.001: |z| < 3.29.
    assert!(
        z.abs() < 3.29,
        "{name}: furnace mean {mean} ± {se} rejects 1 (z = {z})"
    );
}

#[test]
fn diffuse_albedo_one() {
    check(
        "diffuse",
        Material::Diffuse {
            reflectance: ColorParam::constant(1.0),
        },
    );
}

#[test]
fn mirror() {
    check(
        "mirror",
        Material::Mirror {
            reflectance: ColorParam::constant(1.0),
        },
    );
}

#[test]
fn smooth_dielectric() {
    check(
        "dielectric",
        Material::Dielectric {
            int_ior: 1.5,
            ext_ior: 1.0,
            dispersion: None,
            specular_reflectance: ColorParam::constant(1.0),
            specular_transmittance: ColorParam::constant(1.0),
            absorption: None,
        },
    );
}

#[test]
fn thin_dielectric() {
    check(
        "thindielectric",
        Material::ThinDielectric {
            int_ior: 1.5,
            ext_ior: 1.0,
            dispersion: None,
            specular_reflectance: ColorParam::constant(1.0),
            specular_transmittance: ColorParam::constant(1.0),
        },
    );
}

/// Beer–Lambert absorption inside a smooth dielectric: an index-matched (η = 1, no Fresnel
/// reflection) sphere of radius 1 with σ = 0.5, seen through its centre by a 1° camera, so
/// every ray crosses 2·√(1 − b²) ≥ 1.9988 of it: the image is exp(−2σ) = e⁻¹ within 0.1 %.
#[test]
fn beer_lambert_absorption_in_a_dielectric() {
    let sigma = 0.5;
    let (mean, _) = furnace_with_fov(
        Material::Dielectric {
            int_ior: 1.0,
            ext_ior: 1.0,
            dispersion: None,
            specular_reflectance: ColorParam::constant(1.0),
            specular_transmittance: ColorParam::constant(1.0),
            absorption: Some(Vec3::splat(sigma)),
        },
        1.0,
    );
    let expected = (-2.0 * sigma as f64).exp();
    println!("beer: mean {mean:.6}, expected {expected:.6}");
    assert!(
        (mean / expected - 1.0).abs() < 1e-3,
        "mean {mean}, expected {expected}"
    );
}
