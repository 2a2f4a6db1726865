//! Metropolis light transport in primary sample space over BDPT (Kelemen et al. 2002),
//! multiplexed over the strategies by default (Hachisuka, Kaplanyan & Dachsbacher 2014;
//! pbrt-v3's `MLTIntegrator` and its parameters), or Kelemen's own, a state being a whole
//! BDPT sample (Mitsuba 0.6's `pssmlt` with `bidirectional`; see "Kelemen" below).
//!
//! A state is a vector of uniform numbers in three streams (camera subpath, light subpath,
//! connection), drawn lazily. Multiplexed (the default), it fixes a path depth d (per
//! chain), a strategy (s, t) with s + t = d + 2 (the first camera-stream number), a film
//! position, and through BDPT's sampling the whole path; its value is that one strategy's
//! MIS-weighted contribution times the number of strategies of depth d. Mutations: with
//! probability `large_step` every number is drawn afresh, else each is moved by a normal
//! step of deviation `sigma` (wrapping around [0, 1)); a proposal is accepted with
//! probability min(1, y(new) / y(current)), y the luminance, and both states are splatted
//! with their expected weights (Veach's expected-values trick).
//!
//! Normalisation: b, the image's mean luminance summed over the depths, is estimated per
//! depth from independent states: the `bootstrap` ones, and every large step the chains of
//! that depth propose (each an independent fresh state, accepted or not; with the
//! bootstrap alone its own error would stay in the image at every mutation count). The chains start from bootstrap states chosen in proportion
//! to their luminance, and the film's splats, L/y(L) each, are developed times b / mutations
//! per pixel. `--spp` sets the mutations per pixel.
//!
//! Direct illumination apart (Mitsuba 0.6's `directSamples`, 16 by default): paths of one
//! and two edges (emitters seen directly, direct light) are rendered by BDPT limited to two
//! edges at `direct_samples` per pixel, and the chains take the longer ones. Chains on a
//! small bright emitter seen directly hardly ever leave it, and too few bootstrap states
//! find it to start the right number of chains there (`veach-plates`' smallest light came
//! out dark with the chains doing every depth; figures in `bench/README.md`).
//!
//! Kelemen (`MltConfig::multiplexed` false): a state is one whole BDPT sample, a film
//! position and lens sample, then [`Bdpt::li`]'s camera subpath, light subpath and every
//! (s, t) connection. Its contributions are the camera sample's MIS-weighted radiance at its
//! film position and the light-tracing (t = 1) splats at theirs, and y is the sum of their
//! luminances (Mitsuba 0.6's `SplatList`); an accepted or rejected state splats all of them,
//! each times its expected-value weight / y. One population of chains covers every depth,
//! b is the mean of y over the independent states (bootstrap and large steps), and with
//! `direct_samples` ≥ 0 `li` leaves out the strategies of paths of one and two edges
//! (`BdptConfig::min_edges`), which BDPT renders apart as above.
//!
//! Spectral mode: BDPT draws the camera sample's wavelengths from the camera stream, so they
//! are one more coordinate of the state, moved by small steps like the others; y is the
//! luminance of the contributions' linear sRGB. A chain that finds a dispersive caustic
//! keeps its hue for a while (colour noise, as chains keep their brightness).
//!
//! Determinism: bootstrap state k and chain c draw from their own seeds; chains run in
//! blocks whose splats are added in chain order (`drive::run_chains`), so the image does not
//! depend on the thread count (nor on the block size).
//!
//! The module: here the configuration and the render (bootstrap, chains per slot);
//! `sampler.rs` a chain's primary sample vector; `chain.rs` a state's value and one chain.

mod chain;
mod sampler;

use std::time::Instant;

use rayon::prelude::*;

use self::chain::{Chain, Start, Target, run_chain, seed_of};
use self::sampler::MltSampler;
use super::bdpt::{Bdpt, BdptConfig, Subpaths};
use super::{IntegratorModel, camera_unsupported};
use crate::drive::run_chains;
use crate::film::Film;
use crate::math::{Vec2, Vec3};
use crate::sampling::Distribution1D;
use crate::session::{Job, Progress, RenderObserver, RenderOptions, RenderOutcome, Silent};
use crate::spectral::lanes::PathMode;
use crate::stats::Pcg32;
use crate::world::Scene;

/// MLT's parameters (pbrt-v3's names and defaults).
#[derive(Clone, Debug, PartialEq)]
pub struct MltConfig {
    /// Longest path in edges, camera to light, as for every other integrator here (pbrt's
    /// `maxdepth` 5 counts bounces: 6 edges, the default).
    pub max_depth: u32,
    /// States per depth (Kelemen: in all) for the normalisation and the chains' starts.
    pub bootstrap: u32,
    /// Markov chains.
    pub chains: u32,
    /// Probability of a large step.
    pub large_step: f32,
    /// Deviation of a small step.
    pub sigma: f32,
    /// Mitsuba 0.6's `directSamples`: ≥ 0 renders the paths of one and two edges (emitters
    /// seen directly, direct illumination) apart, by BDPT at this many samples per pixel (0:
    /// not at all), and leaves the chains the longer ones; −1: the chains take every depth.
    pub direct_samples: i32,
    /// A state is one strategy of one depth (true, pbrt-v3's) or a whole BDPT sample
    /// (false, Kelemen's, Mitsuba 0.6's `pssmlt`).
    pub multiplexed: bool,
}

impl Default for MltConfig {
    fn default() -> Self {
        MltConfig {
            max_depth: 6,
            bootstrap: 100_000,
            chains: 1000,
            large_step: 0.3,
            sigma: 0.01,
            direct_samples: 16,
            multiplexed: true,
        }
    }
}

impl IntegratorModel for MltConfig {
    fn name(&self) -> &'static str {
        "mlt"
    }

    fn unsupported(&self, scene: &Scene) -> Option<String> {
        camera_unsupported(self.name(), scene)
    }

    /// `opts.spp` mutations per pixel.
    fn render<M: PathMode + Send>(&self, job: &Job) -> RenderOutcome {
        let start = Instant::now();
        let (scene, opts, observer) = (job.scene, job.opts, job.observer);
        let first = if self.direct_samples >= 0 { 2 } else { 0 };
        let mut film = direct_part::<M>(scene, self, opts);
        let kelemen = !self.multiplexed;
        let bcfg = BdptConfig {
            max_depth: self.max_depth as i32,
            // Kelemen's states are whole BDPT samples: without the paths rendered apart.
            min_edges: if kelemen && first > 0 {
                first as u32 + 1
            } else {
                0
            },
            ..BdptConfig::default()
        };
        let bdpt = Bdpt::<M>::new(scene, &bcfg);
        let target = Target {
            scene,
            bdpt: &bdpt,
            kelemen,
        };
        // Populations of chains, each with its own bootstrap states, b and splat layer, in
        // slots `first..slots`. Multiplexed: slot d holds depth d (paths of d + 1 edges),
        // those below `first` rendered apart. Kelemen: one slot for every depth.
        let (first, slots) = if kelemen {
            (0, 1)
        } else {
            (first, (self.max_depth as usize).max(first))
        };
        let mut pop = Population::bootstrap(&target, self, scene.sampler.seed, first..slots);
        let f = &scene.film;
        let pixels = f.width as u64 * f.height as u64;
        let total = opts.spp.max(1) as u64 * pixels;
        let run = Run {
            pixels,
            total,
            start,
            opts,
            observer,
        };
        let (done, cancelled) = pop.chains(&mut film, &run);
        film.set_splat_scale(1.0);
        observer.pass_done(&film, opts.spp);
        RenderOutcome {
            items: 0..0,
            film,
            spp: (done as f64 / pixels.max(1) as f64).round() as u32,
            passes: 1,
            elapsed: start.elapsed(),
            cancelled,
            extra: Vec::new(),
        }
    }
}

/// Paths of one and two edges apart (Mitsuba 0.6's `directSamples`): BDPT limited to two
/// edges, its light-tracing splats baked into the splat layer the chains add to (a blank film
/// when `direct_samples` is not positive).
fn direct_part<M: PathMode + Send>(scene: &Scene, cfg: &MltConfig, opts: &RenderOptions) -> Film {
    if cfg.direct_samples <= 0 {
        return scene.film.film();
    }
    let direct = BdptConfig {
        max_depth: (cfg.max_depth as i32).min(2),
        ..BdptConfig::default()
    };
    let dopts = RenderOptions {
        spp: cfg.direct_samples as u32,
        time_budget: None,
        ..opts.clone()
    };
    let job = Job {
        scene,
        opts: &dopts,
        observer: &Silent,
    };
    let mut film = direct.render::<M>(&job).film;
    film.bake_splat_scale();
    film
}

/// What a render's chains work towards: the mutations to make, the pixels they
/// spread over, and how progress and cancellation reach them.
struct Run<'a> {
    pixels: u64,
    /// Mutations in all (per pixel × pixels).
    total: u64,
    start: Instant,
    opts: &'a RenderOptions,
    observer: &'a dyn RenderObserver,
}

/// The chains' populations, one per slot: the bootstrap states' luminances and, per slot,
/// Σ y and the number of independent states (bootstrap and large steps) behind its b.
struct Population<'a, M: PathMode> {
    target: &'a Target<'a, M>,
    cfg: &'a MltConfig,
    seed: u64,
    first: usize,
    weights: Vec<f32>,
    sums: Vec<(f64, u64)>,
}

impl<'a, M: PathMode> Population<'a, M> {
    /// The bootstrap: `bootstrap` independent states per slot of `slots` (state k in slot
    /// first + k mod slots), in parallel.
    fn bootstrap(
        target: &'a Target<'a, M>,
        cfg: &'a MltConfig,
        seed: u64,
        slots: std::ops::Range<usize>,
    ) -> Self {
        let (first, n_slots) = (slots.start, slots.len());
        let n_boot = cfg.bootstrap.max(1) as usize;
        let weights: Vec<f32> = (0..n_boot * n_slots)
            .into_par_iter()
            .map_init(
                || (Subpaths::default(), Vec::new()),
                |(paths, out), k| {
                    let mut sampler =
                        MltSampler::new(seed_of(seed, k as u64), cfg.sigma, cfg.large_step);
                    target.value(&mut sampler, paths, first + k % n_slots, out)
                },
            )
            .collect();
        // None below `first`.
        let mut sums = vec![(0.0f64, n_boot as u64); slots.end];
        for (k, &w) in weights.iter().enumerate() {
            sums[first + k % n_slots].0 += w as f64;
        }
        Population {
            target,
            cfg,
            seed,
            first,
            weights,
            sums,
        }
    }

    /// b of every slot: the mean y of its independent states.
    fn b(&self) -> Vec<f64> {
        self.sums.iter().map(|&(s, n)| s / n as f64).collect()
    }

    /// `count` split over the slots in proportion to their b (largest remainders).
    fn alloc(&self, count: u64) -> Vec<u64> {
        let b_d = self.b();
        let b_all: f64 = b_d.iter().sum();
        let mut out: Vec<u64> = b_d
            .iter()
            .map(|&b| (count as f64 * b / b_all).floor() as u64)
            .collect();
        let mut rest: Vec<(f64, usize)> = b_d
            .iter()
            .enumerate()
            .map(|(d, &b)| (count as f64 * b / b_all - out[d] as f64, d))
            .collect();
        rest.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
        let short = count.saturating_sub(out.iter().sum());
        for &(_, d) in rest.iter().take(short as usize) {
            out[d] += 1;
        }
        out
    }

    /// Every slot's chains, their splats added to `film`: chains and mutations given to the
    /// slots in proportion to their b, each slot's splat layer normalised by its own b and
    /// mutations (so that no depth's share of the image hangs on how many chains happened to
    /// start there: drawing every chain's start from all depths left `veach-plates`'
    /// directly seen lights dark at any mutation count). Returns the mutations made and
    /// whether the render was cancelled.
    fn chains(&mut self, film: &mut Film, run: &Run) -> (u64, bool) {
        if self.b().iter().sum::<f64>() <= 0.0 {
            return (0, false);
        }
        let chains = (self.cfg.chains.max(1) as u64).min(run.total);
        let chains_d = self.alloc(chains);
        let mutations_d = self.alloc(run.total);
        let mut chain_id = 0u64;
        let mut done = 0u64;
        for d in 0..self.sums.len() {
            let (n_chains, m_total) = (chains_d[d].max(1), mutations_d[d]);
            if self.b()[d] <= 0.0 || m_total == 0 {
                continue;
            }
            let (made, cancelled) = self.slot(film, run, d, (chain_id, n_chains), (m_total, done));
            done += made;
            if cancelled {
                return (done, true);
            }
            chain_id += n_chains;
        }
        (done, false)
    }

    /// Slot `d`'s `n_chains` chains (ids from `first_chain`) making `m_total` mutations,
    /// `done` mutations made before them; returns the mutations made and whether the render
    /// was cancelled.
    fn slot(
        &mut self,
        film: &mut Film,
        run: &Run,
        d: usize,
        (first_chain, n_chains): (u64, u64),
        (m_total, done): (u64, u64),
    ) -> (u64, bool) {
        let (cfg, seed) = (self.cfg, self.seed);
        // This slot's bootstrap states and their weights.
        let n_slots = self.sums.len() - self.first;
        let ks: Vec<usize> = (d - self.first..self.weights.len())
            .step_by(n_slots)
            .collect();
        let starts = Distribution1D::new(&ks.iter().map(|&k| self.weights[k]).collect::<Vec<_>>());
        // Systematic resampling: chain c starts at quantile (c + offset) / chains of the
        // weights, so each bootstrap state gets its share of chains to within one (drawn
        // independently, the count of chains on a small bright emitter would vary by its
        // binomial spread, and chains hardly leave such an emitter).
        let offset = Pcg32::new(seed_of(seed, 0x5354_4152_5400 + d as u64), 7).next_f32() as f64;
        // Blocks of at most 64 chains, fewer if their splats would take more than about
        // 256 MiB, at least one per thread (the image does not depend on it).
        let per_mutation = 2 * if self.target.kelemen {
            cfg.max_depth.max(1) as u64
        } else {
            1
        };
        let chain_bytes =
            (m_total / n_chains + 1) * per_mutation * std::mem::size_of::<(Vec2, Vec3)>() as u64;
        let block = (256u64 << 20)
            .div_ceil(chain_bytes)
            .min(64)
            .max(rayon::current_num_threads() as u64);
        let mut layer = self.target.scene.film.film();
        let mut made = 0u64;
        let target = self.target;
        let mutations = |c: u64| m_total * (c + 1) / n_chains - m_total * c / n_chains;
        let sums = &mut self.sums[d];
        let cancelled = run_chains(
            n_chains,
            block,
            &run.opts.cancel,
            |c| {
                let start = Start {
                    starts: &starts,
                    ks: &ks,
                    slot: d,
                    u: ((c as f64 + offset) / n_chains as f64) as f32,
                };
                run_chain(target, cfg, &start, seed, first_chain + c, mutations(c))
            },
            |_, chain: Chain| {
                for (p, v) in chain.splats {
                    layer.add_splat(p, v);
                }
                sums.0 += chain.large_sum;
                sums.1 += chain.large_count;
            },
            |c1| {
                made = m_total * c1 / n_chains;
                run.observer.progress(&Progress {
                    samples_done: done + made,
                    samples_total: run.total,
                    elapsed: run.start.elapsed(),
                    spp_done: ((done + made) / run.pixels.max(1)) as u32,
                });
            },
        );
        // Splats are L / y(L): b_d / (this slot's mutations per pixel) makes them radiance.
        let b = sums.0 / sums.1 as f64;
        film.add_splat_layer(&layer, b * run.pixels as f64 / made.max(1) as f64);
        (made, cancelled)
    }
}
