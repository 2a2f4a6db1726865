//! The progressive loop of per-sample estimators: work items (a tile × a chunk of sample
//! indices, see `work.rs`) in passes on the current rayon pool.
//!
//! Item `i` renders the samples `[c·K, (c+1)·K)` (`K` = [`CHUNK_SPP`], `c = ⌊i / T⌋`) of the
//! pixels of tile `i mod T` (the film's fixed `tile_size²` tiling) into a film tile, whose
//! f64 sums are then rounded to the film's exact fixed point. A pass runs its items tile by
//! tile (the tiles in parallel, a tile's chunks one after the other, each rounded into the
//! tile's fixed-point sums, the tile merged into the film once); integer sums do not care
//! about that order, so the image is the same bit for bit for any thread count, pass sizes
//! (measured speed, about a second a pass), shard split or resumed run. Passes end on whole chunks,
//! so that between passes every pixel has the same sample count; a time budget, Ctrl-C
//! (the `cancel` flag) or a progressive writer stops at a pass boundary with a consistent
//! image.

use std::ops::Range;
use std::sync::Mutex;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use rayon::prelude::*;

use super::{Estimator, work};
use crate::camera::CameraRay;
use crate::film::FilmTile;
use crate::film::accum::tile_bounds;
use crate::math::{UVec2, Vec3};
use crate::sampling::Sampler;
use crate::session::{Job, Progress, RenderOptions, RenderOutcome, camera_sample};
use crate::spectral::lanes::PathMode;
use crate::world::Scene;

pub use crate::session::CHUNK_SPP;

/// A tile's bounds, `[min, max)`.
type TileBounds = (UVec2, UVec2);

/// The work of a tile render: the tiling and the chunks of sample indices.
pub struct TileWork {
    tiles: Vec<TileBounds>,
    spp: u32,
    chunk: u32,
}

impl TileWork {
    /// The work of rendering `scene`'s film (its tiling by `opts.tile_size`) at `opts.spp`.
    pub fn new(scene: &Scene, opts: &RenderOptions) -> TileWork {
        let (min, max) = scene.film.pixel_bounds();
        TileWork {
            tiles: tile_bounds(min, max, opts.tile_size.max(1)),
            spp: opts.spp.max(1),
            chunk: opts.chunk_spp.max(1),
        }
    }

    /// Items per chunk (the tiles).
    pub fn per_chunk(&self) -> u64 {
        self.tiles.len() as u64
    }

    /// The number of items.
    pub fn len(&self) -> u64 {
        self.per_chunk() * self.spp.div_ceil(self.chunk) as u64
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Item `i`: its tile's bounds and its sample indices.
    pub fn item(&self, i: u64) -> (TileBounds, Range<u32>) {
        let t = self.per_chunk();
        let c = (i / t) as u32;
        let s0 = c * self.chunk;
        (
            self.tiles[(i % t) as usize],
            s0..(s0 + self.chunk).min(self.spp),
        )
    }

    /// The items of `items` grouped by tile: each tile's bounds and the sample ranges of its
    /// chunks in `items`, in order.
    pub fn by_tile(&self, items: Range<u64>) -> Vec<(TileBounds, Vec<Range<u32>>)> {
        let t = self.per_chunk();
        let mut out: Vec<_> = self.tiles.iter().map(|&b| (b, Vec::new())).collect();
        for i in items {
            let (_, samples) = self.item(i);
            out[(i % t) as usize].1.push(samples);
        }
        out.retain(|(_, chunks)| !chunks.is_empty());
        out
    }

    /// Samples per pixel in the chunks before item `end` that are complete from item 0.
    pub fn spp_before(&self, end: u64) -> u32 {
        ((end / self.per_chunk().max(1)) as u32)
            .saturating_mul(self.chunk)
            .min(self.spp)
    }
}

/// Render sample indices `samples` of every pixel of one tile (positions uniform in each
/// pixel, splatted by the film's filter).
fn render_tile<M: PathMode, E: Estimator<M>>(
    scene: &Scene,
    integrator: &E,
    template: &Sampler,
    tile: &mut FilmTile,
    (lo, hi): (UVec2, UVec2),
    samples: Range<u32>,
) {
    // 1 but for an irradiance meter (π): exact, so other cameras' images are unchanged.
    let weight = scene.camera.sample_weight();
    let mut stream = (lo.y..hi.y)
        .flat_map(|y| (lo.x..hi.x).map(move |x| UVec2::new(x, y)))
        .flat_map(|pixel| samples.clone().map(move |index| (pixel, index)));
    Estimator::<M>::li_stream(
        integrator,
        scene,
        template,
        |sampler| {
            let (pixel, index) = stream.next()?;
            Some(camera_sample(scene, sampler, pixel, index))
        },
        |p_film, l| tile.add_sample(p_film, l * weight),
    );
}

/// Render `scene` with the per-sample estimator `integrator` in colour mode `M`: the
/// options' items (all, a shard's range, or what a checkpoint left) in passes of whole
/// chunks, items in parallel, each tile reused by its worker from item to item.
pub fn render_tiles<M: PathMode, E: Estimator<M>>(job: &Job, integrator: &E) -> RenderOutcome {
    render_tiles_phased::<M, _>(job, &mut OnePhase(integrator))
}

/// A per-sample estimator whose state changes between phases of a render, at chunk
/// boundaries fixed in advance (path guiding: each training iteration samples from what the
/// ones before it learnt). A phase's estimator is read only while its items render; the
/// state changes in [`Phased::end_phase`], when every item of the phase is done.
pub trait Phased<M: PathMode> {
    type Phase<'a>: Estimator<M>
    where
        Self: 'a;
    /// The chunk (of `chunks` in all) at which phase `k` ends.
    fn phase_end(&self, k: u32, chunks: u64) -> u64;
    /// The estimator of phase `k`.
    fn phase(&self, k: u32) -> Self::Phase<'_>;
    /// Phase `k` is done (all its items), and phase `k + 1` follows.
    fn end_phase(&mut self, k: u32);
}

/// An estimator that does not change: one phase.
struct OnePhase<'a, E>(&'a E);

impl<M: PathMode, E: Estimator<M>> Phased<M> for OnePhase<'_, E> {
    type Phase<'b>
        = &'b E
    where
        Self: 'b;
    fn phase_end(&self, _k: u32, chunks: u64) -> u64 {
        chunks
    }
    fn phase(&self, _k: u32) -> &E {
        self.0
    }
    fn end_phase(&mut self, _k: u32) {}
}

impl<M: PathMode, E: Estimator<M>> Estimator<M> for &E {
    #[inline(always)]
    fn li(&self, scene: &Scene, cray: &CameraRay, sampler: &mut Sampler) -> Vec3 {
        (*self).li(scene, cray, sampler)
    }
    #[inline(always)]
    fn li_stream<T>(
        &self,
        scene: &Scene,
        template: &Sampler,
        next: impl FnMut(&mut Sampler) -> Option<(T, CameraRay)>,
        done: impl FnMut(T, Vec3),
    ) {
        (*self).li_stream(scene, template, next, done)
    }
}

/// [`render_tiles`] of an estimator in phases: each phase's items (`drive/work.rs`) in passes
/// as [`render_tiles`] runs them, the phase's end at a chunk boundary (a pass never spans
/// two phases), then [`Phased::end_phase`]. Items are a pure function of the item and the
/// phases before, so the image still does not depend on the thread count; it does on the
/// items rendered before, so a phased render is not split into shards (the integrator says
/// so in `work_items`).
pub fn render_tiles_phased<M: PathMode, P: Phased<M>>(job: &Job, phases: &mut P) -> RenderOutcome {
    let start = Instant::now();
    let (scene, opts, observer) = (job.scene, job.opts, job.observer);
    let (blank, template) = job.film_and_sampler();
    let layout = blank.layout();
    let plan = TileWork::new(scene, opts);
    let (range, mut film, mut next) = work::start(opts, plan.len(), blank);
    let pixels = film.pixel_count();
    let samples_total =
        pixels * opts.spp.max(1) as u64 * (range.end - range.start) / plan.len().max(1);
    let done = AtomicU64::new(0);
    let mut passes = 0u32;
    // Tiles kept from item to item and pass to pass, so that their storage is not
    // allocated (and page-faulted) again.
    let spare = Mutex::new(Vec::<FilmTile>::new());
    let per_chunk = plan.per_chunk().max(1);
    let chunks = plan.len() / per_chunk;
    let mut cancelled = false;
    let mut k = 0u32;
    loop {
        let end = phases
            .phase_end(k, chunks)
            .min(chunks)
            .saturating_mul(per_chunk)
            .clamp(next, range.end);
        let integrator = phases.phase(k);
        let (reached, stopped) = work::run(
            job,
            start,
            &mut film,
            range.start..end,
            next,
            per_chunk,
            true,
            |film, items| {
                let shared = Mutex::new(&mut *film);
                let first = items.start;
                plan.by_tile(items.clone())
                    .into_par_iter()
                    .for_each(|(bounds, chunks)| {
                        let mut tile = spare
                            .lock()
                            .expect("a worker panicked")
                            .pop()
                            .unwrap_or_default();
                        let tile = &mut tile;
                        layout.reset_tile(tile, bounds.0, bounds.1);
                        let n = (bounds.1 - bounds.0).as_u64vec2();
                        for samples in chunks {
                            let count = n.x * n.y * samples.len() as u64;
                            render_tile::<M, _>(
                                scene,
                                &integrator,
                                &template,
                                tile,
                                bounds,
                                samples,
                            );
                            tile.finish_unit();
                            let d = done.fetch_add(count, Ordering::Relaxed) + count;
                            observer.progress(&Progress {
                                samples_done: d,
                                samples_total,
                                elapsed: start.elapsed(),
                                spp_done: plan.spp_before(first),
                            });
                        }
                        shared.lock().expect("a worker panicked").merge(tile);
                        spare
                            .lock()
                            .expect("a worker panicked")
                            .push(std::mem::take(tile));
                    });
                passes += 1;
                observer.pass_done(film, plan.spp_before(items.end));
            },
        );
        drop(integrator);
        next = reached;
        if stopped {
            cancelled = true;
            break;
        }
        if next < end || end >= range.end {
            break; // the time budget ran out, or the render is done
        }
        phases.end_phase(k);
        k += 1;
    }
    RenderOutcome {
        film,
        spp: plan.spp_before(next),
        passes,
        elapsed: start.elapsed(),
        cancelled,
        extra: Vec::new(),
        items: range.start..next,
    }
}
