//! The `debug-paths` command: trace N paths through one pixel with a recorder and write their
//! vertices and segments as a PLY edge set (any mesh viewer overlays it on the scene) or JSON.
//!
//! Every vertex carries its position, shading normal, the path throughput on arrival, the
//! density of the direction sampled there and an event code saying how the path left it (or
//! why it ended there): 0 camera, 1 non-delta reflection, 2 non-delta transmission, 3 specular
//! reflection, 4 specular transmission, 5 escaped (a point far along the last direction),
//! 6 absorbed, 7 Russian roulette, 8 maximum depth, 9 scattering in a medium (a collision of
//! the volumetric path tracer; its normal is zero), 10 a `null` boundary crossed.
//!
//! The path tracer's and the volumetric path tracer's paths are recorded; other integrators
//! are refused with a message.

use std::fmt::Write as _;
use std::path::PathBuf;

use build::{BuildOptions, build};
use render::geometry::Ray;
use render::integrators::Integrator;
use render::integrators::path::{
    PathEnd, PathRecorder, RecordedScatter, RecordedVertex, VertexKind, li_recorded,
};
use render::integrators::volpath;
use render::math::{UVec2, Vec3};
use render::sampling::Sampler;
use render::world::Scene;
use scene::Document;

use crate::{Failure, load_scene, parse_define, print_warnings};

#[derive(clap::Args, Debug)]
pub struct Args {
    pub scene: PathBuf,
    /// The pixel the paths go through, `x,y` (0-based, from the top left).
    #[arg(long, value_parser = parse_pixel)]
    pub pixel: (u32, u32),
    /// Number of paths (sample indices 0..N of that pixel).
    #[arg(long, default_value_t = 16)]
    pub count: u32,
    /// Output file (.ply or .json).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Output format (default: from the extension of the output).
    #[arg(long, value_parser = ["ply", "json"])]
    pub format: Option<String>,
    /// Seed of the sample streams (default: the scene's).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Override a scene parameter (Mitsuba `<default>`), e.g. `-D spp=64`.
    #[arg(short = 'D', value_name = "NAME=VALUE", value_parser = parse_define)]
    pub define: Vec<(String, String)>,
}

fn parse_pixel(s: &str) -> Result<(u32, u32), String> {
    let err = || format!("expected x,y such as 120,64, found '{s}'");
    let (x, y) = s.split_once(',').ok_or_else(err)?;
    Ok((
        x.trim().parse().map_err(|_| err())?,
        y.trim().parse().map_err(|_| err())?,
    ))
}

#[derive(Clone, Copy, Debug)]
struct Vertex {
    p: Vec3,
    n: Vec3,
    throughput: Vec3,
    pdf: f32,
    event: u8,
    path: u32,
}

/// About what one vertex and its edge take in the written PLY or JSON text.
const BYTES_OF_TEXT_PER_VERTEX: usize = 160;

/// Collects the vertices and edges of every path.
struct Collector {
    vertices: Vec<Vertex>,
    edges: Vec<(u32, u32)>,
    path: u32,
    /// Length used for the segment of an escaping path.
    far: f32,
    last_dir: Option<Vec3>,
    /// The kind of the last vertex recorded.
    last_kind: VertexKind,
}

impl Collector {
    fn push(&mut self, v: Vertex) {
        let i = self.vertices.len() as u32;
        if let Some(prev) = self.vertices.last()
            && prev.path == v.path
        {
            self.edges.push((i - 1, i));
        }
        self.vertices.push(v);
    }
}

impl PathRecorder for Collector {
    fn camera_ray(&mut self, ray: &Ray) {
        self.last_dir = Some(ray.d.normalize());
        self.push(Vertex {
            p: ray.o,
            n: Vec3::ZERO,
            throughput: Vec3::ONE,
            pdf: 1.0,
            event: 0,
            path: self.path,
        });
    }
    fn vertex(&mut self, v: &RecordedVertex) {
        self.last_kind = v.kind;
        self.push(Vertex {
            p: v.p,
            n: v.n,
            throughput: v.throughput,
            pdf: 0.0,
            event: 6,
            path: self.path,
        });
    }
    fn scatter(&mut self, s: &RecordedScatter) {
        self.last_dir = Some(s.wi);
        if let Some(last) = self.vertices.last_mut() {
            last.pdf = s.pdf;
            last.event = match (self.last_kind, s.scatter.delta, s.scatter.transmission) {
                (VertexKind::Medium, ..) => 9,
                (VertexKind::Null, ..) => 10,
                (_, false, false) => 1,
                (_, false, true) => 2,
                (_, true, false) => 3,
                (_, true, true) => 4,
            };
        }
    }
    fn end(&mut self, why: PathEnd) {
        match why {
            PathEnd::Escaped => {
                if let (Some(last), Some(d)) = (self.vertices.last().copied(), self.last_dir) {
                    self.push(Vertex {
                        p: last.p + d * self.far,
                        n: Vec3::ZERO,
                        throughput: last.throughput,
                        pdf: 0.0,
                        event: 5,
                        path: self.path,
                    });
                }
            }
            PathEnd::Absorbed | PathEnd::Roulette | PathEnd::MaxDepth => {
                if let Some(last) = self.vertices.last_mut() {
                    last.event = match why {
                        PathEnd::Absorbed => 6,
                        PathEnd::Roulette => 7,
                        _ => 8,
                    };
                }
            }
        }
    }
}

fn trace(scene: &Scene, integrator: &Integrator, args: &Args) -> Result<Collector, Failure> {
    // Null crossings of volumetric paths do not count as depth: budget two vertices per level.
    let (path, vol, max_vertices) = match integrator {
        Integrator::Path(cfg) => (Some(cfg), None, cfg.max_depth),
        Integrator::VolPath(cfg) => (None, Some(cfg), cfg.max_depth.saturating_mul(2)),
        _ => {
            return Err(Failure::input(format!(
                "debug-paths records the paths of 'path' and 'volpath'; the scene asks for '{}'",
                integrator.name(),
            )));
        }
    };
    let (x, y) = args.pixel;
    if x >= scene.film.width || y >= scene.film.height {
        return Err(Failure::input(format!(
            "pixel {x},{y} is outside the {}x{} image",
            scene.film.width, scene.film.height
        )));
    }
    // Every vertex is recorded (plus its edge) and written as text: budget for the depth
    // limit (or 64 vertices when paths are unbounded and only roulette ends them).
    let vertices = if max_vertices == u32::MAX {
        64
    } else {
        u64::from(max_vertices).min(1 << 16) + 2
    };
    let per_vertex = (std::mem::size_of::<Vertex>() + 8 + BYTES_OF_TEXT_PER_VERTEX) as u64;
    crate::memory::check(
        &format!("recording {} paths", args.count),
        u64::from(args.count) * vertices * per_vertex,
    )?;
    let (lo, hi) = scene.bounds;
    let far = ((hi - lo).length() * 0.5).clamp(1e-3, 1e6);
    let mut rec = Collector {
        vertices: Vec::new(),
        edges: Vec::new(),
        path: 0,
        far,
        last_dir: None,
        last_kind: VertexKind::Surface,
    };
    let mut sampler = Sampler::new(scene.sampler.kind, args.count.max(1), scene.sampler.seed);
    for index in 0..args.count {
        rec.path = index;
        // The renderer's own camera sample (film position, lens, and shutter time when
        // something moves), so the paths are those of the render.
        let (_, cray) = render::render::camera_sample(scene, &mut sampler, UVec2::new(x, y), index);
        if let Some(cfg) = path {
            li_recorded(scene, &cray, &mut sampler, cfg, &mut rec);
        } else if let Some(cfg) = vol {
            volpath::li_recorded(scene, &cray, &mut sampler, cfg, &mut rec);
        }
    }
    Ok(rec)
}

fn ply(c: &Collector) -> String {
    let mut s = String::new();
    let _ = write!(
        s,
        "ply\nformat ascii 1.0\ncomment penumbra debug-paths: event 0 camera, 1 reflect, 2 transmit, 3 specular reflect, 4 specular transmit, 5 escaped, 6 absorbed, 7 roulette, 8 max depth, 9 medium scatter, 10 null crossing\n\
         element vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         property float throughput_r\nproperty float throughput_g\nproperty float throughput_b\n\
         property float pdf\nproperty uchar event\nproperty uint path\n\
         element edge {}\nproperty int vertex1\nproperty int vertex2\nend_header\n",
        c.vertices.len(),
        c.edges.len()
    );
    for v in &c.vertices {
        let _ = writeln!(
            s,
            "{} {} {} {} {} {} {} {} {} {} {} {}",
            v.p.x,
            v.p.y,
            v.p.z,
            v.n.x,
            v.n.y,
            v.n.z,
            v.throughput.x,
            v.throughput.y,
            v.throughput.z,
            v.pdf,
            v.event,
            v.path
        );
    }
    for (a, b) in &c.edges {
        let _ = writeln!(s, "{a} {b}");
    }
    s
}

/// JSON numbers: non-finite values (which JSON cannot hold) become null.
fn num(x: f32) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        "null".to_string()
    }
}

fn json(c: &Collector) -> String {
    let v3 = |v: Vec3| format!("[{},{},{}]", num(v.x), num(v.y), num(v.z));
    let mut s = String::from("{\"paths\":[");
    let count = c.vertices.last().map_or(0, |v| v.path + 1);
    for path in 0..count {
        if path > 0 {
            s.push(',');
        }
        s.push_str("{\"vertices\":[");
        let mut first = true;
        for v in c.vertices.iter().filter(|v| v.path == path) {
            if !first {
                s.push(',');
            }
            first = false;
            let _ = write!(
                s,
                "{{\"p\":{},\"n\":{},\"throughput\":{},\"pdf\":{},\"event\":{}}}",
                v3(v.p),
                v3(v.n),
                v3(v.throughput),
                num(v.pdf),
                v.event
            );
        }
        s.push_str("]}");
    }
    s.push_str("]}\n");
    s
}

pub fn run(args: Args) -> Result<(), Failure> {
    let Document::Scene(desc) = load_scene(&args.scene, &args.define)? else {
        return Err(Failure::input(format!(
            "{}: this is a test file, not a scene",
            args.scene.display()
        )));
    };
    print_warnings(&desc);
    let format = match &args.format {
        Some(f) => f.clone(),
        None => match args.output.extension().and_then(|e| e.to_str()) {
            Some(e) if e.eq_ignore_ascii_case("json") => "json".to_string(),
            Some(e) if e.eq_ignore_ascii_case("ply") => "ply".to_string(),
            _ => {
                return Err(Failure::input(format!(
                    "{}: expected a .ply or .json output (or --format)",
                    args.output.display()
                )));
            }
        },
    };
    let built = build(
        &desc,
        &BuildOptions {
            seed: args.seed,
            ..Default::default()
        },
    )
    .map_err(Failure::input)?;
    let c = trace(&built.scene, &built.integrator, &args)?;
    let text = if format == "json" { json(&c) } else { ply(&c) };
    // Write beside the target, then rename: never a half-written file.
    let mut tmp = args.output.clone().into_os_string();
    tmp.push(".partial");
    let tmp = PathBuf::from(tmp);
    std::fs::write(&tmp, text)
        .and_then(|()| std::fs::rename(&tmp, &args.output))
        .map_err(|e| Failure::other(format!("{}: {e}", args.output.display())))?;
    eprintln!(
        "wrote {} ({} paths, {} vertices, {} segments)",
        args.output.display(),
        args.count,
        c.vertices.len(),
        c.edges.len()
    );
    Ok(())
}
