//! Mitsuba's `path` crosses `null` surfaces (index-matched boundaries) as a delta
//! transmission of weight 1 that counts as a bounce. So, with unbounded depth, a `null`
//! sphere changes nothing in expectation: shadow rays it blocks lose next-event estimation,
//! and the BSDF-sampled directions through it find the emitter with full weight instead.
//! Test: the image with the sphere minus the image without it has mean 0 in every channel
//! (z-test over 48² independent pixel differences, two-sided, α = 0.001 over 3 channels,
//! Šidák). Absorbing at the sphere instead (the old behaviour) leaves a black disc: rejected.

use base::testing::z_of_mean_difference;
use build::{BuildOptions, render_desc};
use statrs::distribution::{ContinuousCDF, Normal};

fn render(name: &str, sphere: &str) -> Vec<[f32; 3]> {
    let xml = format!(
        r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="-1"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="50"/>
        <transform name="to_world"><lookat origin="0, 1, 3.5" target="0, 0.8, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
        <film type="hdrfilm"><integer name="width" value="48"/><integer name="height" value="48"/><rfilter type="box"/></film>
    </sensor>
    <bsdf type="diffuse" id="grey"><rgb name="reflectance" value="0.7, 0.6, 0.5"/></bsdf>
    <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/><scale value="2"/></transform><ref id="grey"/></shape>
    <shape type="rectangle"><transform name="to_world"><scale value="2"/><translate y="1" z="-1.5"/></transform><ref id="grey"/></shape>
    <shape type="rectangle">
        <transform name="to_world"><rotate x="1" angle="90"/><scale value="0.5"/><translate y="2.2"/></transform>
        <emitter type="area"><rgb name="radiance" value="10, 9, 8"/></emitter>
    </shape>
    {sphere}
</scene>"#
    );
    let desc = scene::load_xml_text(&format!("null-{name}"), &xml).unwrap();
    let out = render_desc(&desc, &BuildOptions::default()).unwrap();
    assert_eq!(out.film.nonfinite_count(), 0);
    out.film
        .develop()
        .pixels
        .iter()
        .map(|p| p.to_array())
        .collect()
}

#[test]
fn a_null_sphere_changes_nothing_in_expectation() {
    let sphere = |bsdf: &str| {
        format!(
            r#"<shape type="sphere"><point name="center" x="0.1" y="0.9" z="0.6"/><float name="radius" value="0.6"/>{bsdf}</shape>"#
        )
    };
    let without = render("without", "");
    let with = render("with", &sphere(r#"<bsdf type="null"/>"#));
    let crit = Normal::new(0.0, 1.0)
        .unwrap()
        .inverse_cdf(1.0 - (1.0 - (1.0 - 0.001f64).powf(1.0 / 3.0)) / 2.0);
    let z = z_of_mean_difference(&with, &without);
    println!("with − without the null sphere: z = {z:.2?} (|z| < {crit:.2})");
    assert!(z.iter().all(|z| z.abs() < crit), "z = {z:?}");
    // Not vacuous: a black (absorbing) sphere in the same place is rejected.
    let black = render(
        "black",
        &sphere(r#"<bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>"#),
    );
    let z = z_of_mean_difference(&black, &without);
    println!("with a black sphere: z = {z:.2?}");
    assert!(z.iter().any(|z| z.abs() >= crit), "z = {z:?}");
}
