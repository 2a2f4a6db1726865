//! Emissive media. A purely absorbing, emitting homogeneous slab of thickness d seen head-on
//! by an orthographic camera reads Le·(1 − e^{−σa·d}) in every pixel (the collision estimator
//! of `volpath`): a z-test per channel on the image mean (pixels are independent; α = 0.001
//! Šidák-corrected over 3 channels, |z| < 3.59). A temperature grid renders finite, positive
//! black-body light.

use std::path::PathBuf;

use build::{BuildOptions, render_desc};
use scene::Document;

fn dir() -> PathBuf {
    let d = std::env::temp_dir().join(format!("penumbra-media-emission-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn render(name: &str, xml: &str) -> render::film::Image {
    let path = dir().join(format!("{name}.xml"));
    std::fs::write(&path, xml).unwrap();
    let Document::Scene(desc) = scene::load(&path, &Default::default()).unwrap() else {
        panic!("not a scene")
    };
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    let out = render_desc(&desc, &BuildOptions::default()).unwrap();
    assert_eq!(out.film.nonfinite_count(), 0);
    out.film.develop()
}

fn scene(medium: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="volpath"><integer name="max_depth" value="-1"/></integrator>
    <sensor type="orthographic">
        <transform name="to_world"><scale value="0.5"/><lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/><rfilter type="box"/></film>
    </sensor>
    <shape type="cube">
        <transform name="to_world"><scale x="2" y="2" z="0.25"/></transform>
        <bsdf type="null"/>
        {medium}
    </shape>
</scene>"#
    )
}

#[test]
fn absorbing_emitting_slab_reads_le_times_its_opacity() {
    let (sigma_a, d) = (3.0f64, 0.5f64);
    let le = [1.0f64, 2.0, 3.0];
    let img = render(
        "slab",
        &scene(
            r#"<medium type="homogeneous" name="interior">
            <float name="sigma_t" value="3"/>
            <float name="albedo" value="0"/>
            <rgb name="radiance" value="1, 2, 3"/>
        </medium>"#,
        ),
    );
    let n = img.pixels.len() as f64;
    for c in 0..3 {
        let v: Vec<f64> = img.pixels.iter().map(|p| p[c] as f64).collect();
        let mean = v.iter().sum::<f64>() / n;
        let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (n - 1.0);
        let se = (var / n).sqrt();
        let want = le[c] * (1.0 - (-sigma_a * d).exp());
        let z = (mean - want) / se.max(1e-12);
        println!("channel {c}: {mean:.5} ± {se:.5}, expected {want:.5} (z = {z:.2})");
        assert!(z.abs() < 3.59, "channel {c}: {mean} ± {se} vs {want}");
    }
}

#[test]
fn a_temperature_grid_glows() {
    let Some(refs) = scene::testing::shared_dir("references") else {
        return;
    };
    let grid = refs.join("scenes/plume-temperature.vol");
    let img = render(
        "hot",
        &scene(&format!(
            r#"<medium type="homogeneous" name="interior">
            <float name="sigma_t" value="2"/>
            <float name="albedo" value="0.5"/>
            <volume type="gridvolume" name="temperature">
                <string name="filename" value="{}"/>
                <transform name="to_world"><scale x="2" y="2" z="0.5"/><translate x="-1" y="-1" z="-0.25"/></transform>
            </volume>
            <float name="emission_scale" value="1e-4"/>
        </medium>"#,
            grid.display()
        )),
    );
    let total: f32 = img.pixels.iter().map(|p| p.x + p.y + p.z).sum();
    assert!(total > 0.0 && total.is_finite(), "{total}");
    // Black bodies of a few thousand kelvin are red: more red than blue overall.
    let (r, b): (f32, f32) = img
        .pixels
        .iter()
        .fold((0.0, 0.0), |(r, b), p| (r + p.x, b + p.z));
    assert!(r > b, "red {r} vs blue {b}");
}
