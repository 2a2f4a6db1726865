//! `build::render_seeds` (one build, a render per seed) gives each seed the very image that
//! `build::render_desc` gives with that seed, for integrators that draw their randomness at
//! render time in different ways: the path tracer, BDPT (light subpaths, splats), the photon
//! mapper (its maps) and SPPM (its photon passes).

use build::{BuildOptions, render_desc, render_seeds};
use scene::IntegratorDesc;

#[test]
fn one_build_renders_every_seed_as_its_own_build_does() {
    let file =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/cornell-box.xml");
    let opts = scene::LoadOptions {
        defines: [("res".to_string(), "24".to_string())].into(),
    };
    let scene::Document::Scene(desc) = scene::load(&file, &opts).unwrap() else {
        panic!("a scene")
    };
    let integrators = [
        None,
        Some(IntegratorDesc::Bdpt {
            max_depth: 5,
            visualize_strategies: false,
            visualize_weights: false,
        }),
    ];
    let mut integrators: Vec<Option<IntegratorDesc>> = integrators.into();
    integrators.push(Some(IntegratorDesc::Photon(scene::PhotonDesc {
        photons: 20_000,
        final_gather: 2,
        ..Default::default()
    })));
    integrators.push(Some(IntegratorDesc::Sppm(scene::SppmDesc {
        photons: Some(2000),
        ..Default::default()
    })));
    for integrator in integrators {
        let opts = BuildOptions {
            spp: Some(4),
            integrator: integrator.clone(),
            ..Default::default()
        };
        let seeds = [3u64, 11];
        let together = render_seeds(&desc, &opts, seeds).unwrap();
        for (seed, out) in seeds.into_iter().zip(together) {
            let alone = render_desc(
                &desc,
                &BuildOptions {
                    seed: Some(seed),
                    ..opts.clone()
                },
            )
            .unwrap();
            assert_eq!(
                out.film.develop().pixels,
                alone.film.develop().pixels,
                "{integrator:?}, seed {seed}"
            );
        }
    }
}
