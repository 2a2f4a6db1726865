//! BDPT's render driver: one sample per pixel and pass, rows in parallel, each row's film
//! tile and light-tracing splats merged in row order; and the per-strategy images.

use std::collections::BTreeMap;
use std::time::Instant;

use super::vertex::Subpaths;
use super::{Bdpt, BdptConfig, StrategyImages, StrategySink};
use crate::drive::{self, run_passes};
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
            let one = crate::film::Film::memory_needed(f.width, f.height, f.crop, &f.filter, 0);
            StrategyImages::strategies(d).count() as u64 * one
        }
        _ => 0,
    }
}

/// BDPT in the colour mode `M`: `opts.spp` passes of one sample per pixel, rows in parallel,
/// each row's film tile and light-tracing splats merged in row order (the image does not
/// depend on the thread count); a time budget or cancellation stops after a whole pass.
/// With `cfg.strategy_images` the outcome also holds one image per strategy (s, t), named
/// by [`StrategyImages::name`]: every contribution splatted at its film position, so that
/// with the box filter the weighted images sum to the image up to rounding.
pub(super) fn render_in<M: PathMode>(job: &Job, cfg: &BdptConfig) -> RenderOutcome {
    let start = Instant::now();
    let (scene, f) = (job.scene, &job.scene.film);
    let (mut film, template) = job.film_and_sampler();
    let (pmin, pmax) = film.pixel_bounds();
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
    let (done, cancelled) = run_passes(job, start, pixel_count, |pass| {
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
        drive::rows(&mut film, row, |film, (splats, records)| {
            for (p, c) in splats {
                film.add_splat(p, c);
            }
            for (s, t, p, c) in records {
                if let Some(img) = strategy_films.get_mut(&(s, t)) {
                    img.add_splat(p, c);
                }
            }
        });
        film.set_splat_scale(1.0 / (per_pass * (pass + 1) as f64));
        job.observer.pass_done(&film, pass + 1);
    });
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
        ..RenderOutcome::of_passes(film, done, start, cancelled)
    }
}
