//! Mitsuba 3's `radiancemeter` sensor (issue 38): a 1×1 film whose every sample is one ray,
//! checked against analytic values.

use glam::Vec3;

use crate::references::render_desc_batches;

/// Loads a Mitsuba scene given as text (written to a temporary file).
fn load(name: &str, xml: &str) -> scene::SceneDesc {
    let dir = std::env::temp_dir().join(format!("penumbra-{name}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("scene.xml");
    std::fs::write(&path, xml).unwrap();
    let loaded = scene::load(&path, &Default::default());
    let _ = std::fs::remove_dir_all(&dir);
    let scene::Document::Scene(desc) = loaded.unwrap() else {
        panic!("not a scene")
    };
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    *desc
}

fn meter_scene(origin: &str, direction: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="2"/></integrator>
    <sensor type="radiancemeter">
        <point name="origin" value="{origin}"/>
        <vector name="direction" value="{direction}"/>
        <sampler type="independent"><integer name="sample_count" value="32"/></sampler>
        <film type="hdrfilm">
            <integer name="width" value="1"/><integer name="height" value="1"/>
        </film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="0.3, 0.5, 0.7"/></emitter>
    <shape type="rectangle">
        <transform name="to_world"><scale value="1000"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.4, 0.2"/></bsdf>
    </shape>
</scene>"#
    )
}

/// The mean and standard error of the single pixel over the batches.
fn pixel_stats(desc: &scene::SceneDesc) -> (Vec3, Vec3) {
    let batches = render_desc_batches(desc, 32, scene::RenderMode::Rgb);
    let vals: Vec<Vec3> = batches
        .iter()
        .map(|img| {
            assert_eq!((img.width, img.height), (1, 1));
            let p = img.get(0, 0);
            Vec3::new(p.x, p.y, p.z)
        })
        .collect();
    let n = vals.len() as f32;
    let mean = vals.iter().copied().sum::<Vec3>() / n;
    let var = vals.iter().map(|v| (*v - mean) * (*v - mean)).sum::<Vec3>() / (n - 1.0);
    (mean, (var / n).powf(0.5))
}

/// Looking up into the sky: exactly the sky's radiance. Looking down at a large diffuse
/// plane under it (direct light only): ρ·L, the plane seeing sky over its whole
/// hemisphere (E = πL, Lo = ρ/π·E).
#[test]
fn radiancemeter_measures_analytic_radiance() {
    let sky = Vec3::new(0.3, 0.5, 0.7);
    let (mean, _) = pixel_stats(&load("meter-up", &meter_scene("0, 0, 1", "0.1, -0.2, 1")));
    assert!((mean - sky).abs().max_element() < 1e-5, "{mean} vs {sky}");

    let want = Vec3::new(0.5, 0.4, 0.2) * sky;
    let (mean, se) = pixel_stats(&load(
        "meter-down",
        &meter_scene("0.2, 0.1, 1", "0.3, 0.2, -1"),
    ));
    // |z| < 4.5 per channel (three channels, α ≈ 2·10⁻⁵), with a floor for a zero spread.
    let z = (mean - want).abs() / se.max(Vec3::splat(1e-6));
    assert!(
        z.max_element() < 4.5,
        "{mean} vs {want} (standard error {se})"
    );
    eprintln!("radiancemeter: {mean} vs {want}, standard error {se}");
}

/// Mitsuba's rules: a 1×1 film, origin and direction together, not with a to_world.
#[test]
fn radiancemeter_refuses_what_mitsuba_refuses() {
    let bad = [
        meter_scene("0, 0, 1", "0, 0, -1")
            .replace(r#"value="1"/><integer"#, r#"value="2"/><integer"#),
        meter_scene("0, 0, 1", "0, 0, -1")
            .replace(r#"<vector name="direction" value="0, 0, -1"/>"#, ""),
    ];
    for (i, xml) in bad.iter().enumerate() {
        let dir =
            std::env::temp_dir().join(format!("penumbra-meter-bad{i}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("scene.xml");
        std::fs::write(&path, xml).unwrap();
        let r = scene::load(&path, &Default::default());
        let _ = std::fs::remove_dir_all(&dir);
        assert!(r.is_err(), "case {i} loads");
    }
}
