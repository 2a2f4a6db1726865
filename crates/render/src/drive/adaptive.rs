//! Adaptive sampling as the CS184 pathtracer defines it (Berkeley CS184 hw3 part 5).
//!
//! Every pixel keeps the running sums s₁ = Σ xₖ and s₂ = Σ xₖ² of its samples' illuminance
//! x = 0.2126 R + 0.7152 G + 0.0722 B. After every `batch` samples it computes the mean
//! μ = s₁/n, the sample variance σ² = (s₂ − s₁²/n)/(n − 1) and the 95 % half-width
//! I = 1.96 σ/√n, and stops when I ≤ `tolerance` · μ (or at `max_spp`). A pixel whose samples
//! are all zero (μ = σ = 0) therefore stops after its first batch.
//!
//! The driver runs rounds of `batch` samples over the pixels that have not stopped, tiles in
//! parallel (see [`render_adaptive`]). Sample `k` of a pixel is the same sample as in the
//! uniform driver (`Sampler::start_pixel_sample(pixel, k)`), so the image is deterministic
//! for any thread count. The film's filter splats samples as usual; with the default box
//! filter (radius ½) a pixel's value is the mean of its own samples.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::{Duration, Instant};

use rayon::prelude::*;

use super::Estimator;
use crate::film::image::Image;
use crate::film::{Film, FilmTile};
use crate::math::{UVec2, Vec3};
use crate::session::{Job, Progress, camera_sample};
use crate::spectral::lanes::PathMode;

/// Confidence-interval factor: 95 % two-sided for a normal mean.
pub const Z_95: f64 = 1.96;

/// The stopping rule.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AdaptiveSettings {
    /// Samples between convergence checks (CS184 `samplesPerBatch`, `-a batch ...`).
    pub batch: u32,
    /// Relative half-width of the 95 % confidence interval (CS184 `maxTolerance`).
    pub tolerance: f32,
}

impl Default for AdaptiveSettings {
    /// CS184's defaults: batches of 32, tolerance 0.05.
    fn default() -> Self {
        AdaptiveSettings {
            batch: 32,
            tolerance: 0.05,
        }
    }
}

impl AdaptiveSettings {
    /// Whether a pixel with `n` samples of illuminance sums `s1`, `s2` has converged.
    pub fn converged(&self, n: u32, s1: f64, s2: f64) -> bool {
        if n < 2 {
            return false;
        }
        let nf = n as f64;
        let mean = s1 / nf;
        let var = ((s2 - s1 * s1 / nf) / (nf - 1.0)).max(0.0);
        Z_95 * (var / nf).sqrt() <= self.tolerance as f64 * mean
    }
}

/// CS184's illuminance (Rec.709 luminance weights).
pub fn illuminance(l: Vec3) -> f64 {
    (0.2126 * l.x + 0.7152 * l.y + 0.0722 * l.z) as f64
}

pub struct AdaptiveOutcome {
    pub film: Film,
    /// Samples taken per pixel of the film's pixel bounds (row-major).
    pub samples: Vec<u32>,
    /// Width and height of `samples`.
    pub size: UVec2,
    /// The cap on samples per pixel.
    pub max_spp: u32,
    pub total_samples: u64,
    pub elapsed: Duration,
    pub cancelled: bool,
}

impl AdaptiveOutcome {
    /// Mean samples per pixel.
    pub fn mean_spp(&self) -> f64 {
        self.total_samples as f64 / self.samples.len().max(1) as f64
    }

    /// The sample-rate heat map: n / max_spp mapped blue (few) → green → red (many), as the
    /// CS184 `*_rate.png`.
    pub fn rate_image(&self) -> Image {
        let pixels = self
            .samples
            .iter()
            .map(|&n| heat(n as f32 / self.max_spp.max(1) as f32))
            .collect();
        Image::from_pixels(self.size.x, self.size.y, pixels).expect("size matches")
    }
}

/// Blue → cyan → green → yellow → red for t in [0, 1] (linear RGB).
fn heat(t: f32) -> Vec3 {
    let t = t.clamp(0.0, 1.0) * 4.0;
    let c = |x: f32| x.clamp(0.0, 1.0);
    Vec3::new(c(t - 2.0), c(t.min(4.0 - t)), c(2.0 - t))
}

/// Running sums of one pixel.
#[derive(Clone, Copy, Default)]
struct PixelState {
    s1: f64,
    s2: f64,
    n: u32,
    done: bool,
}

/// Render with per-pixel adaptive sampling, at most `opts.spp` samples per pixel.
///
/// The render runs in rounds of `batch` samples: in each round every pixel that has not yet
/// stopped takes its next `batch` samples (tiles in parallel on the current rayon pool) and
/// then checks the stopping rule, exactly when the one-pixel-at-a-time loop of the course
/// would (after every `batch` samples). Tiles whose pixels have all stopped drop out of later
/// rounds; the tiles of a round are merged into the film in a fixed order, so the image is
/// bit-identical for any thread count. Rounds are short, so no worker idles long behind one
/// slow tile at the end, and `opts.cancel` stops after the current round with every pixel the
/// mean of the samples it has. `opts.time_budget` and `opts.pass_duration` are ignored.
pub fn render_adaptive<M: PathMode, E: Estimator<M>>(
    job: &Job,
    integrator: &E,
    settings: &AdaptiveSettings,
) -> AdaptiveOutcome {
    let start = Instant::now();
    let (scene, opts, observer) = (job.scene, job.opts, job.observer);
    let (mut film, template) = job.film_and_sampler();
    let max_spp = opts.spp.max(1);
    let batch = settings.batch.max(1);
    let tile_list = film.tile_bounds(opts.tile_size.max(1));
    let (pmin, pmax) = film.pixel_bounds();
    let size = pmax - pmin;
    let samples_total = size.x as u64 * size.y as u64 * max_spp as u64;
    let done = AtomicU64::new(0);
    let mut states: Vec<Vec<PixelState>> = tile_list
        .iter()
        .map(|&(lo, hi)| {
            let n = (hi - lo).as_u64vec2();
            vec![PixelState::default(); (n.x * n.y) as usize]
        })
        .collect();
    // One tile per region for the whole render, cleared before each round it takes part in.
    let mut tiles: Vec<FilmTile> = tile_list
        .iter()
        .map(|&(lo, hi)| film.tile(lo, hi))
        .collect();
    let mut ran = vec![false; tile_list.len()];

    let mut cancelled = false;
    let mut spp_round = 0u32;
    while spp_round < max_spp {
        if opts.cancel.load(Ordering::Relaxed) {
            cancelled = true;
            break;
        }
        let (s0, s1) = (spp_round, (spp_round + batch).min(max_spp));
        tile_list
            .par_iter()
            .zip(states.par_iter_mut())
            .zip(tiles.par_iter_mut().zip(ran.par_iter_mut()))
            .for_each(|((&(lo, hi), state), (tile, ran))| {
                *ran = !state.iter().all(|p| p.done);
                if !*ran {
                    return;
                }
                tile.clear();
                let w = hi.x - lo.x;
                let active: Vec<usize> = (0..state.len()).filter(|&i| !state[i].done).collect();
                let mut samples = active.iter().flat_map(|&i| (s0..s1).map(move |k| (i, k)));
                integrator.li_stream(
                    scene,
                    &template,
                    |sampler| {
                        let (i, k) = samples.next()?;
                        let pixel = lo + UVec2::new(i as u32 % w, i as u32 / w);
                        let (p_film, cray) = camera_sample(scene, sampler, pixel, k);
                        Some(((i, p_film), cray))
                    },
                    |(i, p_film), l| {
                        tile.add_sample(p_film, l);
                        let v = illuminance(l);
                        if v.is_finite() {
                            state[i].s1 += v;
                            state[i].s2 += v * v;
                        }
                    },
                );
                for &i in &active {
                    let p = &mut state[i];
                    p.n = s1;
                    p.done = s1 >= max_spp
                        || (s1.is_multiple_of(batch) && settings.converged(s1, p.s1, p.s2));
                }
                let taken = (active.len() * (s1 - s0) as usize) as u64;
                let d = done.fetch_add(taken, Ordering::Relaxed) + taken;
                observer.progress(&Progress {
                    samples_done: d,
                    samples_total,
                    elapsed: start.elapsed(),
                    spp_done: s0,
                });
            });
        let mut any = false;
        for (t, _) in tiles.iter().zip(&ran).filter(|(_, ran)| **ran) {
            film.merge(t);
            any = true;
        }
        spp_round = s1;
        if !any {
            break;
        }
        observer.pass_done(&film, spp_round);
    }

    let mut samples = vec![0u32; size.x as usize * size.y as usize];
    let mut total = 0u64;
    for (&(lo, hi), state) in tile_list.iter().zip(&states) {
        let w = (hi.x - lo.x) as usize;
        for (i, p) in state.iter().enumerate() {
            let (x, y) = (
                lo.x - pmin.x + (i % w) as u32,
                lo.y - pmin.y + (i / w) as u32,
            );
            samples[y as usize * size.x as usize + x as usize] = p.n;
            total += p.n as u64;
        }
    }
    AdaptiveOutcome {
        film,
        samples,
        size,
        max_spp,
        total_samples: total,
        elapsed: start.elapsed(),
        cancelled,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stopping_rule() {
        let s = AdaptiveSettings {
            batch: 4,
            tolerance: 0.05,
        };
        // Constant samples: zero variance, converged as soon as n ≥ 2.
        assert!(s.converged(4, 4.0, 4.0));
        assert!(!s.converged(1, 1.0, 1.0));
        // All-zero pixel: 0 ≤ 0 converges.
        assert!(s.converged(4, 0.0, 0.0));
        // Samples 0 and 2 alternating: mean 1, σ ≈ 1; needs n ≥ (1.96/0.05)² ≈ 1537.
        let sums = |n: u32| (n as f64, 2.0 * n as f64);
        let (a, b) = sums(1000);
        assert!(!s.converged(1000, a, b));
        let (a, b) = sums(1600);
        assert!(s.converged(1600, a, b));
    }

    #[test]
    fn heat_map_ends() {
        assert_eq!(heat(0.0), Vec3::new(0.0, 0.0, 1.0));
        assert_eq!(heat(1.0), Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(heat(0.5), Vec3::new(0.0, 1.0, 0.0));
    }
}
