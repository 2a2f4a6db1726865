//! Integrators: estimate the radiance (or an AOV) arriving along a camera ray.
//!
//! Closed-set dispatch: [`Integrator`] is an enum and `li` matches on it. Each integrator draws
//! its random numbers from the sampler it is handed, so the estimate is a pure function of the
//! sampler's stream.

mod aov;
pub mod bdpt;
mod direct;
pub mod mlt;
pub mod path;
pub mod photon;
pub mod photons;
pub mod ptracer;
pub mod sppm;
pub mod transport;
pub mod volpath;

use self::path::PathConfig;

use crate::camera::CameraRay;
use crate::math::Vec3;
use crate::spectral::lanes::{RgbMode, SpectralMode};
use base::RenderMode;

/// Spectral mode with the built-in sRGB upsampling table.
type Spectral = SpectralMode<'static>;
use crate::sampling::Sampler;
use crate::world::Scene;

/// The integrators this build can run.
#[derive(Clone, Debug)]
pub enum Integrator {
    /// Shading normal at the first hit (world space, components in [-1,1]); 0 on a miss.
    Normals,
    /// Reflectance colour at the first hit; 0 on a miss.
    Albedo,
    /// Distance along the camera ray to the first hit; 0 on a miss.
    Depth,
    /// Fraction of the cosine-weighted hemisphere that is unoccluded within `length`.
    AmbientOcclusion { samples: u32, length: f32 },
    /// Path tracing and its restrictions (Whitted, Nori's variants).
    Path(PathConfig),
    /// Mitsuba's `volpath`: path tracing through participating media.
    VolPath(volpath::VolPathConfig),
    /// Mitsuba's `direct`: `emitter_samples` + `bsdf_samples` combined with MIS.
    Direct {
        emitter_samples: u32,
        bsdf_samples: u32,
    },
    /// Stochastic progressive photon mapping: not an estimator per camera sample, so
    /// the render driver (`render.rs`) runs it as a whole ([`sppm::render`]).
    Sppm(sppm::SppmConfig),
    /// Photon mapping: its maps are traced when the render starts, so
    /// the render driver (`render.rs`) runs it ([`photon::PhotonMapper`]).
    Photon(photon::PhotonConfig),
    /// Light tracing (Mitsuba 3's particle tracer): light paths splatted into the film, run
    /// as a whole by the render driver ([`ptracer::render`]).
    Ptracer(ptracer::PtracerConfig),
    /// Bidirectional path tracing: light-tracing strategies splat into the film, so the
    /// render driver runs it as a whole ([`bdpt::render`]).
    Bdpt(bdpt::BdptConfig),
    /// Metropolis light transport over BDPT ([`mlt::render`]).
    Mlt(mlt::MltConfig),
}

/// An integrator the scene asks for that this build does not have.
#[derive(Clone, Debug, thiserror::Error)]
#[error("integrator '{0}' is not implemented yet")]
pub struct UnsupportedIntegrator(pub String);

impl Integrator {
    pub fn name(&self) -> &'static str {
        match self {
            Integrator::Normals => "normals",
            Integrator::Albedo => "albedo",
            Integrator::Depth => "depth",
            Integrator::AmbientOcclusion { .. } => "ao",
            Integrator::Path(_) => "path",
            Integrator::VolPath(_) => "volpath",
            Integrator::Direct { .. } => "direct",
            Integrator::Sppm(c) => match c.kind {
                sppm::Progressive::Stochastic => "sppm",
                sppm::Progressive::Fixed { .. } => "ppm",
            },
            Integrator::Photon(_) => "photon",
            Integrator::Ptracer(_) => "ptracer",
            Integrator::Bdpt(_) => "bdpt",
            Integrator::Mlt(_) => "mlt",
        }
    }

    /// Whether [`Self::li`] estimates the radiance of one camera sample (every integrator
    /// but the photon-mapping family and the light tracer, which the render driver,
    /// `render.rs`, runs as a whole).
    pub fn per_sample(&self) -> bool {
        !matches!(
            self,
            Integrator::Sppm(_)
                | Integrator::Photon(_)
                | Integrator::Ptracer(_)
                | Integrator::Bdpt(_)
                | Integrator::Mlt(_)
        )
    }

    /// Why `scene` cannot be rendered with this integrator: light paths start only in
    /// emitting media that fill bounded shapes, and cannot reach an orthographic camera.
    pub fn unsupported(&self, scene: &Scene) -> Option<String> {
        if self.per_sample() {
            return None;
        }
        if matches!(
            self,
            Integrator::Ptracer(_) | Integrator::Photon(_) | Integrator::Sppm(_)
        ) && let Err(why) = photons::volume_emitters(scene)
        {
            return Some(format!("{}: {why}", self.name()));
        }
        if let Integrator::Bdpt(cfg) = self
            && cfg.strategy_images.is_some()
            && cfg.max_depth < 0
        {
            return Some(
                "bdpt: per-strategy images need a finite max depth (e.g. --max-depth 6; \
                 pbrt-v4's default maxdepth 5 is 6 edges)"
                    .to_string(),
            );
        }
        if matches!(
            self,
            Integrator::Ptracer(_) | Integrator::Bdpt(_) | Integrator::Mlt(_)
        ) && !scene.camera.supports_importance()
        {
            return Some(format!(
                "{}: light paths cannot be connected to an orthographic camera (use path)",
                self.name()
            ));
        }
        None
    }

    /// The estimate along one camera ray; 0 for an integrator that is not
    /// [`Self::per_sample`] (callers check).
    pub fn li(&self, scene: &Scene, cray: &CameraRay, sampler: &mut Sampler) -> Vec3 {
        match self {
            Integrator::Normals => aov::normals(scene, cray),
            Integrator::Albedo => aov::albedo(scene, cray),
            Integrator::Depth => aov::depth(scene, cray),
            Integrator::AmbientOcclusion { samples, length } => {
                aov::ambient_occlusion(scene, cray, sampler, *samples, *length)
            }
            Integrator::Path(cfg) => match scene.mode {
                RenderMode::Rgb => path::li(scene, cray, sampler, cfg),
                RenderMode::Spectral => path::li_in::<Spectral>(scene, cray, sampler, cfg),
            },
            Integrator::VolPath(cfg) => match scene.mode {
                RenderMode::Rgb => volpath::li(scene, cray, sampler, cfg),
                RenderMode::Spectral => volpath::li_in::<Spectral>(scene, cray, sampler, cfg),
            },
            Integrator::Direct {
                emitter_samples,
                bsdf_samples,
            } => {
                let (e, b) = (*emitter_samples, *bsdf_samples);
                match scene.mode {
                    RenderMode::Rgb => direct::li(scene, cray, sampler, e, b),
                    RenderMode::Spectral => direct::li_in::<Spectral>(scene, cray, sampler, e, b),
                }
            }
            Integrator::Sppm(_)
            | Integrator::Photon(_)
            | Integrator::Ptracer(_)
            | Integrator::Bdpt(_)
            | Integrator::Mlt(_) => Vec3::ZERO,
        }
    }

    /// Estimates for a stream of camera samples: `next` sets the sampler up for the next sample
    /// and returns its tag and camera ray (`None`: no more); `done` receives each estimate with
    /// its tag, not necessarily in order. The path tracer keeps several paths in flight
    /// ([`path::li_batched`]); the others trace one sample at a time with [`Integrator::li`].
    pub fn li_stream<T>(
        &self,
        scene: &Scene,
        template: &Sampler,
        mut next: impl FnMut(&mut Sampler) -> Option<(T, CameraRay)>,
        mut done: impl FnMut(T, Vec3),
    ) {
        if let Integrator::Path(cfg) = self
            && cfg.only_depth.is_none()
        {
            // A separate instantiation for clamping: the default loop is untouched.
            if let Some(max) = cfg.clamp {
                let clamped = |tag, l| done(tag, path::clamp_sample(l, max));
                return match scene.mode {
                    RenderMode::Rgb => {
                        path::li_batched::<_, RgbMode>(scene, cfg, template, next, clamped)
                    }
                    RenderMode::Spectral => {
                        path::li_batched::<_, Spectral>(scene, cfg, template, next, clamped)
                    }
                };
            }
            return match scene.mode {
                RenderMode::Rgb => path::li_batched::<_, RgbMode>(scene, cfg, template, next, done),
                RenderMode::Spectral => {
                    path::li_batched::<_, Spectral>(scene, cfg, template, next, done)
                }
            };
        }
        let mut sampler = template.clone();
        while let Some((tag, cray)) = next(&mut sampler) {
            done(tag, self.li(scene, &cray, &mut sampler));
        }
    }
}
