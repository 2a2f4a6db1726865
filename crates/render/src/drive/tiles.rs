//! The progressive loop of per-sample estimators: tiles × passes on the current rayon pool.
//!
//! A pass adds samples `[s0, s1)` to every pixel. Tiles of a pass run in parallel and are
//! merged into the film after the pass in a fixed order, so the image is bit-identical for any
//! thread count (a different split into passes changes only the f64 rounding of the sums).
//! Passes are sized from the measured speed (about a second each), so a time budget, Ctrl-C
//! (the `cancel` flag) or a progressive writer stops at a pass boundary with a consistent
//! image.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use rayon::prelude::*;

use super::Estimator;
use crate::film::FilmTile;
use crate::math::UVec2;
use crate::sampling::Sampler;
use crate::session::{Job, Progress, RenderOutcome, camera_sample};
use crate::spectral::lanes::PathMode;
use crate::world::Scene;

/// Render sample indices `[s0, s1)` of every pixel of one tile (positions uniform in each
/// pixel, splatted by the film's filter).
fn render_tile<M: PathMode, E: Estimator<M>>(
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
    Estimator::<M>::li_stream(
        integrator,
        scene,
        template,
        |sampler| {
            let (pixel, index) = samples.next()?;
            Some(camera_sample(scene, sampler, pixel, index))
        },
        |p_film, l| tile.add_sample(p_film, l),
    );
}

/// Render `scene` with the per-sample estimator `integrator` in colour mode `M`: passes of
/// whole samples per pixel, tiles in parallel (each tile's samples handed to the estimator as
/// one stream of camera rays), film tiles allocated once and cleared each pass.
pub fn render_tiles<M: PathMode, E: Estimator<M>>(job: &Job, integrator: &E) -> RenderOutcome {
    let start = Instant::now();
    let (scene, opts, observer) = (job.scene, job.opts, job.observer);
    let (mut film, template) = job.film_and_sampler();
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
                render_tile::<M, E>(scene, integrator, &template, tile, bounds, s0, s1);
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
        extra: Vec::new(),
    }
}
