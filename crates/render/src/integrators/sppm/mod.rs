//! Progressive photon mapping: stochastic (SPPM, Hachisuka & Jensen 2009) with pbrt-v4's
//! semantics, and the original with fixed visible points (PPM, Hachisuka, Ogaki & Jensen
//! 2008, [`Progressive::Fixed`]: the camera pass below runs once, with `eye_samples` paths
//! per pixel, each its own measurement with its own radius; photons deposit from their
//! first hit, since no next-event estimate is made). `--spp` is the number of iterations;
//! each SPPM iteration
//!
//! 1. traces one camera path per pixel (the shared camera-side walk of the photon-mapping
//!    family) to its first vertex that is not a delta bounce — a *visible point*: a surface
//!    with a non-delta BSDF lobe, or a collision in a medium — adding the emission seen
//!    directly or through delta bounces and one next-event estimate at the visible point
//!    (`ld`); a BSDF with delta and non-delta lobes (smooth plastic) gets a visible point for
//!    its non-delta part and its path goes on through the delta part when the BSDF samples
//!    it, so a pixel may hold several (`visible.rs`);
//! 2. puts the visible points in a hash grid of cells as wide as the largest radius
//!    (`grid.rs`);
//! 3. traces `photons` photon paths from the lights and emitting media (chosen by power);
//!    from its second event on (the first is direct light, already in `ld`) a photon adds
//!    β·f(wo, wi) to every visible point of its kind — a surface hit to surface points, a
//!    collision in a medium to points in that medium, f then the phase function — within
//!    its pixel's radius of that kind whose camera path leaves room for it (`max_depth`
//!    bounds the whole path: camera edges + photon edges);
//! 4. shrinks each pixel's radii, one for its surface points and one for its points in media
//!    (volumetric visible points: photons there are a density per volume, so the kernel is
//!    a sphere): with M photons found, N' = N + αM, R' = R·(N'/(N + M))^(1/d),
//!    τ' = (τ + Σ β_vp·Φ)·(R'/R)^d, d = 2 on surfaces and 3 in media.
//!
//! The pixel's radiance after k iterations of `photons` photons is
//! Σ ld / k + τ₂ / (k·photons·π·R₂²) + τ₃ / (k·photons·4/3·π·R₃³). A visible point in a
//! medium keeps its camera throughput divided by σs there: the photons' collision density
//! already holds σs (their power after a collision is σs/σt of it), so that the sum is the
//! in-scattered radiance the path's collision stands for.
//!
//! Determinism: camera paths draw from the pixel's sampler stream (sample index = iteration),
//! photon `j` of iteration `i` from its own stream, and photons are traced in fixed chunks whose
//! contributions are added to the pixels in chunk order: the image is a function of the seed
//! and never of the thread count.
//!
//! Spectral mode: in SPPM all the paths of an iteration carry one set of wavelengths, which
//! follows a rank-1 lattice over the iterations; PPM's visible points are traced once, so
//! they are spread over [`super::photon::WAVELENGTH_SETS`] sets by slot and each pass
//! traces a group of photons per set.

mod grid;
mod visible;

use std::time::Instant;

use rayon::prelude::*;

use self::grid::Grid;
use self::visible::{CameraPass, CameraSample, Gatherers, VisiblePoint};
use super::photons::{self, PhotonHit, PhotonJob, PhotonLights};
use super::{IntegratorModel, volume_unsupported};
use crate::drive::run_passes;
use crate::film::{Film, Filter};
use crate::math::{PI, UVec2, Vec2, Vec3};
use crate::sampling::Sampler;
use crate::session::{Job, RenderOptions, RenderOutcome};
use crate::spectral::lanes::PathMode;
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
    pub(super) fn allows(&self, edges: u32) -> bool {
        self.max_depth < 0 || edges <= self.max_depth as u32
    }
}

/// A kernel's statistics across iterations (pbrt-v4's per-pixel SPPM state).
#[derive(Clone, Copy)]
struct Kernel {
    radius: f32,
    /// N: photons kept (fractional).
    n: f32,
    /// τ: flux kept, already times the visible points' throughput.
    tau: Vec3,
}

impl Kernel {
    /// The iteration found `m` photons adding `dphi`: keep the fraction α of them and shrink
    /// the radius so that the density estimate in `dims` dimensions keeps its value.
    fn shrink(&mut self, dphi: Vec3, m: u32, alpha: f32, dims: u32) {
        if m == 0 {
            return;
        }
        let n_new = self.n + alpha * m as f32;
        let ratio = n_new / (self.n + m as f32);
        let (r_new, shrink) = if dims == 2 {
            let r_new = self.radius * ratio.sqrt();
            (r_new, (r_new / self.radius) * (r_new / self.radius))
        } else {
            let r_new = self.radius * ratio.cbrt();
            let s = r_new / self.radius;
            (r_new, s * s * s)
        };
        self.tau = (self.tau + dphi) * shrink;
        self.n = n_new;
        self.radius = r_new;
    }

    /// τ / (photons · kernel volume): the radiance the flux stands for.
    fn radiance(&self, photons: f64, dims: u32) -> Vec3 {
        if self.tau == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let r = self.radius as f64;
        let size = if dims == 2 {
            PI as f64 * r * r
        } else {
            4.0 / 3.0 * PI as f64 * r * r * r
        };
        Vec3::from((self.tau.as_dvec3() / (photons * size)).as_vec3())
    }
}

/// A measurement's statistics across iterations.
#[derive(Clone, Copy)]
struct Slot {
    /// SPPM: Σ over iterations of the emission seen along delta bounces and the next-event
    /// estimates. PPM: the emission seen along the slot's fixed path.
    ld: Vec3,
    /// The surface kernel and the volume kernel.
    kernels: [Kernel; 2],
}

/// One row's camera pass: each slot's `ld` (linear sRGB) and the row's visible points.
type CameraRow<C> = (Vec<Vec3>, Vec<VisiblePoint<C>>);

/// Peak bytes of SPPM's state for `scene`: a slot per pixel (per eye sample in PPM), about one
/// visible point per slot, the grid's entries (up to 27
/// cells a point) and an iteration's photon contributions (about two per photon).
pub fn memory_needed(scene: &Scene, cfg: &SppmConfig) -> u64 {
    let f = &scene.film;
    let pixels = f.width as u64 * f.height as u64;
    let eye = match cfg.kind {
        Progressive::Stochastic => 1,
        Progressive::Fixed { eye_samples } => eye_samples.max(1) as u64,
    };
    // At the size of a spectral one, the larger.
    let vp = std::mem::size_of::<VisiblePoint<Vec3>>().max(std::mem::size_of::<
        VisiblePoint<crate::spectral::SampledSpectrum>,
    >()) as u64;
    let slots = pixels * eye;
    let photons = cfg.photons.unwrap_or(pixels);
    slots * (std::mem::size_of::<Slot>() as u64 + vp + 27 * 4 + 8)
        + photons.saturating_mul(2 * std::mem::size_of::<(u32, Vec3)>() as u64)
}

impl IntegratorModel for SppmConfig {
    fn name(&self) -> &'static str {
        match self.kind {
            Progressive::Stochastic => "sppm",
            Progressive::Fixed { .. } => "ppm",
        }
    }

    fn unsupported(&self, scene: &Scene) -> Option<String> {
        volume_unsupported(self.name(), scene)
    }

    fn memory(&self, scene: &Scene) -> Option<(&'static str, u64)> {
        Some((
            "keeping the visible points and photon contributions",
            memory_needed(scene, self),
        ))
    }

    /// `opts.spp` iterations (a time budget or cancellation stops after a whole iteration).
    fn render<M: PathMode + Send>(&self, job: &Job) -> RenderOutcome {
        render_in::<M>(job, self)
    }
}

/// SPPM in the colour mode `M`: every path of an iteration (camera and photon) carries
/// the same wavelengths, drawn per iteration from the seed (pbrt-v4 draws them per pixel
/// and per photon; a shared set is what lets a photon's flux be weighed by a visible point's
/// BSDF at the same wavelengths — the extended-Nori write-up's one map per wavelength set).
fn render_in<M: PathMode + Send>(job: &Job, cfg: &SppmConfig) -> RenderOutcome {
    let start = Instant::now();
    let mut sppm = Sppm::<M>::new(job.scene, cfg, job.opts);
    let pixel_count = sppm.pixel_count() as u64;
    let (done, cancelled) = run_passes(job, start, pixel_count, |iteration| {
        if sppm.nee || iteration == 0 {
            sppm.camera_pass(iteration);
        }
        sppm.photon_pass(iteration);
    });
    let film = sppm.develop(done);
    job.observer.pass_done(&film, done);
    RenderOutcome::of_passes(film, done, start, cancelled)
}

/// SPPM's state between iterations.
struct Sppm<'a, M: PathMode> {
    scene: &'a Scene,
    cfg: &'a SppmConfig,
    film: Film,
    pmin: UVec2,
    size: UVec2,
    /// Camera paths per pixel (PPM's eye samples; 1 for SPPM).
    eye: u32,
    /// Next-event estimates at the visible points (SPPM; PPM gathers every photon).
    nee: bool,
    /// The edge of a photon path from which it deposits (its first hit is direct light,
    /// which SPPM estimates by next-event estimation).
    first: u32,
    /// Wavelength-set groups (`photons::wavelength_set`; RGB mode draws nothing). SPPM: set
    /// k for iteration k, shared by all its paths. PPM in spectral mode: set g for the slots
    /// s ≡ g (mod `WAVELENGTH_SETS`), fixed with the visible points (neighbouring pixels and
    /// eye samples get different sets); each pass traces a group of photons per set,
    /// gathered only by that set's visible points (the extended-Nori write-up's map per
    /// wavelength set).
    groups: u32,
    group_photons: u64,
    slots: Vec<Slot>,
    /// The visible points of each group.
    vps: Vec<Vec<VisiblePoint<M::C>>>,
    lights: PhotonLights,
    /// Where the point and spot lights are (segment estimates in media).
    points: Vec<Vec3>,
    camera_template: Sampler,
}

impl<'a, M: PathMode + Send> Sppm<'a, M> {
    fn new(scene: &'a Scene, cfg: &'a SppmConfig, opts: &RenderOptions) -> Self {
        let f = &scene.film;
        let box_filter = Filter::new(&FilterDesc::Box { radius: 0.5 });
        let film = Film::new(f.width, f.height, f.crop, box_filter);
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
        let groups = if M::SPECTRAL && !nee {
            super::photon::WAVELENGTH_SETS
        } else {
            1
        };
        let kernel = Kernel {
            radius: radius0,
            n: 0.0,
            tau: Vec3::ZERO,
        };
        let slot = Slot {
            ld: Vec3::ZERO,
            kernels: [kernel; 2],
        };
        Sppm {
            scene,
            cfg,
            film,
            pmin,
            size,
            eye,
            nee,
            first: if nee { 2 } else { 1 },
            groups,
            group_photons: photons.div_ceil(groups as u64),
            slots: vec![slot; pixel_count * eye as usize],
            vps: (0..groups).map(|_| Vec::new()).collect(),
            lights: PhotonLights::new(scene),
            points: scene.lights.iter().filter_map(|l| l.position()).collect(),
            camera_template: Sampler::new(
                scene.sampler.kind,
                opts.spp.max(eye),
                scene.sampler.seed,
            ),
        }
    }

    fn pixel_count(&self) -> usize {
        (self.size.x as usize) * (self.size.y as usize)
    }

    /// The uniform number of wavelength set `set`.
    fn set_u(&self, set: u32) -> f32 {
        photons::wavelength_set(self.scene.sampler.seed, set as u64)
    }

    /// The camera pass, one row per task: every iteration (SPPM) or once (PPM).
    fn camera_pass(&mut self, iteration: u32) {
        let (size, eye) = (self.size, self.eye);
        let pass = CameraPass {
            scene: self.scene,
            cfg: self.cfg,
            points: &self.points,
        };
        let rows: Vec<CameraRow<M::C>> = (0..size.y)
            .into_par_iter()
            .map(|y| {
                let mut sampler = self.camera_template.clone();
                let mut vps = Vec::new();
                let mut ld = Vec::with_capacity(size.x as usize * eye as usize);
                for x in 0..size.x {
                    for e in 0..eye {
                        let slot = (y * size.x + x) * eye + e;
                        // SPPM's iteration is its sample index and its wavelength set;
                        // PPM's eye sample is its sample index.
                        let (sample, set) = if self.nee {
                            (iteration, iteration)
                        } else {
                            (e, slot % self.groups)
                        };
                        let c = CameraSample {
                            pixel: self.pmin + UVec2::new(x, y),
                            sample,
                            slot,
                            nee: self.nee,
                        };
                        let m = M::from_u(self.set_u(set));
                        ld.push(pass.camera_path(&mut sampler, &c, &m, &mut vps));
                    }
                }
                (ld, vps)
            })
            .collect();
        self.vps.iter_mut().for_each(Vec::clear);
        let row_slots = size.x as usize * eye as usize;
        for (y, (ld, v)) in rows.into_iter().enumerate() {
            for (k, l) in ld.into_iter().enumerate() {
                self.slots[y * row_slots + k].ld += l;
            }
            for vp in v {
                self.vps[(vp.slot % self.groups) as usize].push(vp);
            }
        }
    }

    /// The grid, then photons in fixed chunks, merged in order, per group; then every
    /// slot's kernels shrink by what they found.
    fn photon_pass(&mut self, iteration: u32) {
        let (scene, cfg) = (self.scene, self.cfg);
        let radii: Vec<[f32; 2]> = (self.slots.iter())
            .map(|s| s.kernels.map(|k| k.radius))
            .collect();
        let slot_count = self.slots.len();
        let mut phi = vec![[Vec3::ZERO; 2]; slot_count];
        let mut found = vec![[0u32; 2]; slot_count];
        for (g, vps) in self.vps.iter().enumerate() {
            let sphere = |i: usize| {
                let v = &vps[i];
                (v.p, radii[v.slot as usize][v.in_medium() as usize])
            };
            let Some(grid) = Grid::build(vps.len(), sphere) else {
                continue;
            };
            if !self.lights.any() {
                break;
            }
            let set = if self.nee { iteration } else { g as u32 };
            let u = self.set_u(set);
            let gatherers = Gatherers {
                cfg,
                grid: &grid,
                vps,
                radii: &radii,
                first: self.first,
            };
            let job = PhotonJob {
                lights: &self.lights,
                max_depth: cfg.max_depth,
                seed: scene.sampler.seed,
            };
            let pass = iteration * self.groups + g as u32;
            let lists = photons::trace_all(
                scene,
                &job,
                (pass, self.group_photons),
                |_| M::from_u(u),
                // Each chunk converts with its own pair of modes (a spectral mode is not Sync).
                || (Vec::new(), (M::from_u(u), M::from_u(u).terminate())),
                |(out, modes), hit: &PhotonHit<M::C>, photon: &M, _: &mut Sampler| {
                    gatherers.gather(hit, photon, modes, out)
                },
            );
            for (list, _) in lists {
                for (v, c) in list {
                    let vp = &vps[v as usize];
                    let (slot, kind) = (vp.slot as usize, vp.in_medium() as usize);
                    phi[slot][kind] += c;
                    found[slot][kind] += 1;
                }
            }
        }
        for ((s, dphi), m) in self.slots.iter_mut().zip(&phi).zip(&found) {
            s.kernels[0].shrink(dphi[0], m[0], cfg.alpha, 2);
            s.kernels[1].shrink(dphi[1], m[1], cfg.alpha, 3);
        }
    }

    /// The film after `done` iterations: one sample at each pixel's centre, weight 1 under
    /// the box filter.
    fn develop(mut self, done: u32) -> Film {
        if done == 0 {
            return self.film;
        }
        let (pmin, pmax) = self.film.pixel_bounds();
        let mut tile = self.film.tile(pmin, pmax);
        // Photons each measurement could gather from.
        let np = done as f64 * self.group_photons as f64;
        // SPPM sums `ld` over the iterations; PPM's is the fixed path's.
        let ld_scale = if self.nee { 1.0 / done as f32 } else { 1.0 };
        let width = self.size.x as usize;
        for (i, px) in self.slots.chunks(self.eye as usize).enumerate() {
            let mut l = Vec3::ZERO;
            for s in px {
                l += s.ld * ld_scale + s.kernels[0].radiance(np, 2) + s.kernels[1].radiance(np, 3);
            }
            let (x, y) = ((i % width) as u32, (i / width) as u32);
            let centre = (pmin + UVec2::new(x, y)).as_vec2() + Vec2::splat(0.5);
            tile.add_sample(centre, l / self.eye as f32);
        }
        self.film.merge(&tile);
        self.film
    }
}
