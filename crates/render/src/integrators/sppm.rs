//! Progressive photon mapping: stochastic (SPPM, Hachisuka & Jensen 2009) with pbrt-v4's
//! semantics, and the original with fixed visible points (PPM, Hachisuka, Ogaki & Jensen
//! 2008, [`Progressive::Fixed`]: the camera pass below runs once, with `eye_samples` paths
//! per pixel, each its own measurement with its own radius; photons deposit from their
//! first hit, since no next-event estimate is made). `--spp` is the number of iterations;
//! each SPPM iteration
//!
//! 1. traces one camera path per pixel to its first vertex with a non-delta BSDF lobe — a
//!    *visible point* — adding the emission seen directly or through delta bounces and one
//!    next-event estimate at the visible point (`ld`); a BSDF with delta and non-delta lobes
//!    (smooth plastic) gets a visible point for its non-delta part and its path goes on
//!    through the delta part when the BSDF samples it, so a pixel may hold several;
//! 2. puts the visible points in a hash grid of cells as wide as the largest radius
//!    (counting sort, so the grid is the same whatever the thread count);
//! 3. traces `photons` photon paths from the lights (chosen by power, [`Light::sample_le`]);
//!    from its second surface hit on (the first is direct light, already in `ld`) a photon
//!    adds β·f(wo, wi) to every visible point within its pixel's radius whose camera path
//!    leaves room for it (`max_depth` bounds the whole path: camera edges + photon edges);
//! 4. shrinks each pixel's radius: with M photons found, N' = N + αM, R' = R·√(N'/(N + M)),
//!    τ' = (τ + Σ β_vp·Φ)·R'²/R².
//!
//! The pixel's radiance after k iterations of `photons` photons is
//! Σ ld / k + τ / (k·photons·π·R²).
//!
//! Determinism: camera paths draw from the pixel's sampler stream (sample index = iteration),
//! photon `j` of iteration `i` from its own stream, and photons are traced in fixed chunks whose
//! contributions are added to the pixels in chunk order: the image is a function of the seed
//! and never of the thread count.
//!
//! Spectral mode: in SPPM all the paths of an iteration carry one set of wavelengths, which
//! follows a rank-1 lattice over the iterations; PPM's visible points are traced once, so
//! they are spread over [`super::photon::WAVELENGTH_SETS`] sets by slot and each pass
//! traces a group of photons per set ([`render`]). Not yet: media.

use std::time::Instant;

use rayon::prelude::*;

use super::photons::{self, PhotonHit, PhotonLights};
use crate::bsdf::{Bsdf, TransportMode};
use crate::film::{Film, Filter};
use crate::math::{Frame, PI, UVec2, Vec2, Vec3};
use crate::sampling::Sampler;
use crate::session::{RenderObserver, RenderOptions, RenderOutcome, camera_sample, run_passes};
use crate::spectral::lanes::{Color, PathMode, RgbMode, SpectralMode};
use crate::world::Scene;
use base::FilterDesc;

/// The parameters of [`render`].
#[derive(Clone, Debug, PartialEq)]
pub struct SppmConfig {
    /// Longest path in edges, camera to light (−1: unbounded; Mitsuba's `max_depth`).
    pub max_depth: i32,
    /// Russian roulette on camera paths through delta bounces from this depth on.
    pub rr_depth: u32,
    /// Photon paths per iteration; `None`: the number of pixels (pbrt-v4).
    pub photons: Option<u64>,
    /// Initial radius of every pixel; `None`: 5 × the scene's bounding radius divided by the
    /// film's larger side (Mitsuba 0.6's guess).
    pub initial_radius: Option<f32>,
    /// The fraction α of the new photons a pixel keeps (pbrt-v4: 2/3).
    pub alpha: f32,
    /// Stochastic (SPPM) or fixed visible points (PPM).
    pub kind: Progressive,
}

/// Which progressive photon mapping.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Progressive {
    /// SPPM: new visible points every iteration, one camera path per pixel; direct light by
    /// next-event estimation at the visible points.
    #[default]
    Stochastic,
    /// PPM (Hachisuka, Ogaki & Jensen 2008): `eye_samples` camera paths per pixel traced
    /// once; their visible points keep their own radius and gather every photon, direct
    /// light included.
    Fixed { eye_samples: u32 },
}

impl Default for SppmConfig {
    fn default() -> Self {
        SppmConfig {
            max_depth: -1,
            rr_depth: 5,
            photons: None,
            initial_radius: None,
            alpha: 2.0 / 3.0,
            kind: Progressive::Stochastic,
        }
    }
}

impl SppmConfig {
    fn allows(&self, edges: u32) -> bool {
        self.max_depth < 0 || edges <= self.max_depth as u32
    }
}

/// A camera path's first vertex with a non-delta BSDF lobe.
struct VisiblePoint<C: Color> {
    /// The measurement it adds to: the pixel (row-major within the crop window) in SPPM,
    /// the pixel's eye sample in PPM.
    slot: u32,
    /// Edges from the camera to this point.
    depth: u32,
    p: Vec3,
    /// Towards the camera, in the BSDF's frame.
    wo: Vec3,
    frame: Frame,
    bsdf: Bsdf<C>,
    /// Camera path throughput up to here.
    beta: C,
    /// Whether the camera path's secondary wavelengths were terminated (spectral mode).
    terminated: bool,
}

/// One row's camera pass: each slot's `ld` (linear sRGB) and the row's visible points.
type CameraRow<C> = (Vec<Vec3>, Vec<VisiblePoint<C>>);

/// A measurement's statistics across iterations.
#[derive(Clone, Copy)]
struct Slot {
    /// SPPM: Σ over iterations of the emission seen along delta bounces and the next-event
    /// estimates. PPM: the emission seen along the slot's fixed path.
    ld: Vec3,
    radius: f32,
    /// N: photons kept (fractional).
    n: f32,
    /// τ: flux kept, already times the visible points' throughput.
    tau: Vec3,
}

/// Counting-sorted hash grid over the visible points.
struct Grid {
    lo: Vec3,
    inv_cell: f32,
    res: [i64; 3],
    /// Table slot → range in `items`.
    starts: Vec<u32>,
    items: Vec<u32>,
}

fn hash_cell(c: [i64; 3], slots: usize) -> usize {
    let h = (c[0].wrapping_mul(73_856_093))
        ^ (c[1].wrapping_mul(19_349_663))
        ^ (c[2].wrapping_mul(83_492_791));
    (h as u64 % slots as u64) as usize
}

impl Grid {
    fn build<C: Color>(
        vps: &[VisiblePoint<C>],
        radius: impl Fn(&VisiblePoint<C>) -> f32,
    ) -> Option<Grid> {
        let max_r = vps.iter().map(&radius).fold(0.0f32, f32::max);
        if vps.is_empty() || !(max_r > 0.0 && max_r.is_finite()) {
            return None;
        }
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for v in vps {
            lo = lo.min(v.p);
            hi = hi.max(v.p);
        }
        lo -= Vec3::splat(max_r);
        hi += Vec3::splat(max_r);
        let inv_cell = 1.0 / max_r;
        let ext = (hi - lo) * inv_cell;
        let res = [ext.x, ext.y, ext.z].map(|e| (e.ceil() as i64).clamp(1, 1 << 20));
        let slots = vps.len().next_power_of_two().max(1);
        let cell = |p: Vec3, res: &[i64; 3]| -> [i64; 3] {
            let q = (p - lo) * inv_cell;
            let q = [q.x, q.y, q.z];
            std::array::from_fn(|k| (q[k].floor() as i64).clamp(0, res[k] - 1))
        };
        // Count, then fill, in visible point order.
        let mut counts = vec![0u32; slots + 1];
        let each = |f: &mut dyn FnMut(usize, u32)| {
            for (i, v) in vps.iter().enumerate() {
                let r = Vec3::splat(radius(v));
                let (a, b) = (cell(v.p - r, &res), cell(v.p + r, &res));
                for z in a[2]..=b[2] {
                    for y in a[1]..=b[1] {
                        for x in a[0]..=b[0] {
                            f(hash_cell([x, y, z], slots), i as u32);
                        }
                    }
                }
            }
        };
        each(&mut |s, _| counts[s + 1] += 1);
        for s in 0..slots {
            counts[s + 1] += counts[s];
        }
        let mut items = vec![0u32; counts[slots] as usize];
        let mut fill = counts.clone();
        each(&mut |s, i| {
            items[fill[s] as usize] = i;
            fill[s] += 1;
        });
        Some(Grid {
            lo,
            inv_cell,
            res,
            starts: counts,
            items,
        })
    }

    /// The visible points whose cells may hold `p`.
    fn near(&self, p: Vec3) -> &[u32] {
        let q = (p - self.lo) * self.inv_cell;
        let mut c = [0i64; 3];
        for (k, x) in [q.x, q.y, q.z].into_iter().enumerate() {
            let x = x.floor();
            if !(x >= 0.0 && (x as i64) < self.res[k]) {
                return &[];
            }
            c[k] = x as i64;
        }
        let s = hash_cell(c, self.starts.len() - 1);
        &self.items[self.starts[s] as usize..self.starts[s + 1] as usize]
    }
}

/// Camera pass for one pixel: the estimate `ld` and the visible points.
#[allow(clippy::too_many_arguments)]
fn camera_path<M: PathMode>(
    scene: &Scene,
    cfg: &SppmConfig,
    sampler: &mut Sampler,
    pixel: UVec2,
    sample: u32,
    slot: u32,
    nee: bool,
    m: &M,
    vps: &mut Vec<VisiblePoint<M::C>>,
) -> Vec3 {
    let (_, cray) = camera_sample(scene, sampler, pixel, sample);
    // The shortest photon path that can reach a visible point: 2 edges when next-event
    // estimation has the direct light, else 1.
    let first = if nee { 2 } else { 1 };
    let ld = photons::walk(
        scene,
        cray.ray,
        cray.t_max,
        M::C::ONE,
        0,
        true,
        cfg.max_depth,
        cfg.rr_depth,
        m,
        sampler,
        |v, sampler| {
            if cfg.allows(v.depth + first) {
                vps.push(VisiblePoint {
                    slot,
                    depth: v.depth,
                    p: v.si.p,
                    wo: v.wo,
                    frame: *v.frame,
                    bsdf: v.bsdf.clone(),
                    beta: v.beta,
                    terminated: m.terminated(),
                });
            }
            if nee && cfg.allows(v.depth + 1) {
                photons::next_event(scene, v.si, v.bsdf, v.frame, v.wo, sampler, m)
            } else {
                M::C::ZERO
            }
        },
    );
    m.to_rgb(ld)
}

/// Add photon `hit` to every visible point within its slot's radius whose camera path leaves
/// room for it: (visible point, β_vp·f·β_photon as linear sRGB). Both paths carry the
/// iteration's wavelengths; `modes` converts with all of them or, when either path has
/// terminated its secondary wavelengths, the hero's alone.
#[allow(clippy::too_many_arguments)]
fn gather<M: PathMode>(
    cfg: &SppmConfig,
    grid: &Grid,
    vps: &[VisiblePoint<M::C>],
    radii: &[f32],
    first: u32,
    hit: &PhotonHit<M::C>,
    photon: &M,
    modes: &(M, M),
    out: &mut Vec<(u32, Vec3)>,
) {
    if hit.edges < first || hit.si.is_none() {
        return;
    }
    let p = hit.p;
    for &v in grid.near(p) {
        let vp = &vps[v as usize];
        let r = radii[vp.slot as usize];
        if (vp.p - p).length_squared() > r * r || !cfg.allows(vp.depth + hit.edges) {
            continue;
        }
        let wl = vp.frame.to_local(hit.wi);
        if wl.z == 0.0 {
            continue;
        }
        // eval is f·|cos θi|; the photon's flux already holds the cosine.
        let f = vp.bsdf.eval(vp.wo, wl, TransportMode::Radiance) / wl.z.abs();
        if f.is_black() {
            continue;
        }
        let mode = if vp.terminated || photon.terminated() {
            &modes.1
        } else {
            &modes.0
        };
        out.push((v, mode.to_rgb(vp.beta * f * hit.beta)));
    }
}

/// Peak bytes of SPPM's state for `scene`: a slot per pixel (per eye sample in PPM), about one
/// visible point per slot (at the spectral size when spectral), the grid's entries (up to 27
/// cells a point) and an iteration's photon contributions (about two per photon).
pub fn memory_needed(scene: &Scene, cfg: &SppmConfig) -> u64 {
    let f = &scene.film;
    let pixels = f.width as u64 * f.height as u64;
    let eye = match cfg.kind {
        Progressive::Stochastic => 1,
        Progressive::Fixed { eye_samples } => eye_samples.max(1) as u64,
    };
    let vp = match scene.mode {
        base::RenderMode::Rgb => std::mem::size_of::<VisiblePoint<Vec3>>(),
        base::RenderMode::Spectral => {
            std::mem::size_of::<VisiblePoint<crate::spectral::SampledSpectrum>>()
        }
    } as u64;
    let slots = pixels * eye;
    let photons = cfg.photons.unwrap_or(pixels);
    slots * (std::mem::size_of::<Slot>() as u64 + vp + 27 * 4 + 8)
        + photons.saturating_mul(2 * std::mem::size_of::<(u32, Vec3)>() as u64)
}

/// Render `scene` with SPPM: `opts.spp` iterations (a time budget or cancellation stops
/// after a whole iteration).
pub fn render(
    scene: &Scene,
    cfg: &SppmConfig,
    opts: &RenderOptions,
    observer: &dyn RenderObserver,
) -> RenderOutcome {
    match scene.mode {
        base::RenderMode::Rgb => render_in::<RgbMode>(scene, cfg, opts, observer),
        base::RenderMode::Spectral => {
            render_in::<SpectralMode<'static>>(scene, cfg, opts, observer)
        }
    }
}

/// [`render`] in the colour mode `M`: every path of an iteration (camera and photon) carries
/// the same wavelengths, drawn per iteration from the seed (pbrt-v4 draws them per pixel
/// and per photon; a shared set is what lets a photon's flux be weighed by a visible point's
/// BSDF at the same wavelengths — the extended-Nori write-up's one map per wavelength set).
fn render_in<M: PathMode + Send>(
    scene: &Scene,
    cfg: &SppmConfig,
    opts: &RenderOptions,
    observer: &dyn RenderObserver,
) -> RenderOutcome {
    let start = Instant::now();
    let f = &scene.film;
    let box_filter = Filter::new(&FilterDesc::Box { radius: 0.5 });
    let mut film = Film::new(f.width, f.height, f.crop, box_filter);
    let (pmin, pmax) = film.pixel_bounds();
    let size = pmax - pmin;
    let pixel_count = (size.x as usize) * (size.y as usize);
    let photons = cfg.photons.unwrap_or(pixel_count as u64).max(1);
    let radius0 = cfg.initial_radius.unwrap_or_else(|| {
        let (lo, hi) = scene.bounds;
        let r = 0.5 * (hi - lo).length();
        let r = if r.is_finite() && r > 0.0 { r } else { 1.0 };
        5.0 * r / f.width.max(f.height).max(1) as f32
    });
    let (eye, nee) = match cfg.kind {
        Progressive::Stochastic => (1, true),
        Progressive::Fixed { eye_samples } => (eye_samples.max(1), false),
    };
    // The edge of a photon path from which it deposits (its first hit is direct light,
    // which SPPM estimates by next-event estimation).
    let first = if nee { 2 } else { 1 };
    let slot_count = pixel_count * eye as usize;
    let mut slots = vec![
        Slot {
            ld: Vec3::ZERO,
            radius: radius0,
            n: 0.0,
            tau: Vec3::ZERO,
        };
        slot_count
    ];
    let lights = PhotonLights::new(scene);
    let camera_template = Sampler::new(scene.sampler.kind, opts.spp.max(eye), scene.sampler.seed);
    // Wavelength sets (`photons::wavelength_set`; RGB mode draws nothing). SPPM: set k for
    // iteration k, shared by all its paths. PPM in spectral mode: set g for the slots
    // s ≡ g (mod `WAVELENGTH_SETS`), fixed with the visible points (neighbouring pixels and
    // eye samples get different sets); each pass traces a group of photons per set,
    // gathered only by that set's visible points (the extended-Nori write-up's map per
    // wavelength set).
    let u_of = |set: u32| photons::wavelength_set(scene.sampler.seed, set as u64);
    let groups = match scene.mode {
        base::RenderMode::Spectral if !nee => super::photon::WAVELENGTH_SETS,
        _ => 1,
    };
    let group_photons = photons.div_ceil(groups as u64);
    let mut vps: Vec<Vec<VisiblePoint<M::C>>> = (0..groups).map(|_| Vec::new()).collect();
    let (done, cancelled) = run_passes(opts, observer, start, pixel_count as u64, |iteration| {
        // 1. Camera pass, one row per task: every iteration (SPPM) or once (PPM).
        if nee || iteration == 0 {
            let rows: Vec<CameraRow<M::C>> = (0..size.y)
                .into_par_iter()
                .map(|y| {
                    let mut sampler = camera_template.clone();
                    let mut vps = Vec::new();
                    let mut ld = Vec::with_capacity(size.x as usize * eye as usize);
                    for x in 0..size.x {
                        let pixel = pmin + UVec2::new(x, y);
                        for e in 0..eye {
                            let slot = (y * size.x + x) * eye + e;
                            // SPPM's iteration is its sample index and its wavelength
                            // set; PPM's eye sample is its sample index.
                            let (sample, set) = if nee {
                                (iteration, iteration)
                            } else {
                                (e, slot % groups)
                            };
                            ld.push(camera_path(
                                scene,
                                cfg,
                                &mut sampler,
                                pixel,
                                sample,
                                slot,
                                nee,
                                &M::from_u(u_of(set)),
                                &mut vps,
                            ));
                        }
                    }
                    (ld, vps)
                })
                .collect();
            vps.iter_mut().for_each(Vec::clear);
            let row_slots = size.x as usize * eye as usize;
            for (y, (ld, v)) in rows.into_iter().enumerate() {
                for (k, l) in ld.into_iter().enumerate() {
                    slots[y * row_slots + k].ld += l;
                }
                for vp in v {
                    vps[(vp.slot % groups) as usize].push(vp);
                }
            }
        }
        // 2. The grid; 3. photons in fixed chunks, merged in order; per group.
        let radii: Vec<f32> = slots.iter().map(|p| p.radius).collect();
        let mut slot_phi = vec![Vec3::ZERO; slot_count];
        let mut slot_m = vec![0u32; slot_count];
        for (g, vps) in vps.iter().enumerate() {
            let Some(grid) = Grid::build(vps, |v| radii[v.slot as usize]) else {
                continue;
            };
            if !lights.any() {
                break;
            }
            let set = if nee { iteration } else { g as u32 };
            let u = u_of(set);
            let lists = photons::trace_all(
                scene,
                &lights,
                cfg.max_depth,
                scene.sampler.seed,
                iteration * groups + g as u32,
                group_photons,
                |_| M::from_u(u),
                // Each chunk converts with its own pair of modes (a spectral mode is not Sync).
                || (Vec::new(), (M::from_u(u), M::from_u(u).terminate())),
                |(out, modes), hit, photon: &M, _: &mut Sampler| {
                    gather(cfg, &grid, vps, &radii, first, hit, photon, modes, out)
                },
            );
            for (list, _) in lists {
                for (v, c) in list {
                    let slot = vps[v as usize].slot as usize;
                    slot_phi[slot] += c;
                    slot_m[slot] += 1;
                }
            }
        }
        // 4. Radius reduction per slot.
        for ((p, &dphi), &m) in slots.iter_mut().zip(&slot_phi).zip(&slot_m) {
            if m == 0 {
                continue;
            }
            let n_new = p.n + cfg.alpha * m as f32;
            let r_new = p.radius * (n_new / (p.n + m as f32)).sqrt();
            let shrink = (r_new / p.radius) * (r_new / p.radius);
            p.tau = (p.tau + dphi) * shrink;
            p.n = n_new;
            p.radius = r_new;
        }
    });
    // The film: one sample at each pixel's centre, weight 1 under the box filter.
    if done > 0 {
        let mut tile = film.tile(pmin, pmax);
        // Photons each measurement could gather from.
        let np = done as f64 * group_photons as f64;
        // SPPM sums `ld` over the iterations; PPM's is the fixed path's.
        let ld_scale = if nee { 1.0 / done as f32 } else { 1.0 };
        for (i, px) in slots.chunks(eye as usize).enumerate() {
            let mut l = Vec3::ZERO;
            for p in px {
                let area = PI as f64 * (p.radius as f64) * (p.radius as f64);
                let indirect = p.tau.as_dvec3() / (np * area);
                l += p.ld * ld_scale + Vec3::from(indirect.as_vec3());
            }
            let (x, y) = ((i % size.x as usize) as u32, (i / size.x as usize) as u32);
            let centre = (pmin + UVec2::new(x, y)).as_vec2() + Vec2::splat(0.5);
            tile.add_sample(centre, l / eye as f32);
        }
        film.merge(&tile);
    }
    observer.pass_done(&film, done);
    RenderOutcome {
        film,
        spp: done,
        passes: done,
        elapsed: start.elapsed(),
        cancelled,
        extra: Vec::new(),
    }
}
