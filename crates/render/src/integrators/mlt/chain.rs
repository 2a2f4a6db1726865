//! One Markov chain: the value of a state (a strategy of BDPT, or a whole BDPT sample), and
//! the mutations with their expected-value splats.

use super::MltConfig;
use super::sampler::MltSampler;
use crate::camera::CameraRay;
use crate::integrators::bdpt::{Bdpt, Subpaths};
use crate::math::{Vec2, Vec3};
use crate::sampling::{Distribution1D, ONE_MINUS_EPSILON, Samples};
use crate::spectral::lanes::PathMode;
use crate::stats::Pcg32;
use crate::world::Scene;

pub(super) fn luminance(c: Vec3) -> f32 {
    c.dot(Vec3::new(0.212_671, 0.715_160, 0.072_169))
}

/// What the chains explore: the scene, the BDPT whose samples are the states, and the
/// variant.
pub(super) struct Target<'a, M: PathMode> {
    pub(super) scene: &'a Scene,
    pub(super) bdpt: &'a Bdpt<'a, M>,
    pub(super) kelemen: bool,
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
    pub(super) fn value(
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
pub(super) fn film_sample(scene: &Scene, sampler: &mut MltSampler) -> (Vec2, CameraRay) {
    let f = &scene.film;
    let res = Vec2::new(f.width as f32, f.height as f32);
    let p_film = (sampler.next_2d() * res).min(res - Vec2::splat(1e-3));
    (p_film, scene.camera.generate_ray(p_film, sampler.next_2d()))
}

/// Where a chain of one slot starts: a bootstrap state of that slot, chosen in proportion
/// to its luminance (`ks` its indices among all bootstrap states) by the quantile `u`.
pub(super) struct Start<'a> {
    pub(super) starts: &'a Distribution1D,
    pub(super) ks: &'a [usize],
    pub(super) slot: usize,
    pub(super) u: f32,
}

pub(super) fn seed_of(seed: u64, k: u64) -> u64 {
    crate::sampling::sampler::hash2(seed, k)
}

/// What a chain hands back: its splats, and the luminance sum and count of the large steps
/// it proposed (for b in its slot).
pub(super) struct Chain {
    pub(super) splats: Vec<(Vec2, Vec3)>,
    pub(super) large_sum: f64,
    pub(super) large_count: u64,
}

/// One chain.
pub(super) fn run_chain<M: PathMode>(
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
