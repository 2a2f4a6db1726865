//! Declared spectra reach spectral mode in Mitsuba 3's spectral units: a scene declaring
//! every kind (a tabulated reflectance, `d65` with a scale, `blackbody`, `uniform`, named
//! conductors) is built in spectral mode and its runtime parameters are sampled at chosen
//! wavelengths, against values Mitsuba 3.9.1 `llvm_ad_spectral` gives.
//!
//! The Mitsuba numbers were produced with the installed Mitsuba (`/tmp/mi`), e.g.
//! ```text
//! DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so /tmp/mi/bin/python -c '
//! import mitsuba as mi, drjit as dr; mi.set_variant("llvm_ad_spectral")
//! s = mi.load_dict({"type": "d65", "scale": 0.3})       # or "blackbody", "irregular", ...
//! si = dr.zeros(mi.SurfaceInteraction3f); si.wavelengths = mi.Spectrum([l]*4)
//! print(s.eval(si)[0][0])'
//! ```
//! and, for the conductors, the weight of `conductor` (`material` Cu/Au) `sample()` at
//! cos θ = 1 and 0.5 with `si.wavelengths` set likewise (the Fresnel reflectance of Mitsuba's
//! measured η, k at that wavelength).

use base::RenderMode;
use build::{BuildOptions, build};
use render::bsdf::Bsdf;
use render::lights::Light;
use render::materials::{MaterialKind, Then};
use render::math::Vec3;
use render::spectral::lanes::{ColorMode, SpectralMode};
use render::spectral::{RgbToSpectrumTable, SampledSpectrum, SampledWavelengths};
use render::textures::{TexCoord, TexRef};
use render::world::Scene;

const SCENE: &str = r#"<scene version="3.0.0">
    <emitter type="constant"><spectrum name="radiance" type="d65"><float name="scale" value="0.3"/></spectrum></emitter>
    <shape type="rectangle">
        <emitter type="area"><spectrum name="radiance" type="blackbody"><float name="temperature" value="3000"/></spectrum></emitter>
    </shape>
    <shape type="sphere"><bsdf type="diffuse"><spectrum name="reflectance" value="400:0.05, 500:0.05, 540:0.85, 580:0.05, 700:0.05"/></bsdf></shape>
    <shape type="sphere"><bsdf type="conductor"><string name="material" value="Cu"/></bsdf></shape>
    <shape type="sphere"><bsdf type="conductor"><string name="material" value="Au"/></bsdf></shape>
    <shape type="sphere"><bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.45, 0.7"/></bsdf></shape>
    <emitter type="point"><spectrum name="intensity" value="2.5"/></emitter>
</scene>"#;

fn built(mode: RenderMode) -> Scene {
    let desc = scene::load_xml_text("declared-spectra", SCENE).expect("scene loads");
    let opts = BuildOptions {
        mode,
        ..Default::default()
    };
    build(&desc, &opts).expect("scene builds").scene
}

/// A spectral mode whose four wavelengths are `lo`, `lo + d`, `lo + 2d`, `lo + 3d`.
fn at(lo: f32, d: f32) -> SpectralMode<'static> {
    let wl = SampledWavelengths::sample_uniform(0.0, lo, lo + 4.0 * d);
    for i in 0..4 {
        assert!((wl.lambda(i) - (lo + i as f32 * d)).abs() < 1e-3);
    }
    SpectralMode::new(wl, RgbToSpectrumTable::srgb())
}

fn close(got: SampledSpectrum, want: [f32; 4], what: &str) {
    for i in 0..4 {
        let tol = 2e-5 * want[i].abs().max(1e-3);
        assert!(
            (got[i] - want[i]).abs() <= tol,
            "{what}: lane {i}: {} vs Mitsuba's {}",
            got[i],
            want[i]
        );
    }
}

/// The scattering model of shape `i`.
fn kind(scene: &Scene, i: usize) -> &MaterialKind {
    let m = &scene.materials[scene.shapes[i].material.unwrap() as usize];
    match &m.surface.then {
        Then::Model(Some(k)) => k,
        _ => panic!("shape {i}: not a plain model"),
    }
}

#[test]
fn declared_spectra_have_mitsubas_spectral_values() {
    let scene = built(RenderMode::Spectral);
    let tex = TexCoord::default();

    // d65 × 0.3 (unit luminance D65: the CIE 5 nm table / 98.997…), seen from any direction.
    let m = at(400.0, 100.0);
    let sky = scene
        .lights
        .iter()
        .find(|l| matches!(l, Light::Constant(_)))
        .unwrap();
    close(
        sky.environment(Vec3::Z, &m),
        [0.250_778_97, 0.331_384_4, 0.272_753_2, 0.217_002_94],
        "d65",
    );
    // Between the 5 nm nodes D65 is linear: 452.5 nm.
    let m2 = at(452.5, 100.0);
    assert!((sky.environment(Vec3::Z, &m2)[0] - 0.3 * 1.183_960_2).abs() < 1e-6);

    // blackbody 3000 K: Planck in W·m⁻²·sr⁻¹·nm⁻¹, unnormalised.
    let area = scene.shapes[0].emission.expect("an emitter");
    close(
        m.illuminant_at(&scene, &area, tex),
        [72.197_395, 260.267_67, 517.502, 750.596_4],
        "blackbody",
    );

    // A tabulated reflectance: linear between nodes, 0 outside them (360 nm).
    let MaterialKind::Diffuse { reflectance } = kind(&scene, 1) else {
        panic!()
    };
    close(
        at(400.0, 50.0).albedo_at(&scene, reflectance, tex),
        [0.05, 0.05, 0.05, 0.65],
        "tabulated",
    );
    assert_eq!(at(360.0, 1.0).albedo_at(&scene, reflectance, tex)[0], 0.0);

    // Measured conductors: the Fresnel reflectance of Mitsuba's η, k.
    for (shape, name, normal, grazing) in [
        (
            2,
            "Cu",
            [0.492_903_6, 0.594_385_7, 0.852_718_8, 0.954_199_3],
            [0.514_697_1, 0.596_903, 0.845_735_7, 0.947_887_7],
        ),
        (
            3,
            "Au",
            [0.391_062_8, 0.512_695_7, 0.916_006_8, 0.962_363_5],
            [0.416_069_9, 0.549_177_3, 0.910_690_5, 0.957_393_8],
        ),
    ] {
        let Bsdf::Conductor(c) = kind(&scene, shape).bsdf_in(&scene.textures, tex, &m) else {
            panic!("{name}: not a smooth conductor")
        };
        close(c.reflectance(1.0), normal, name);
        close(c.reflectance(0.5), grazing, name);
    }

    // An RGB reflectance is still upsampled (not a declared spectrum).
    let MaterialKind::Diffuse { reflectance } = kind(&scene, 4) else {
        panic!()
    };
    assert!(matches!(reflectance, TexRef::Const(_)));

    // A uniform emission spectrum is flat (no D65 factor), as Mitsuba's `uniform`.
    let point = scene
        .lights
        .iter()
        .find_map(|l| match l {
            Light::Point(p) => Some(p),
            _ => None,
        })
        .unwrap();
    let s = point.spectrum.as_deref().expect("declared");
    let v = m.illuminant_declared(point.intensity, Some(s));
    close(v, [2.5; 4], "uniform");
}

/// RGB mode's runtime scene has no trace of the declarations: constants of the RGB values
/// the loader converted them to, no conductor or light spectra.
#[test]
fn rgb_mode_builds_rgb_constants() {
    let scene = built(RenderMode::Rgb);
    assert!(matches!(scene.shapes[0].emission, Some(TexRef::Const(_))));
    for i in 1..5 {
        match kind(&scene, i) {
            MaterialKind::Diffuse { reflectance } => {
                assert!(matches!(reflectance, TexRef::Const(_)))
            }
            MaterialKind::Conductor { spectra, .. } => assert!(spectra.is_none()),
            k => panic!("{k:?}"),
        }
    }
    for l in &scene.lights {
        match l {
            Light::Constant(c) => assert!(c.spectrum.is_none()),
            Light::Point(p) => assert!(p.spectrum.is_none()),
            _ => {}
        }
    }
}
