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
//! bootstrap alone the mean of Mitsuba's Cornell box was 1 % high at every mutation count,
//! the bootstrap's own error). The chains start from bootstrap states chosen in proportion
//! to their luminance, and the film's splats, L/y(L) each, are developed times b / mutations
//! per pixel. `--spp` sets the mutations per pixel.
//!
//! Direct illumination apart (Mitsuba 0.6's `directSamples`, 16 by default): paths of one
//! and two edges (emitters seen directly, direct light) are rendered by BDPT limited to two
//! edges at `direct_samples` per pixel, and the chains take the longer ones. Chains on a
//! small bright emitter seen directly hardly ever leave it, and too few bootstrap states
//! find it to start the right number of chains there: on `veach-plates` the smallest light
//! came out 36 % dark with the chains doing every depth (the image mean −1.6 % at 1024
//! mutations per pixel; −0.5 % with them apart).
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
//! blocks whose splats are added in chain order, so the image does not depend on the thread
//! count (nor on the block size).

use std::sync::atomic::Ordering;
use std::time::Instant;

use rayon::prelude::*;

use super::bdpt::{self, Bdpt, BdptConfig, Subpaths};
use crate::camera::CameraRay;
use crate::math::{PI, Vec2, Vec3};
use crate::sampling::{Distribution1D, ONE_MINUS_EPSILON, Samples};
use crate::session::{Progress, RenderObserver, RenderOptions, RenderOutcome, Silent};
use crate::spectral::lanes::{PathMode, RgbMode, SpectralMode};
use crate::stats::Pcg32;
use crate::world::Scene;
use base::RenderMode;

/// The parameters of [`render`] (pbrt-v3's names and defaults).
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

const STREAMS: usize = 3;

#[derive(Clone, Copy, Default)]
struct PrimarySample {
    /// Drawn at all: a number no state has used yet is a fresh uniform one (the target
    /// density does not depend on it).
    drawn: bool,
    value: f32,
    modified: u64,
    backup: f32,
    backup_modified: u64,
}

/// A Markov chain's primary sample vector (pbrt-v3's `MLTSampler`).
struct MltSampler {
    rng: Pcg32,
    sigma: f32,
    large_step_p: f32,
    x: Vec<PrimarySample>,
    iteration: u64,
    large_step: bool,
    last_large_step: u64,
    stream: usize,
    index: usize,
}

impl MltSampler {
    fn new(seed: u64, sigma: f32, large_step_p: f32) -> MltSampler {
        MltSampler {
            rng: Pcg32::new(seed, 0x4D4C_545F),
            sigma,
            large_step_p,
            x: Vec::new(),
            iteration: 0,
            // The first state is drawn afresh.
            large_step: true,
            last_large_step: 0,
            stream: 0,
            index: 0,
        }
    }

    fn start_iteration(&mut self) {
        self.iteration += 1;
        self.large_step = self.rng.next_f32() < self.large_step_p;
    }

    fn accept(&mut self) {
        if self.large_step {
            self.last_large_step = self.iteration;
        }
    }

    fn reject(&mut self) {
        for x in &mut self.x {
            if x.modified == self.iteration {
                x.value = x.backup;
                x.modified = x.backup_modified;
            }
        }
        self.iteration -= 1;
    }

    /// A standard normal number (Box–Muller).
    fn normal(&mut self) -> f32 {
        let u1 = 1.0 - self.rng.next_f32();
        let u2 = self.rng.next_f32();
        (-2.0 * u1.ln()).sqrt() * (2.0 * PI * u2).cos()
    }

    fn next(&mut self) -> f32 {
        let i = self.stream + STREAMS * self.index;
        self.index += 1;
        if i >= self.x.len() {
            self.x.resize(i + 1, PrimarySample::default());
        }
        if !self.x[i].drawn {
            let v = self.rng.next_f32();
            self.x[i] = PrimarySample {
                drawn: true,
                value: v,
                modified: self.iteration,
                backup: v,
                backup_modified: self.iteration,
            };
            return v;
        }
        // Bring the number up to date: a fresh draw if it missed the last large step, then
        // the small steps since (one normal step of the combined deviation).
        if self.x[i].modified < self.last_large_step {
            let v = self.rng.next_f32();
            self.x[i].value = v;
            self.x[i].modified = self.last_large_step;
        }
        let x = self.x[i];
        self.x[i].backup = x.value;
        self.x[i].backup_modified = x.modified;
        let value = if self.large_step {
            self.rng.next_f32()
        } else {
            let steps = (self.iteration - x.modified) as f32;
            let v = x.value + self.normal() * self.sigma * steps.sqrt();
            let v = v - v.floor();
            if v < 1.0 { v } else { 0.0 }
        };
        self.x[i].value = value;
        self.x[i].modified = self.iteration;
        value
    }
}

impl Samples for MltSampler {
    fn next_1d(&mut self) -> f32 {
        self.next()
    }
    fn next_2d(&mut self) -> Vec2 {
        let a = self.next();
        Vec2::new(a, self.next())
    }
    fn start_stream(&mut self, stream: usize) {
        self.stream = stream;
        self.index = 0;
    }
}

fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.212_671, 0.715_160, 0.072_169))
}

/// What the chains explore: the scene, the BDPT whose samples are the states, and the
/// variant.
struct Target<'a, M: PathMode> {
    scene: &'a Scene,
    bdpt: &'a Bdpt<'a, M>,
    kelemen: bool,
}

impl<M: PathMode> Target<'_, M> {
    /// The value of the state `sampler` holds: its contributions (film position, value) in
    /// `out`, and y, the sum of their luminances (0, and `out` empty, for a state that makes
    /// nothing or something not finite). Multiplexed, `slot` is the depth d, and the state
    /// one strategy of d (pbrt-v3's `MLTIntegrator::L`); Kelemen, `slot` is 0, and the state
    /// a whole BDPT sample. Its subpaths are built in `paths`.
    ///
    /// Streams (`Samples::start_stream`): both variants draw the film position, lens and
    /// camera subpath from stream 0, the light subpath from 1 and the connections from 2.
    /// For Kelemen's states too they matter: `li` draws everything from one `Samples`, and
    /// with one stream a small step that makes the camera subpath a vertex longer or shorter
    /// (Russian roulette, a direction that now leaves the scene) would move every number of
    /// the light subpath to another coordinate, a large step for it in effect. (Mitsuba
    /// 0.6's `pssmlt` likewise keeps three samplers: sensor, emitter and direct.)
    fn value(
        &self,
        sampler: &mut MltSampler,
        paths: &mut Subpaths<M::C>,
        slot: usize,
        out: &mut Vec<(Vec2, Vec3)>,
    ) -> f32 {
        let scene = self.scene;
        out.clear();
        sampler.start_stream(0);
        if self.kelemen {
            let (p_film, cray) = film_sample(scene, sampler);
            let l = self.bdpt.li(scene, &cray, sampler, paths, out, &mut ());
            if l != Vec3::ZERO {
                out.push((p_film, l));
            }
            let y: f32 = out.iter().map(|&(_, c)| luminance(c)).sum();
            if y.is_finite() && y > 0.0 {
                return y;
            }
            out.clear();
            return 0.0;
        }
        let (s, t, n) = if slot == 0 {
            (0, 2, 1)
        } else {
            let n = slot + 2;
            let s = ((sampler.next_1d() * n as f32) as usize).min(n - 1);
            (s, n - s, n)
        };
        let (p_film, cray) = film_sample(scene, sampler);
        let Some((p, c)) = self
            .bdpt
            .strategy(scene, (&cray, p_film), (s, t), sampler, paths)
        else {
            return 0.0;
        };
        let c = c * n as f32;
        let y = luminance(c);
        if c.is_finite() && y > 0.0 {
            out.push((p, c));
            y
        } else {
            0.0
        }
    }
}

/// A film position uniform over the image and the camera ray through it.
fn film_sample(scene: &Scene, sampler: &mut MltSampler) -> (Vec2, CameraRay) {
    let f = &scene.film;
    let res = Vec2::new(f.width as f32, f.height as f32);
    let p_film = (sampler.next_2d() * res).min(res - Vec2::splat(1e-3));
    (p_film, scene.camera.generate_ray(p_film, sampler.next_2d()))
}

/// Render `scene` with MLT: `opts.spp` mutations per pixel.
pub fn render(
    scene: &Scene,
    cfg: &MltConfig,
    opts: &RenderOptions,
    observer: &dyn RenderObserver,
) -> RenderOutcome {
    match scene.mode {
        RenderMode::Rgb => render_in::<RgbMode>(scene, cfg, opts, observer),
        RenderMode::Spectral => render_in::<SpectralMode<'static>>(scene, cfg, opts, observer),
    }
}

fn render_in<M: PathMode>(
    scene: &Scene,
    cfg: &MltConfig,
    opts: &RenderOptions,
    observer: &dyn RenderObserver,
) -> RenderOutcome {
    let start = Instant::now();
    let f = &scene.film;
    // 0. Paths of one and two edges apart (Mitsuba 0.6's `directSamples`): BDPT limited to
    // two edges, its light-tracing splats baked into the splat layer the chains add to.
    let first = if cfg.direct_samples >= 0 { 2 } else { 0 };
    let mut film = if cfg.direct_samples > 0 {
        let direct = BdptConfig {
            max_depth: (cfg.max_depth as i32).min(2),
            ..BdptConfig::default()
        };
        let dopts = RenderOptions {
            spp: cfg.direct_samples as u32,
            time_budget: None,
            ..opts.clone()
        };
        let mut film = bdpt::render(scene, &direct, &dopts, &Silent).film;
        film.bake_splat_scale();
        film
    } else {
        f.film()
    };
    let kelemen = !cfg.multiplexed;
    let bcfg = BdptConfig {
        max_depth: cfg.max_depth as i32,
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
    let seed = scene.sampler.seed;
    // Populations of chains, each with its own bootstrap states, b and splat layer, in
    // slots `first..slots`. Multiplexed: slot d holds depth d (paths of d + 1 edges), those
    // below `first` rendered apart. Kelemen: one slot for every depth.
    let (first, slots) = if kelemen {
        (0, 1)
    } else {
        (first, (cfg.max_depth as usize).max(first))
    };
    let n_slots = slots - first;
    let n_boot = cfg.bootstrap.max(1) as usize;
    // 1. Bootstrap: state k is in slot first + k mod n_slots.
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
    // Per slot: Σ y and the number of independent states (none below `first`).
    let mut sums = vec![(0.0f64, n_boot as u64); slots];
    for (k, &w) in weights.iter().enumerate() {
        sums[first + k % n_slots].0 += w as f64;
    }
    let b_boot = sums.iter().map(|&(s, n)| s / n as f64).sum::<f64>();
    let pixels = f.width as u64 * f.height as u64;
    let mpp = opts.spp.max(1) as u64;
    let total = mpp * pixels;
    let chains = (cfg.chains.max(1) as u64).min(total);
    // Splats a mutation makes at most, for the block size: a state's contributions, the
    // current's and the proposal's (Kelemen: the camera sample's and up to max_depth − 1
    // light-tracing ones).
    let per_mutation = 2 * if kelemen {
        cfg.max_depth.max(1) as u64
    } else {
        1
    };
    let mut done_mutations = 0u64;
    let mut cancelled = false;
    if b_boot > 0.0 {
        // 2. The chains, slot by slot: each slot gets chains and mutations in proportion to
        // its b (largest remainders), and its own splat layer normalised by its own b and
        // mutations, so that no depth's share of the image hangs on how many chains happened
        // to start there (drawing every chain's start from all depths left `veach-plates`'
        // directly seen lights 3 % dark at any mutation count).
        let b_d: Vec<f64> = sums.iter().map(|&(s, n)| s / n as f64).collect();
        let alloc = |count: u64| -> Vec<u64> {
            let mut out: Vec<u64> = b_d
                .iter()
                .map(|&b| (count as f64 * b / b_boot).floor() as u64)
                .collect();
            let mut rest: Vec<(f64, usize)> = b_d
                .iter()
                .enumerate()
                .map(|(d, &b)| (count as f64 * b / b_boot - out[d] as f64, d))
                .collect();
            rest.sort_by(|x, y| y.0.total_cmp(&x.0).then(x.1.cmp(&y.1)));
            let short = count.saturating_sub(out.iter().sum());
            for &(_, d) in rest.iter().take(short as usize) {
                out[d] += 1;
            }
            out
        };
        let chains_d = alloc(chains);
        let mutations_d = alloc(total);
        let mut chain_id = 0u64;
        for d in 0..slots {
            let (n_chains, m_total) = (chains_d[d].max(1), mutations_d[d]);
            if b_d[d] <= 0.0 || m_total == 0 || cancelled {
                continue;
            }
            // This slot's bootstrap states and their weights.
            let ks: Vec<usize> = (d - first..weights.len()).step_by(n_slots).collect();
            let starts = Distribution1D::new(&ks.iter().map(|&k| weights[k]).collect::<Vec<_>>());
            // Systematic resampling: chain c starts at quantile (c + offset) / chains of the
            // weights, so each bootstrap state gets its share of chains to within one (drawn
            // independently, a light holding 5 % of 300 chains' weight got 15 ± 4 of them, and
            // chains hardly leave a small bright emitter).
            let offset =
                Pcg32::new(seed_of(seed, 0x5354_4152_5400 + d as u64), 7).next_f32() as f64;
            // Chains run in blocks, their splats held until the block is merged: at most 64,
            // fewer if their splats would take more than about 256 MiB, at least one per
            // thread (the image does not depend on it).
            let chain_bytes = (m_total / n_chains + 1)
                * per_mutation
                * std::mem::size_of::<(Vec2, Vec3)>() as u64;
            let block = (256u64 << 20)
                .div_ceil(chain_bytes)
                .min(64)
                .max(rayon::current_num_threads() as u64);
            let mut layer = f.film();
            let mut made = 0u64;
            let mut c0 = 0u64;
            while c0 < n_chains {
                if opts.cancel.load(Ordering::Relaxed) {
                    cancelled = true;
                    break;
                }
                let c1 = (c0 + block).min(n_chains);
                let lists: Vec<Chain> = (c0..c1)
                    .into_par_iter()
                    .map(|c| {
                        let m = m_total * (c + 1) / n_chains - m_total * c / n_chains;
                        let start = Start {
                            starts: &starts,
                            ks: &ks,
                            slot: d,
                            u: ((c as f64 + offset) / n_chains as f64) as f32,
                        };
                        run_chain(&target, cfg, &start, seed, chain_id + c, m)
                    })
                    .collect();
                for chain in lists {
                    for (p, v) in chain.splats {
                        layer.add_splat(p, v);
                    }
                    sums[d].0 += chain.large_sum;
                    sums[d].1 += chain.large_count;
                }
                made = m_total * c1 / n_chains;
                done_mutations += made - m_total * c0 / n_chains;
                c0 = c1;
                observer.progress(&Progress {
                    samples_done: done_mutations,
                    samples_total: total,
                    elapsed: start.elapsed(),
                    spp_done: (done_mutations / pixels.max(1)) as u32,
                });
            }
            chain_id += n_chains;
            // Splats are L / y(L): b_d / (this slot's mutations per pixel) makes them
            // radiance.
            let b = sums[d].0 / sums[d].1 as f64;
            film.add_splat_layer(&layer, b * pixels as f64 / made.max(1) as f64);
        }
    }
    film.set_splat_scale(1.0);
    let made = done_mutations as f64 / pixels.max(1) as f64;
    observer.pass_done(&film, opts.spp);
    RenderOutcome {
        film,
        spp: made.round() as u32,
        passes: 1,
        elapsed: start.elapsed(),
        cancelled,
        extra: Vec::new(),
    }
}

/// Where a chain of one slot starts: a bootstrap state of that slot, chosen in proportion
/// to its luminance (`ks` its indices among all bootstrap states) by the quantile `u`.
struct Start<'a> {
    starts: &'a Distribution1D,
    ks: &'a [usize],
    slot: usize,
    u: f32,
}

fn seed_of(seed: u64, k: u64) -> u64 {
    crate::sampling::sampler::hash2(seed, k)
}

/// What a chain hands back: its splats, and the luminance sum and count of the large steps
/// it proposed (for b in its slot).
struct Chain {
    splats: Vec<(Vec2, Vec3)>,
    large_sum: f64,
    large_count: u64,
}

/// One chain.
fn run_chain<M: PathMode>(
    target: &Target<M>,
    cfg: &MltConfig,
    start: &Start,
    seed: u64,
    chain: u64,
    mutations: u64,
) -> Chain {
    let mut rng = Pcg32::new(seed_of(seed, 0x4348_4149_4E00 + chain), 7);
    let (i, _, _) = start.starts.sample_discrete(start.u.min(ONE_MINUS_EPSILON));
    let k = start.ks[i];
    let slot = start.slot;
    // The chain starts in bootstrap state k (same seed: the same numbers).
    let mut sampler = MltSampler::new(seed_of(seed, k as u64), cfg.sigma, cfg.large_step);
    let mut out = Chain {
        splats: Vec::new(),
        large_sum: 0.0,
        large_count: 0,
    };
    let mut paths = Subpaths::default();
    let (mut current, mut proposed) = (Vec::new(), Vec::new());
    let mut y_cur = target.value(&mut sampler, &mut paths, slot, &mut current);
    if y_cur <= 0.0 {
        return out;
    }
    out.splats.reserve(2 * mutations as usize);
    for _ in 0..mutations {
        sampler.start_iteration();
        let y = target.value(&mut sampler, &mut paths, slot, &mut proposed);
        if sampler.large_step {
            out.large_count += 1;
            out.large_sum += y as f64;
        }
        let accept = if y > 0.0 { (y / y_cur).min(1.0) } else { 0.0 };
        // Both states splatted with their expected weights (zero ones left out).
        if accept > 0.0 {
            let w = accept / y;
            out.splats.extend(proposed.iter().map(|&(p, c)| (p, c * w)));
        }
        if accept < 1.0 {
            let w = (1.0 - accept) / y_cur;
            out.splats.extend(current.iter().map(|&(p, c)| (p, c * w)));
        }
        if rng.next_f32() < accept {
            std::mem::swap(&mut current, &mut proposed);
            y_cur = y;
            sampler.accept();
        } else {
            sampler.reject();
        }
    }
    out
}
