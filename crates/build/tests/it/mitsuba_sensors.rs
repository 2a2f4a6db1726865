//! Mitsuba 3's `radiancemeter` and `irradiancemeter` sensors (issue 38): 1×1 films, checked
//! against analytic values, the irradiance meter also against Mitsuba 3.9.1's render of
//! `scenes/mitsuba/irradiancemeter.xml`.

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
    pixel_stats_spp(desc, 32)
}

/// [`pixel_stats`] over batches of `spp` samples.
fn pixel_stats_spp(desc: &scene::SceneDesc, spp: u32) -> (Vec3, Vec3) {
    let batches = render_desc_batches(desc, spp, scene::RenderMode::Rgb);
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

/// A scene with an irradiance meter on `meter_shape` (its shape element's inner XML: a type
/// attribute is given by `ty`), `rest` the other elements.
fn irradiance_scene(ty: &str, meter_shape: &str, rest: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="2"/></integrator>
    {rest}
    <shape type="{ty}">
        {meter_shape}
        <sensor type="irradiancemeter">
            <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
            <film type="hdrfilm">
                <integer name="width" value="1"/><integer name="height" value="1"/>
            </film>
        </sensor>
    </shape>
</scene>"#
    )
}

/// Under a constant sky of radiance L every point of a convex shape sees sky over its whole
/// hemisphere: E = π·L, with no variance (a disk, a sphere, a cube and a cylinder: every way
/// a point is placed). A small disk under a coaxial emitting disk of radius R at height h
/// (nothing else): E = π·L·R²/(R² + h²).
#[test]
fn irradiancemeter_measures_analytic_irradiance() {
    let l = Vec3::new(0.3, 0.5, 0.7);
    let sky = r#"<emitter type="constant"><rgb name="radiance" value="0.3, 0.5, 0.7"/></emitter>"#;
    let xform =
        r#"<transform name="to_world"><rotate x="1" angle="30"/><translate z="2"/></transform>"#;
    for ty in ["disk", "sphere", "cube", "cylinder"] {
        let (mean, _) = pixel_stats(&load(
            &format!("irr-sky-{ty}"),
            &irradiance_scene(ty, xform, sky),
        ));
        let want = std::f32::consts::PI * l;
        assert!(
            ((mean - want) / want).abs().max_element() < 1e-5,
            "{ty}: {mean} vs {want}"
        );
    }

    let (r, h, le) = (0.5f32, 1.5f32, 2.0f32);
    let light = format!(
        r#"<shape type="disk">
        <transform name="to_world"><scale value="{r}"/><rotate x="1" angle="180"/><translate z="{h}"/></transform>
        <emitter type="area"><rgb name="radiance" value="{le}"/></emitter>
    </shape>"#
    );
    let tiny = r#"<transform name="to_world"><scale value="0.001"/></transform>"#;
    let (mean, se) = pixel_stats_spp(
        &load("irr-disk", &irradiance_scene("disk", tiny, &light)),
        4096,
    );
    let want = std::f32::consts::PI * le * r * r / (r * r + h * h);
    // |z| < 4.5 per channel (three channels, α ≈ 2·10⁻⁵).
    let z = (mean - Vec3::splat(want)).abs() / se.max(Vec3::splat(1e-6));
    eprintln!("irradiancemeter under a disk light: {mean} vs {want}, standard error {se}");
    assert!(
        z.max_element() < 4.5,
        "{mean} vs {want} (standard error {se})"
    );
}

/// `scenes/mitsuba/irradiancemeter.xml` (a tilted disk lit by an area light, a floor, a
/// sphere's shadow and a sky, paths of up to 4 bounces) against Mitsuba 3.9.1's 32 × 65536
/// samples: 32 batches of 16384 samples here, each channel's difference of the means within
/// 4 combined standard errors (three channels, α ≈ 2·10⁻⁴).
#[test]
fn irradiancemeter_matches_mitsuba() {
    use crate::repo_references::mitsuba_scenes;
    let dir = mitsuba_scenes();
    let scene::Document::Scene(desc) =
        scene::load(&dir.join("irradiancemeter.xml"), &Default::default()).unwrap()
    else {
        panic!("not a scene")
    };
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    let opts = build::BuildOptions {
        spp: Some(16384),
        ..Default::default()
    };
    let vals: Vec<Vec3> = build::render_seeds(&desc, &opts, 0..32)
        .unwrap()
        .iter()
        .map(|o| {
            let p = o.film.develop().get(0, 0);
            Vec3::new(p.x, p.y, p.z)
        })
        .collect();
    let n = vals.len() as f32;
    let mean = vals.iter().copied().sum::<Vec3>() / n;
    let var = vals.iter().map(|v| (*v - mean) * (*v - mean)).sum::<Vec3>() / (n - 1.0);
    let se = (var / n).powf(0.5);
    let reference = render::compare::load_reference(&dir.join("refs/irradiancemeter")).unwrap();
    let (rm, rs) = (reference.mean.get(0, 0), reference.stderr.get(0, 0));
    let (rm, rs) = (Vec3::new(rm.x, rm.y, rm.z), Vec3::new(rs.x, rs.y, rs.z));
    let z = (mean - rm) / (se * se + rs * rs).powf(0.5);
    eprintln!(
        "irradiancemeter vs Mitsuba: {mean} ± {se} vs {rm} ± {rs}, ratio {}, z {z}",
        mean / rm
    );
    assert!(z.abs().max_element() < 4.0, "z = {z}");
}

/// Mitsuba's rules: nested in a shape, no to_world of its own, a 1×1 film; no other sensor
/// in a shape; and the integrators that do not start their paths at the camera refuse it.
#[test]
fn irradiancemeter_refuses_what_mitsuba_refuses() {
    let good = irradiance_scene("disk", "", "");
    let bad = [
        good.replace(r#"value="1"/><integer"#, r#"value="2"/><integer"#),
        good.replace(
            r#"<sensor type="irradiancemeter">"#,
            r#"<sensor type="irradiancemeter"><transform name="to_world"><translate z="1"/></transform>"#,
        ),
        good.replace("irradiancemeter", "perspective"),
        meter_scene("0, 0, 1", "0, 0, -1").replace("radiancemeter", "irradiancemeter"),
    ];
    for (i, xml) in bad.iter().enumerate() {
        let dir = std::env::temp_dir().join(format!("penumbra-irr-bad{i}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("scene.xml");
        std::fs::write(&path, xml).unwrap();
        let r = scene::load(&path, &Default::default());
        let _ = std::fs::remove_dir_all(&dir);
        assert!(r.is_err(), "case {i} loads");
    }
    let desc = load(
        "irr-bdpt",
        &good.replace(r#"<integrator type="path">"#, r#"<integrator type="bdpt">"#),
    );
    assert!(build::build(&desc, &Default::default()).is_err());
}
