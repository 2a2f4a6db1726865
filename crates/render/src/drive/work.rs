//! Work items: the fixed units a render is split into, so that shards, passes of any size
//! and resumed runs add up to the single uninterrupted render bit for bit.
//!
//! A driver numbers its work `0..n` (the tile loop: item `i` is tile `i mod T` of the fixed
//! tiling for the sample indices of chunk `⌊i / T⌋`, [`super::CHUNK_SPP`] indices a chunk;
//! BDPT: item `i` is row `i mod H` of pass `⌊i / H⌋`). An item's contribution is a pure
//! function of the scene, the options and the item (the sampler is a function of seed, pixel
//! and sample index), summed in f64 by one thread in a fixed order and rounded into the
//! film's exact fixed-point sums ([`crate::film::accum`]). So any set of items gives the
//! same film whichever process, thread or pass rendered them and in which order: a shard
//! renders a range of items ([`RenderOptions::items`]), a resumed render continues after
//! the last finished item of a checkpoint ([`RenderOptions::resume`]), and a merge adds
//! the films of ranges that cover `0..n` once.

use std::ops::Range;
use std::sync::atomic::Ordering;
use std::time::Instant;

use crate::film::Film;
use crate::session::{Job, RenderOptions};

pub use crate::session::Resume;

/// The items this render does (`0..n` or the options' range, clipped to `0..n`), the film
/// it starts from and the first item to render.
pub fn start(opts: &RenderOptions, n: u64, blank: Film) -> (Range<u64>, Film, u64) {
    let range = match &opts.items {
        Some(r) => r.start.min(n)..r.end.min(n),
        None => 0..n,
    };
    match &opts.resume {
        Some(r) if r.items.start == range.start && r.items.end <= range.end => {
            (range, r.film.clone(), r.items.end)
        }
        _ => {
            let first = range.start;
            (range, blank, first)
        }
    }
}

/// Runs the items `next..range.end` in passes that end on multiples of `unit` items (or at
/// the range's end): `pass(film, items)` renders one pass into `film`. With `by_speed` a
/// pass holds as many units as fit in the options' pass duration (one at first), else one
/// unit. Stops between passes when cancelled or when not even one more unit fits in what is
/// left of the time budget (at the measured speed), and tells the observer
/// of the items done after every pass ([`crate::session::RenderObserver::checkpoint`]).
/// Returns the next item and whether the render was cancelled.
#[allow(clippy::too_many_arguments)]
pub fn run(
    job: &Job,
    start: Instant,
    film: &mut Film,
    range: Range<u64>,
    mut next: u64,
    unit: u64,
    by_speed: bool,
    mut pass: impl FnMut(&mut Film, Range<u64>),
) -> (u64, bool) {
    let (opts, observer) = (job.opts, job.observer);
    let unit = unit.max(1);
    let mut units = 1u64;
    while next < range.end {
        if opts.cancel.load(Ordering::Relaxed) {
            return (next, true);
        }
        let end = ((next / unit + units) * unit).min(range.end);
        let pass_start = Instant::now();
        pass(film, next..end);
        let items = end - next;
        next = end;
        observer.checkpoint(film, range.start..next);
        let per_item = pass_start.elapsed().as_secs_f64() / items as f64;
        if by_speed {
            let want = opts.pass_duration.as_secs_f64() / (per_item * unit as f64).max(1e-12);
            units = want.floor().clamp(1.0, (1u64 << 30) as f64) as u64;
        }
        if let Some(budget) = opts.time_budget {
            let left = budget.as_secs_f64() - start.elapsed().as_secs_f64();
            let one = per_item * unit as f64;
            if left < one {
                break; // not even one more unit fits in the budget
            }
            if by_speed {
                units = units.min((left / one.max(1e-12)).floor().max(1.0) as u64);
            }
        }
    }
    (next, false)
}
