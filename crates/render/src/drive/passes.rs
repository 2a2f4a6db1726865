//! The pass loop of the integrators that render a whole pass themselves (SPPM's iterations,
//! light tracing, BDPT) and one such pass over the film's rows.

use std::ops::Range;
use std::sync::atomic::Ordering;
use std::time::Instant;

use rayon::prelude::*;

use crate::film::{Film, FilmTile};
use crate::math::UVec2;
use crate::session::{Job, Progress};

/// Runs `pass(k)` for k = 0, 1, … until `opts.spp` passes are done, the time budget is spent
/// (after at least one pass) or the render is cancelled (between passes), reporting progress
/// after each (`samples_per_pass` samples). Returns the passes done and whether it was
/// cancelled.
pub fn run_passes(
    job: &Job,
    start: Instant,
    samples_per_pass: u64,
    mut pass: impl FnMut(u32),
) -> (u32, bool) {
    let (opts, observer) = (job.opts, job.observer);
    let target = opts.spp.max(1);
    let mut done = 0u32;
    while done < target {
        if opts.cancel.load(Ordering::Relaxed) {
            return (done, true);
        }
        if let Some(b) = opts.time_budget
            && done > 0
            && start.elapsed() >= b
        {
            break;
        }
        pass(done);
        done += 1;
        observer.progress(&Progress {
            samples_done: done as u64 * samples_per_pass,
            samples_total: target as u64 * samples_per_pass,
            elapsed: start.elapsed(),
            spp_done: done,
        });
    }
    (done, false)
}

/// One pass over `film`'s pixel rows `ys` in parallel: `row(y, tile)` renders row `y` into a
/// film tile of its own and returns whatever else it made; then, in row order, each tile is
/// merged into the film and `merge` is handed the rest (light-tracing splats, say).
pub fn rows<T: Send>(
    film: &mut Film,
    ys: Range<u32>,
    row: impl Fn(u32, &mut FilmTile) -> T + Sync,
    mut merge: impl FnMut(&mut Film, T),
) {
    let (pmin, pmax) = film.pixel_bounds();
    let done: Vec<(FilmTile, T)> = ys
        .into_par_iter()
        .map(|y| {
            let mut tile = film.tile(UVec2::new(pmin.x, y), UVec2::new(pmax.x, y + 1));
            let rest = row(y, &mut tile);
            (tile, rest)
        })
        .collect();
    for (tile, rest) in done {
        film.merge(&tile);
        merge(film, rest);
    }
}
