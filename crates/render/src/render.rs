//! The render driver: tiles × passes on the current rayon pool.
//!
//! A pass adds samples `[s0, s1)` to every pixel. Tiles of a pass run in parallel and are
//! merged into the film after the pass in a fixed order, so the image is bit-identical for any
//! thread count (a different split into passes changes only the f64 rounding of the sums). Passes are
//! sized from the measured speed (about a second each), so a time budget, Ctrl-C (the
//! `cancel` flag) or a progressive writer stops at a pass boundary with a consistent image.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::{Duration, Instant};

use rayon::prelude::*;

use crate::camera::CameraRay;
use crate::film::{Film, FilmTile};
use crate::integrators::Integrator;
use crate::integrators::photon::{PhotonMapper, PhotonMaps};
use crate::math::{UVec2, Vec2, Vec3};
use crate::sampling::Sampler;
use crate::world::Scene;

#[derive(Clone, Debug)]
pub struct RenderOptions {
    /// Samples per pixel to reach (upper bound when a time budget is set).
    pub spp: u32,
    /// Stop after the pass during which this much time has elapsed (passes are planned to fit).
    pub time_budget: Option<Duration>,
    pub tile_size: u32,
    /// Set it (e.g. from a Ctrl-C handler) to stop after the current pass.
    pub cancel: Arc<AtomicBool>,
    /// Target duration of one pass.
    pub pass_duration: Duration,
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions {
            spp: 16,
            time_budget: None,
            tile_size: 16,
            cancel: Arc::new(AtomicBool::new(false)),
            pass_duration: Duration::from_secs(1),
        }
    }
}

/// What the progress callback is told.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    /// Pixel samples finished so far.
    pub samples_done: u64,
    /// Pixel samples planned in all (spp × pixels); with a time budget, an estimate.
    pub samples_total: u64,
    pub elapsed: Duration,
    /// Samples per pixel completed in whole passes.
    pub spp_done: u32,
}

pub struct RenderOutcome {
    pub film: Film,
    pub spp: u32,
    pub passes: u32,
    pub elapsed: Duration,
    pub cancelled: bool,
}

/// Events reported while rendering.
pub trait RenderObserver: Sync {
    /// Called often (after every tile) from worker threads.
    fn progress(&self, _p: &Progress) {}
    /// Called after every pass with the film so far (e.g. progressive output).
    fn pass_done(&self, _film: &Film, _spp: u32) {}
}

/// An observer that ignores everything.
pub struct Silent;
impl RenderObserver for Silent {}

/// Sets `sampler` up for sample `index` of `pixel` and draws its film position (uniform in
/// the pixel) and camera ray.
#[inline]
pub fn camera_sample(
    scene: &Scene,
    sampler: &mut Sampler,
    pixel: UVec2,
    index: u32,
) -> (Vec2, CameraRay) {
    sampler.start_pixel_sample(pixel, index);
    let p_film = pixel.as_vec2() + sampler.next_2d();
    let u_lens = sampler.next_2d();
    let mut cray = scene.camera.generate_ray(p_film, u_lens);
    if scene.has_motion {
        // Motion blur: one time per camera sample, uniform over the shutter. Only scenes
        // with moving shapes draw it, so static ones keep their random number streams.
        cray.ray.time = shutter_time(sampler);
    }
    (p_film, cray)
}

/// The time of a camera sample (motion blur), out of line: static scenes never call it.
#[inline(never)]
fn shutter_time(sampler: &mut Sampler) -> f32 {
    sampler.next_1d()
}

/// What estimates the radiance of a stream of camera samples: an [`Integrator`] that works
/// per sample, or one with state built for the render first (the photon mapper's maps).
pub trait Estimator: Sync {
    /// See [`Integrator::li_stream`].
    fn li_stream<T>(
        &self,
        scene: &Scene,
        template: &Sampler,
        next: impl FnMut(&mut Sampler) -> Option<(T, CameraRay)>,
        done: impl FnMut(T, Vec3),
    );
}

impl Estimator for Integrator {
    #[inline]
    fn li_stream<T>(
        &self,
        scene: &Scene,
        template: &Sampler,
        next: impl FnMut(&mut Sampler) -> Option<(T, CameraRay)>,
        done: impl FnMut(T, Vec3),
    ) {
        Integrator::li_stream(self, scene, template, next, done)
    }
}

impl Estimator for PhotonMapper<'_> {
    fn li_stream<T>(
        &self,
        scene: &Scene,
        template: &Sampler,
        mut next: impl FnMut(&mut Sampler) -> Option<(T, CameraRay)>,
        mut done: impl FnMut(T, Vec3),
    ) {
        let mut sampler = template.clone();
        while let Some((tag, cray)) = next(&mut sampler) {
            done(tag, self.li(scene, &cray, &mut sampler));
        }
    }
}

/// Render sample indices `[s0, s1)` of every pixel of one tile (positions uniform in each
/// pixel, splatted by the film's filter).
fn render_tile<E: Estimator>(
    scene: &Scene,
    integrator: &E,
    template: &Sampler,
    tile: &mut FilmTile,
    (lo, hi): (UVec2, UVec2),
    s0: u32,
    s1: u32,
) {
    let mut samples = (lo.y..hi.y)
        .flat_map(|y| (lo.x..hi.x).map(move |x| UVec2::new(x, y)))
        .flat_map(|pixel| (s0..s1).map(move |index| (pixel, index)));
    integrator.li_stream(
        scene,
        template,
        |sampler| {
            let (pixel, index) = samples.next()?;
            Some(camera_sample(scene, sampler, pixel, index))
        },
        |p_film, l| tile.add_sample(p_film, l),
    );
}

/// Peak bytes of the film state [`render`] allocates for `scene` (see [`Film::memory_needed`]).
pub fn memory_needed(scene: &Scene, opts: &RenderOptions) -> u64 {
    let f = &scene.film;
    Film::memory_needed(f.width, f.height, f.crop, &f.filter, opts.tile_size)
}

/// Render `scene` with `integrator` on the current rayon pool.
pub fn render(
    scene: &Scene,
    integrator: &Integrator,
    opts: &RenderOptions,
    observer: &dyn RenderObserver,
) -> RenderOutcome {
    match integrator {
        Integrator::Sppm(cfg) => crate::integrators::sppm::render(scene, cfg, opts, observer),
        Integrator::Photon(cfg) => {
            let start = Instant::now();
            let maps = PhotonMaps::build(scene, cfg, scene.sampler.seed);
            let mapper = PhotonMapper { cfg, maps };
            let mut out = render_samples(scene, &mapper, opts, observer);
            out.elapsed = start.elapsed();
            out
        }
        _ => render_samples(scene, integrator, opts, observer),
    }
}

/// The tile and pass loop of [`render`] for an [`Estimator`].
fn render_samples<E: Estimator>(
    scene: &Scene,
    integrator: &E,
    opts: &RenderOptions,
    observer: &dyn RenderObserver,
) -> RenderOutcome {
    let start = Instant::now();
    let f = &scene.film;
    let mut film = Film::new(f.width, f.height, f.crop, f.filter);
    let template = Sampler::new(scene.sampler.kind, opts.spp.max(1), scene.sampler.seed);
    let tile_list = film.tile_bounds(opts.tile_size.max(1));
    // One tile per region for the whole render, cleared before each pass.
    let mut tiles: Vec<FilmTile> = tile_list
        .iter()
        .map(|&(lo, hi)| film.tile(lo, hi))
        .collect();
    let (pmin, pmax) = film.pixel_bounds();
    let pixels = (pmax - pmin).as_u64vec2();
    let pixels = pixels.x * pixels.y;
    let target = opts.spp.max(1);

    let done = AtomicU64::new(0);
    let mut spp_done = 0u32;
    let mut passes = 0u32;
    let mut pass_spp = 1u32;
    let mut cancelled = false;
    while spp_done < target {
        if opts.cancel.load(Ordering::Relaxed) {
            cancelled = true;
            break;
        }
        let s0 = spp_done;
        let s1 = (s0 + pass_spp).min(target);
        let pass_start = Instant::now();
        let samples_total = pixels * target as u64;
        tile_list
            .par_iter()
            .zip(tiles.par_iter_mut())
            .for_each(|(&bounds, tile)| {
                tile.clear();
                render_tile(scene, integrator, &template, tile, bounds, s0, s1);
                let n = (bounds.1 - bounds.0).as_u64vec2();
                let d = done.fetch_add(n.x * n.y * (s1 - s0) as u64, Ordering::Relaxed)
                    + n.x * n.y * (s1 - s0) as u64;
                observer.progress(&Progress {
                    samples_done: d,
                    samples_total,
                    elapsed: start.elapsed(),
                    spp_done: s0,
                });
            });
        for t in &tiles {
            film.merge(t);
        }
        spp_done = s1;
        passes += 1;
        observer.pass_done(&film, spp_done);

        // Size the next pass from the measured speed.
        let per_spp = pass_start.elapsed().as_secs_f64() / (s1 - s0) as f64;
        let mut next = (opts.pass_duration.as_secs_f64() / per_spp.max(1e-9)).floor();
        if let Some(budget) = opts.time_budget {
            let left = budget.as_secs_f64() - start.elapsed().as_secs_f64();
            if left <= 0.0 {
                break;
            }
            next = next.min((left / per_spp.max(1e-9)).floor());
            if next < 1.0 {
                // Not even one more sample per pixel fits in the budget.
                break;
            }
        }
        pass_spp = next.clamp(1.0, (1u32 << 20) as f64) as u32;
    }
    RenderOutcome {
        film,
        spp: spp_done,
        passes,
        elapsed: start.elapsed(),
        cancelled,
    }
}
