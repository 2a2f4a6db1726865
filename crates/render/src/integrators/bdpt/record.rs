//! Recording BDPT samples (`debug-paths`): [`Bdpt::record`] runs [`Bdpt::li`] with a
//! [`StrategyLog`] as its strategy sink, and returns both subpaths and every strategy with a
//! nonzero contribution: its joint, MIS weight and weighted value.

use super::{Bdpt, Joint, Kind, StrategySink, Subpaths, Vertex};
use crate::camera::CameraRay;
use crate::math::{Vec2, Vec3};
use crate::sampling::Samples;
use crate::spectral::lanes::RgbMode;
use crate::world::Scene;

/// What kind of point a [`BdptVertex`] is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BdptVertexKind {
    /// The camera subpath's first vertex, or the lens point sampled for t = 1.
    Camera,
    /// A light subpath's first vertex (on emitter `light`), or the light point sampled for
    /// s = 1.
    Light { light: u32 },
    /// A surface hit (on an emitter if the camera subpath reached one).
    Surface,
    /// A scattering event in a medium.
    Medium,
    /// Where a camera subpath left the scene: the environment, in the direction from the
    /// previous vertex to `p`.
    Infinite,
}

/// A subpath vertex as [`Bdpt::record`] saw it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BdptVertex {
    pub kind: BdptVertexKind,
    pub p: Vec3,
    /// Geometric normal (zero at points, medium vertices and infinity).
    pub n: Vec3,
    /// Throughput from the subpath's start to here (one at the camera; zero at a light
    /// subpath's first vertex and at a light point sampled for s = 1, whose emission the
    /// next vertex's throughput or the connection carries).
    pub beta: Vec3,
    /// Density with which its own subpath sampled it (per unit area; per unit solid angle at
    /// infinity).
    pub pdf_fwd: f32,
    /// Density with which the other subpath would have sampled it (as its subpath left it;
    /// a connection overrides the ones around its joint for its weight).
    pub pdf_rev: f32,
    /// Left by a delta lobe.
    pub delta: bool,
    /// At infinity (the environment; `p` is one unit away from the previous vertex, or on
    /// the disk an environment's light subpath starts from).
    pub at_infinity: bool,
}

impl BdptVertex {
    fn of(v: &Vertex) -> BdptVertex {
        BdptVertex {
            kind: match v.kind {
                Kind::Camera => BdptVertexKind::Camera,
                Kind::Light(light) => BdptVertexKind::Light { light },
                Kind::Infinite => BdptVertexKind::Infinite,
                Kind::Surface => BdptVertexKind::Surface,
                Kind::Medium => BdptVertexKind::Medium,
            },
            p: v.p,
            n: v.ng,
            beta: v.beta,
            pdf_fwd: v.pdf_fwd,
            pdf_rev: v.pdf_rev,
            delta: v.delta,
            at_infinity: v.at_infinity,
        }
    }
}

/// One strategy of a recorded sample with a nonzero contribution.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BdptConnection {
    /// Light subpath vertices used.
    pub s: usize,
    /// Camera subpath vertices used.
    pub t: usize,
    /// The camera side of the joint: camera vertex t − 1, or for t = 1 the lens point
    /// sampled.
    pub from: BdptVertex,
    /// The light side: light vertex s − 1, for s = 1 the light point sampled, none for s = 0
    /// (the camera subpath reached an emitter by itself).
    pub to: Option<BdptVertex>,
    /// The power-heuristic weight.
    pub weight: f32,
    /// The weighted contribution: added to the estimate for t ≥ 2, splatted for t = 1.
    pub value: Vec3,
    /// Where a t = 1 contribution splats on the film.
    pub p_film: Option<Vec2>,
}

/// One camera sample's subpaths and strategies ([`Bdpt::record`]).
#[derive(Clone, Debug, Default)]
pub struct BdptSample {
    pub camera: Vec<BdptVertex>,
    pub light: Vec<BdptVertex>,
    /// In the order `li` evaluates them (t outer, s inner).
    pub connections: Vec<BdptConnection>,
    /// What `li` returned: the sum of the t ≥ 2 values.
    pub li: Vec3,
    /// What `li` splatted: the t = 1 values, with their film positions.
    pub splats: Vec<(Vec2, Vec3)>,
}

/// [`Bdpt::record`]'s sink: the joint of the strategy being evaluated, until `li` reports
/// its value; the strategies with a nonzero one.
#[derive(Default)]
struct StrategyLog {
    joint: Option<(usize, usize, BdptVertex, Option<BdptVertex>)>,
    connections: Vec<BdptConnection>,
}

impl StrategySink<Vec3> for StrategyLog {
    fn joint(&mut self, s: usize, t: usize, joint: &Joint, _w: f32) {
        let (from, to) = (BdptVertex::of(joint.pt), joint.qs.map(BdptVertex::of));
        self.joint = Some((s, t, from, to));
    }

    fn add(&mut self, s: usize, t: usize, splat_at: Option<Vec2>, value: Vec3, weight: f32) {
        // Every nonzero contribution was weighted at a joint, told just before.
        let (_, _, from, to) = self
            .joint
            .take()
            .filter(|j| (j.0, j.1) == (s, t))
            .expect("a strategy's contribution comes after its joint");
        self.connections.push(BdptConnection {
            s,
            t,
            from,
            to,
            weight,
            value,
            p_film: splat_at,
        });
    }
}

impl<'a> Bdpt<'a, RgbMode> {
    /// [`Self::li`] for one camera sample, recorded: the subpaths (built in `paths`), every
    /// strategy with a nonzero contribution, the estimate and the splats. Given the sampler
    /// of a render's camera sample, the same numbers as that render's (`li` itself runs).
    pub fn record(
        &self,
        scene: &Scene,
        cray: &CameraRay,
        sampler: &mut impl Samples,
        paths: &mut Subpaths,
    ) -> BdptSample {
        let mut log = StrategyLog::default();
        let mut splats = Vec::new();
        let li = self.li(scene, cray, sampler, paths, &mut splats, &mut log);
        BdptSample {
            camera: paths.camera.iter().map(BdptVertex::of).collect(),
            light: paths.light.iter().map(BdptVertex::of).collect(),
            connections: log.connections,
            li,
            splats,
        }
    }
}
