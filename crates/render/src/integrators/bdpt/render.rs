//! BDPT's render driver: one sample per pixel and pass, rows in parallel, each row's film
//! tile and light-tracing splats merged in row order; and the per-strategy images. Its work
//! items (`drive/work.rs`) are the rows of the passes: item `i` is row `i mod H` of pass
//! `⌊i / H⌋` (H the film's stored rows), so shards and resumed renders split it exactly.

use std::collections::BTreeMap;
use std::time::Instant;

use super::vertex::Subpaths;
use super::{Bdpt, BdptConfig, StrategyImages, StrategySink};
use crate::drive::{self, work};
use crate::film::{Film, FilmTile};
use crate::math::{UVec2, Vec2, Vec3};
use crate::session::{Job, RenderOutcome, camera_sample};
use crate::spectral::lanes::{Color, PathMode};
use crate::world::Scene;

/// The per-strategy images' part of one camera sample: (s, t, film position, value).
struct StrategyRecord<'a> {
    p_film: Vec2,
    weighted: bool,
    out: &'a mut Vec<(u16, u16, Vec2, Vec3)>,
}

impl<C: Color> StrategySink<C> for StrategyRecord<'_> {
    fn add(&mut self, s: usize, t: usize, splat_at: Option<Vec2>, value: Vec3, weight: f32) {
        let v = if self.weighted { value } else { value / weight };
        self.out
            .push((s as u16, t as u16, splat_at.unwrap_or(self.p_film), v));
    }
}

/// Bytes the per-strategy images of `cfg` take (0 without them).
pub fn memory_needed(scene: &Scene, cfg: &BdptConfig) -> u64 {
    match (cfg.strategy_images, u32::try_from(cfg.max_depth)) {
        (Some(_), Ok(d)) => {
            let f = &scene.film;
            let one = crate::film::Film::memory_needed(f.width, f.height, f.crop, &f.filter, 0, 1);
            StrategyImages::strategies(d).count() as u64 * one
        }
        _ => 0,
    }
}

/// The work items of a BDPT render of `scene` at `spp` (see the module docs).
pub fn work_items(scene: &Scene, spp: u32) -> u64 {
    let (pmin, pmax) = scene.film.pixel_bounds();
    spp.max(1) as u64 * (pmax.y - pmin.y) as u64
}

/// BDPT in the colour mode `M`: `opts.spp` passes of one sample per pixel (or the options'
/// range of items, or what a checkpoint left), rows in parallel, each row's film tile and
/// light-tracing splats rounded into the film's exact sums (the image does not depend on
/// the thread count, nor on how the items were split); a time budget or cancellation stops
/// after a whole pass.
/// With `cfg.strategy_images` the outcome also holds one image per strategy (s, t), named
/// by [`StrategyImages::name`]: every contribution splatted at its film position, so that
/// with the box filter the weighted images sum to the image up to rounding.
pub(super) fn render_in<M: PathMode>(job: &Job, cfg: &BdptConfig) -> RenderOutcome {
    let start = Instant::now();
    let (scene, f) = (job.scene, &job.scene.film);
    let (blank, template) = job.film_and_sampler();
    let (pmin, pmax) = blank.pixel_bounds();
    let rows = (pmax.y - pmin.y).max(1) as u64;
    let spp = job.opts.spp.max(1);
    let (range, mut film, next) = work::start(job.opts, work_items(scene, spp), blank);
    let pixel_count = film.pixel_count();
    let bdpt = Bdpt::<M>::new(scene, cfg);
    // The camera's importance is normalised over the full image: light paths per pixel of
    // it, per pass.
    let per_pass = pixel_count.max(1) as f64 / (f.width as f64 * f.height as f64);
    // Every strategy's image, black ones too (the set of files depends on max_depth only).
    let mut strategy_films: BTreeMap<(u16, u16), Film> = match cfg.strategy_images {
        Some(_) => StrategyImages::strategies(cfg.max_depth.max(0) as u32)
            .map(|(s, t)| ((s as u16, t as u16), f.film()))
            .collect(),
        None => BTreeMap::new(),
    };
    let shard = job.opts.items.is_some();
    let (next, cancelled) = work::run(
        job,
        start,
        &mut film,
        range.clone(),
        next,
        rows,
        false,
        |film, items| {
            let pass = (items.start / rows) as u32;
            let ys =
                pmin.y + (items.start % rows) as u32..pmin.y + ((items.end - 1) % rows) as u32 + 1;
            let row = |y: u32, tile: &mut FilmTile| {
                let mut splats = Vec::new();
                let mut records = Vec::new();
                let mut paths = Subpaths::default();
                let mut sampler = template.clone();
                for x in pmin.x..pmax.x {
                    let (p_film, cray) = camera_sample(scene, &mut sampler, UVec2::new(x, y), pass);
                    let (s, p) = (&mut sampler, &mut paths);
                    let l = match cfg.strategy_images {
                        None => bdpt.li(scene, &cray, s, p, &mut splats, &mut ()),
                        Some(kind) => {
                            let mut record = StrategyRecord {
                                p_film,
                                weighted: kind == StrategyImages::Weighted,
                                out: &mut records,
                            };
                            bdpt.li(scene, &cray, s, p, &mut splats, &mut record)
                        }
                    };
                    tile.add_sample(p_film, l);
                }
                (splats, records)
            };
            drive::rows(film, ys, row, |film, (splats, records)| {
                for (p, c) in splats {
                    film.add_splat(p, c);
                }
                for (s, t, p, c) in records {
                    if let Some(img) = strategy_films.get_mut(&(s, t)) {
                        img.add_splat(p, c);
                    }
                }
            });
            // The light paths per pixel so far; a shard's film is developed as a part of the
            // whole render's.
            let passes = if shard {
                spp
            } else {
                (items.end / rows) as u32
            };
            film.set_splat_scale(1.0 / (per_pass * passes as f64));
            job.observer.pass_done(film, pass + 1);
            job.observer.progress(&crate::session::Progress {
                samples_done: (items.end - range.start) * (pixel_count / rows),
                samples_total: (range.end - range.start) * (pixel_count / rows),
                elapsed: start.elapsed(),
                spp_done: pass + 1,
            });
        },
    );
    let done = if shard { 0 } else { (next / rows) as u32 };
    // Light-tracing images (t = 1) are normalised as the film's splats; the others hold one
    // sample per pixel and pass.
    let extra = strategy_films
        .into_iter()
        .map(|((s, t), mut img)| {
            let paths_per_pixel = if t == 1 { per_pass } else { 1.0 };
            img.set_splat_scale(1.0 / (paths_per_pixel * done.max(1) as f64));
            (StrategyImages::name(s as usize, t as usize), img)
        })
        .collect();
    RenderOutcome {
        extra,
        items: range.start..next,
        ..RenderOutcome::of_passes(film, done, start, cancelled)
    }
}
