//! The batched loop: [`li_batched`] keeps [`BATCH`] paths in flight, and the shadow sink
//! ([`Shadows`]) that lets it share the per-vertex step with the single-path loop.
//!
//! # Why
//!
//! One path at a time, every step waits for the one before it: the closest hit, then shading
//! at it (emission, emitter sampling, the next direction), then the next closest hit along
//! the ray just chosen, with a shadow ray in between. Across paths the steps are independent.
//! So each round runs one stage over all paths in flight before the next stage — closest
//! hits ([`Scene::hit`], the 20-byte accelerator hit only), shading ([`Scene::surface`]
//! computes the interaction in place and lends it to [`Tracer::vertex`]), then the shadow
//! rays of the whole batch — and the out-of-order core overlaps the memory waits of
//! different paths. Finished paths are replaced by new camera samples in place (what it
//! saves: `bench/README.md`, "Design measurements").
//!
//! # The invariant: the same estimate as the single-path loop, bit for bit
//!
//! Both loops run the same step, [`Tracer::vertex`]; they differ only in the shadow sink
//! next-event estimation hands its candidate contributions to. [`Shadows::Immediate`] (the
//! single-path loop, [`li`](super::li), and anything with a recorder) traces each shadow ray
//! at once and adds the contribution if it is unblocked; [`Shadows::Deferred`] queues it with
//! the path's slot, and the round adds it to that slot's sum after the batch's shadow rays.
//! The two agree because
//!
//! - each path owns its sampler (set up by `next` for its camera sample) and draws the same
//!   random numbers in the same order: shadow rays draw none, and occlusion is a pure
//!   function of the ray (alpha cut-outs hash the ray and primitive);
//! - each path's sum receives the same terms in the same order: the deferred contributions
//!   of a vertex are added after everything else that vertex adds and before anything the
//!   next vertex adds, which is where the immediate sink adds them. A zero candidate (an MIS
//!   weight of 0) is skipped by the immediate sink and added by the deferred one, which
//!   changes nothing: a sum that starts at +0 is never −0.
//!
//! The one exception is `splitting`: the N − 1 split-off continuations are traced to their
//! ends at once, with the immediate sink, so in the batched loop their contributions come
//! before the splitting vertex's emitter samples instead of after (`tests/it/path_variants.rs`
//! compares every other variant bit for bit). Paths with a recorder, or with `only_depth`
//! (which needs one), use the single-path loop.

use super::PathConfig;
use super::record::NoRecorder;
use super::state::{PathState, ShadowQuery, Shadows, Tracer};
use crate::accel::Hit;
use crate::camera::CameraRay;
use crate::math::Vec3;
use crate::sampling::Sampler;
use crate::spectral::lanes::{Color, PathMode};
use crate::world::Scene;

/// Paths in flight at once in [`li_batched`].
const BATCH: usize = 32;

/// A path in flight.
struct Slot<T, M: PathMode> {
    sampler: Sampler,
    mode: M,
    st: PathState<M::C>,
    result: M::C,
    tag: T,
}

/// [`li`](super::li) for a stream of camera rays, `BATCH` (32) paths at a time (see the module
/// docs: the estimates are the same). `next` sets the sampler up for the next camera sample
/// and returns its tag and ray (`None`: no more); `done` receives each path's estimate with
/// its tag, in the order the paths end, as linear sRGB: each path runs in the colour mode
/// `M` (set up per camera sample by [`PathMode::start`]).
pub fn li_batched<T, M: PathMode>(
    scene: &Scene,
    cfg: &PathConfig,
    template: &Sampler,
    mut next: impl FnMut(&mut Sampler) -> Option<(T, CameraRay)>,
    mut done: impl FnMut(T, Vec3),
) {
    let mut slots: Vec<Slot<T, M>> = Vec::with_capacity(BATCH);
    let mut hits: Vec<Option<Hit>> = Vec::with_capacity(BATCH);
    let mut queue: Vec<(ShadowQuery<M::C>, u32)> = Vec::with_capacity(BATCH);
    let mut alive = [false; BATCH];
    let mut sampler = template.clone();
    if cfg.max_depth == 0 {
        while let Some((tag, _)) = next(&mut sampler) {
            done(tag, Vec3::ZERO);
        }
        return;
    }
    let mut more = true;
    while more && slots.len() < BATCH {
        match next(&mut sampler) {
            None => more = false,
            Some((tag, cray)) => {
                let mut sampler = sampler.clone();
                let mode = M::start(&mut sampler);
                slots.push(Slot {
                    sampler,
                    mode,
                    st: PathState::start(scene, cfg, &cray),
                    result: M::C::ZERO,
                    tag,
                })
            }
        }
    }
    while !slots.is_empty() {
        hits.extend(slots.iter().map(|s| scene.hit(&s.st.ray, s.st.t_max)));
        for (k, (s, &hit)) in slots.iter_mut().zip(&hits).enumerate() {
            let mut tracer = Tracer {
                scene,
                cfg,
                sampler: &mut s.sampler,
                rec: &mut NoRecorder,
                mode: &s.mode,
                result: &mut s.result,
                shadows: Shadows::Deferred {
                    queue: &mut queue,
                    slot: k as u32,
                },
            };
            let (ray, t_max) = (s.st.ray, s.st.t_max);
            let st = &mut s.st;
            alive[k] = scene.surface(&ray, t_max, hit, |si| tracer.vertex(st, si));
        }
        hits.clear();
        for (q, slot) in queue.drain(..) {
            if !scene.occluded(&q.ray, q.t_max) {
                slots[slot as usize].result += q.l;
            }
        }
        // A finished path's slot takes the next camera sample in place (building a new slot
        // and moving it in cost a 224-byte copy per path); without one, the slot goes. From
        // the back, so that `swap_remove` only moves paths already looked at (alive).
        for k in (0..slots.len()).rev() {
            if alive[k] {
                continue;
            }
            let s = &mut slots[k];
            match if more { next(&mut s.sampler) } else { None } {
                Some((tag, cray)) => {
                    let mode = M::start(&mut s.sampler);
                    let old = std::mem::replace(&mut s.mode, mode);
                    s.st = PathState::start(scene, cfg, &cray);
                    let result = std::mem::replace(&mut s.result, M::C::ZERO);
                    done(std::mem::replace(&mut s.tag, tag), old.to_rgb(result));
                }
                None => {
                    more = false;
                    let s = slots.swap_remove(k);
                    done(s.tag, s.mode.to_rgb(s.result));
                }
            }
        }
    }
}
