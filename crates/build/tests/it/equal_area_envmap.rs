//! pbrt-v4's equal-area octahedral environment maps render as the same environment stored as
//! a lat-long map: a smooth sky with a bright lobe, written once as a 128² equal-area square
//! and once resampled (nearest, as pbrt-v4 looks the square up) into a 1024 × 512 lat-long
//! image, lights a diffuse sphere seen against it. Path tracer; the block t-test of 16 × 32
//! spp equal-area renders against 8 × 128 spp lat-long ones (α = 0.01, Šidák-corrected
//! inside `compare`).

use build::{BuildOptions, render_seeds};
use render::compare::{Reference, TestImages, compare};
use render::film::Image;
use render::image_io::write_image;
use render::math::{Vec2, Vec3};
use render::sampling::warp::{equal_area_sphere_to_square, equal_area_square_to_sphere};
use scene::{Emitter, EnvMapping};

fn sky(d: Vec3) -> Vec3 {
    let lobe = d
        .dot(Vec3::new(0.5, 0.6, 0.62).normalize())
        .max(0.0)
        .powi(8);
    Vec3::new(0.3 + 0.2 * d.y, 0.4 + 0.1 * d.x, 0.5 - 0.2 * d.z) + Vec3::new(6.0, 5.0, 3.0) * lobe
}

fn maps(dir: &std::path::Path) -> (std::path::PathBuf, std::path::PathBuf) {
    let n = 128u32;
    let mut square = Image::new(n, n);
    for y in 0..n {
        for x in 0..n {
            let uv = (Vec2::new(x as f32, y as f32) + 0.5) / n as f32;
            square.set(x, y, sky(equal_area_square_to_sphere(uv)));
        }
    }
    let (w, h) = (1024u32, 512u32);
    let mut latlong = Image::new(w, h);
    for y in 0..h {
        for x in 0..w {
            // Mitsuba's lat-long grid: columns at pixel centres, rows at grid vertices; local
            // direction (sin θ sin φ, cos θ, −sin θ cos φ).
            let (u, v) = ((x as f32 + 0.5) / w as f32, y as f32 / (h - 1) as f32);
            let (theta, phi) = (v * std::f32::consts::PI, u * std::f32::consts::TAU);
            let d = Vec3::new(
                theta.sin() * phi.sin(),
                theta.cos(),
                -theta.sin() * phi.cos(),
            );
            let uv = equal_area_sphere_to_square(d);
            let px = |t: f32| ((t * n as f32) as u32).min(n - 1);
            latlong.set(x, y, square.get(px(uv.x), px(uv.y)));
        }
    }
    let (a, b) = (dir.join("sky-square.exr"), dir.join("sky-latlong.exr"));
    write_image(&a, &square).unwrap();
    write_image(&b, &latlong).unwrap();
    (a, b)
}

fn scene_xml(latlong: &std::path::Path) -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="4"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="50"/>
        <transform name="to_world"><lookat origin="0.5, 0.8, 4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="48"/><integer name="height" value="48"/></film>
    </sensor>
    <emitter type="envmap"><string name="filename" value="{}"/></emitter>
    <shape type="sphere"><bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.6, 0.5"/></bsdf></shape>
</scene>"#,
        latlong.display()
    )
}

fn batches(desc: &scene::SceneDesc, count: u64, spp: u32) -> Vec<Image> {
    let opts = BuildOptions {
        spp: Some(spp),
        ..Default::default()
    };
    render_seeds(desc, &opts, 300..300 + count)
        .unwrap()
        .into_iter()
        .map(|out| {
            assert_eq!(out.film.nonfinite_count(), 0);
            out.film.develop()
        })
        .collect()
}

#[test]
fn equal_area_map_renders_as_the_same_lat_long_map() {
    let dir = std::env::temp_dir().join(format!("penumbra-equal-area-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (square, latlong) = maps(&dir);
    let reference_desc = scene::load_xml_text("latlong", &scene_xml(&latlong)).unwrap();
    let mut desc = reference_desc.clone();
    let Emitter::EnvMap { path, mapping, .. } = &mut desc.emitters[0].emitter else {
        panic!("the scene's emitter is an envmap");
    };
    *path = square;
    *mapping = EnvMapping::EqualArea;
    let reference = Reference::from_batches(&batches(&reference_desc, 8, 128)).unwrap();
    let result = compare(&reference, &TestImages::Batches(batches(&desc, 16, 32))).unwrap();
    println!("equal-area vs lat-long: {result}");
    assert!(result.passed, "{result}");
}
