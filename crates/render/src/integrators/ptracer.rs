//! Light tracing (Mitsuba 3's `ptracer`, the particle tracer; the t = 1 strategies of
//! bidirectional path tracing): paths start at the lights and every vertex they reach on a
//! surface with a non-delta lobe, or in a medium, is connected to the camera's lens
//! ([`Camera::sample_wi`]) and splatted into the film where the connection lands.
//!
//! Each of the `--spp` passes traces one light path per pixel of the full image (the
//! photon tracer, [`photons::trace_all`]: lights chosen by power, importance transport,
//! pbrt-v4's roulette, free flights in media), and the film develops its splats divided by
//! the number of passes (see `film::accum`). A vertex x with throughput β, reached from
//! direction ωₗ, adds
//!
//! β · f(ωₗ → ω_c) · |cos θ_c| · Tr(x ↔ lens) · We·|cos θ_lens| / (d² · p_lens)
//!
//! (f in importance mode, the phase function in a medium) at the film position of the
//! connection ω_c. Emitters seen directly come from the camera side: one camera ray per
//! pixel and pass, which adds the emission (or environment) it meets first, through media
//! and null surfaces (unless `hide_emitters`). Surfaces seen only through delta bounces (a
//! mirror, glass) are out of reach of both: no light path reaches a pinhole through a
//! delta bounce, so this integrator does not render them (use `bdpt` or `path`).
//! Orthographic cameras cannot be connected to.
//!
//! `max_depth` counts edges camera to light as everywhere: a vertex `k` edges from the
//! light makes a path of k + 1. Determinism: light path `j` of pass `p` draws from its own
//! stream (its lens samples and transmittance estimates too), and splats are added to the
//! film in chunk order: the image does not depend on the thread count.
//!
//! Spectral mode: light path `j` of pass `p` carries its own wavelengths (a rank-1 lattice
//! over the paths, [`photons::wavelength_set`]), each splat converted with them.

use std::time::Instant;

use super::photons::{self, CameraWalk, PhotonHit, PhotonJob, PhotonLights};
use super::transport::{Connection, From, transmittance};
use super::{IntegratorModel, camera_unsupported, volume_unsupported};
use crate::bsdf::TransportMode;
use crate::camera::CameraRay;
use crate::drive::{self, run_passes};
use crate::lights::ShadowTarget;
use crate::math::{UVec2, Vec2, Vec3};
use crate::sampling::Sampler;
use crate::session::{Job, RenderOutcome, camera_sample};
use crate::spectral::lanes::{Color, PathMode};
use crate::world::Scene;
use base::TransmittanceEstimator;

/// The parameters of the light tracer.
#[derive(Clone, Debug, PartialEq)]
pub struct PtracerConfig {
    /// Longest path in edges, camera to light (−1: unbounded).
    pub max_depth: i32,
    /// Leave out the emitters the camera sees directly.
    pub hide_emitters: bool,
}

impl Default for PtracerConfig {
    fn default() -> Self {
        PtracerConfig {
            max_depth: -1,
            hide_emitters: false,
        }
    }
}

impl IntegratorModel for PtracerConfig {
    fn name(&self) -> &'static str {
        "ptracer"
    }

    fn unsupported(&self, scene: &Scene) -> Option<String> {
        volume_unsupported(self.name(), scene).or_else(|| camera_unsupported(self.name(), scene))
    }

    /// `opts.spp` passes (a time budget or cancellation stops after a whole pass).
    fn render<M: PathMode + Send>(&self, job: &Job) -> RenderOutcome {
        render_in::<M>(job, self)
    }
}

fn render_in<M: PathMode>(job: &Job, cfg: &PtracerConfig) -> RenderOutcome {
    let start = Instant::now();
    let (scene, f) = (job.scene, &job.scene.film);
    let (mut film, template) = job.film_and_sampler();
    let (pmin, pmax) = film.pixel_bounds();
    let pixel_count = film.pixel_count();
    // The camera's importance is normalised over the full image: one light path per pixel
    // of it makes one pass.
    let paths = f.width as u64 * f.height as u64;
    let lights = PhotonLights::new(scene);
    let seed = scene.sampler.seed;
    let (done, cancelled) = run_passes(job, start, pixel_count, |pass| {
        // 1. Emitters seen directly: one camera ray per pixel, rows in parallel, merged in
        // row order.
        drive::rows(
            &mut film,
            pmin.y..pmax.y,
            |y, tile| {
                let mut sampler = template.clone();
                for x in pmin.x..pmax.x {
                    let (p_film, cray) = camera_sample(scene, &mut sampler, UVec2::new(x, y), pass);
                    let m = M::start(&mut sampler);
                    let l = if cfg.hide_emitters {
                        M::C::ZERO
                    } else {
                        seen_emission(scene, &cray, &mut sampler, &m)
                    };
                    tile.add_sample(p_film, m.to_rgb(l));
                }
            },
            |_, ()| {},
        );
        // 2. Light paths, their splats added in chunk order.
        if lights.any() {
            let job = PhotonJob {
                lights: &lights,
                max_depth: cfg.max_depth,
                seed,
            };
            let lists = photons::trace_all(
                scene,
                &job,
                (pass, paths),
                |j| M::from_u(photons::wavelength_set(seed, pass as u64 * paths + j)),
                Vec::new,
                |out: &mut Vec<(Vec2, Vec3)>, hit, m: &M, sampler: &mut Sampler| {
                    if let Some(s) = connect(scene, cfg, hit, m, sampler) {
                        out.push(s);
                    }
                },
            );
            for list in lists {
                for (p, l) in list {
                    film.add_splat(p, l);
                }
            }
        }
        film.set_splat_scale(1.0 / (pass + 1) as f64);
        job.observer.pass_done(&film, pass + 1);
    });
    RenderOutcome::of_passes(film, done, start, cancelled)
}

/// The emission a camera ray meets without scattering: an emitter's surface or the
/// environment at the end of its free flights through media (attenuated by them; `null`
/// surfaces let it through), or a medium's own emission at the collision that ends it (the
/// collision estimator, as `volpath`'s). Light scattered on the way is the light paths'.
fn seen_emission<M: PathMode>(
    scene: &Scene,
    cray: &CameraRay,
    sampler: &mut Sampler,
    m: &M,
) -> M::C {
    let w = CameraWalk::camera_walker(scene, cray, m, sampler);
    let walk = CameraWalk {
        depth: 0,
        see_emitters: true,
        see_media: true,
        max_depth: 1,
        rr_depth: u32::MAX,
    };
    // Nothing is estimated at the first vertex: what it scatters comes from the light paths.
    let mut nothing = |_: &photons::Vertex<M::C>, _: &mut Sampler| M::C::ZERO;
    walk.run(scene, w, M::C::ONE, m, sampler, &mut nothing)
}

/// The splat of light path vertex `hit` connected to the camera: its film position and
/// linear sRGB value, or `None` when the connection is blocked, leaves the film or would
/// make the path longer than `max_depth`.
fn connect<M: PathMode>(
    scene: &Scene,
    cfg: &PtracerConfig,
    hit: &PhotonHit<M::C>,
    m: &M,
    sampler: &mut Sampler,
) -> Option<(Vec2, Vec3)> {
    let v = &hit.v;
    if cfg.max_depth >= 0 && v.depth + 1 > cfg.max_depth as u32 {
        return None;
    }
    let c = scene.camera.sample_wi(v.p, sampler.next_2d())?;
    let f = v.at.eval(c.wi, TransportMode::Importance);
    if f.is_black() {
        return None;
    }
    let from = match v.si {
        Some(si) => From::Surface(si),
        None => From::Medium(v.p, 0.0),
    };
    let query = Connection {
        from,
        wi: c.wi,
        target: ShadowTarget::Point(c.p_lens),
        medium: v.medium,
    };
    let tr = transmittance(scene, &query, TransmittanceEstimator::default(), sampler, m);
    if tr.is_black() {
        return None;
    }
    Some((c.p_film, m.to_rgb(v.beta * f * tr * c.weight)))
}
