//! Tangent-space normal maps (Mitsuba's `normalmap` BSDF, the OBJ `map_bump`/`norm`):
//! - furnace: a normal-mapped diffuse plane of albedo 0.8 under a uniform environment of
//!   radiance 1 reflects exactly 0.8 wherever the view direction stays above the perturbed
//!   normal (here: tilts ≤ 35°, views within 15° of the geometric normal). Path tracer,
//!   64×64 × 64 spp; the image mean must be within 1 % of 0.8 and pass a z-test at α = 0.001;
//! - the map is applied: under an overhead directional light the same plane's shading varies
//!   with the perturbed normals (cos θ′), while the plane without the map is uniform.

use build::BuildOptions;
use build::render_desc;
use render::compare::image_mean;
use render::film::Image;
use render::image_io::write_image;
use render::math::Vec3;
use scene::{Document, LoadOptions};

fn dir() -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("penumbra-normal-map-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A 32×32 float normal map: x, y = ±0.2 sinusoids around 0.5, z = 0.9 (tilts ≤ 35°).
fn normal_map() -> std::path::PathBuf {
    let path = dir().join("normals.exr");
    let mut img = Image::new(32, 32);
    for y in 0..32 {
        for x in 0..32 {
            let (u, v) = (x as f32 / 32.0, y as f32 / 32.0);
            img.pixels[y * 32 + x] = Vec3::new(
                0.5 + 0.2 * (std::f32::consts::TAU * 2.0 * u).sin(),
                0.5 + 0.2 * (std::f32::consts::TAU * 3.0 * v).cos(),
                0.9,
            );
        }
    }
    write_image(&path, &img).unwrap();
    path
}

fn scene(bsdf: &str, light: &str, name: &str) -> scene::SceneDesc {
    let xml = format!(
        r#"<scene version="3.0.0">
    <integrator type="path"/>
    <sensor type="perspective">
        <float name="fov" value="30"/>
        <transform name="to_world"><lookat origin="0, 3, 0" target="0, 0, 0" up="0, 0, -1"/></transform>
        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="64"/>
            <rfilter type="box"/></film>
    </sensor>
    {light}
    <shape type="rectangle">
        <transform name="to_world"><scale value="10"/><rotate x="1" angle="-90"/></transform>
        {bsdf}
    </shape>
</scene>"#
    );
    let file = dir().join(name);
    std::fs::write(&file, xml).unwrap();
    let Document::Scene(desc) = scene::load(&file, &LoadOptions::default()).unwrap() else {
        panic!("not a scene")
    };
    *desc
}

fn mapped_bsdf() -> String {
    format!(
        r#"<bsdf type="normalmap">
            <texture name="normalmap" type="bitmap">
                <string name="filename" value="{}"/><boolean name="raw" value="true"/>
                <transform name="to_uv"><scale value="4"/></transform>
            </texture>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf>
        </bsdf>"#,
        normal_map().display()
    )
}

fn run(desc: &scene::SceneDesc, spp: u32) -> (Image, Image) {
    let out = render_desc(
        desc,
        &BuildOptions {
            spp: Some(spp),
            seed: Some(5),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(out.film.nonfinite_count(), 0);
    (out.film.develop(), out.film.develop_stderr())
}

#[test]
fn normal_mapped_diffuse_plane_furnace() {
    let desc = scene(
        &mapped_bsdf(),
        r#"<emitter type="constant"><rgb name="radiance" value="1"/></emitter>"#,
        "furnace.xml",
    );
    let (img, se) = run(&desc, 64);
    let (mean, se) = image_mean(&img, &se);
    let z = (mean - 0.8) / se.max(1e-9);
    println!("normal-mapped furnace: mean {mean:.5} ± {se:.5} (z = {z:.2})");
    assert!((mean / 0.8 - 1.0).abs() < 0.01, "mean {mean}");
    assert!(z.abs() < 3.29, "mean {mean} ± {se} rejects 0.8 (z = {z})");
}

#[test]
fn the_map_changes_the_shading() {
    let light = r#"<emitter type="directional">
        <vector name="direction" x="0" y="-1" z="0"/><rgb name="irradiance" value="1"/>
    </emitter>"#;
    let spread = |desc: &scene::SceneDesc| {
        let (img, _) = run(desc, 4);
        let v: Vec<f32> = img.pixels.iter().map(|p| p.x).collect();
        let m = v.iter().sum::<f32>() / v.len() as f32;
        (v.iter().map(|x| (x - m).powi(2)).sum::<f32>() / v.len() as f32).sqrt() / m
    };
    let plain = scene(
        r#"<bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf>"#,
        light,
        "plain.xml",
    );
    let mapped = scene(&mapped_bsdf(), light, "mapped.xml");
    let (s_plain, s_mapped) = (spread(&plain), spread(&mapped));
    println!("relative spread: plain {s_plain:.4}, mapped {s_mapped:.4}");
    assert!(
        s_plain < 1e-3,
        "a flat plane under a directional light is uniform"
    );
    // cos θ′ ranges over [0.82, 1] for these tilts: a spread of a few per cent.
    assert!(s_mapped > 0.02, "the normal map must modulate the shading");
}
