//! Beer–Lambert absorption inside dielectrics (COMP30019's coloured `Refractive`, CENG795's
//! `AbsorptionCoefficient`) is a medium of the runtime scene: the build step makes one purely
//! absorbing homogeneous medium per material that declares it and puts it inside the shapes
//! using that material. The path tracer applies it only when every medium of the scene comes
//! from Beer absorption (Mitsuba's `path` ignores media); `volpath` sees it like any other.
//!
//! Path against volpath: the same COMP30019 scene (an amber glass ball on a floor under an
//! area light), 32×32 pixels × 64 spp each, seed 11, box filter, so every pixel's estimate
//! is independent of the others'. Per pixel the difference of the two images has mean 0 when
//! both integrators converge to the same image, so its pixel mean over its standard error
//! (pixel spread / √1024) is a z statistic. Two-sided per channel, α = 0.001 family-wise over
//! the 3 channels (Šidák: each at 1 − 0.999^⅓, |z| < 3.59). The same test rejects a volpath
//! render of the ball without its absorption (what volpath rendered before absorption went
//! through the media), so it is not vacuous.

use std::path::PathBuf;

use base::testing::z_of_mean_difference;
use build::{BuildOptions, Built, build, render_desc};
use render::integrators::Integrator;
use render::math::Vec3;
use render::media::{MediumKind, Phase};
use scene::{
    Document, FloatParam, IntegratorDesc, Material, MaterialDesc, MaterialId, PathDesc, SceneDesc,
    TransmittanceEstimator,
};
use statrs::distribution::{ContinuousCDF, Normal};

fn load(name: &str, text: &str) -> SceneDesc {
    let d = std::env::temp_dir().join(format!("penumbra-beer-media-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    let path: PathBuf = d.join(name);
    std::fs::write(&path, text).unwrap();
    let Document::Scene(desc) = scene::load(&path, &Default::default()).unwrap() else {
        panic!("not a scene")
    };
    *desc
}

fn material_id(desc: &SceneDesc, name: &str) -> u32 {
    desc.materials
        .iter()
        .position(|m| m.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("no material {name}")) as u32
}

/// The scene material's declared Beer coefficient.
fn declared_sigma(desc: &SceneDesc, id: u32) -> Vec3 {
    match &desc.materials[id as usize].material {
        Material::Dielectric {
            absorption: Some(s),
            ..
        } => (*s).into(),
        m => panic!("not an absorbing dielectric: {m:?}"),
    }
}

const SHAPES: &str = r#"Material "Floor" Diffuse (.6, .6, .6) 1
Material "Amber" Refractive (.9, .6, .2) 1.5
Material "Tea" Refractive (.5, .3, .1) 1.33
Material "Unused" Refractive (.8, .8, .8) 1.5
Material "Glass" Refractive (1, 1, 1) 1.5
PointLight "Key" (0, 0.8, 1) (1, 1, 1)
Plane "Floor" (0, -1, 0) (0, 1, 0) "Floor"
Sphere "A1" (-0.6, -0.7, 2) 0.3 "Amber"
Sphere "A2" (0, -0.7, 2) 0.3 "Amber"
Sphere "T" (0.6, -0.7, 2) 0.3 "Tea"
Sphere "G" (0, 0, 2.5) 0.3 "Glass"
Camera 60 (0, 0, 0) (0, 0, 0)
"#;

/// One medium per material that declares absorption (used or not), σt = σ exactly, albedo
/// 0, isotropic, no emission; every shape with that material gets it as its interior, and
/// normal maps, bump maps and masks around the material share it.
#[test]
fn one_absorbing_medium_per_absorbing_material() {
    let mut desc = load("shapes.txt", SHAPES);
    assert!(desc.media.is_empty());
    let (amber, tea, unused, glass) = (
        material_id(&desc, "Amber"),
        material_id(&desc, "Tea"),
        material_id(&desc, "Unused"),
        material_id(&desc, "Glass"),
    );
    // A mask around Amber (a wrapper: same inside) and a twosided one (no inside).
    let wrap = |desc: &mut SceneDesc, material| {
        desc.materials.push(MaterialDesc {
            material,
            ambient: Default::default(),
            name: None,
            loc: Default::default(),
        });
        MaterialId(desc.materials.len() as u32 - 1)
    };
    let masked = wrap(
        &mut desc,
        Material::Mask {
            nested: MaterialId(amber),
            opacity: FloatParam::Const(1.0),
        },
    );
    let two = wrap(
        &mut desc,
        Material::TwoSided {
            front: MaterialId(amber),
            back: None,
        },
    );
    let mut extra = desc.shapes[1].clone();
    extra.material = Some(masked);
    desc.shapes.push(extra.clone());
    extra.material = Some(two);
    desc.shapes.push(extra);

    let Built {
        scene, integrator, ..
    } = build(&desc, &BuildOptions::default()).unwrap();
    assert_eq!(scene.media.len(), 3, "Amber, Tea and Unused");
    let interior_of = |m: u32| -> Vec<Option<u32>> {
        desc.shapes
            .iter()
            .zip(&scene.shapes)
            .filter(|(d, _)| d.material == Some(MaterialId(m)))
            .map(|(_, s)| s.interior)
            .collect()
    };
    let a = interior_of(amber);
    assert_eq!(a.len(), 2);
    assert!(a[0].is_some() && a[0] == a[1], "{a:?}");
    assert_eq!(interior_of(masked.0), a[..1]);
    assert_eq!(interior_of(two.0), [None]);
    let t = interior_of(tea);
    assert!(t[0].is_some() && t[0] != a[0], "{t:?}");
    assert_eq!(interior_of(glass), [None]);
    assert!(scene.shapes.iter().all(|s| s.exterior.is_none()));
    // The unused material's medium is the remaining one.
    let u = (0..3)
        .find(|&i| Some(i) != a[0] && Some(i) != t[0])
        .unwrap();
    for (m, id) in [(a[0].unwrap(), amber), (t[0].unwrap(), tea), (u, unused)] {
        let medium = &scene.media[m as usize];
        let MediumKind::Homogeneous(h) = &medium.kind else {
            panic!("not homogeneous")
        };
        assert_eq!(h.sigma_t, declared_sigma(&desc, id));
        assert_eq!(h.sigma_s, Vec3::ZERO);
        assert_eq!(medium.phase, Phase::Isotropic);
        assert!(medium.emission.is_none() && medium.is_purely_absorbing());
    }
    // COMP30019's default is Whitted, a path tracer configuration: it applies the media.
    let Integrator::Path(cfg) = integrator else {
        panic!("a path tracer expected")
    };
    assert!(cfg.media_absorption);
}

/// A scene that declares media of its own keeps Mitsuba's `path` semantics (media ignored),
/// a shape's declared interior wins over its material's absorption, and the absorbing
/// material's medium still goes inside its other shapes (for `volpath`).
#[test]
fn declared_media_keep_path_ignoring_media() {
    let mut desc = load(
        "declared.xml",
        r#"<scene version="3.0.0">
    <medium type="homogeneous" id="fog"><rgb name="sigma_t" value="0.5, 0.5, 0.5"/><rgb name="albedo" value="0.8, 0.8, 0.8"/></medium>
    <bsdf type="dielectric" id="glass"/>
    <shape type="sphere"><point name="center" x="-1" y="0" z="0"/><ref id="glass"/></shape>
    <shape type="sphere"><point name="center" x="1" y="0" z="0"/><ref id="glass"/><ref name="interior" id="fog"/></shape>
</scene>"#,
    );
    assert_eq!(desc.media.len(), 1);
    let Material::Dielectric { absorption, .. } = &mut desc.materials[0].material else {
        panic!("a dielectric expected")
    };
    *absorption = Some(Vec3::new(0.1, 0.2, 0.3).into());
    for (integrator, applied) in [
        (IntegratorDesc::Path(PathDesc::default()), false),
        (IntegratorDesc::Whitted { max_depth: 5 }, false),
    ] {
        let Built {
            scene, integrator, ..
        } = build(
            &desc,
            &BuildOptions {
                integrator: Some(integrator),
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!(scene.media.len(), 2, "the fog and the glass's absorption");
        assert_eq!(scene.shapes[0].interior, Some(1));
        assert_eq!(scene.shapes[1].interior, Some(0), "declared interior kept");
        let Integrator::Path(cfg) = integrator else {
            panic!("a path tracer expected")
        };
        assert_eq!(cfg.media_absorption, applied);
    }
}

const BALL: &str = r#"Material "Floor" Diffuse (.6, .6, .6) 1
Material "Wall" Diffuse (.5, .5, .8) 1
Material "Amber" Refractive (.7, .4, .15) 1.5
PlaneLight "Panel" (0, 0.99, 2) (1, 1) (0, 0, 0) (1, 1, 1) 4
Plane "Floor" (0, -1, 0) (0, 1, 0) "Floor"
Triangle "BackA" (-2, -1, 3.5) (-2, 1, 3.5) (2, 1, 3.5) "Wall"
Triangle "BackB" (-2, -1, 3.5) (2, 1, 3.5) (2, -1, 3.5) "Wall"
Sphere "Ball" (0, -0.4, 2) 0.6 "Amber"
Camera 60 (0, 0, 0) (0, 0, 0)
"#;

fn render_ball(desc: &SceneDesc, integrator: IntegratorDesc) -> Vec<[f32; 3]> {
    let out = render_desc(
        desc,
        &BuildOptions {
            spp: Some(64),
            resolution: Some((32, 32)),
            seed: Some(11),
            integrator: Some(integrator),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(out.film.nonfinite_count(), 0);
    out.film
        .develop()
        .pixels
        .iter()
        .map(|p| p.to_array())
        .collect()
}

fn volpath() -> IntegratorDesc {
    IntegratorDesc::VolPath {
        max_depth: -1,
        rr_depth: 5,
        hide_emitters: false,
        equiangular: true,
        transmittance: TransmittanceEstimator::default(),
        sample_emission: false,
    }
}

/// |z| above which a channel rejects: two-sided, α = 0.001 over 3 channels (Šidák).
fn z_critical() -> f64 {
    let per_channel = 1.0 - (1.0 - 0.001f64).powf(1.0 / 3.0);
    Normal::new(0.0, 1.0)
        .unwrap()
        .inverse_cdf(1.0 - per_channel / 2.0)
}

#[test]
fn path_and_volpath_agree_on_absorbing_glass() {
    let desc = load("ball.txt", BALL);
    let path = render_ball(&desc, IntegratorDesc::Path(PathDesc::default()));
    let vol = render_ball(&desc, volpath());
    let (z, crit) = (z_of_mean_difference(&path, &vol), z_critical());
    println!("path − volpath: z = {z:.2?} (|z| < {crit:.2})");
    assert!(z.iter().all(|z| z.abs() < crit), "z = {z:?}");

    // Not vacuous: volpath without the ball's absorption is rejected.
    let mut clear = desc.clone();
    for m in &mut clear.materials {
        if let Material::Dielectric { absorption, .. } = &mut m.material {
            *absorption = None;
        }
    }
    let lost = render_ball(&clear, volpath());
    let z = z_of_mean_difference(&path, &lost);
    println!("path − volpath without absorption: z = {z:.2?}");
    assert!(z.iter().any(|z| z.abs() >= crit), "z = {z:?}");
}
