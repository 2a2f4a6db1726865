//! What an observer of a path sees: the [`PathRecorder`] trait, the events it is told about
//! (vertices, scattering, contributions and their origin, the end of the path), and the two
//! recorders of the tracer itself — [`NoRecorder`] (compiles to nothing) and [`DepthFilter`]
//! (CS184's "only the last bounce"). Render layers and the path visualiser implement their
//! own.

use crate::geometry::Ray;
use crate::math::Vec3;
use crate::sampling::sdtree::DTree;
use crate::spectral::lanes::Color;

/// How a path left a vertex.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Scatter {
    /// Perfectly specular (mirror reflection or smooth refraction).
    pub delta: bool,
    /// Crossed the surface.
    pub transmission: bool,
}

/// How a contribution reached the estimate.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Via {
    /// A path segment hit an emitter (or escaped to the environment).
    Emission,
    /// Next-event estimation (a shadow ray to a sampled emitter point).
    EmitterSample,
    /// The ambient term of the Whitted integrator.
    Ambient,
}

/// Where a contribution to the estimate comes from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Contribution {
    /// Path segments from the camera to the emitting point (1: emitter seen directly).
    pub depth: u32,
    /// How the path left its first surface vertex (`None`: it had not left it yet).
    pub first: Option<Scatter>,
    pub via: Via,
}

/// What a recorded vertex is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum VertexKind {
    /// A surface hit.
    Surface,
    /// A real collision in a participating medium (volumetric path tracer).
    Medium,
    /// An index-matched (`null`) boundary crossed without scattering (volumetric path tracer).
    Null,
}

/// A vertex as recorded (throughput in the colour type `C` of the path's mode).
#[derive(Clone, Copy, Debug)]
pub struct RecordedVertex<C = Vec3> {
    pub p: Vec3,
    /// Shading normal (zero at a medium vertex).
    pub n: Vec3,
    /// Segments traced before reaching this vertex (1 for the first hit).
    pub depth: u32,
    /// Throughput of the path up to this vertex.
    pub throughput: C,
    pub kind: VertexKind,
}

/// A direction sampled at the last recorded vertex.
#[derive(Clone, Copy, Debug)]
pub struct RecordedScatter<C = Vec3> {
    pub scatter: Scatter,
    /// The sampled direction (world space, unit length).
    pub wi: Vec3,
    /// Solid-angle density (or discrete probability for delta lobes).
    pub pdf: f32,
    /// Throughput after the bounce (and after Russian roulette reweighting).
    pub throughput: C,
}

/// Why a path stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PathEnd {
    /// No surface hit: the path left the scene.
    Escaped,
    /// `max_depth` reached.
    MaxDepth,
    /// Russian roulette.
    Roulette,
    /// The surface does not scatter (no BSDF, failed sample, zero throughput, or a non-delta
    /// vertex of a Whitted tracer).
    Absorbed,
}

/// Observes the events of the paths traced by [`li_recorded`](super::li_recorded), whose
/// colours are of type `C` (RGB unless the path runs in spectral mode).
pub trait PathRecorder<C = Vec3> {
    fn camera_ray(&mut self, _ray: &Ray) {}
    fn vertex(&mut self, _v: &RecordedVertex<C>) {}
    fn scatter(&mut self, _s: &RecordedScatter<C>) {}
    fn end(&mut self, _why: PathEnd) {}
    /// Radiance `l` was added to the estimate.
    fn contribution(&mut self, _l: C, _c: Contribution) {}
    /// The learnt distribution of incident light at the vertex last told to
    /// [`Self::vertex`], to sample directions from beside the BSDF (path guiding's recorder,
    /// `guided.rs`). `None` for every other recorder: the tracer then samples as it always
    /// did, and its default instantiation ([`NoRecorder`]) compiles the question away.
    #[inline(always)]
    fn guide(&self) -> Option<&DTree> {
        None
    }
}

/// Records nothing.
pub struct NoRecorder;
impl<C> PathRecorder<C> for NoRecorder {}

/// Sums the contributions of paths with exactly `depth` segments (one bounce only).
pub struct DepthFilter<C = Vec3> {
    pub depth: u32,
    pub sum: C,
}

impl<C: Color> PathRecorder<C> for DepthFilter<C> {
    fn contribution(&mut self, l: C, c: Contribution) {
        if c.depth == self.depth {
            self.sum += l;
        }
    }
}
