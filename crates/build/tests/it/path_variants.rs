//! The path tracer's course variants change only the noise, never the mean: brute force (no
//! next-event estimation), uniform hemisphere directions (CS184 `-H`), several emitter samples
//! per vertex, one sample per emitter (CS184 `-l`), splitting at the first vertex (CENG795),
//! fixed-probability and no Russian roulette, the balance heuristic.
//!
//! Reference: the default configuration (Mitsuba's `path`) in 32 batches, turned into a mean
//! and a standard error with 31 degrees of freedom exactly as a Mitsuba reference is. Each
//! variant: 8 independent batches, block t-test of `render::compare` (α = 0.01 family-wise,
//! Šidák over the block-channels). The scene is a closed box with a large ceiling light plus
//! a small spherical one (so NEE chooses between two emitters), diffuse walls, a rough metal
//! sphere and a glass sphere (delta chains for splitting and caustics for brute force), and a
//! fixed depth of 6 segments so that "no Russian roulette" terminates.

use build::render_desc;
use build::{BuildOptions, build};
use render::compare::{Reference, TestImages, compare};
use render::film::Image;
use render::math::{UVec2, Vec3};
use render::render::camera_sample;
use render::sampling::Sampler;
use render::spectral::lanes::RgbMode;
use scene::{
    DirectionSampling, Document, IntegratorDesc, LoadOptions, MisHeuristic, PathDesc,
    RussianRoulette, SceneDesc,
};

const SCENE: &str = r#"<scene version="3.0.0">
    <sensor type="perspective">
        <float name="fov" value="45"/>
        <transform name="to_world"><lookat origin="0, 1, 3.4" target="0, 1, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm">
            <integer name="width" value="32"/><integer name="height" value="32"/>
            <rfilter type="box"/>
        </film>
    </sensor>
    <bsdf type="diffuse" id="white"><rgb name="reflectance" value="0.7, 0.7, 0.7"/></bsdf>
    <bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.6, 0.1, 0.1"/></bsdf>
    <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="-90"/></transform><ref id="white"/></shape>
    <shape type="rectangle"><transform name="to_world"><rotate x="1" angle="90"/><translate y="2"/></transform><ref id="white"/></shape>
    <shape type="rectangle"><transform name="to_world"><translate y="1" z="-1"/></transform><ref id="white"/></shape>
    <shape type="rectangle"><transform name="to_world"><rotate y="1" angle="90"/><translate x="-1" y="1"/></transform><ref id="red"/></shape>
    <shape type="rectangle"><transform name="to_world"><rotate y="1" angle="-90"/><translate x="1" y="1"/></transform><ref id="white"/></shape>
    <shape type="rectangle"><transform name="to_world"><rotate y="1" angle="180"/><translate y="1" z="3.5"/></transform><ref id="white"/></shape>
    <shape type="rectangle">
        <transform name="to_world"><scale x="0.6" y="0.6"/><rotate x="1" angle="90"/><translate y="1.99"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0, 0, 0"/></bsdf>
        <emitter type="area"><rgb name="radiance" value="4, 4, 4"/></emitter>
    </shape>
    <shape type="sphere">
        <point name="center" x="0.7" y="1.5" z="-0.6"/><float name="radius" value="0.08"/>
        <emitter type="area"><rgb name="radiance" value="8, 6, 3"/></emitter>
    </shape>
    <shape type="sphere">
        <point name="center" x="-0.45" y="0.4" z="-0.3"/><float name="radius" value="0.4"/>
        <bsdf type="roughconductor"><string name="material" value="Au"/><float name="alpha" value="0.3"/></bsdf>
    </shape>
    <shape type="sphere">
        <point name="center" x="0.45" y="0.35" z="0.3"/><float name="radius" value="0.35"/>
        <bsdf type="dielectric"/>
    </shape>
</scene>"#;

const SPP: u32 = 16;

fn scene_desc() -> SceneDesc {
    let dir = std::env::temp_dir().join(format!("penumbra-path-variants-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // One file per call: the tests run in parallel and must not read a half-written file.
    static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let file = dir.join(format!("box-{n}.xml"));
    std::fs::write(&file, SCENE).unwrap();
    let Document::Scene(desc) = scene::load(&file, &LoadOptions::default()).unwrap() else {
        panic!("not a scene")
    };
    *desc
}

fn batches(desc: &SceneDesc, path: &PathDesc, seeds: std::ops::Range<u64>) -> Vec<Image> {
    seeds
        .map(|seed| {
            let out = render_desc(
                desc,
                &BuildOptions {
                    spp: Some(SPP),
                    seed: Some(seed),
                    integrator: Some(IntegratorDesc::Path(path.clone())),
                    ..Default::default()
                },
            )
            .unwrap();
            assert_eq!(out.film.nonfinite_count(), 0);
            out.film.develop()
        })
        .collect()
}

fn reference_of(images: &[Image]) -> Reference {
    Reference::from_batches(images).unwrap()
}

fn base() -> PathDesc {
    PathDesc {
        max_depth: 6,
        ..PathDesc::default()
    }
}

/// The configurations tested against the default one.
fn variants() -> Vec<(&'static str, PathDesc)> {
    vec![
        (
            "brute force",
            PathDesc {
                nee: false,
                ..base()
            },
        ),
        (
            "uniform hemisphere",
            PathDesc {
                directions: DirectionSampling::UniformHemisphere,
                ..base()
            },
        ),
        (
            "uniform hemisphere, brute force",
            PathDesc {
                directions: DirectionSampling::UniformHemisphere,
                nee: false,
                ..base()
            },
        ),
        (
            "4 emitter samples",
            PathDesc {
                light_samples: 4,
                ..base()
            },
        ),
        (
            "all emitters, 3 samples each",
            PathDesc {
                light_samples: 3,
                all_lights: true,
                ..base()
            },
        ),
        (
            "splitting 4",
            PathDesc {
                splitting: 4,
                ..base()
            },
        ),
        (
            "fixed roulette",
            PathDesc {
                rr: RussianRoulette::Fixed { after: 2, q: 0.3 },
                ..base()
            },
        ),
        (
            "no roulette",
            PathDesc {
                rr: RussianRoulette::Off,
                ..base()
            },
        ),
        (
            "balance heuristic",
            PathDesc {
                mis: MisHeuristic::Balance,
                ..base()
            },
        ),
    ]
}

#[test]
fn variants_converge_to_the_default() {
    let desc = scene_desc();
    let reference = reference_of(&batches(&desc, &base(), 1000..1032));
    let variants = variants();
    let mut failures = Vec::new();
    for (i, (name, v)) in variants.iter().enumerate() {
        let seeds = 100 * (i as u64 + 1);
        let result = compare(
            &reference,
            &TestImages::Batches(batches(&desc, v, seeds..seeds + 8)),
        )
        .unwrap();
        println!("{name}: {result}");
        if !result.passed {
            failures.push(format!("{name}: {result}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// The test above can fail: direct light only (indirect light missing) must be rejected.
#[test]
fn a_biased_variant_is_rejected() {
    let desc = scene_desc();
    let reference = reference_of(&batches(&desc, &base(), 1000..1032));
    let biased = PathDesc {
        max_depth: 2,
        ..base()
    };
    let result = compare(
        &reference,
        &TestImages::Batches(batches(&desc, &biased, 50..58)),
    )
    .unwrap();
    assert!(!result.passed, "{result}");
}

/// The render loop keeps several paths in flight and tests their shadow rays together
/// (`Estimator::li_stream`); every estimate must be the one the single-path loop
/// (`Estimator::li`) gives for the same sample, bit for bit: the same random numbers in the
/// same order, the same sums. With splitting the split-off paths' contributions are added in a
/// different order, so there the estimates agree to rounding.
#[test]
fn batched_paths_equal_one_at_a_time() {
    let desc = scene_desc();
    let mut configs = vec![("default", base())];
    configs.extend(variants());
    configs.push((
        "unbounded depth",
        PathDesc {
            max_depth: -1,
            ..base()
        },
    ));
    configs.push((
        "depth 0",
        PathDesc {
            max_depth: 0,
            ..base()
        },
    ));
    for (name, path) in configs {
        let build::Built {
            scene, integrator, ..
        } = build(
            &desc,
            &BuildOptions {
                spp: Some(SPP),
                seed: Some(7),
                integrator: Some(IntegratorDesc::Path(path.clone())),
                ..Default::default()
            },
        )
        .unwrap();
        let template = Sampler::new(scene.sampler.kind, SPP, scene.sampler.seed);
        let samples: Vec<(UVec2, u32)> = (0..32)
            .flat_map(|y| (0..32).map(move |x| UVec2::new(x, y)))
            .flat_map(|pixel| (0..SPP).map(move |i| (pixel, i)))
            .collect();
        let mut sampler = template.clone();
        let single: Vec<Vec3> = samples
            .iter()
            .map(|&(pixel, index)| {
                let (_, cray) = camera_sample(&scene, &mut sampler, pixel, index);
                render::render::li(&scene, &integrator, &cray, &mut sampler).unwrap()
            })
            .collect();
        let mut batched = vec![None; samples.len()];
        let mut next = samples.iter().enumerate();
        let per_sample = integrator.li_stream_in::<RgbMode, _>(
            &scene,
            &template,
            |sampler| {
                let (k, &(pixel, index)) = next.next()?;
                Some((k, camera_sample(&scene, sampler, pixel, index).1))
            },
            |k, l| {
                assert!(batched[k].is_none(), "{name}: sample {k} reported twice");
                batched[k] = Some(l);
            },
        );
        assert!(
            per_sample,
            "{name}: the path tracer is a per-sample integrator"
        );
        let mut nonzero = 0;
        for (k, (a, b)) in single.iter().zip(&batched).enumerate() {
            let b = b.unwrap_or_else(|| panic!("{name}: sample {k} not reported"));
            nonzero += usize::from(*a != Vec3::ZERO);
            if path.splitting > 1 {
                let tol = 1e-5 * a.abs().max_element().max(1e-3);
                assert!(
                    (*a - b).abs().max_element() <= tol,
                    "{name}: sample {k}: {a} vs {b}"
                );
            } else {
                assert_eq!(a.to_array(), b.to_array(), "{name}: sample {k}");
            }
        }
        // Not a vacuous comparison: many estimates carry light (none at depth 0; brute force
        // finds the lights on a fifth of its paths).
        if path.max_depth != 0 {
            assert!(
                nonzero > samples.len() / 10,
                "{name}: {nonzero} non-zero estimates"
            );
        }
    }
}
