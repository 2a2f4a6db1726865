//! The state of a path between two segments ([`PathState`]) and what its steps work with
//! besides it ([`Tracer`]): the scene and configuration, the path's sampler, recorder,
//! colour mode, running estimate, and the sink its next-event estimates go to ([`Shadows`]:
//! tested at once, or queued for the batch).

use super::PathConfig;
use super::record::{Contribution, PathRecorder, Scatter, Via};
use crate::bsdf::Bsdf;
use crate::camera::CameraRay;
use crate::geometry::Ray;
use crate::integrators::transport::Previous;
use crate::math::{Frame, Vec3};
use crate::sampling::Sampler;
use crate::shapes::SurfaceInteraction;
use crate::spectral::lanes::{Color, PathMode};
use crate::world::Scene;

/// The state of a path between two segments (throughput in the colour type `C` of its mode).
#[derive(Clone, Copy)]
pub(super) struct PathState<C> {
    pub(super) ray: Ray,
    pub(super) t_max: f32,
    pub(super) throughput: C,
    pub(super) eta: f32,
    /// Segments traced so far.
    pub(super) depth: u32,
    pub(super) prev: Option<Previous>,
    pub(super) first: Option<Scatter>,
    /// Splitting still to be done at the next vertex.
    pub(super) split: bool,
    /// The medium the path is in, when the configuration applies media
    /// ([`PathConfig::media_absorption`]; otherwise always `None`).
    pub(super) medium: Option<u32>,
    /// A non-delta bounce happened: emission found after delta bounces from here is caustic.
    pub(super) diffuse_seen: bool,
}

impl<C: Color> PathState<C> {
    pub(super) fn start(scene: &Scene, cfg: &PathConfig, cray: &CameraRay) -> PathState<C> {
        PathState {
            ray: cray.ray,
            t_max: cray.t_max,
            throughput: C::ONE,
            eta: 1.0,
            depth: 0,
            prev: None,
            first: None,
            split: cfg.splitting > 1,
            medium: scene.camera_medium.filter(|_| cfg.media_absorption),
            diffuse_seen: false,
        }
    }

    /// The segment just traced follows a delta bounce that follows a non-delta one.
    #[inline]
    pub(super) fn caustic(&self) -> bool {
        self.diffuse_seen && self.prev.is_some_and(|p| p.delta)
    }

    /// A contribution of this path reaching the camera along `depth` segments.
    #[inline]
    pub(super) fn contribution(&self, via: Via, depth: u32) -> Contribution {
        Contribution {
            depth,
            first: self.first,
            via,
        }
    }
}

/// A vertex that scatters: its interaction, its BSDF in its shading frame, and the direction
/// back along the path in that frame.
#[derive(Clone, Copy)]
pub(super) struct Shading<'a, C: Color> {
    pub(super) si: &'a SurfaceInteraction,
    pub(super) bsdf: &'a Bsdf<C>,
    pub(super) frame: &'a Frame,
    pub(super) wo: Vec3,
}

/// What a path's vertex step works with besides the path's state: among others its colour
/// mode `M` (RGB, or spectral with the path's wavelengths), which every colour the path
/// meets goes through.
pub(super) struct Tracer<'a, R, M: PathMode> {
    pub(super) scene: &'a Scene,
    pub(super) cfg: &'a PathConfig,
    pub(super) sampler: &'a mut Sampler,
    pub(super) rec: &'a mut R,
    pub(super) mode: &'a M,
    /// The path's estimate so far.
    pub(super) result: &'a mut M::C,
    /// Where next-event estimation's candidate contributions go.
    pub(super) shadows: Shadows<'a, M::C>,
}

/// A candidate contribution `l` of next-event estimation and its shadow segment.
pub(super) struct ShadowQuery<C> {
    pub(super) ray: Ray,
    pub(super) t_max: f32,
    pub(super) l: C,
}

/// Where next-event estimation's candidate contributions go: each counts only if its shadow
/// segment is unblocked.
pub(super) enum Shadows<'a, C> {
    /// Test each shadow ray when it is made (the single-path loop).
    Immediate,
    /// Queue it with the slot of its path, to be tested with the rest of the batch after
    /// every path of the batch has been shaded.
    Deferred {
        queue: &'a mut Vec<(ShadowQuery<C>, u32)>,
        slot: u32,
    },
}

impl<R: PathRecorder<M::C>, M: PathMode> Tracer<'_, R, M> {
    /// Add `l` to the estimate and tell the recorder where it came from.
    #[inline]
    pub(super) fn add(&mut self, l: M::C, c: Contribution) {
        *self.result += l;
        self.rec.contribution(l, c);
    }

    /// Add `q.l` to the estimate (and tell the recorder) unless `q.ray` is blocked within
    /// `(0, q.t_max)`, or queue it for the batch to do so.
    #[inline]
    pub(super) fn shadow(&mut self, q: ShadowQuery<M::C>, c: Contribution) {
        match &mut self.shadows {
            // A zero value (an MIS weight of 0) is neither traced nor recorded.
            Shadows::Immediate => {
                if !q.l.is_black() && !self.scene.occluded(&q.ray, q.t_max) {
                    self.add(q.l, c);
                }
            }
            Shadows::Deferred { queue, slot } => queue.push((q, *slot)),
        }
    }
}
