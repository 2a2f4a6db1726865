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
//! The path tracer's and the volumetric path tracer's paths are recorded as above. With `bdpt`
//! or `mlt` (the scene's integrator or `--integrator`), each of the N camera samples is a BDPT
//! sample of that pixel (`Bdpt::record`: the numbers of a BDPT render's sample of that index;
//! for `mlt`, the BDPT its chains mutate), written as its camera subpath, its light subpath
//! and every strategy (s, t) with a nonzero contribution:
//! - a vertex has its position, geometric normal, throughput β, the densities `pdf_fwd` and
//!   `pdf_rev` (per unit area, per unit solid angle at infinity), whether a delta lobe left it,
//!   and a kind: 0 camera (or lens point), 1 light (an emitter point), 2 surface, 3 medium,
//!   4 environment (a camera subpath that left the scene; placed, like a light point sampled
//!   at infinity, far along its direction); and in the PLY which subpath it is on: 0 camera,
//!   1 light, 2 a point a connection sampled afresh (the light point for s = 1, the lens point
//!   for t = 1);
//! - a connection joins camera vertex t − 1 (or the lens point, t = 1) and light vertex s − 1
//!   (or the light point, s = 1; nothing for s = 0, the camera subpath reaching an emitter by
//!   itself: a degenerate edge in the PLY), with its MIS weight, its weighted value (RGB) and,
//!   for t = 1, the film position it splats to. PLY edges say segment (0) or connection (1),
//!   with s and t (−1 for segments); JSON gives each path `camera`, `light` and `connections`.
//!
//! Other integrators are refused with a message.

use std::fmt::Write as _;
use std::path::PathBuf;

use build::spec::parse_integrator;
use build::{BuildOptions, build};
use render::geometry::Ray;
use render::integrators::Integrator;
use render::integrators::bdpt::{
    Bdpt, BdptConfig, BdptSample, BdptVertex, BdptVertexKind, Subpaths,
};
use render::integrators::path::{
    PathEnd, PathRecorder, RecordedScatter, RecordedVertex, VertexKind, li_recorded,
};
use render::integrators::volpath;
use render::math::{UVec2, Vec2, Vec3};
use render::sampling::Sampler;
use render::world::Scene;
use scene::{Document, IntegratorDesc};

use crate::{Failure, TransportArgs, load_scene, parse_define, print_warnings};

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
    /// Replace the scene's integrator, as `render --integrator` does (the scene's max depth
    /// is kept). path and volpath record their paths; bdpt and mlt record BDPT samples:
    /// camera subpath, light subpath and every connection strategy (s, t) with a nonzero
    /// contribution (its MIS weight, weighted value and, for t = 1, film position).
    #[arg(long, value_parser = parse_integrator)]
    pub integrator: Option<IntegratorDesc>,
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

/// Half the scene's diagonal: where points at infinity are drawn.
fn far(scene: &Scene) -> f32 {
    let (lo, hi) = scene.bounds;
    ((hi - lo).length() * 0.5).clamp(1e-3, 1e6)
}

fn check_pixel(scene: &Scene, args: &Args) -> Result<(), Failure> {
    let (x, y) = args.pixel;
    if x >= scene.film.width || y >= scene.film.height {
        return Err(Failure::input(format!(
            "pixel {x},{y} is outside the {}x{} image",
            scene.film.width, scene.film.height
        )));
    }
    Ok(())
}

fn trace(scene: &Scene, integrator: &Integrator, args: &Args) -> Result<Collector, Failure> {
    // Null crossings of volumetric paths do not count as depth: budget two vertices per level.
    let (path, vol, max_vertices) = match integrator {
        Integrator::Path(cfg) => (Some(cfg), None, cfg.max_depth),
        Integrator::VolPath(cfg) => (None, Some(cfg), cfg.max_depth.saturating_mul(2)),
        _ => {
            return Err(Failure::input(format!(
                "debug-paths records the paths of 'path', 'volpath', 'bdpt' and 'mlt', not \
                 '{}'",
                integrator.name(),
            )));
        }
    };
    check_pixel(scene, args)?;
    let (x, y) = args.pixel;
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
    let mut rec = Collector {
        vertices: Vec::new(),
        edges: Vec::new(),
        path: 0,
        far: far(scene),
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

/// The BDPT samples of one pixel.
struct BdptRecord {
    samples: Vec<BdptSample>,
    far: f32,
}

/// About what one recorded BDPT vertex or connection takes, as text and in memory.
const BYTES_PER_BDPT_ITEM: usize = 320;

fn trace_bdpt(scene: &Scene, cfg: &BdptConfig, args: &Args) -> Result<BdptRecord, Failure> {
    check_pixel(scene, args)?;
    // Subpaths of at most max_depth + 1 vertices (64 when only roulette ends them), and a
    // connection per strategy of at most max_depth edges: about half of the (s, t) pairs.
    let verts = if cfg.max_depth < 0 {
        64
    } else {
        u64::from(cfg.max_depth.unsigned_abs()).min(1 << 16) + 1
    };
    let per_sample = 2 * verts + verts * (verts + 1) / 2;
    crate::memory::check(
        &format!("recording {} BDPT samples", args.count),
        u64::from(args.count) * per_sample * BYTES_PER_BDPT_ITEM as u64,
    )?;
    let bdpt = Bdpt::new(scene, cfg);
    let mut paths = Subpaths::default();
    let mut sampler = Sampler::new(scene.sampler.kind, args.count.max(1), scene.sampler.seed);
    let pixel = UVec2::new(args.pixel.0, args.pixel.1);
    let samples = (0..args.count)
        .map(|index| {
            // The BDPT render's camera sample and sampler stream (`bdpt::render`).
            let (_, cray) = render::render::camera_sample(scene, &mut sampler, pixel, index);
            bdpt.record(scene, &cray, &mut sampler, &mut paths)
        })
        .collect();
    Ok(BdptRecord {
        samples,
        far: far(scene),
    })
}

/// The kind code of a BDPT vertex (module doc).
fn kind_code(k: BdptVertexKind) -> u8 {
    match k {
        BdptVertexKind::Camera => 0,
        BdptVertexKind::Light { .. } => 1,
        BdptVertexKind::Surface => 2,
        BdptVertexKind::Medium => 3,
        BdptVertexKind::Infinite => 4,
    }
}

/// Where to draw `v`: a camera subpath's exit to the environment, or a light point sampled at
/// infinity, `far` along its direction from `from`, the vertex it was seen from; any other
/// vertex where it is.
fn shown(v: &BdptVertex, from: Option<&BdptVertex>, far: f32) -> Vec3 {
    match from {
        Some(a) if v.at_infinity && v.kind != BdptVertexKind::Camera => {
            a.p + (v.p - a.p).normalize_or_zero() * far
        }
        _ => v.p,
    }
}

/// A recorded sample's vertices as drawn: camera subpath, light subpath, then each
/// connection's point sampled afresh (s = 1 light point, t = 1 lens point), with for each
/// connection the indices (in that list) of its two ends.
struct Drawn<'a> {
    vertices: Vec<(Vec3, &'a BdptVertex, u8)>,
    ends: Vec<(usize, usize)>,
}

fn drawn(sample: &BdptSample, far: f32) -> Drawn<'_> {
    let (cam, light) = (&sample.camera, &sample.light);
    let mut vertices = Vec::with_capacity(cam.len() + light.len());
    for (i, v) in cam.iter().enumerate() {
        let prev = i.checked_sub(1).map(|j| &cam[j]);
        vertices.push((shown(v, prev, far), v, 0));
    }
    for v in light {
        vertices.push((v.p, v, 1));
    }
    let mut ends = Vec::with_capacity(sample.connections.len());
    for c in &sample.connections {
        let from = if c.t == 1 {
            vertices.push((c.from.p, &c.from, 2));
            vertices.len() - 1
        } else {
            c.t - 1
        };
        let to = match (&c.to, c.s) {
            (None, _) => from,
            (Some(q), 1) => {
                vertices.push((shown(q, Some(&c.from), far), q, 2));
                vertices.len() - 1
            }
            (Some(_), s) => cam.len() + s - 1,
        };
        ends.push((from, to));
    }
    Drawn { vertices, ends }
}

fn ply_bdpt(r: &BdptRecord) -> String {
    let drawn: Vec<Drawn> = r.samples.iter().map(|s| drawn(s, r.far)).collect();
    let nv: usize = drawn.iter().map(|d| d.vertices.len()).sum();
    let ne: usize = r
        .samples
        .iter()
        .map(|s| {
            s.camera.len().saturating_sub(1) + s.light.len().saturating_sub(1) + s.connections.len()
        })
        .sum();
    let mut s = String::new();
    let _ = write!(
        s,
        "ply\nformat ascii 1.0\n\
         comment penumbra debug-paths, BDPT samples: vertex kind 0 camera, 1 light, 2 surface, 3 medium, 4 environment; \
         subpath 0 camera, 1 light, 2 sampled by a connection (s = 1 light point, t = 1 lens point); \
         edge kind 0 subpath segment, 1 connection of strategy (s, t) (s = t = -1 for segments; s = 0 a degenerate edge)\n\
         element vertex {nv}\nproperty float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\n\
         property float beta_r\nproperty float beta_g\nproperty float beta_b\n\
         property float pdf_fwd\nproperty float pdf_rev\nproperty uchar kind\nproperty uchar delta\n\
         property uint path\nproperty uchar subpath\n\
         element edge {ne}\nproperty int vertex1\nproperty int vertex2\nproperty uchar kind\n\
         property int s\nproperty int t\nproperty float weight\n\
         property float value_r\nproperty float value_g\nproperty float value_b\n\
         property float film_x\nproperty float film_y\nend_header\n",
    );
    for (path, d) in drawn.iter().enumerate() {
        for (p, v, subpath) in &d.vertices {
            let _ = writeln!(
                s,
                "{} {} {} {} {} {} {} {} {} {} {} {} {} {path} {subpath}",
                p.x,
                p.y,
                p.z,
                v.n.x,
                v.n.y,
                v.n.z,
                v.beta.x,
                v.beta.y,
                v.beta.z,
                v.pdf_fwd,
                v.pdf_rev,
                kind_code(v.kind),
                u8::from(v.delta),
            );
        }
    }
    let mut base = 0;
    for (sample, d) in r.samples.iter().zip(&drawn) {
        let cam = sample.camera.len();
        let segments = (1..cam).chain((1..sample.light.len()).map(|i| cam + i));
        for i in segments {
            let _ = writeln!(s, "{} {} 0 -1 -1 0 0 0 0 -1 -1", base + i - 1, base + i);
        }
        for (c, &(a, b)) in sample.connections.iter().zip(&d.ends) {
            let film = c.p_film.unwrap_or(Vec2::splat(-1.0));
            let _ = writeln!(
                s,
                "{} {} 1 {} {} {} {} {} {} {} {}",
                base + a,
                base + b,
                c.s,
                c.t,
                c.weight,
                c.value.x,
                c.value.y,
                c.value.z,
                film.x,
                film.y
            );
        }
        base += d.vertices.len();
    }
    s
}

fn json_bdpt(r: &BdptRecord) -> String {
    let v3 = |v: Vec3| format!("[{},{},{}]", num(v.x), num(v.y), num(v.z));
    let vertex = |p: Vec3, v: &BdptVertex| {
        let light = match v.kind {
            BdptVertexKind::Light { light } => format!(",\"light\":{light}"),
            _ => String::new(),
        };
        format!(
            "{{\"p\":{},\"n\":{},\"beta\":{},\"pdf_fwd\":{},\"pdf_rev\":{},\"kind\":{}{light},\"delta\":{}}}",
            v3(p),
            v3(v.n),
            v3(v.beta),
            num(v.pdf_fwd),
            num(v.pdf_rev),
            kind_code(v.kind),
            v.delta
        )
    };
    let mut s = String::from("{\"paths\":[");
    for (path, sample) in r.samples.iter().enumerate() {
        if path > 0 {
            s.push(',');
        }
        let d = drawn(sample, r.far);
        let list = |subpath: u8| {
            let items: Vec<String> = d
                .vertices
                .iter()
                .filter(|(_, _, k)| *k == subpath)
                .map(|(p, v, _)| vertex(*p, v))
                .collect();
            items.join(",")
        };
        let _ = write!(
            s,
            "{{\"camera\":[{}],\"light\":[{}],\"li\":{},\"connections\":[",
            list(0),
            list(1),
            v3(sample.li)
        );
        for (k, (c, &(a, b))) in sample.connections.iter().zip(&d.ends).enumerate() {
            if k > 0 {
                s.push(',');
            }
            let to = match c.to {
                Some(_) => v3(d.vertices[b].0),
                None => "null".to_string(),
            };
            let _ = write!(
                s,
                "{{\"s\":{},\"t\":{},\"from\":{},\"to\":{to},\"weight\":{},\"value\":{}",
                c.s,
                c.t,
                v3(d.vertices[a].0),
                num(c.weight),
                v3(c.value)
            );
            // The point the strategy sampled afresh, in full.
            if c.t == 1 {
                let _ = write!(s, ",\"lens\":{}", vertex(d.vertices[a].0, &c.from));
            }
            if let (1, Some(q)) = (c.s, &c.to) {
                let _ = write!(s, ",\"light_point\":{}", vertex(d.vertices[b].0, q));
            }
            if let Some(f) = c.p_film {
                let _ = write!(s, ",\"p_film\":[{},{}]", num(f.x), num(f.y));
            }
            s.push('}');
        }
        s.push_str("]}");
    }
    s.push_str("]}\n");
    s
}

pub fn run(args: Args) -> Result<(), Failure> {
    let Document::Scene(mut desc) = load_scene(&args.scene, &args.define)? else {
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
    // `--integrator` as `render` takes it: the scene's path length kept.
    let mut integrator = args.integrator.clone();
    TransportArgs::default().apply(&mut desc, &mut integrator)?;
    let built = build(
        &desc,
        &BuildOptions {
            seed: args.seed,
            integrator,
            ..Default::default()
        },
    )
    .map_err(Failure::input)?;
    let scene = &built.scene;
    let bdpt = match &built.integrator {
        Integrator::Bdpt(cfg) => Some(cfg.clone()),
        // MLT mutates BDPT's strategies: its paths are BDPT samples.
        Integrator::Mlt(cfg) => Some(BdptConfig {
            max_depth: cfg.max_depth as i32,
            ..BdptConfig::default()
        }),
        _ => None,
    };
    let (text, vertices, segments) = if let Some(cfg) = bdpt {
        if let Some(why) = built.integrator.unsupported(scene) {
            return Err(Failure::input(why));
        }
        let r = trace_bdpt(scene, &cfg, &args)?;
        let text = if format == "json" {
            json_bdpt(&r)
        } else {
            ply_bdpt(&r)
        };
        let sizes = r.samples.iter().map(|s| {
            let (c, l) = (s.camera.len(), s.light.len());
            (c + l, c.saturating_sub(1) + l.saturating_sub(1))
        });
        let (v, e) = sizes.fold((0, 0), |(v, e), (a, b)| (v + a, e + b));
        let connections: usize = r.samples.iter().map(|s| s.connections.len()).sum();
        (
            text,
            format!("{v} subpath vertices"),
            format!("{e} segments, {connections} connections"),
        )
    } else {
        let c = trace(scene, &built.integrator, &args)?;
        let text = if format == "json" { json(&c) } else { ply(&c) };
        (
            text,
            format!("{} vertices", c.vertices.len()),
            format!("{} segments", c.edges.len()),
        )
    };
    // Write beside the target, then rename: never a half-written file.
    let mut tmp = args.output.clone().into_os_string();
    tmp.push(".partial");
    let tmp = PathBuf::from(tmp);
    std::fs::write(&tmp, text)
        .and_then(|()| std::fs::rename(&tmp, &args.output))
        .map_err(|e| Failure::other(format!("{}: {e}", args.output.display())))?;
    eprintln!(
        "wrote {} ({} paths, {vertices}, {segments})",
        args.output.display(),
        args.count,
    );
    Ok(())
}
