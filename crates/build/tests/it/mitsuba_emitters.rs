//! Mitsuba 3 emitters of issue 38 (`sunsky`, `directionalarea`, `projector`) against Mitsuba 3.9.1's renders of the same files
//! (`scenes/mitsuba/refs/`, the rule of `repo_references.rs`), and the χ² test of the
//! `sunsky` emitter's sampling against its density.

use build::{BuildOptions, build};
use glam::{Mat4, Vec3};
use render::stats::{Chi2Config, chi2_test, sidak};
use scene::{Emitter, EmitterDesc, SceneDesc, SunSkyDesc};

use crate::repo_references::check_repo_reference;

/// `sunsky` with `sun_direction`: the Hošek–Wilkie sky and a uniform sun.
#[test]
fn sunsky() {
    check_repo_reference("sunsky");
}

/// `sunsky.xml` in spectral mode against Mitsuba's `llvm_ad_spectral` (the 11-channel
/// datasets, interpolated in wavelength, black beyond 720 nm as in Mitsuba).
#[test]
fn sunsky_spectral() {
    check_repo_reference("sunsky_spectral");
}

/// `sunsky` placed by date, time and place, with `complex_sun` widened to 4°, an RGB
/// albedo and a y-up frame.
#[test]
fn sunsky_place() {
    check_repo_reference("sunsky_place");
}

/// `directionalarea` under the particle tracer: a tilted rectangle's collimated beam past a
/// shadowing sphere, a disk's onto a tilted panel (the emitters themselves invisible, as in
/// Mitsuba 3.9.1).
#[test]
fn directionalarea() {
    check_repo_reference("directionalarea");
}

/// `projector`: a bitmap slide (bilinear, non-square, `fov` on y, `scale`) at a slant over a
/// floor and a sphere, and a constant-irradiance projector with a focal length on a wall.
#[test]
fn projector() {
    check_repo_reference("projector");
}

/// The projector's emitted rays (`sample_le`, uniform in the image's cone with weight
/// I/pdf): `projector.xml` rendered by the particle tracer matches the reference of its
/// `path` form.
#[test]
fn projector_light_tracing() {
    let dir = crate::repo_references::mitsuba_scenes();
    let text = std::fs::read_to_string(dir.join("projector.xml")).unwrap();
    // In the scene's folder, so that its slide resolves.
    let path = dir.join(format!("projector_ptracer_{}.tmp.xml", std::process::id()));
    std::fs::write(
        &path,
        text.replace(
            r#"<integrator type="path">"#,
            r#"<integrator type="ptracer">"#,
        ),
    )
    .unwrap();
    let loaded = scene::load(&path, &Default::default());
    let _ = std::fs::remove_file(&path);
    let scene::Document::Scene(desc) = loaded.unwrap() else {
        panic!("not a scene")
    };
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    let batches = crate::references::render_desc_batches(
        &desc,
        crate::references::SPP,
        scene::RenderMode::Rgb,
    );
    crate::references::check_against(
        &dir.join("refs/projector"),
        "projector (ptracer)",
        batches,
        // Another estimator than Mitsuba's `path`: its noise is not compared.
        f64::INFINITY,
        crate::references::SPP,
    );
}

/// The Mitsuba 3 form of `v06/legacy_box.xml` (`mitsuba_legacy.rs`) against its reference.
#[test]
fn legacy_box() {
    check_repo_reference("legacy_box");
}

/// Mitsuba 3's `prb` (its differentiable path tracer, rendering forward what `path`
/// renders): `sunsky.xml` with `prb` renders the reference of its `path` form.
#[test]
fn prb_renders_as_path() {
    let dir = crate::repo_references::mitsuba_scenes();
    let text = std::fs::read_to_string(dir.join("sunsky.xml")).unwrap();
    let tmp = std::env::temp_dir().join(format!("penumbra-prb-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let path = tmp.join("sunsky_prb.xml");
    std::fs::write(
        &path,
        text.replace(r#"<integrator type="path">"#, r#"<integrator type="prb">"#),
    )
    .unwrap();
    let scene::Document::Scene(desc) = scene::load(&path, &Default::default()).unwrap() else {
        panic!("not a scene")
    };
    let _ = std::fs::remove_dir_all(&tmp);
    assert!(desc.warnings.is_empty(), "{:?}", desc.warnings);
    let batches = crate::references::render_desc_batches(
        &desc,
        crate::references::SPP,
        scene::RenderMode::Rgb,
    );
    crate::references::check_against(
        &dir.join("refs/sunsky"),
        "sunsky (prb)",
        batches,
        1.225e-4,
        crate::references::SPP,
    );
}

/// A scene of one `sunsky` emitter and nothing else (the build needs a camera).
fn sky_scene(d: SunSkyDesc) -> SceneDesc {
    let path = crate::repo_references::mitsuba_scenes().join("sunsky.xml");
    let scene::Document::Scene(mut desc) = scene::load(&path, &Default::default()).unwrap() else {
        panic!("not a scene")
    };
    desc.shapes.clear();
    desc.emitters = vec![EmitterDesc {
        name: None,
        emitter: Emitter::SunSky(d),
        medium: None,
        loc: Default::default(),
    }];
    *desc
}

/// The sky's sampling (sun cone and tabulated sky) follows `pdf_li`: the sky alone, and sky
/// and sun together with the sun widened to 20° so that the χ² cells resolve its cone; a
/// sun low over the horizon and one high, in a rotated frame.
#[test]
fn sunsky_sampling_matches_its_pdf() {
    let base = SunSkyDesc {
        turbidity: 3.0,
        albedo: Vec3::splat(0.3),
        sun_direction: Vec3::new(0.5, 0.2, 0.3).normalize(),
        sun_scale: 1.0,
        sky_scale: 1.0,
        sun_aperture: 20.0,
        complex_sun: false,
        to_world: Mat4::IDENTITY,
    };
    let cases = [
        ("sky and sun", base.clone()),
        (
            "sky only, high sun, rotated frame",
            SunSkyDesc {
                sun_scale: 0.0,
                turbidity: 7.0,
                sun_direction: Vec3::new(0.1, 0.9, 0.3).normalize(),
                to_world: Mat4::from_rotation_x(-std::f32::consts::FRAC_PI_2),
                ..base.clone()
            },
        ),
        (
            "low sun, complex",
            SunSkyDesc {
                sun_direction: Vec3::new(-0.7, 0.3, 0.08).normalize(),
                complex_sun: true,
                ..base.clone()
            },
        ),
    ];
    let level = sidak(0.01, cases.len());
    let mut failures = Vec::new();
    for (i, (name, d)) in cases.into_iter().enumerate() {
        let built = build(&sky_scene(d), &BuildOptions::default()).unwrap();
        let scene = &built.scene;
        let light = &scene.lights[0];
        let r = render::lights::Receiver::at(Vec3::ZERO.into());
        let cfg = Chi2Config {
            res: 24,
            sample_count: 300_000,
            min_exp_frequency: 5.0,
            significance: level,
            seed: 7 + i as u64,
        };
        let result = chi2_test(
            |u2, _| {
                light
                    .sample_li(scene, &r, u2, &render::spectral::lanes::RgbMode)
                    .map(|s| s.wi)
            },
            |wi| light.pdf_li(scene, &r, wi, None),
            &cfg,
        );
        eprintln!("{name}: {}", result.message);
        if !result.passed {
            failures.push(format!("{name}: {}", result.message));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
