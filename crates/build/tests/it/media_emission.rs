//! Emissive media. A purely absorbing, emitting homogeneous slab of thickness d seen head-on
//! by an orthographic camera reads Le·(1 − e^{−σa·d}) in every pixel (the collision estimator
//! of `volpath`): a z-test per channel on the image mean (pixels are independent; α = 0.001
//! Šidák-corrected over 3 channels, |z| < 3.59). A temperature grid renders finite, positive
//! black-body light.

use build::{BuildOptions, render_desc};

fn render(name: &str, xml: &str) -> render::film::Image {
    let desc = scene::load_xml_text(name, xml).unwrap();
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

/// A smoke plume that glows (density and temperature grids): emission found only at
/// collisions and emission importance-sampled from every scattering vertex are two unbiased
/// estimators of the same image; their image means agree (z-test, α = 0.001: |z| < 3.29).
#[test]
fn emission_sampling_and_collisions_agree() {
    let Some(refs) = scene::testing::shared_dir("references") else {
        return;
    };
    let scenes = refs.join("scenes");
    let xml = |sample: bool| {
        format!(
            r#"<scene version="3.0.0">
    <integrator type="volpath"><integer name="max_depth" value="8"/><boolean name="sample_emission" value="{sample}"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0.2, 1.2, 3.5" target="0, 0.7, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="64"/></sampler>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/><rfilter type="box"/></film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world"><rotate x="1" angle="-90"/><scale value="4"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf>
    </shape>
    <shape type="cube">
        <transform name="to_world"><translate x="1" y="1" z="1"/><scale value="0.8"/><translate x="-0.8" y="0.001" z="-0.8"/></transform>
        <bsdf type="null"/>
        <medium type="heterogeneous" name="interior">
            <volume type="gridvolume" name="sigma_t">
                <string name="filename" value="{dir}/plume-density.vol"/>
                <transform name="to_world"><scale value="1.6"/><translate x="-0.8" y="0.001" z="-0.8"/></transform>
            </volume>
            <volume type="gridvolume" name="temperature">
                <string name="filename" value="{dir}/plume-temperature.vol"/>
                <transform name="to_world"><scale value="1.6"/><translate x="-0.8" y="0.001" z="-0.8"/></transform>
            </volume>
            <float name="emission_scale" value="0.01"/>
            <float name="scale" value="6"/>
            <rgb name="albedo" value="0.6, 0.6, 0.6"/>
        </medium>
    </shape>
</scene>"#,
            dir = scenes.display()
        )
    };
    let mean = |sample: bool| {
        let desc = scene::load_xml_text(&format!("plume-{sample}"), &xml(sample)).unwrap();
        let out = render_desc(&desc, &BuildOptions::default()).unwrap();
        assert_eq!(out.film.nonfinite_count(), 0);
        render::compare::image_mean(&out.film.develop(), &out.film.develop_stderr())
    };
    let (a, sa) = mean(true);
    let (b, sb) = mean(false);
    let z = (a - b) / (sa * sa + sb * sb).sqrt().max(1e-12);
    println!("sampled {a:.5} ± {sa:.5}, collisions {b:.5} ± {sb:.5} (z = {z:.2})");
    assert!(a > 0.0 && b > 0.0);
    assert!(z.abs() < 3.29, "the estimators disagree: z = {z}");
}

/// A glowing, scattering homogeneous sphere (null boundary) over a floor lit by an area
/// light, seen by a perspective camera.
fn glowing_sphere(integrator: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    {integrator}
    <sensor type="perspective">
        <float name="fov" value="45"/>
        <transform name="to_world"><lookat origin="0, 1.5, 4" target="0, 0.6, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="32"/></sampler>
        <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="32"/><rfilter type="box"/></film>
    </sensor>
    <shape type="rectangle">
        <transform name="to_world"><rotate x="1" angle="-90"/><scale value="3"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.5, 0.5, 0.5"/></bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world"><rotate x="1" angle="90"/><scale value="0.5"/><translate x="1" y="2.5"/></transform>
        <emitter type="area"><rgb name="radiance" value="4, 4, 4"/></emitter>
    </shape>
    <shape type="sphere">
        <point name="center" x="0" y="0.7" z="0"/><float name="radius" value="0.6"/>
        <bsdf type="null"/>
        <medium type="homogeneous" name="interior">
            <rgb name="sigma_t" value="1, 2, 3"/>
            <float name="albedo" value="0.5"/>
            <rgb name="radiance" value="1, 0.5, 0.2"/>
        </medium>
    </shape>
</scene>"#
    )
}

/// `count` renders of the glowing sphere with `integrator` at `spp`, seeds 100, 101, ….
fn batches(integrator: &str, count: u64, spp: u32) -> Vec<render::film::Image> {
    let desc = scene::load_xml_text("glow", &glowing_sphere(integrator)).unwrap();
    let opts = BuildOptions {
        spp: Some(spp),
        ..Default::default()
    };
    build::render_seeds(&desc, &opts, 100..100 + count)
        .unwrap()
        .into_iter()
        .map(|out| {
            assert_eq!(out.film.nonfinite_count(), 0, "{integrator}");
            out.film.develop()
        })
        .collect()
}

/// The glowing sphere by `volpath`, 8 × 512 spp: the reference of the two tests below,
/// rendered once for both.
fn volpath_reference() -> &'static render::compare::Reference {
    static REFERENCE: std::sync::OnceLock<render::compare::Reference> = std::sync::OnceLock::new();
    REFERENCE.get_or_init(|| {
        let volpath =
            r#"<integrator type="volpath"><integer name="max_depth" value="8"/></integrator>"#;
        render::compare::Reference::from_batches(&batches(volpath, 8, 512)).unwrap()
    })
}

/// BDPT and MLT find a medium's emission (by the camera subpath's collision estimator,
/// the one strategy that samples it) and light scattered in it: BDPT against `volpath` by
/// the block t-test (16 × 32 spp against 8 × 512 spp, α = 0.01 Šidák-corrected inside);
/// MLT's image mean over 4 seeds against volpath's, z-test at α = 0.001 per channel
/// (Šidák over 3: |z| < 3.59).
#[test]
fn bdpt_and_mlt_render_emitting_media_as_volpath_does() {
    use render::compare::{TestImages, compare};
    let reference = volpath_reference();
    let bdpt = r#"<integrator type="bdpt"><integer name="max_depth" value="8"/></integrator>"#;
    let result = compare(reference, &TestImages::Batches(batches(bdpt, 16, 32))).unwrap();
    println!("bdpt: {result}");
    assert!(result.passed, "bdpt: {result}");

    let mlt = r#"<integrator type="pssmlt"><integer name="maxDepth" value="8"/>
        <integer name="luminanceSamples" value="20000"/><integer name="chains" value="64"/></integrator>"#;
    let means: Vec<[f64; 3]> = batches(mlt, 4, 256)
        .iter()
        .map(|img| {
            let n = img.pixels.len() as f64;
            [0, 1, 2].map(|c| img.pixels.iter().map(|p| p[c] as f64).sum::<f64>() / n)
        })
        .collect();
    let r = &reference.mean;
    for c in 0..3 {
        let want = r.pixels.iter().map(|p| p[c] as f64).sum::<f64>() / r.pixels.len() as f64;
        let m = means.iter().map(|x| x[c]).sum::<f64>() / 4.0;
        let sd = (means.iter().map(|x| (x[c] - m).powi(2)).sum::<f64>() / 3.0).sqrt();
        let z = (m - want) / (sd / 2.0).max(1e-4 * want);
        println!("mlt channel {c}: {m:.5} (sd of seeds {sd:.5}) vs volpath {want:.5}: z = {z:.2}");
        assert!(z.abs() < 3.59, "mlt channel {c}: {m} vs {want}");
    }
}

/// Light paths start in emitting media too (`photons/sources.rs`): on the glowing sphere,
/// light tracing and the photon mapper (10⁶ photons, its maps read directly) pass the block
/// t-test against `volpath` (16 × 32 spp against 8 × 512, α = 0.01 Šidák-corrected inside).
/// SPPM (256 iterations, radius 0.03) is a density estimate biased at a finite radius, most
/// at the medium's boundary, where its kernel reaches outside it: its image mean is within
/// 1.5 % of volpath's per channel (measured +0.5 / −0.6 / −1.4 %).
#[test]
fn light_paths_start_in_emitting_media() {
    use render::compare::{TestImages, compare};
    let reference = volpath_reference();
    for integrator in [
        r#"<integrator type="ptracer"><integer name="max_depth" value="8"/></integrator>"#,
        r#"<integrator type="photonmapper"><integer name="max_depth" value="8"/>
                <integer name="globalPhotons" value="1000000"/></integrator>"#,
    ] {
        let result = compare(reference, &TestImages::Batches(batches(integrator, 16, 32))).unwrap();
        println!("{integrator}: {result}");
        assert!(result.passed, "{integrator}: {result}");
    }

    let mean = |img: &render::film::Image| {
        let n = img.pixels.len() as f64;
        [0, 1, 2].map(|c| img.pixels.iter().map(|p| p[c] as f64).sum::<f64>() / n)
    };
    let want = mean(&reference.mean);
    let sppm = r#"<integrator type="sppm"><integer name="max_depth" value="8"/>
                <float name="initial_radius" value="0.03"/></integrator>"#;
    let got = mean(&batches(sppm, 1, 256)[0]);
    for c in 0..3 {
        let r = got[c] / want[c];
        println!("sppm: channel {c} ratio {r:.4}");
        assert!((r - 1.0).abs() < 0.015, "sppm: channel {c}: {r}");
    }
}
