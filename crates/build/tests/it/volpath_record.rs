//! The volumetric path tracer with a recorder (`volpath::li_recorded`, what `debug-paths`
//! uses) traces the same paths as without one: for every sample the recorded contributions
//! sum to the estimate bit for bit, and the recorded events form one well-ordered path
//! (camera, then vertices each followed by a direction or the end), with medium collisions
//! inside the smoke sphere and null crossings on its surface.

use std::path::Path;

use build::{BuildOptions, build};
use render::geometry::Ray;
use render::integrators::Integrator;
use render::integrators::path::{
    Contribution, PathEnd, PathRecorder, RecordedScatter, RecordedVertex, VertexKind,
};
use render::integrators::volpath;
use render::math::{UVec2, Vec3};
use render::render::camera_sample;
use render::sampling::Sampler;
use scene::Document;

#[derive(Default)]
struct Log {
    sum: Vec3,
    events: Vec<char>,
    medium: Vec<Vec3>,
    null: Vec<Vec3>,
}

impl PathRecorder for Log {
    fn camera_ray(&mut self, _ray: &Ray) {
        self.events.push('c');
    }
    fn vertex(&mut self, v: &RecordedVertex) {
        self.events.push('v');
        match v.kind {
            VertexKind::Medium => {
                assert_eq!(v.n, Vec3::ZERO);
                self.medium.push(v.p);
            }
            VertexKind::Null => self.null.push(v.p),
            VertexKind::Surface => {}
        }
    }
    fn scatter(&mut self, s: &RecordedScatter) {
        assert!(s.pdf > 0.0 && s.wi.is_normalized());
        self.events.push('s');
    }
    fn end(&mut self, _why: PathEnd) {
        self.events.push('e');
    }
    fn contribution(&mut self, l: Vec3, c: Contribution) {
        assert!(c.depth >= 1);
        self.sum += l;
    }
}

#[test]
fn recorded_paths_are_the_rendered_paths() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/media/smoky-box.xml");
    let Document::Scene(desc) = scene::load(&path, &Default::default()).unwrap() else {
        panic!("not a scene")
    };
    let built = build(&desc, &BuildOptions::default()).unwrap();
    let Integrator::VolPath(cfg) = &built.integrator else {
        panic!("the example asks for volpath")
    };
    let scene = &built.scene;
    let (centre, radius) = (Vec3::new(-0.4, 0.6, -0.25), 0.45f32);
    let (mut medium, mut null, mut nonzero) = (0, 0, 0);
    // Pixels across the smoke sphere, the glass cube and the walls.
    for (x, y) in [
        (69, 122),
        (60, 110),
        (80, 130),
        (130, 150),
        (140, 160),
        (20, 20),
    ] {
        for index in 0..32 {
            let pixel = UVec2::new(x, y);
            let mut a = Sampler::new(scene.sampler.kind, 32, scene.sampler.seed);
            let mut b = a.clone();
            let (_, cray) = camera_sample(scene, &mut a, pixel, index);
            let plain = volpath::li(scene, &cray, &mut a, cfg);
            let (_, cray) = camera_sample(scene, &mut b, pixel, index);
            let mut log = Log::default();
            let recorded = volpath::li_recorded(scene, &cray, &mut b, cfg, &mut log);
            assert_eq!(
                plain.to_array(),
                recorded.to_array(),
                "pixel {x},{y} #{index}"
            );
            assert_eq!(log.sum.to_array(), plain.to_array(), "contributions sum");
            nonzero += usize::from(plain != Vec3::ZERO);
            // c (v s)* v? e: a direction only ever follows a vertex, and the path ends once.
            let ev: String = log.events.iter().collect();
            assert!(ev.starts_with('c') && ev.ends_with('e'), "{ev}");
            assert_eq!(ev.matches('e').count(), 1, "{ev}");
            assert!(!ev.contains("ss") && !ev.contains("cs"), "{ev}");
            for p in &log.medium {
                // The blue medium lives in the cube (x > 0), the smoke in the sphere.
                assert!(p.x > 0.0 || (*p - centre).length() <= radius * 1.001, "{p}");
            }
            for p in &log.null {
                assert!(((*p - centre).length() - radius).abs() < 1e-3, "{p}");
            }
            medium += log.medium.len();
            null += log.null.len();
        }
    }
    assert!(
        medium > 0 && null > 0 && nonzero > 0,
        "{medium} {null} {nonzero}"
    );
}
