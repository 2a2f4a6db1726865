//! BDPT's subpaths: a random walk from the camera or from a light, on the transport layer's
//! walker (free flights in media, `null` surfaces crossed), storing a vertex at every
//! surface and medium collision with its forward density and setting the previous vertex's
//! reverse density one step late; Russian roulette from the fifth vertex.

use super::vertex::{Kind, Scattered, Vertex, convert_density, local_dir};
use super::{Bdpt, RR_FROM};
use crate::bsdf::TransportMode;
use crate::camera::CameraRay;
use crate::integrators::transport::{self, Walker, roulette};
use crate::math::Vec3;
use crate::media::Flight;
use crate::sampling::Samples;
use crate::spectral::lanes::{Color, PathMode};
use crate::world::Scene;

/// How a subpath's random walk starts, besides its walker: the throughput and solid-angle
/// density of its first ray, how it transports, and how many vertices the subpath may hold.
pub(super) struct WalkStart<C> {
    pub(super) beta: C,
    pub(super) pdf_dir: f32,
    pub(super) mode: TransportMode,
    pub(super) max_vertices: usize,
}

impl<M: PathMode> Bdpt<'_, M> {
    /// Extend `path` (its last vertex the start) by the walk of walker `w` from `start`; free
    /// flights in media sample the walker's hero lane of `m`, the subpath's colour mode.
    pub(super) fn random_walk(
        &self,
        (mut w, start): (Walker, WalkStart<M::C>),
        scene: &Scene,
        sampler: &mut impl Samples,
        path: &mut Vec<Vertex<M::C>>,
        m: &M,
    ) {
        let WalkStart {
            mut beta,
            mut pdf_dir,
            mode,
            max_vertices,
        } = start;
        let mut ratio = M::C::ONE;
        // The free-flight factor since the last vertex, in the hero lane and in every lane
        // relative to it.
        let mut seg = 1.0f32;
        let mut seg_lanes = M::C::ONE;
        // The product of relative indices of refraction crossed (Russian roulette).
        let mut eta = 1.0f32;
        // Bounded: null crossings add no vertex.
        for _ in 0..(1 << 16) {
            if path.len() >= max_vertices {
                return;
            }
            let sigma_lanes = w.medium.and_then(|_| self.flight_sigma(scene, w.medium, m));
            let sigma = sigma_lanes.map(|s| s.lane(w.hero));
            let ahead = w.ahead(scene);
            let (weight, r) = match w.fly(scene, &ahead, sampler, m) {
                Flight::Scatter {
                    d,
                    weight,
                    ratio: r,
                    emit,
                } => {
                    let p = w.ray.at(d);
                    let med = w.medium(scene).expect("collisions happen in media");
                    // An emitting medium's light, by the collision estimator (as
                    // `volpath`'s), with the throughput before the collision.
                    let emitted = match &med.emission {
                        Some(e) if mode == TransportMode::Radiance => {
                            beta * emit * e.radiance_in(p, m)
                        }
                        _ => M::C::ZERO,
                    };
                    beta *= weight;
                    ratio *= r;
                    let prev = path.last().expect("a subpath has a start");
                    let mut v = Vertex::new(Kind::Medium, p, beta);
                    v.medium = w.medium;
                    v.ratio = ratio;
                    v.phase = med.phase.clone();
                    v.le = emitted;
                    v.terminated = m.terminated();
                    v.to_prev = -w.ray.d;
                    if let (Some(s), Some(sl)) = (sigma, sigma_lanes) {
                        v.seg = seg * (-s * d).exp();
                        v.seg_lanes = seg_lanes * ((M::C::splat(s) - sl) * d).exp();
                        v.sigma = s;
                    }
                    v.pdf_fwd = convert_density(pdf_dir, prev, &v) * v.seg * v.sigma;
                    let n = path.len() + 1;
                    let Some(sc) = Self::scatter_medium(&v, (n, eta), max_vertices, sampler, m)
                    else {
                        path.push(v);
                        return;
                    };
                    // The phase function is symmetric: the reverse density is the same.
                    path[n - 2].pdf_rev =
                        convert_density(sc.pdf_rev, &v, prev) * v.seg * prev.sigma;
                    seg = 1.0;
                    seg_lanes = M::C::ONE;
                    w.scatter(v.p, sc.wi);
                    beta = sc.beta;
                    eta = sc.eta;
                    pdf_dir = sc.pdf_dir;
                    path.push(v);
                    continue;
                }
                Flight::Pass { weight, ratio } => (weight, ratio),
            };
            beta *= weight;
            ratio *= r;
            if let (Some(s), Some(sl)) = (sigma, sigma_lanes) {
                seg *= (-s * ahead.end).exp();
                seg_lanes *= ((M::C::splat(s) - sl) * ahead.end).exp();
            }
            let si = w.surface(scene, ahead);
            if let Some(si) = &si
                && scene.is_null(si)
            {
                w.cross(scene, si);
                continue;
            }
            let Some(si) = si else {
                if mode == TransportMode::Radiance {
                    let prev = path.last().expect("a subpath has a start");
                    let mut v = Vertex::new(Kind::Infinite, prev.p + w.ray.d, beta);
                    v.le = transport::environment(scene, w.ray.d, m, M::C::ONE, |_, _| 1.0);
                    v.ratio = ratio;
                    v.terminated = m.terminated();
                    v.seg = seg;
                    v.seg_lanes = seg_lanes;
                    v.pdf_fwd = pdf_dir * seg;
                    path.push(v);
                }
                return;
            };
            // The BSDF first: a dispersive one may terminate the secondary wavelengths, which
            // the vertex's emission and flag then see.
            let bsdf = scene.bsdf_at_in(&si, m);
            let prev = path.last().expect("a subpath has a start");
            let mut v = Vertex::new(Kind::Surface, si.p, beta);
            v.ng = si.ng;
            v.medium = w.medium;
            v.ratio = ratio;
            v.terminated = m.terminated();
            if mode == TransportMode::Radiance
                && let Some(l) = scene.shape_light(&si)
            {
                v.le = scene.lights[l as usize].le(scene, &si, m);
            }
            v.seg = seg;
            v.seg_lanes = seg_lanes;
            v.pdf_fwd = convert_density(pdf_dir, prev, &v) * seg;
            v.bsdf = bsdf;
            if let Some((_, frame)) = &v.bsdf {
                v.to_prev = local_dir(frame, v.p, prev.p);
            }
            let wo = si.wo;
            v.si = Some(si);
            // The walk goes on from here unless the path is full, the surface has no BSDF,
            // or sampling or Russian roulette ends it.
            let n = path.len() + 1;
            let scattered = if n < max_vertices {
                Self::scatter(&v, wo, (n, eta), sampler, mode, m)
            } else {
                None
            };
            let Some(sc) = scattered else {
                path.push(v);
                return;
            };
            v.delta = sc.delta;
            // The reverse density of the previous vertex: from this one back to it.
            let prev = path.last().expect("a subpath has a start");
            let rev = convert_density(sc.pdf_rev, &v, prev) * seg * prev.sigma;
            path[n - 2].pdf_rev = rev;
            seg = 1.0;
            seg_lanes = M::C::ONE;
            w.leave(scene, v.si.as_ref().expect("stored above"), sc.wi);
            beta = sc.beta;
            eta = sc.eta;
            pdf_dir = sc.pdf_dir;
            path.push(v);
        }
    }

    /// The direction a walk leaves surface vertex `v` (its `n`th; `eta` the walk's product
    /// of relative indices so far: `(n, eta)`) in by sampling its BSDF, `wo` the world
    /// direction back along the incoming ray; none without a BSDF, if sampling fails,
    /// Russian roulette ends the path or the throughput is left zero or not finite.
    fn scatter(
        v: &Vertex<M::C>,
        wo: Vec3,
        (n, mut eta): (usize, f32),
        sampler: &mut impl Samples,
        mode: TransportMode,
        m: &M,
    ) -> Option<Scattered<M::C>> {
        let (bsdf, frame) = v.bsdf.as_ref()?;
        let wo = frame.to_local(wo);
        let u1 = sampler.next_1d();
        let bs = bsdf.sample(wo, u1, sampler.next_2d(), mode)?;
        // A delta lobe's direction has probability 1 in the discrete measure both ways
        // (Veach's thesis, ch. 10; Mitsuba 0.6), so that the next vertex's area density
        // keeps its geometric factor (pbrt stores 0 and reads it as 1, which drops it).
        let (pdf_dir, pdf_rev) = if bs.delta {
            (1.0, 1.0)
        } else {
            (bs.pdf, bsdf.pdf(bs.wi, wo))
        };
        let beta = v.beta * bs.weight;
        if mode == TransportMode::Radiance {
            eta *= bs.eta;
        }
        Some(Scattered {
            wi: frame.to_world(bs.wi),
            beta: Self::roulette(beta, v.ratio, eta, n, sampler, m)?,
            eta,
            pdf_dir,
            pdf_rev,
            delta: bs.delta,
        })
    }

    /// The direction a walk leaves medium vertex `v` (its `n`th, the walk's product of
    /// relative indices `eta`) in, by sampling its phase function; none once the path is
    /// full or Russian roulette ends it.
    fn scatter_medium(
        v: &Vertex<M::C>,
        (n, eta): (usize, f32),
        max_vertices: usize,
        sampler: &mut impl Samples,
        m: &M,
    ) -> Option<Scattered<M::C>> {
        if n >= max_vertices {
            return None;
        }
        let (wi, pdf) = v.phase.sample(v.to_prev, sampler.next_2d());
        Some(Scattered {
            wi,
            beta: Self::roulette(v.beta, v.ratio, eta, n, sampler, m)?,
            eta,
            pdf_dir: pdf,
            pdf_rev: pdf,
            delta: false,
        })
    }

    /// Russian roulette (the transport layer's throughput rule) on the throughput `beta`
    /// leaving the `n`th vertex, by its effective value (β over the mean channel density
    /// ratio, in the lanes that still count) and the walk's product of relative indices
    /// `eta`: the survivor's throughput, or none. A camera subpath's `eta` is pbrt-v4's
    /// `etaScale` (radiance is scaled by 1/η² entering glass and back leaving it: inside a
    /// dense glass β alone would end most paths that leave it again); light subpaths'
    /// importance has no such factor: 1.
    fn roulette(
        mut beta: M::C,
        ratio: M::C,
        eta: f32,
        n: usize,
        sampler: &mut impl Samples,
        m: &M,
    ) -> Option<M::C> {
        if n >= RR_FROM {
            let q = roulette::throughput(m.live_max(beta * m.hero_weight(ratio)), eta);
            if !roulette::survive(&mut beta, q, sampler.next_1d()) {
                return None;
            }
        }
        (!beta.is_black() && beta.is_finite()).then_some(beta)
    }

    /// The camera subpath of at most `max_vertices` vertices (the camera's included), free
    /// flights in lane `hero`.
    pub(super) fn camera_subpath(
        &self,
        scene: &Scene,
        cray: &CameraRay,
        (hero, max_vertices): (usize, usize),
        sampler: &mut impl Samples,
        path: &mut Vec<Vertex<M::C>>,
        m: &M,
    ) {
        let mut v = Vertex::new(Kind::Camera, cray.lens, M::C::ONE);
        v.medium = scene.camera_medium;
        path.push(v);
        let (_, pdf_dir) = scene.camera.pdf_we(cray.ray.d.normalize());
        let start = WalkStart {
            beta: M::C::ONE,
            pdf_dir,
            mode: TransportMode::Radiance,
            max_vertices,
        };
        let w = Walker::camera(scene, cray, hero);
        self.random_walk((w, start), scene, sampler, path, m);
    }

    /// The light subpath of at most `max_vertices` vertices (the light's included), free
    /// flights in lane `hero`.
    pub(super) fn light_subpath(
        &self,
        scene: &Scene,
        (hero, max_vertices): (usize, usize),
        sampler: &mut impl Samples,
        path: &mut Vec<Vertex<M::C>>,
        m: &M,
    ) {
        let (li, pmf, _) = self.dist.sample_discrete(sampler.next_1d());
        let (u_pos, u_dir) = (sampler.next_2d(), sampler.next_2d());
        if !self.any || pmf.is_nan() || pmf <= 0.0 || max_vertices == 0 {
            return;
        }
        let light = &scene.lights[li];
        let Some(e) = light.sample_le(scene, u_pos, u_dir, m) else {
            return;
        };
        if e.pdf_pos <= 0.0 || e.pdf_dir <= 0.0 {
            return;
        }
        let mut v = Vertex::new(Kind::Light(li as u32), e.p, M::C::ZERO);
        v.ng = e.n;
        v.medium = scene.light_media.get(li).copied().flatten();
        let infinite = light.is_infinite();
        v.at_infinity = infinite;
        v.pdf_fwd = if infinite {
            0.0 // set below, once the direction density of every infinite light is known
        } else {
            pmf * e.pdf_pos
        };
        let w = Walker::new(e.ray, f32::INFINITY, v.medium, hero);
        let start = WalkStart {
            beta: e.weight / pmf,
            pdf_dir: e.pdf_dir,
            mode: TransportMode::Importance,
            max_vertices,
        };
        path.push(v);
        self.random_walk((w, start), scene, sampler, path, m);
        if infinite {
            // pbrt: the first surface's density is the disk's, times its cosine; the
            // light vertex's that of the direction (every infinite light's).
            if path.len() > 1 {
                let next = &path[1];
                let mut pdf = e.pdf_pos;
                if next.on_surface() {
                    pdf *= next.ng.dot(e.ray.d).abs();
                }
                path[1].pdf_fwd = pdf * next.seg * next.sigma;
            }
            let (p, ng) = (path[0].p, path[0].ng);
            path[0].pdf_fwd = scene
                .infinite_lights
                .iter()
                .map(|&i| {
                    let (_, dir) = scene.lights[i as usize].pdf_le(scene, p, ng, e.ray.d);
                    self.dist.pmf(i as usize) * dir
                })
                .sum();
        }
    }
}
