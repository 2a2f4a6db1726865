//! Benchmark of `render::accel` against obvhs' CWBVH and Embree 3 on the same rays, 2 threads.
//!
//! Scenes and ray sets:
//! - **bumpy sphere**: a tessellated UV sphere of radius 1 (708 × 708 quads → 1,002,528
//!   triangles) whose radius is displaced by a sum of sines (amplitude ≈ 0.1), so the surface
//!   is closed, bumpy and has varied triangle sizes (small near the poles).
//!   - `random` (closest hit and occlusion): 1M rays with origins uniform in the mesh bounds
//!     (inside and outside the surface) and directions uniform on the sphere (fixed seed);
//!     closest-hit rays are unbounded, occlusion rays have `t_max` uniform in `[0, ½·diag)`.
//!   - `camera`, `bounce`, `shadow`: a pinhole camera 3.4 units away (1024 × 1024 rays); from
//!     each camera hit a cosine-distributed ray about the geometric normal, and a shadow ray to
//!     a uniform point of a 2 × 2 square light above the sphere, both spawned robustly from
//!     the renderer's own surface interaction (`shapes::interaction`).
//! - **classroom**: Bitterli's *classroom* (Mitsuba form, 103,832 triangles), with the
//!   camera, first-bounce and shadow rays a path tracer traces there at 4 spp, recorded by
//!   `cargo bench -p penumbra-build --bench record_rays` into `target/rays/classroom.rays`
//!   (the renderer cannot load scenes itself). Without that file the scene is skipped with a
//!   notice.
//!
//! Peers measured in the same run on the same rays: obvhs' stock CWBVH traversal with its own
//! (Möller–Trumbore) triangle test, and Embree 3 (`--features embree`, system libembree3,
//! high-quality build, one geometry per mesh). Build times are the best of three builds.
//!
//! Run: `cargo bench -p penumbra-render --bench accel [--features embree] [-- SCENE…]` where
//! SCENE is `sphere` or `classroom` (default both). Set `ACCEL_PEERS` to a comma-separated
//! subset of `penumbra,obvhs,embree` to measure fewer structures, and `ACCEL_RAYS_MAX` to trace
//! at most that many rays of each set.

use std::hint::black_box;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use rayon::prelude::*;
use render::accel::{Accel, AccelShape, Hit};
use render::geometry::Ray;
use render::math::{Vec2, Vec3};
use render::sampling::warp::square_to_cosine_hemisphere;
use render::shapes::{Reads, ShapeGeom, interaction};

const GRID: u32 = 708;
const RAYS: usize = 1_000_000;
const CAMERA_RES: u32 = 1024;
const THREADS: usize = 2;
/// Each measurement is the best of this many passes over all rays.
const REPEATS: usize = 3;

struct Rng(u64);
impl Rng {
    fn f(&mut self) -> f32 {
        // SplitMix64.
        self.0 = self.0.wrapping_add(0x9e3779b97f4a7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58476d1ce4e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d049bb133111eb);
        ((z ^ (z >> 31)) >> 40) as f32 / (1u64 << 24) as f32
    }
}

type Mesh = (Vec<Vec3>, Vec<[u32; 3]>);

/// A set of rays traced with one kind of query.
struct RaySet {
    name: &'static str,
    occlusion: bool,
    rays: Vec<(Ray, f32)>,
}

struct BenchScene {
    name: &'static str,
    meshes: Vec<Mesh>,
    sets: Vec<RaySet>,
}

fn bumpy_sphere() -> Mesh {
    let n = GRID;
    let mut pos = Vec::with_capacity(((n + 1) * (n + 1)) as usize);
    for i in 0..=n {
        let theta = std::f32::consts::PI * i as f32 / n as f32;
        for j in 0..=n {
            let phi = 2.0 * std::f32::consts::PI * (j % n) as f32 / n as f32;
            let dir = Vec3::new(
                theta.sin() * phi.cos(),
                theta.sin() * phi.sin(),
                theta.cos(),
            );
            let r = 1.0
                + 0.04 * (13.0 * dir.x + 2.0).sin() * (11.0 * dir.y).cos()
                + 0.03 * (29.0 * dir.z + 1.0).sin()
                + 0.02 * (61.0 * (dir.x + dir.y)).sin() * (47.0 * dir.z).cos();
            pos.push(dir * r);
        }
    }
    let mut idx = Vec::with_capacity((2 * n * n) as usize);
    let at = |i: u32, j: u32| i * (n + 1) + j;
    for i in 0..n {
        for j in 0..n {
            let (a, b, c, d) = (at(i, j), at(i, j + 1), at(i + 1, j), at(i + 1, j + 1));
            idx.push([a, c, b]);
            idx.push([b, c, d]);
        }
    }
    (pos, idx)
}

fn sphere_scene(pool: &rayon::ThreadPool) -> BenchScene {
    let (pos, idx) = bumpy_sphere();
    let mut rng = Rng(0x5eed);
    let (lo, hi) = pos
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), &p| {
            (a.min(p), b.max(p))
        });
    let diag = (hi - lo).length();
    let random: Vec<(Ray, f32)> = (0..RAYS)
        .map(|_| {
            let o = lo + (hi - lo) * Vec3::new(rng.f(), rng.f(), rng.f());
            let z = 1.0 - 2.0 * rng.f();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * std::f32::consts::PI * rng.f();
            let d = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            (Ray::new(o, d), 0.5 * diag * rng.f())
        })
        .collect();

    // Camera, bounce and shadow rays, traced with our accelerator and spawned from the
    // renderer's surface interactions.
    let geom = ShapeGeom::Mesh {
        positions: pos.clone().into(),
        normals: None,
        uvs: None,
        indices: idx.clone().into(),
    };
    let accel = pool.install(|| Accel::build(vec![geom.accel_shape()]));
    let eye = Vec3::new(0.4, -3.2, 1.0);
    let fwd = (-eye).normalize();
    let right = fwd.cross(Vec3::Z).normalize();
    let up = right.cross(fwd);
    let half = (20.0f32).to_radians().tan();
    let camera: Vec<(Ray, f32)> = (0..CAMERA_RES * CAMERA_RES)
        .map(|i| {
            let (x, y) = (i % CAMERA_RES, i / CAMERA_RES);
            let sx = (2.0 * (x as f32 + 0.5) / CAMERA_RES as f32 - 1.0) * half;
            let sy = (1.0 - 2.0 * (y as f32 + 0.5) / CAMERA_RES as f32) * half;
            (Ray::new(eye, fwd + sx * right + sy * up), f32::INFINITY)
        })
        .collect();
    let reads = Reads {
        tangent: false,
        uv: false,
    };
    let (light_o, light_size) = (Vec3::new(-1.0, -1.0, 3.0), 2.0);
    let spawned: Vec<((Ray, f32), (Ray, f32))> = pool.install(|| {
        camera
            .par_iter()
            .enumerate()
            .filter_map(|(i, (ray, t_max))| {
                let hit = accel.intersect(ray, *t_max)?;
                let si = interaction(&geom, &hit, ray, false, reads);
                let mut rng = Rng(i as u64 ^ 0xb0b);
                let ng = if si.ng.dot(si.wo) < 0.0 {
                    -si.ng
                } else {
                    si.ng
                };
                let local = square_to_cosine_hemisphere(Vec2::new(rng.f(), rng.f()));
                let (t, b) = ng.any_orthonormal_pair();
                let d = t * local.x + b * local.y + ng * local.z;
                let target = light_o + light_size * Vec3::new(rng.f(), rng.f(), 0.0);
                Some(((si.spawn_ray(d), f32::INFINITY), si.spawn_ray_to(target)))
            })
            .collect()
    });
    let (bounce, shadow) = spawned.into_iter().unzip();
    BenchScene {
        name: "bumpy sphere",
        meshes: vec![(pos, idx)],
        sets: vec![
            RaySet {
                name: "random",
                occlusion: false,
                rays: random.iter().map(|(r, _)| (*r, f32::INFINITY)).collect(),
            },
            RaySet {
                name: "random",
                occlusion: true,
                rays: random,
            },
            RaySet {
                name: "camera",
                occlusion: false,
                rays: camera,
            },
            RaySet {
                name: "bounce",
                occlusion: false,
                rays: bounce,
            },
            RaySet {
                name: "shadow",
                occlusion: true,
                rays: shadow,
            },
        ],
    }
}

/// The recorded classroom (see the module documentation), or `None` with a notice.
fn classroom_scene() -> Option<BenchScene> {
    // The target directory this benchmark runs from (`target/release/deps/accel-…`), else
    // the workspace's.
    let exe = std::env::current_exe().ok()?;
    let path: PathBuf = [
        exe.parent()?.parent()?.parent()?.to_path_buf(),
        PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../target")),
    ]
    .iter()
    .map(|t| t.join("rays/classroom.rays"))
    .find(|p| p.exists())
    .unwrap_or_else(|| PathBuf::from("target/rays/classroom.rays"));
    let Ok(bytes) = std::fs::read(&path) else {
        println!(
            "notice: classroom skipped: no {} (record it with `cargo bench -p penumbra-build \
             --bench record_rays`, which needs ../shared/scenes/bench/classroom)",
            path.display()
        );
        return None;
    };
    let mut rd = Reader {
        bytes: &bytes,
        at: 0,
    };
    assert_eq!(
        rd.take(8),
        b"PNRAYS01",
        "{}: not a ray file",
        path.display()
    );
    let mut meshes = Vec::new();
    for _ in 0..rd.u32() {
        let (nv, nt) = (rd.u32() as usize, rd.u32() as usize);
        let pos = (0..nv)
            .map(|_| Vec3::new(rd.f32(), rd.f32(), rd.f32()))
            .collect();
        let idx = (0..nt).map(|_| [rd.u32(), rd.u32(), rd.u32()]).collect();
        meshes.push((pos, idx));
    }
    let mut sets = Vec::new();
    for _ in 0..rd.u32() {
        let len = rd.u32() as usize;
        let name: &'static str = String::from_utf8(rd.take(len).to_vec())
            .expect("name")
            .leak();
        let occlusion = rd.take(1)[0] == 1;
        let rays = (0..rd.u32())
            .map(|_| {
                let o = Vec3::new(rd.f32(), rd.f32(), rd.f32());
                let d = Vec3::new(rd.f32(), rd.f32(), rd.f32());
                (Ray::new(o, d), rd.f32())
            })
            .collect();
        sets.push(RaySet {
            name,
            occlusion,
            rays,
        });
    }
    Some(BenchScene {
        name: "classroom",
        meshes,
        sets,
    })
}

/// Little-endian reader of the ray file.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> &[u8] {
        let s = &self.bytes[self.at..self.at + n];
        self.at += n;
        s
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take(4).try_into().expect("4 bytes"))
    }
    fn f32(&mut self) -> f32 {
        f32::from_bits(self.u32())
    }
}

/// CPU time of this process in seconds: the sum over its threads of the time they ran
/// (`/proc/self/task/*/schedstat`, nanoseconds), else user + system time from
/// `/proc/self/stat` (10 ms ticks); 0 elsewhere.
fn cpu_secs() -> f64 {
    if let Ok(tasks) = std::fs::read_dir("/proc/self/task") {
        let mut ns = 0u64;
        let mut any = false;
        for t in tasks.flatten() {
            if let Some(v) = std::fs::read_to_string(t.path().join("schedstat"))
                .ok()
                .and_then(|s| s.split_whitespace().next()?.parse::<u64>().ok())
            {
                ns += v;
                any = true;
            }
        }
        if any {
            return ns as f64 * 1e-9;
        }
    }
    let s = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let f: Vec<&str> = s
        .rsplit(')')
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect();
    let t = |i: usize| f.get(i).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    (t(11) + t(12)) / 100.0
}

/// Seconds of wall time and of process CPU time. The CPU time is what to compare on a
/// machine shared with other jobs: wall time there depends on how much of the 2 cores the
/// scheduler gave us.
#[derive(Clone, Copy)]
struct Timing {
    wall: f64,
    cpu: f64,
}

/// Best wall time and best process CPU time over `REPEATS` runs of `f`.
fn best_of<T>(mut f: impl FnMut() -> T) -> (Timing, T) {
    let mut best = Timing {
        wall: f64::INFINITY,
        cpu: f64::INFINITY,
    };
    let mut out = None;
    for _ in 0..REPEATS {
        let c0 = cpu_secs();
        let t0 = Instant::now();
        let r = f();
        best.wall = best.wall.min(t0.elapsed().as_secs_f64());
        best.cpu = best.cpu.min(cpu_secs() - c0);
        out = Some(r);
    }
    (best, out.expect("REPEATS > 0"))
}

/// The best wall time of `REPEATS` builds, and the last structure built.
fn best_build<T>(mut f: impl FnMut() -> T) -> (Duration, T) {
    let mut best = Duration::MAX;
    let mut out = None;
    for _ in 0..REPEATS {
        drop(out.take());
        let t0 = Instant::now();
        let r = f();
        best = best.min(t0.elapsed());
        out = Some(r);
    }
    (best, out.expect("REPEATS > 0"))
}

/// A structure under test: closest-hit distance (−1 for a miss) and occlusion.
trait Tracer: Sync {
    fn closest(&self, r: &Ray, t_max: f32) -> f32;
    fn occluded(&self, r: &Ray, t_max: f32) -> bool;
}

struct Figures {
    name: &'static str,
    build: Duration,
    /// Per ray set: timing and the number of hits (or occluded rays).
    sets: Vec<(Timing, usize)>,
    /// Per closest-hit set: the rays whose hit differs from ours.
    differ: Vec<Option<usize>>,
}

fn measure<T: Tracer>(
    pool: &rayon::ThreadPool,
    name: &'static str,
    build: Duration,
    tracer: &T,
    sets: &[RaySet],
    ours: Option<&[Vec<f32>]>,
) -> (Figures, Vec<Vec<f32>>) {
    let mut out = Figures {
        name,
        build,
        sets: Vec::new(),
        differ: Vec::new(),
    };
    let mut ts = Vec::new();
    for (k, s) in sets.iter().enumerate() {
        let rays = &s.rays;
        let timing = if s.occlusion {
            best_of(|| {
                pool.install(|| {
                    rays.par_iter()
                        .filter(|(r, tm)| tracer.occluded(r, *tm))
                        .count()
                })
            })
        } else {
            best_of(|| {
                pool.install(|| {
                    rays.par_iter()
                        .filter(|(r, tm)| tracer.closest(r, *tm) >= 0.0)
                        .count()
                })
            })
        };
        out.sets.push(timing);
        #[cfg(feature = "stats")]
        {
            let c = render::accel::stats::take();
            if c[3] + c[7] > 0 {
                let (r, n, l) = if s.occlusion {
                    (c[7], c[4], c[5])
                } else {
                    (c[3], c[0], c[1])
                };
                let r = r as f64;
                println!(
                    "  {name} {}: per ray {:.2} inner nodes, {:.2} leaves",
                    label(s),
                    n as f64 / r,
                    l as f64 / r
                );
            }
        }
        if s.occlusion {
            out.differ.push(None);
            ts.push(Vec::new());
            continue;
        }
        let t: Vec<f32> = pool.install(|| {
            rays.par_iter()
                .map(|(r, tm)| tracer.closest(r, *tm))
                .collect()
        });
        out.differ.push(ours.map(|o| {
            o[k].iter()
                .zip(&t)
                .filter(|&(&a, &b)| {
                    (a < 0.0) != (b < 0.0) || (a - b).abs() > 1e-4 * a.abs().max(1.0)
                })
                .count()
        }));
        ts.push(t);
    }
    (out, ts)
}

struct Ours(Accel);
impl Tracer for Ours {
    #[inline]
    fn closest(&self, r: &Ray, t_max: f32) -> f32 {
        self.0.intersect(r, t_max).map_or(-1.0, |h: Hit| h.t)
    }
    #[inline]
    fn occluded(&self, r: &Ray, t_max: f32) -> bool {
        self.0.occluded(r, t_max)
    }
}

fn main() {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(THREADS)
        .build()
        .expect("thread pool");
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with('-'))
        .collect();
    let want = |s: &str| args.is_empty() || args.iter().any(|a| a == s);
    let peers = std::env::var("ACCEL_PEERS").unwrap_or_else(|_| "penumbra,obvhs,embree".into());
    let peer = |s: &str| peers.split(',').any(|p| p.trim() == s);

    let mut scenes = Vec::new();
    if want("sphere") {
        scenes.push(sphere_scene(&pool));
    }
    if want("classroom") {
        scenes.extend(classroom_scene());
    }
    // A quick look (or a run under valgrind): at most this many rays per set.
    if let Some(max) = std::env::var("ACCEL_RAYS_MAX")
        .ok()
        .and_then(|v| v.parse().ok())
    {
        for s in scenes.iter_mut().flat_map(|s| s.sets.iter_mut()) {
            s.rays.truncate(max);
        }
    }
    for sc in &scenes {
        run(&pool, sc, &peer);
    }
}

fn run(pool: &rayon::ThreadPool, sc: &BenchScene, peer: &dyn Fn(&str) -> bool) {
    let tris: usize = sc.meshes.iter().map(|m| m.1.len()).sum();
    println!();
    println!(
        "== {}: {} triangles in {} meshes; {THREADS} threads; rays: {}",
        sc.name,
        tris,
        sc.meshes.len(),
        sc.sets
            .iter()
            .map(|s| format!("{} {}", s.rays.len(), label(s)))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let mut all = Vec::new();
    let mut ours_t = None;
    if peer("penumbra") {
        let shapes: Vec<AccelShape> = sc
            .meshes
            .iter()
            .map(|(p, i)| AccelShape::Triangles {
                positions: Arc::from(p.as_slice()),
                indices: Arc::from(i.as_slice()),
            })
            .collect();
        let (build, accel) = best_build(|| Ours(pool.install(|| Accel::build(shapes.clone()))));
        let (f, t) = measure(pool, "penumbra BVH8", build, &accel, &sc.sets, None);
        all.push(f);
        ours_t = Some(t);
    }
    if peer("obvhs") {
        all.push(obvhs_peer(pool, sc, ours_t.as_deref()));
    }
    #[cfg(feature = "embree")]
    if peer("embree") {
        all.push(embree::run(pool, sc, ours_t.as_deref()));
    }
    #[cfg(not(feature = "embree"))]
    println!("Embree 3: not measured (build with `--features embree`; needs libembree-dev 3.x)");

    println!("Mrays per CPU-second (Mrays/s wall in brackets); build in ms (wall)");
    print!("{:<14} {:>7}", "structure", "build");
    for s in &sc.sets {
        print!(" | {:>17}", label(s));
    }
    println!();
    for f in &all {
        print!("{:<14} {:>7.0}", f.name, f.build.as_secs_f64() * 1e3);
        for ((t, _), s) in f.sets.iter().zip(&sc.sets) {
            let n = s.rays.len();
            print!(" | {:>7.2} ({:>7.2})", mrays(n, t.cpu), mrays(n, t.wall));
        }
        println!();
    }
    for f in &all {
        let counts: Vec<String> = f.sets.iter().map(|(_, c)| c.to_string()).collect();
        let differ: Vec<String> = f
            .differ
            .iter()
            .zip(&sc.sets)
            .filter_map(|(d, s)| d.map(|d| format!("{d} on {}", s.name)))
            .collect();
        println!(
            "{:<14} hits/occluded: {}; closest hits differing from ours: {}",
            f.name,
            counts.join(" "),
            if differ.is_empty() {
                "-".into()
            } else {
                differ.join(", ")
            }
        );
    }
    if let Some(ours) = all.iter().find(|f| f.name == "penumbra BVH8") {
        for p in all.iter().filter(|f| f.name != ours.name) {
            print!(
                "penumbra / {}: build time {:.2}; speed per CPU-s",
                p.name,
                ours.build.as_secs_f64() / p.build.as_secs_f64()
            );
            for ((o, q), s) in ours.sets.iter().zip(&p.sets).zip(&sc.sets) {
                print!(" {} {:.2}", label(s), q.0.cpu / o.0.cpu);
            }
            println!();
        }
    }
}

fn label(s: &RaySet) -> String {
    format!(
        "{} {}",
        s.name,
        if s.occlusion { "occl" } else { "closest" }
    )
}

fn mrays(n: usize, secs: f64) -> f64 {
    n as f64 / secs / 1e6
}

fn obvhs_peer(pool: &rayon::ThreadPool, sc: &BenchScene, ours: Option<&[Vec<f32>]>) -> Figures {
    use obvhs::BvhBuildParams;
    use obvhs::cwbvh::CwBvh;
    use obvhs::cwbvh::builder::build_cwbvh_from_tris;
    use obvhs::ray::{Ray as ORay, RayHit};
    use obvhs::triangle::Triangle;

    struct Peer {
        bvh: CwBvh,
        tris: Vec<Triangle>,
    }
    impl Tracer for Peer {
        fn closest(&self, r: &Ray, t_max: f32) -> f32 {
            let ray = ORay::new(r.o, r.d, 0.0, t_max);
            let mut hit = RayHit::none();
            if self.bvh.ray_traverse(ray, &mut hit, |ray, id| {
                self.tris[self.bvh.primitive_indices[id] as usize].intersect(ray)
            }) {
                hit.t
            } else {
                -1.0
            }
        }
        fn occluded(&self, r: &Ray, t_max: f32) -> bool {
            let ray = ORay::new(r.o, r.d, 0.0, t_max);
            !self.bvh.ray_traverse_miss(ray, |ray, id| {
                self.tris[self.bvh.primitive_indices[id] as usize].intersect(ray)
            })
        }
    }

    let tris: Vec<Triangle> = sc
        .meshes
        .iter()
        .flat_map(|(pos, idx)| {
            idx.iter().map(|t| Triangle {
                v0: pos[t[0] as usize],
                v1: pos[t[1] as usize],
                v2: pos[t[2] as usize],
            })
        })
        .collect();
    let (build, bvh) = best_build(|| {
        pool.install(|| {
            build_cwbvh_from_tris(
                &tris,
                BvhBuildParams::medium_build(),
                &mut Duration::default(),
            )
        })
    });
    let peer = Peer { bvh, tris };
    let (f, _) = measure(pool, "obvhs CWBVH", build, &peer, &sc.sets, ours);
    black_box(&peer.bvh);
    f
}

/// Minimal hand-written FFI to the system's Embree 3 (`libembree3.so`, Debian `libembree-dev`).
#[cfg(feature = "embree")]
mod embree {
    use super::*;
    use std::ffi::{c_char, c_uint, c_void};

    type Device = *mut c_void;
    type Scene = *mut c_void;
    type Geometry = *mut c_void;

    const GEOMETRY_TYPE_TRIANGLE: c_uint = 0;
    const BUFFER_TYPE_INDEX: c_uint = 0;
    const BUFFER_TYPE_VERTEX: c_uint = 1;
    const FORMAT_UINT3: c_uint = 0x5003;
    const FORMAT_FLOAT3: c_uint = 0x9003;
    const BUILD_QUALITY_HIGH: c_uint = 2;
    const INVALID_ID: c_uint = u32::MAX;

    #[repr(C, align(16))]
    #[derive(Clone, Copy)]
    struct RtcRay {
        org: [f32; 3],
        tnear: f32,
        dir: [f32; 3],
        time: f32,
        tfar: f32,
        mask: c_uint,
        id: c_uint,
        flags: c_uint,
    }

    #[repr(C, align(16))]
    #[derive(Clone, Copy)]
    struct RtcHit {
        ng: [f32; 3],
        u: f32,
        v: f32,
        prim_id: c_uint,
        geom_id: c_uint,
        inst_id: [c_uint; 1],
    }

    #[repr(C)]
    struct RtcRayHit {
        ray: RtcRay,
        hit: RtcHit,
    }

    /// `RTCIntersectContext` for RTC_MAX_INSTANCE_LEVEL_COUNT = 1 and RTC_MIN_WIDTH = 0.
    #[repr(C)]
    struct RtcContext {
        flags: c_uint,
        filter: Option<unsafe extern "C" fn(*const c_void)>,
        inst_id: [c_uint; 1],
    }

    #[link(name = "embree3")]
    unsafe extern "C" {
        fn rtcNewDevice(config: *const c_char) -> Device;
        fn rtcReleaseDevice(device: Device);
        fn rtcNewScene(device: Device) -> Scene;
        fn rtcReleaseScene(scene: Scene);
        fn rtcSetSceneBuildQuality(scene: Scene, quality: c_uint);
        fn rtcNewGeometry(device: Device, ty: c_uint) -> Geometry;
        fn rtcSetNewGeometryBuffer(
            geometry: Geometry,
            ty: c_uint,
            slot: c_uint,
            format: c_uint,
            byte_stride: usize,
            item_count: usize,
        ) -> *mut c_void;
        fn rtcCommitGeometry(geometry: Geometry);
        fn rtcAttachGeometry(scene: Scene, geometry: Geometry) -> c_uint;
        fn rtcReleaseGeometry(geometry: Geometry);
        fn rtcCommitScene(scene: Scene);
        fn rtcIntersect1(scene: Scene, context: *mut RtcContext, rayhit: *mut RtcRayHit);
        fn rtcOccluded1(scene: Scene, context: *mut RtcContext, ray: *mut RtcRay);
    }

    /// A committed scene and its device, only read after commit: Embree documents
    /// `rtcIntersect1` / `rtcOccluded1` on a committed scene as thread-safe.
    struct Committed {
        device: Device,
        scene: Scene,
    }
    // SAFETY: a committed Embree scene is immutable and its query functions are thread-safe.
    unsafe impl Sync for Committed {}
    // SAFETY: as above; the handles are plain pointers owned by the Embree device.
    unsafe impl Send for Committed {}

    impl Drop for Committed {
        fn drop(&mut self) {
            // SAFETY: no queries run any more (we are dropped); handles are valid and
            // released once.
            unsafe {
                rtcReleaseScene(self.scene);
                rtcReleaseDevice(self.device);
            }
        }
    }

    fn context() -> RtcContext {
        RtcContext {
            flags: 0,
            filter: None,
            inst_id: [INVALID_ID],
        }
    }

    fn ray(r: &Ray, tfar: f32) -> RtcRay {
        RtcRay {
            org: r.o.to_array(),
            tnear: 0.0,
            dir: r.d.to_array(),
            time: 0.0,
            tfar,
            mask: u32::MAX,
            id: 0,
            flags: 0,
        }
    }

    impl Tracer for Committed {
        fn closest(&self, r: &Ray, t_max: f32) -> f32 {
            let mut rh = RtcRayHit {
                ray: ray(r, t_max),
                hit: RtcHit {
                    ng: [0.0; 3],
                    u: 0.0,
                    v: 0.0,
                    prim_id: 0,
                    geom_id: INVALID_ID,
                    inst_id: [INVALID_ID],
                },
            };
            let mut ctx = context();
            // SAFETY: committed scene, valid context and ray-hit structs of the C layout.
            unsafe { rtcIntersect1(self.scene, &mut ctx, &mut rh) };
            if rh.hit.geom_id == INVALID_ID {
                -1.0
            } else {
                rh.ray.tfar
            }
        }
        fn occluded(&self, r: &Ray, t_max: f32) -> bool {
            let mut rr = ray(r, t_max);
            let mut ctx = context();
            // SAFETY: committed scene, valid context and ray struct of the C layout.
            unsafe { rtcOccluded1(self.scene, &mut ctx, &mut rr) };
            rr.tfar == f32::NEG_INFINITY
        }
    }

    /// Builds one triangle geometry from `pos`, `idx` and attaches it to `scene`.
    fn attach(device: Device, scene: Scene, pos: &[Vec3], idx: &[[u32; 3]]) {
        // SAFETY: `device` is valid and TRIANGLE is a valid RTCGeometryType.
        let geom = unsafe { rtcNewGeometry(device, GEOMETRY_TYPE_TRIANGLE) };
        // SAFETY: Embree allocates a buffer of `pos.len()` float3 items with a 12-byte stride (it
        // pads the allocation for 16-byte loads) and returns a pointer to it, or null on error.
        let vb = unsafe {
            rtcSetNewGeometryBuffer(geom, BUFFER_TYPE_VERTEX, 0, FORMAT_FLOAT3, 12, pos.len())
        } as *mut f32;
        assert!(!vb.is_null());
        // SAFETY: `vb` points to `3 * pos.len()` writable floats (see above), not aliased.
        let vbs = unsafe { std::slice::from_raw_parts_mut(vb, 3 * pos.len()) };
        for (d, p) in vbs.chunks_exact_mut(3).zip(pos) {
            d.copy_from_slice(&p.to_array());
        }
        // SAFETY: as for the vertex buffer: `idx.len()` uint3 items, 12-byte stride.
        let ib = unsafe {
            rtcSetNewGeometryBuffer(geom, BUFFER_TYPE_INDEX, 0, FORMAT_UINT3, 12, idx.len())
        } as *mut u32;
        assert!(!ib.is_null());
        // SAFETY: `ib` points to `3 * idx.len()` writable u32s, not aliased.
        let ibs = unsafe { std::slice::from_raw_parts_mut(ib, 3 * idx.len()) };
        for (d, t) in ibs.chunks_exact_mut(3).zip(idx) {
            d.copy_from_slice(t);
        }
        // SAFETY: valid handles; the scene takes its own reference to the geometry, so
        // releasing ours after attaching is the documented pattern.
        unsafe {
            rtcCommitGeometry(geom);
            rtcAttachGeometry(scene, geom);
            rtcReleaseGeometry(geom);
        }
    }

    pub(super) fn run(
        pool: &rayon::ThreadPool,
        sc: &BenchScene,
        ours: Option<&[Vec<f32>]>,
    ) -> Figures {
        let (build, committed) = best_build(|| {
            // SAFETY: a null config string is allowed and selects the defaults.
            let device = unsafe { rtcNewDevice(std::ptr::null()) };
            assert!(!device.is_null(), "rtcNewDevice failed");
            // SAFETY: `device` is a valid device handle.
            let scene = unsafe { rtcNewScene(device) };
            // SAFETY: `scene` is a valid scene handle; HIGH is a valid RTCBuildQuality.
            unsafe { rtcSetSceneBuildQuality(scene, BUILD_QUALITY_HIGH) };
            for (pos, idx) in &sc.meshes {
                attach(device, scene, pos, idx);
            }
            // SAFETY: a valid scene with its geometries committed.
            unsafe { rtcCommitScene(scene) };
            Committed { device, scene }
        });
        let (f, _) = measure(pool, "Embree 3", build, &committed, &sc.sets, ours);
        f
    }
}
