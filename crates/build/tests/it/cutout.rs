//! Alpha cut-outs (Mitsuba's `mask` BSDF, OBJ `map_d`/`d`): a surface of opacity α is hit
//! with probability α and passed through otherwise, for camera rays, scattered rays and
//! shadow rays alike. Analytic checks (z-tests at α = 0.001, |z| < 3.29, 64×64 pixels):
//! - a black plane of opacity 0.3 in front of a uniform environment of radiance 1 shows 0.7;
//! - a diffuse floor (ρ = 0.5) seen and lit through a black mask of opacity 0.4: under an
//!   emitting ceiling (radiance 1, wide enough to act as an infinite plane) the floor receives
//!   (1 − α)·π·L and the camera, above the mask, sees (1 − α)²·ρ·L = 0.18 — found by
//!   BSDF-sampled rays, as next-event estimation of so large an emitter has a negligible MIS
//!   weight; under a directional light of irradiance 1 it sees (1 − α)²·ρ/π, found by shadow
//!   rays alone (a delta light);
//! - a fully opaque mask (α = 1) is an ordinary surface and α = 0 an absent one;
//! - an opacity bitmap with an alpha channel (an RGBA `map_d`) uses that channel, not red.

use build::BuildOptions;
use build::render_desc;
use render::compare::image_mean;
use scene::{Document, LoadOptions};

fn scene(body: &str, name: &str) -> scene::SceneDesc {
    let xml = format!(
        r#"<scene version="3.0.0">
    <integrator type="path"/>
    <sensor type="perspective">
        <float name="fov" value="30"/>
        <transform name="to_world"><lookat origin="0, 1.5, 0" target="0, 0, 0" up="0, 0, -1"/></transform>
        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="64"/>
            <rfilter type="box"/></film>
    </sensor>
    {body}
</scene>"#
    );
    let dir = std::env::temp_dir().join(format!("penumbra-cutout-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join(name);
    std::fs::write(&file, xml).unwrap();
    let Document::Scene(desc) = scene::load(&file, &LoadOptions::default()).unwrap() else {
        panic!("not a scene")
    };
    *desc
}

fn masked_black_plane(height: f32, opacity: f32) -> String {
    format!(
        r#"<shape type="rectangle">
        <transform name="to_world"><scale value="100"/><rotate x="1" angle="-90"/><translate y="{height}"/></transform>
        <bsdf type="mask"><float name="opacity" value="{opacity}"/>
            <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
        </bsdf>
    </shape>"#
    )
}

/// Mean over pixels and channels, and its standard error (from the per-pixel standard errors).
fn mean_and_se(desc: &scene::SceneDesc, spp: u32) -> (f64, f64) {
    let out = render_desc(
        desc,
        &BuildOptions {
            spp: Some(spp),
            seed: Some(3),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(out.film.nonfinite_count(), 0);
    image_mean(&out.film.develop(), &out.film.develop_stderr())
}

fn check(what: &str, (mean, se): (f64, f64), expected: f64) {
    let z = (mean - expected) / se.max(1e-12);
    println!("{what}: mean {mean:.5} ± {se:.5}, expected {expected:.5} (z = {z:.2})");
    assert!(
        z.abs() < 3.29,
        "{what}: {mean} ± {se} rejects {expected} (z = {z})"
    );
}

#[test]
fn camera_rays_pass_a_partial_mask() {
    let env = r#"<emitter type="constant"><rgb name="radiance" value="1"/></emitter>"#;
    let desc = scene(
        &format!("{env}{}", masked_black_plane(0.0, 0.3)),
        "view.xml",
    );
    check("opacity 0.3 over radiance 1", mean_and_se(&desc, 16), 0.7);
    // The limits are exact: every sample sees the same thing.
    let opaque = scene(
        &format!("{env}{}", masked_black_plane(0.0, 1.0)),
        "opaque.xml",
    );
    assert_eq!(mean_and_se(&opaque, 2).0, 0.0);
    let absent = scene(
        &format!("{env}{}", masked_black_plane(0.0, 0.0)),
        "absent.xml",
    );
    assert!((mean_and_se(&absent, 2).0 - 1.0).abs() < 1e-6);
}

#[test]
fn light_reaches_through_a_mask_by_both_strategies() {
    // A diffuse floor (ρ = 0.5) under a black mask of opacity 0.4, lit by `light`.
    let lit_floor = |light: &str, name: &str| {
        let body = format!(
            r#"{light}
    <shape type="rectangle">
        <transform name="to_world"><scale value="1000"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf>
    </shape>
    {}"#,
            masked_black_plane(1.0, 0.4)
        );
        mean_and_se(&scene(&body, name), 64)
    };
    let ceiling = r#"<shape type="rectangle">
        <transform name="to_world"><scale value="1000"/><rotate x="1" angle="90"/><translate y="2"/></transform>
        <emitter type="area"><rgb name="radiance" value="1"/></emitter>
    </shape>"#;
    // A 1000 m ceiling 2 m up subtends all but 2·10⁻⁶ of the cosine-weighted hemisphere.
    check(
        "ceiling through opacity 0.4",
        lit_floor(ceiling, "lit.xml"),
        0.6 * 0.6 * 0.5,
    );
    let sun = r#"<emitter type="directional">
        <vector name="direction" x="0" y="-1" z="0"/><rgb name="irradiance" value="1"/>
    </emitter>"#;
    let expected = 0.6 * 0.6 * 0.5 / std::f64::consts::PI;
    check(
        "sun through opacity 0.4",
        lit_floor(sun, "sun.xml"),
        expected,
    );
}

#[test]
fn an_rgba_opacity_map_uses_its_alpha_channel() {
    let dir = std::env::temp_dir().join(format!("penumbra-cutout-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // Red 255 everywhere (opaque if red were read), alpha 64/255.
    let png = dir.join("leaf.png");
    image::RgbaImage::from_pixel(4, 4, image::Rgba([255, 0, 0, 64]))
        .save(&png)
        .unwrap();
    let body = format!(
        r#"<emitter type="constant"><rgb name="radiance" value="1"/></emitter>
    <shape type="rectangle">
        <transform name="to_world"><scale value="100"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="mask">
            <texture name="opacity" type="bitmap"><string name="filename" value="{}"/></texture>
            <bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>
        </bsdf>
    </shape>"#,
        png.display()
    );
    let desc = scene(&body, "rgba.xml");
    check(
        "RGBA opacity map",
        mean_and_se(&desc, 16),
        1.0 - 64.0 / 255.0,
    );
}
