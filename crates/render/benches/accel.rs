//! Benchmark of `render::accel` on a ~1M-triangle mesh with 1M incoherent rays on 2 threads.
//!
//! Scene: a tessellated UV sphere of radius 1 (708 × 708 quads → 1,000,000 + triangles) whose
//! radius is displaced by a sum of sines (amplitude ≈ 0.1), so the surface is closed, bumpy and
//! has varied triangle sizes (small near the poles). Rays: origins uniform in the mesh bounds
//! (so both inside and outside the surface), directions uniform on the sphere (fixed seed).
//! Closest-hit rays have `t_max = ∞`; occlusion rays have `t_max` uniform in `[0, ½·diag)`, so
//! a mix of occluded and unoccluded shadow rays.
//!
//! Peers measured in the same run on the same rays: obvhs' stock CWBVH traversal with its own
//! (Möller–Trumbore) triangle test, and Embree 3 (`--features embree`, system libembree3).
//! Run: `cargo bench -p penumbra-render --bench accel [--features embree]`.

use std::hint::black_box;
use std::sync::Arc;
use std::time::{Duration, Instant};

use rayon::prelude::*;
use render::accel::{Accel, AccelShape};
use render::geometry::Ray;
use render::math::Vec3;

const GRID: u32 = 708;
const RAYS: usize = 1_000_000;
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

fn mesh() -> (Vec<Vec3>, Vec<[u32; 3]>) {
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

/// CPU time of this process (Linux `/proc/self/stat`, clock ticks of 10 ms); 0 elsewhere.
fn cpu_secs() -> f64 {
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

fn mrays(n: usize, secs: f64) -> f64 {
    n as f64 / secs / 1e6
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

/// Seconds of wall time and of process CPU time (user + system, 10 ms resolution). The CPU
/// time is what to compare on a machine shared with other jobs: wall time there depends on
/// how much of the 2 cores the scheduler gave us.
#[derive(Clone, Copy)]
struct Timing {
    wall: f64,
    cpu: f64,
}

struct Figures {
    name: &'static str,
    build: Duration,
    closest: Timing,
    occluded: Timing,
    hits: usize,
    occl: usize,
}

fn main() {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(THREADS)
        .build()
        .expect("thread pool");
    let (pos, idx) = mesh();
    println!(
        "mesh: {} triangles, {} vertices; {RAYS} rays, {THREADS} threads",
        idx.len(),
        pos.len()
    );

    let mut rng = Rng(0x5eed);
    let (lo, hi) = pos
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(a, b), &p| {
            (a.min(p), b.max(p))
        });
    let diag = (hi - lo).length();
    let rays: Vec<(Ray, f32)> = (0..RAYS)
        .map(|_| {
            let o = lo + (hi - lo) * Vec3::new(rng.f(), rng.f(), rng.f());
            let z = 1.0 - 2.0 * rng.f();
            let r = (1.0 - z * z).max(0.0).sqrt();
            let phi = 2.0 * std::f32::consts::PI * rng.f();
            let d = Vec3::new(r * phi.cos(), r * phi.sin(), z);
            (Ray::new(o, d), 0.5 * diag * rng.f())
        })
        .collect();

    let mut all = Vec::new();

    // ---- ours
    let positions: Arc<[Vec3]> = pos.clone().into();
    let indices: Arc<[[u32; 3]]> = idx.clone().into();
    let t0 = Instant::now();
    let accel = pool.install(|| Accel::build(vec![AccelShape::Triangles { positions, indices }]));
    let build = t0.elapsed();
    let (closest, hits) = best_of(|| {
        pool.install(|| {
            rays.par_iter()
                .filter(|(r, _)| accel.intersect(r, f32::INFINITY).is_some())
                .count()
        })
    });
    let (occluded, occl) = best_of(|| {
        pool.install(|| {
            rays.par_iter()
                .filter(|(r, tm)| accel.occluded(r, *tm))
                .count()
        })
    });
    all.push(Figures {
        name: "penumbra BVH8",
        build,
        closest,
        occluded,
        hits,
        occl,
    });
    // A checksum of the closest hits, so peers can be compared for agreement.
    let ours_t: Vec<f32> = pool.install(|| {
        rays.par_iter()
            .map(|(r, _)| accel.intersect(r, f32::INFINITY).map_or(-1.0, |h| h.t))
            .collect()
    });
    drop(accel);

    // ---- obvhs stock CWBVH
    all.push(obvhs_peer(&pool, &pos, &idx, &rays, &ours_t));

    // ---- Embree 3
    #[cfg(feature = "embree")]
    all.push(embree::run(&pool, &pos, &idx, &rays, &ours_t));
    #[cfg(not(feature = "embree"))]
    println!("Embree 3: not measured (build with `--features embree`; needs libembree-dev 3.x)");

    println!();
    println!(
        "{:<16} {:>9} | {:>13} {:>13} | {:>13} {:>13} | {:>7} {:>8}",
        "", "", "closest-hit", "", "occlusion", "", "", ""
    );
    println!(
        "{:<16} {:>9} | {:>13} {:>13} | {:>13} {:>13} | {:>7} {:>8}",
        "structure",
        "build ms",
        "Mrays/s wall",
        "Mrays/CPU-s",
        "Mrays/s wall",
        "Mrays/CPU-s",
        "hits",
        "occluded"
    );
    for f in &all {
        println!(
            "{:<16} {:>9.0} | {:>13.2} {:>13.2} | {:>13.2} {:>13.2} | {:>7} {:>8}",
            f.name,
            f.build.as_secs_f64() * 1e3,
            mrays(RAYS, f.closest.wall),
            mrays(RAYS, f.closest.cpu),
            mrays(RAYS, f.occluded.wall),
            mrays(RAYS, f.occluded.cpu),
            f.hits,
            f.occl
        );
    }
    let ours = &all[0];
    for peer in &all[1..] {
        println!(
            "penumbra / {}: build time {:.2}; speed (per CPU-s) closest-hit {:.2}, occlusion {:.2}; \
             (wall) {:.2}, {:.2}",
            peer.name,
            ours.build.as_secs_f64() / peer.build.as_secs_f64(),
            peer.closest.cpu / ours.closest.cpu,
            peer.occluded.cpu / ours.occluded.cpu,
            peer.closest.wall / ours.closest.wall,
            peer.occluded.wall / ours.occluded.wall,
        );
    }
}

fn obvhs_peer(
    pool: &rayon::ThreadPool,
    pos: &[Vec3],
    idx: &[[u32; 3]],
    rays: &[(Ray, f32)],
    ours_t: &[f32],
) -> Figures {
    use obvhs::BvhBuildParams;
    use obvhs::cwbvh::builder::build_cwbvh_from_tris;
    use obvhs::ray::{Ray as ORay, RayHit};
    use obvhs::triangle::Triangle;

    let tris: Vec<Triangle> = idx
        .iter()
        .map(|t| Triangle {
            v0: pos[t[0] as usize],
            v1: pos[t[1] as usize],
            v2: pos[t[2] as usize],
        })
        .collect();
    let t0 = Instant::now();
    let bvh = pool.install(|| {
        build_cwbvh_from_tris(
            &tris,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        )
    });
    let build = t0.elapsed();
    let closest_t = |r: &Ray| {
        let ray = ORay::new_inf(r.o, r.d);
        let mut hit = RayHit::none();
        if bvh.ray_traverse(ray, &mut hit, |ray, id| {
            tris[bvh.primitive_indices[id] as usize].intersect(ray)
        }) {
            hit.t
        } else {
            -1.0
        }
    };
    let (closest, hits) =
        best_of(|| pool.install(|| rays.par_iter().filter(|(r, _)| closest_t(r) >= 0.0).count()));
    let (occluded, occl) = best_of(|| {
        pool.install(|| {
            rays.par_iter()
                .filter(|(r, tm)| {
                    let ray = ORay::new(r.o, r.d, 0.0, *tm);
                    !bvh.ray_traverse_miss(ray, |ray, id| {
                        tris[bvh.primitive_indices[id] as usize].intersect(ray)
                    })
                })
                .count()
        })
    });
    let differ = pool.install(|| {
        rays.par_iter()
            .zip(ours_t.par_iter())
            .filter(|((r, _), t)| {
                let t = **t;
                let o = closest_t(r);
                (o < 0.0) != (t < 0.0) || (o - t).abs() > 1e-4 * t.abs().max(1.0)
            })
            .count()
    });
    println!(
        "obvhs CWBVH: {differ} closest hits differ from ours (its triangle test is not watertight)"
    );
    black_box(&bvh);
    Figures {
        name: "obvhs CWBVH",
        build,
        closest,
        occluded,
        hits,
        occl,
    }
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

    /// The committed scene, only read after commit: Embree documents `rtcIntersect1` /
    /// `rtcOccluded1` on a committed scene as thread-safe.
    struct SharedScene(Scene);
    // SAFETY: a committed Embree scene is immutable and its query functions are thread-safe.
    unsafe impl Sync for SharedScene {}
    // SAFETY: as above; the handle is a plain pointer owned by the Embree device.
    unsafe impl Send for SharedScene {}

    impl SharedScene {
        fn get(&self) -> Scene {
            self.0
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

    pub(super) fn run(
        pool: &rayon::ThreadPool,
        pos: &[Vec3],
        idx: &[[u32; 3]],
        rays: &[(Ray, f32)],
        ours_t: &[f32],
    ) -> Figures {
        let t0 = Instant::now();
        // SAFETY: a null config string is allowed and selects the defaults.
        let device = unsafe { rtcNewDevice(std::ptr::null()) };
        assert!(!device.is_null(), "rtcNewDevice failed");
        // SAFETY: `device` is a valid device handle.
        let scene = unsafe { rtcNewScene(device) };
        // SAFETY: `scene` is a valid scene handle; HIGH is a valid RTCBuildQuality.
        unsafe { rtcSetSceneBuildQuality(scene, BUILD_QUALITY_HIGH) };
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
            rtcCommitScene(scene);
        }
        let build = t0.elapsed();
        let shared = &SharedScene(scene);
        let closest_t = |r: &Ray| {
            let mut rh = RtcRayHit {
                ray: ray(r, f32::INFINITY),
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
            unsafe { rtcIntersect1(shared.get(), &mut ctx, &mut rh) };
            if rh.hit.geom_id == INVALID_ID {
                -1.0
            } else {
                rh.ray.tfar
            }
        };
        let (closest, hits) = best_of(|| {
            pool.install(|| rays.par_iter().filter(|(r, _)| closest_t(r) >= 0.0).count())
        });
        let (occluded, occl) = best_of(|| {
            pool.install(|| {
                rays.par_iter()
                    .filter(|(r, tm)| {
                        let mut rr = ray(r, *tm);
                        let mut ctx = context();
                        // SAFETY: committed scene, valid context and ray struct of the C layout.
                        unsafe { rtcOccluded1(shared.get(), &mut ctx, &mut rr) };
                        rr.tfar == f32::NEG_INFINITY
                    })
                    .count()
            })
        });
        let differ = pool.install(|| {
            rays.par_iter()
                .zip(ours_t.par_iter())
                .filter(|((r, _), t)| {
                    let t = **t;
                    let o = closest_t(r);
                    (o < 0.0) != (t < 0.0) || (o - t).abs() > 1e-4 * t.abs().max(1.0)
                })
                .count()
        });
        println!("Embree 3: {differ} closest hits differ from ours");
        // SAFETY: no queries are running any more; handles are valid and released once.
        unsafe {
            rtcReleaseScene(scene);
            rtcReleaseDevice(device);
        }
        Figures {
            name: "Embree 3",
            build,
            closest,
            occluded,
            hits,
            occl,
        }
    }
}
