use render::build::{BuildOptions, build};
use render::geometry::Ray;
use render::math::Vec3;
fn main() {
    let doc = scene::load(
        std::path::Path::new("/work/shared/scenes/standard/mitsuba-cbox/cbox-rgb.xml"),
        &Default::default(),
    )
    .unwrap();
    let scene::Document::Scene(desc) = doc else {
        panic!()
    };
    let sc = build(&desc, &BuildOptions::default()).unwrap();
    let light = Vec3::new(278.0, 548.0, 279.5);
    for (name, cam) in [
        ("green", Vec3::new(278.0, 300.0, 100.0)),
        ("red", Vec3::new(278.0, 300.0, 100.0)),
    ] {
        let mut occ = 0;
        let mut n = 0;
        for i in 0..40 {
            for j in 0..40 {
                let target = if name == "green" {
                    Vec3::new(0.0, 10.0 + i as f32 * 13.0, 10.0 + j as f32 * 13.0)
                } else {
                    Vec3::new(551.0, 10.0 + i as f32 * 13.0, 10.0 + j as f32 * 13.0)
                };
                let ray = Ray::new(cam, (target - cam).normalize());
                let Some(si) = sc.intersect(&ray, f32::INFINITY) else {
                    continue;
                };
                if si.shape != if name == "green" { 4 } else { 5 } {
                    continue;
                }
                n += 1;
                let (sr, t) = si.spawn_ray_to(light);
                if sc.occluded(&sr, t) {
                    occ += 1;
                    if occ < 4 {
                        let h = sc.accel.intersect(&sr, t).unwrap();
                        println!(
                            "{name}: p={} o={} hit shape {} t={}",
                            si.p, sr.o, h.shape, h.t
                        );
                    }
                }
            }
        }
        println!("{name}: {occ}/{n} occluded");
    }
}
