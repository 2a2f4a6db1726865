use render::build::{BuildOptions, build};
use render::integrators::Integrator;
use render::render::{RenderOptions, Silent, render};
use std::time::Duration;
fn main() {
    let doc = scene::load(
        std::path::Path::new("/work/shared/references/scenes/lights.xml"),
        &Default::default(),
    )
    .unwrap();
    let scene::Document::Scene(desc) = doc else {
        panic!()
    };
    for (spp, pd) in [(32u32, 0.0f64), (32, 100.0), (1, 0.0)] {
        let mut acc = [0f64; 3];
        let seeds = if spp == 1 { 64 } else { 4 };
        for seed in 0..seeds {
            let sc = build(
                &desc,
                &BuildOptions {
                    spp: Some(spp),
                    seed: Some(seed),
                    ..Default::default()
                },
            )
            .unwrap();
            let integ = Integrator::from_desc(&sc.integrator).unwrap();
            let out = render(
                &sc,
                &integ,
                &RenderOptions {
                    spp,
                    pass_duration: Duration::from_secs_f64(pd),
                    ..Default::default()
                },
                &Silent,
            );
            let img = out.film.develop();
            for y in 80..88 {
                for x in 56..64 {
                    let p = img.get(x, y);
                    acc[0] += p.x as f64;
                    acc[1] += p.y as f64;
                    acc[2] += p.z as f64;
                }
            }
        }
        println!(
            "spp {spp} pass {pd}: {:?}",
            acc.map(|v| v / (64.0 * seeds as f64))
        );
    }
}
