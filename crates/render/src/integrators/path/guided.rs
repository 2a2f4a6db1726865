//! Path guiding (Müller et al. 2017, "Practical Path Guiding"): the path tracer learns the
//! incident light of the scene online, in an SD-tree ([`SdTree`]), and samples directions
//! from it beside the BSDF.
//!
//! # The render
//!
//! [`render`] runs the tile loop in phases ([`drive::Phased`]) of doubling length: 1, 2, 4, …
//! chunks of sample indices (`CHUNK_SPP` samples per pixel each); the last phase takes what
//! is left once it is shorter than twice the phase before (so the final, best-guided phase
//! holds about half the samples). Every phase but the last records training samples into
//! the tree; between phases the tree is refined ([`SdTree::refine`]). The first phase samples
//! the BSDF only. Every phase's samples are unbiased (the distribution a phase samples from is
//! fixed while it runs), so the image is the average of all of them, as in the unguided
//! render; the film is the same film.
//!
//! # Sampling: one-sample MIS of the BSDF and the learnt distribution
//!
//! At a vertex whose BSDF is guidable ([`Bsdf::guidable`]: no delta lobe, nor a glossy lobe
//! that the learnt distribution would only waste samples on) and whose spatial leaf has
//! learnt something, the
//! next direction comes from the BSDF with probability α = ½ and from the leaf's quadtree
//! otherwise; its weight is f·cos / (α·p_bsdf + (1 − α)·p_guide), the density of the mixture
//! (the one-sample MIS estimator with the balance heuristic, unbiased wherever the BSDF's
//! density covers f). Next-event estimation weighs its samples against that same mixture
//! density (`nee.rs`), and emission found by a guided direction against NEE with it (the
//! path's `Previous::pdf`), so the MIS of emitter and direction sampling stays a partition of
//! unity. Other vertices sample the BSDF alone.
//!
//! # Training and determinism
//!
//! The guided recorder ([`GuideRecorder`]) keeps each non-delta vertex of the path (its
//! spatial leaf, the direction and its density, the inverse of the throughput after it) and
//! adds every later contribution, divided by that throughput, to the vertex's incident
//! radiance; when the path ends each vertex records radiance / density at its direction
//! ([`SdTree::record`]: 64-bit fixed point, atomic integer adds, so the sums do not depend on
//! which thread adds first). The tree changes only between phases. So the image is a pure
//! function of the scene, seed and sample count, the same for any thread count. Paths run
//! one at a time (the single-path loop: the recorder needs the immediate shadow sink), so a
//! guided render does not use the batched loop.
//!
//! # Why Müller et al. 2017 and not Ruppert et al. 2020 (Open PGL's VMMs)
//!
//! The SD-tree's training is a set of integer sums over a fixed topology between
//! refinements, which makes a deterministic, thread-count-independent result direct; its
//! density is exact (piecewise constant) and cheap to sample and evaluate, which the χ² test
//! checks exactly; and its memory is a node count, easy to bound. The parallax-aware VMMs fit
//! better with fewer samples (and handle glossy products better), but their weighted EM
//! updates are floating-point reductions whose result depends on order, and the mixture
//! fitting has more knobs; for an offline renderer whose images must be bit-identical across
//! thread counts, the SD-tree is the smaller risk.

use super::record::{Contribution, PathRecorder, RecordedScatter, RecordedVertex};
use super::{PathConfig, clamp_sample, li_recorded_in};
use crate::bsdf::{Bsdf, BsdfSample, TransportMode};
use crate::camera::CameraRay;
use crate::drive::{self, Estimator, Phased};
use crate::math::{Frame, Vec2, Vec3};
use crate::sampling::Sampler;
use crate::sampling::sdtree::{DTree, SdStats, SdTree};
use crate::session::{Job, RenderOutcome};
use crate::spectral::lanes::{Color, PathMode};
use crate::world::Scene;

/// Probability of sampling the BSDF at a guided vertex (the rest: the learnt distribution).
pub const BSDF_FRACTION: f32 = 0.5;

/// Path guiding's settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Guiding {
    /// The most memory the SD-tree may hold (bytes).
    pub max_bytes: u64,
    /// `c` of the spatial split rule: a leaf splits after `c·√(2^k)` samples in iteration `k`.
    pub split_threshold: f32,
}

impl Default for Guiding {
    fn default() -> Self {
        Guiding {
            max_bytes: 256 << 20,
            split_threshold: 4000.0,
        }
    }
}

/// The density of the mixture at a guided vertex, given the BSDF's density `pdf_bsdf` of the
/// world direction `wi`.
#[inline]
pub fn mixture_pdf(pdf_bsdf: f32, g: &DTree, wi: Vec3) -> f32 {
    BSDF_FRACTION * pdf_bsdf + (1.0 - BSDF_FRACTION) * g.pdf(wi)
}

/// A direction at a guided vertex (BSDF without delta lobes): the BSDF's sample with
/// probability α (`u1` chooses, then is reused by the BSDF), else the learnt distribution's
/// (from `u2`); weighted by the mixture's density.
#[inline(never)]
pub fn sample<C: Color>(
    bsdf: &Bsdf<C>,
    frame: &Frame,
    wo: Vec3,
    g: &DTree,
    u1: f32,
    u2: Vec2,
) -> Option<BsdfSample<C>> {
    let mode = TransportMode::Radiance;
    let (wi, eta, pdf_guide) = if u1 < BSDF_FRACTION {
        let bs = bsdf.sample(wo, u1 / BSDF_FRACTION, u2, mode)?;
        if bs.delta {
            return Some(bs);
        }
        (bs.wi, bs.eta, g.pdf(frame.to_world(bs.wi)))
    } else {
        // Only Russian roulette reads η; 1 keeps it unbiased.
        let (d, pdf) = g.sample(u2);
        (frame.to_local(d), 1.0, pdf)
    };
    let (f, pdf_bsdf) = bsdf.eval_pdf(wo, wi, mode);
    let pdf = BSDF_FRACTION * pdf_bsdf + (1.0 - BSDF_FRACTION) * pdf_guide;
    if f.is_black() || pdf.is_nan() || pdf <= 0.0 {
        return None;
    }
    Some(BsdfSample {
        wi,
        weight: f / pdf,
        pdf,
        delta: false,
        transmission: wi.z * wo.z < 0.0,
        eta,
    })
}

/// Non-delta vertices of a path kept for training (deeper ones are not recorded).
const MAX_RECORDS: usize = 32;

#[derive(Clone, Copy)]
struct Record<C> {
    leaf: u32,
    wi: Vec3,
    pdf: f32,
    inv_throughput: C,
    radiance: C,
}

/// The recorder of a guided path: it answers [`PathRecorder::guide`] from the tree, and, when
/// training, keeps the path's non-delta vertices and the light that reaches each.
pub struct GuideRecorder<'a, C> {
    tree: &'a SdTree,
    /// Sample from the tree (false in the first phase, before it has learnt anything).
    sample: bool,
    /// Keep training records.
    train: bool,
    leaf: u32,
    guide: Option<&'a DTree>,
    records: [Option<Record<C>>; MAX_RECORDS],
    len: usize,
}

impl<'a, C: Color> GuideRecorder<'a, C> {
    pub fn new(tree: &'a SdTree, sample: bool, train: bool) -> Self {
        GuideRecorder {
            tree,
            sample,
            train,
            leaf: 0,
            guide: None,
            records: [None; MAX_RECORDS],
            len: 0,
        }
    }

    /// Record the path's training samples into the tree.
    pub fn finish(&self) {
        for r in self.records[..self.len].iter().flatten() {
            self.tree.record(r.leaf, r.wi, r.radiance.mean() / r.pdf);
        }
    }
}

impl<C: Color> PathRecorder<C> for GuideRecorder<'_, C> {
    #[inline]
    fn vertex(&mut self, v: &RecordedVertex<C>) {
        if self.sample || self.train {
            self.leaf = self.tree.leaf(v.p);
            self.guide = if self.sample {
                self.tree.guide(self.leaf)
            } else {
                None
            };
        }
    }

    #[inline]
    fn scatter(&mut self, s: &RecordedScatter<C>) {
        self.guide = None;
        if !self.train
            || s.scatter.delta
            || self.len == MAX_RECORDS
            || s.pdf.is_nan()
            || s.pdf <= 0.0
        {
            return;
        }
        let t = s.throughput;
        self.records[self.len] = Some(Record {
            leaf: self.leaf,
            wi: s.wi.normalize(),
            pdf: s.pdf,
            inv_throughput: C::from_fn(|i| {
                let x = t.lane(i);
                if x > 0.0 { 1.0 / x } else { 0.0 }
            }),
            radiance: C::ZERO,
        });
        self.len += 1;
    }

    #[inline]
    fn contribution(&mut self, l: C, _c: Contribution) {
        for r in self.records[..self.len].iter_mut().flatten() {
            r.radiance += l * r.inv_throughput;
        }
    }

    #[inline(always)]
    fn guide(&self) -> Option<&DTree> {
        self.guide
    }
}

/// One phase of a guided render: the path tracer with the guided recorder.
pub struct GuidedPhase<'a> {
    cfg: &'a PathConfig,
    tree: &'a SdTree,
    sample: bool,
    train: bool,
}

impl<M: PathMode> Estimator<M> for GuidedPhase<'_> {
    fn li(&self, scene: &Scene, cray: &CameraRay, sampler: &mut Sampler) -> Vec3 {
        let mode = M::start(sampler);
        let mut rec = GuideRecorder::new(self.tree, self.sample, self.train);
        let l = mode.to_rgb(li_recorded_in(
            scene, cray, sampler, self.cfg, &mode, &mut rec,
        ));
        if self.train {
            rec.finish();
        }
        self.cfg.clamp.map_or(l, |max| clamp_sample(l, max))
    }
}

/// The phases of a guided render (see the module docs).
struct Training<'a> {
    cfg: &'a PathConfig,
    tree: SdTree,
    /// Phases that end before the last one (the last phase does not train).
    last: Option<u32>,
}

/// The chunk at which phase `k` ends, of `chunks`, and whether it is the last.
pub fn phase_end(k: u32, chunks: u64) -> (u64, bool) {
    // Phase k holds 2^k chunks and ends at 2^(k+1) − 1, unless what would be left is
    // shorter than the next phase.
    let end = (1u64 << (k + 1).min(62)) - 1;
    let next_len = 1u64 << (k + 1).min(62);
    if end >= chunks || chunks - end < next_len {
        (chunks, true)
    } else {
        (end, false)
    }
}

impl<M: PathMode> Phased<M> for Training<'_> {
    type Phase<'b>
        = GuidedPhase<'b>
    where
        Self: 'b;

    fn phase_end(&self, k: u32, chunks: u64) -> u64 {
        phase_end(k, chunks).0
    }

    fn phase(&self, k: u32) -> GuidedPhase<'_> {
        GuidedPhase {
            cfg: self.cfg,
            tree: &self.tree,
            sample: k > 0,
            // The last phase does not train (nothing would use what it learnt).
            train: self.last != Some(k),
        }
    }

    fn end_phase(&mut self, _k: u32) {
        self.tree.refine();
    }
}

/// A guided render of `scene` by the path tracer `cfg` (see the module docs); the SD-tree's
/// size at the end is returned beside the render.
pub fn render<M: PathMode>(job: &Job, cfg: &PathConfig, g: &Guiding) -> (RenderOutcome, SdStats) {
    let (lo, hi) = job.scene.accel.bounds();
    let plan = drive::TileWork::new(job.scene, job.opts);
    let chunks = plan.len() / plan.per_chunk().max(1);
    let last = (0..64).find(|&k| phase_end(k, chunks).1);
    let mut t = Training {
        cfg,
        tree: SdTree::new(lo, hi, g.split_threshold as f64, g.max_bytes),
        last,
    };
    let outcome = drive::render_tiles_phased::<M, _>(job, &mut t);
    let stats = t.tree.stats();
    (outcome, stats)
}
