//! The camera side of the photon-mapping family: a walk from the camera (or from a gathering
//! point) through delta bounces to the first vertex that is not one — a surface with a
//! non-delta lobe, or a collision in a medium — where the integrator makes its estimates
//! ([`CameraWalk`]); and the one next-event estimate SPPM and the photon mapper make there
//! ([`next_event`]).

use crate::bsdf::TransportMode;
use crate::camera::CameraRay;
use crate::integrators::transport::{self, Connection, Event, From, Scatterer, Walker, roulette};
use crate::lights::Receiver;
use crate::math::Vec3;
use crate::media::{Flight, Medium};
use crate::sampling::Sampler;
use crate::shapes::SurfaceInteraction;
use crate::spectral::lanes::{Color, PathMode};
use crate::world::Scene;

/// What a camera-side walk hands its caller where it stops being a chain of delta bounces:
/// a surface with a non-delta lobe, or a collision in a medium.
pub struct Vertex<'a, C: Color> {
    /// What scatters there.
    pub at: Scatterer<'a, C>,
    /// The surface (`None` at a collision in a medium).
    pub si: Option<&'a SurfaceInteraction>,
    pub p: Vec3,
    /// The medium the walk is in there (at a surface, the one it arrived through).
    pub medium: Option<u32>,
    /// Edges from the walk's start (camera or gathering point) counted from
    /// [`CameraWalk::depth`].
    pub depth: u32,
    /// The walk's throughput up to here, with its spectral-MIS weight.
    pub beta: C,
    /// The path's time (motion blur).
    pub time: f32,
    /// The lane the walk's free flights are sampled in.
    pub hero: usize,
}

impl<'a, C: Color> Vertex<'a, C> {
    /// The vertex where walker `w` met the surface `si` that scatters by `at`, `depth` edges
    /// from its start, with throughput `beta`.
    pub fn surface(
        at: Scatterer<'a, C>,
        si: &'a SurfaceInteraction,
        w: &Walker,
        depth: u32,
        beta: C,
    ) -> Self {
        Vertex {
            at,
            si: Some(si),
            p: si.p,
            medium: w.medium,
            depth,
            beta,
            time: si.time,
            hero: w.hero,
        }
    }

    /// The vertex where walker `w` collided at `p` in its medium (scattering by `at`).
    pub fn collision(at: Scatterer<'a, C>, p: Vec3, w: &Walker, depth: u32, beta: C) -> Self {
        Vertex {
            at,
            si: None,
            p,
            medium: w.medium,
            depth,
            beta,
            time: w.ray.time,
            hero: w.hero,
        }
    }
}

/// A segment of a camera-side walk through a medium, before its free flight is sampled.
pub struct Segment<'a, C> {
    pub walker: &'a Walker,
    pub medium: &'a Medium,
    /// The distance to the surface ahead.
    pub end: f32,
    /// Edges before the segment.
    pub depth: u32,
    /// The walk's throughput at the segment's start, with its spectral-MIS weight.
    pub beta: C,
}

/// What a camera-side walk's owner does on the way: its estimates at the vertex where the
/// walk stops being a delta chain (times the throughput there, which the walk applies), and
/// optionally its own estimate of a medium segment in place of a free flight: the weight the
/// walk crosses the segment with and the radiance the estimate adds (`None`: sample a free
/// flight).
pub trait Visit<M: PathMode> {
    fn vertex(&mut self, v: &Vertex<M::C>, sampler: &mut Sampler) -> M::C;

    fn segment(&mut self, _seg: &Segment<M::C>, _sampler: &mut Sampler) -> Option<(M::C, M::C)> {
        None
    }
}

impl<M: PathMode, F: FnMut(&Vertex<M::C>, &mut Sampler) -> M::C> Visit<M> for F {
    fn vertex(&mut self, v: &Vertex<M::C>, sampler: &mut Sampler) -> M::C {
        self(v, sampler)
    }
}

/// The rules of a camera-side walk: edges already made before its ray, which emission it
/// sees, the longest path (−1: unbounded) and the depth from which Russian roulette plays on
/// the throughput.
#[derive(Clone, Copy)]
pub struct CameraWalk {
    pub depth: u32,
    /// Emitting surfaces and the environment met through delta bounces (a camera path;
    /// a final gathering ray leaves them to next-event estimation).
    pub see_emitters: bool,
    /// Emitting media, by the collision the walk stops at (their light is no light
    /// sample's: every walk sees it).
    pub see_media: bool,
    pub max_depth: i32,
    pub rr_depth: u32,
}

impl CameraWalk {
    fn allows(&self, edges: u32) -> bool {
        self.max_depth < 0 || edges <= self.max_depth as u32
    }

    /// The walker of a camera ray: in scenes with media its direction is made a unit vector
    /// and a hero lane drawn for free flights; without, the ray is taken as it is and nothing
    /// is drawn.
    pub fn camera_walker<M: PathMode>(
        scene: &Scene,
        cray: &CameraRay,
        m: &M,
        sampler: &mut Sampler,
    ) -> Walker {
        if scene.media.is_empty() {
            Walker::new(cray.ray, cray.t_max, None, 0)
        } else {
            Walker::camera(scene, cray, m.hero(sampler.next_1d()))
        }
    }

    /// Follow walker `w` (throughput `beta`) through delta bounces: emission met along the way
    /// counts as `see_emitters` and `see_media` say; at the vertex where the walk stops being a delta chain
    /// `visit` adds its estimate (times the throughput there) — at a surface whose BSDF also
    /// has delta lobes the walk goes on when one is sampled, with Russian roulette. Returns
    /// the emission and estimates, in the mode's colour.
    pub fn run<M: PathMode>(
        &self,
        scene: &Scene,
        mut w: Walker,
        mut beta: M::C,
        m: &M,
        sampler: &mut Sampler,
        visit: &mut impl Visit<M>,
    ) -> M::C {
        let mut depth = self.depth;
        let mut ratio = M::C::ONE;
        let power = |beta: M::C, ratio: M::C| beta * m.hero_weight(ratio);
        let mut l = M::C::ZERO;
        // Bounded: null crossings add no edge.
        for _ in 0..(1 << 16) {
            let ahead = w.ahead(scene);
            let own = w.medium(scene).and_then(|medium| {
                let seg = Segment {
                    walker: &w,
                    medium,
                    end: ahead.end,
                    depth,
                    beta: power(beta, ratio),
                };
                visit.segment(&seg, sampler)
            });
            let flight = match own {
                Some((weight, radiance)) => {
                    l += radiance;
                    Flight::Pass {
                        weight,
                        ratio: M::C::ONE,
                    }
                }
                None => w.fly(scene, &ahead, sampler, m),
            };
            let event = w.event(scene, ahead, flight);
            let (si, pass) = match event {
                Event::Collision {
                    p,
                    weight,
                    ratio: r,
                    emit,
                    ..
                } => {
                    depth += 1;
                    ratio *= r;
                    let med = w.medium(scene).expect("collisions happen in media");
                    if self.see_media
                        && let Some(e) = &med.emission
                    {
                        l += power(beta, ratio) * emit * e.radiance_in(p, m);
                    }
                    beta *= weight;
                    let at = Scatterer::Medium {
                        phase: &med.phase,
                        wo: -w.ray.d,
                    };
                    let v = Vertex::collision(at, p, &w, depth, power(beta, ratio));
                    l += v.beta * visit.vertex(&v, sampler);
                    break;
                }
                Event::Escape(pass) => {
                    pass.apply(&mut beta, &mut ratio);
                    if self.see_emitters {
                        let env = transport::environment(
                            scene,
                            w.ray.d,
                            m,
                            power(beta, ratio),
                            |_, _| 1.0,
                        );
                        l += env;
                    }
                    break;
                }
                Event::Null(si, pass) => {
                    pass.apply(&mut beta, &mut ratio);
                    if self.see_emitters
                        && let Some((_, le)) = transport::emitter_hit(scene, &si, m)
                    {
                        l += power(beta, ratio) * le;
                    }
                    w.cross(scene, &si);
                    continue;
                }
                Event::Surface(si, pass) => (si, pass),
            };
            pass.apply(&mut beta, &mut ratio);
            depth += 1;
            if self.see_emitters
                && let Some((_, le)) = transport::emitter_hit(scene, &si, m)
            {
                l += power(beta, ratio) * le;
            }
            // A surface that does not scatter absorbs (an emitter without a BSDF).
            let Some((bsdf, frame)) = scene.bsdf_at_in(&si, m) else {
                break;
            };
            let wo = frame.to_local(si.wo);
            if bsdf.has_smooth() {
                let at = Scatterer::surface(&bsdf, &frame, wo);
                let v = Vertex::surface(at, &si, &w, depth, power(beta, ratio));
                l += v.beta * visit.vertex(&v, sampler);
            }
            if !self.allows(depth + 1) {
                break;
            }
            let u1 = sampler.next_1d();
            let Some(bs) = bsdf.sample(wo, u1, sampler.next_2d(), TransportMode::Radiance) else {
                break;
            };
            if !bs.delta {
                break;
            }
            beta *= bs.weight;
            if depth >= self.rr_depth {
                let q = roulette::throughput(m.live_max(power(beta, ratio)), 1.0);
                if !roulette::survive(&mut beta, q, sampler.next_1d()) {
                    break;
                }
            }
            let b = m.live_max(power(beta, ratio));
            if b <= 0.0 || !b.is_finite() {
                break;
            }
            w.leave(scene, &si, frame.to_world(bs.wi));
        }
        l
    }
}

/// One light sample at a camera vertex (light sampling only, as pbrt-v4's SPPM; the photon
/// maps hold the rest): f·Li·Tr / (p·pmf), the connection's transmittance through media
/// and `null` surfaces by the shadow query.
pub fn next_event<M: PathMode>(
    scene: &Scene,
    v: &Vertex<M::C>,
    sampler: &mut Sampler,
    m: &M,
) -> M::C {
    let (receiver, from) = match v.si {
        Some(si) => (Receiver::from(si), From::Surface(si)),
        None => (Receiver::at(v.p), From::Medium(v.p, v.time)),
    };
    let Some(e) = transport::sample_emitter(scene, &receiver, sampler, m) else {
        return M::C::ZERO;
    };
    let ls = &e.ls;
    let f = v.at.eval(ls.wi, TransportMode::Radiance);
    if f.is_black() {
        return M::C::ZERO;
    }
    let c = Connection {
        from,
        wi: ls.wi,
        target: ls.target,
        medium: v.medium,
    };
    let tr = transport::transmittance(
        scene,
        &c,
        base::TransmittanceEstimator::default(),
        sampler,
        m,
    );
    if tr.is_black() {
        return M::C::ZERO;
    }
    f * ls.li / (ls.pdf * e.pmf) * tr
}
