//! Integrators: twelve ways of estimating the light that reaches the camera, each a thin
//! policy over the transport layer (`transport/`: the walk, the shadow query, next-event
//! estimation's parts, the emission rule, MIS and roulette) and driven by the loops of
//! `crate::drive`.
//!
//! Every integrator implements [`IntegratorModel`]: its name, why a scene is beyond it, what
//! it keeps besides the film, and its render in a colour mode `M` (RGB or spectral, chosen
//! once, at the top: `render::render`). Those that estimate each camera sample on their own
//! (the AOVs, `path`, `volpath`, `direct`) are also a [`crate::drive::Estimator`] and render
//! through the tile loop; the light-path integrators (SPPM/PPM, the photon mapper, light
//! tracing, BDPT, MLT) run their own passes, iterations or chains through the drive's loops.
//! [`Integrator`] is the closed set the scene asks for, dispatched by one macro.

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

pub use self::aov::Aov;
pub use self::direct::DirectConfig;

use self::path::PathConfig;
use crate::camera::CameraRay;
use crate::drive::{self, Estimator, adaptive};
use crate::math::Vec3;
use crate::sampling::Sampler;
use crate::session::{Job, RenderOptions, RenderOutcome};
use crate::spectral::lanes::PathMode;
use crate::world::Scene;

/// What every integrator is.
pub trait IntegratorModel: Sync {
    /// The name the command line and messages use.
    fn name(&self) -> &'static str;

    /// Why `scene` cannot be rendered with this integrator (`None`: it can).
    fn unsupported(&self, _scene: &Scene) -> Option<String> {
        None
    }

    /// What the integrator keeps besides the film (photon maps, visible points, one image
    /// per strategy), with what it is called, and its peak bytes.
    fn memory(&self, _scene: &Scene) -> Option<(&'static str, u64)> {
        None
    }

    /// Render `scene`, its paths in the colour mode `M`.
    fn render<M: PathMode + Send>(&self, job: &Job) -> RenderOutcome;

    /// The number of work items of a render of `scene` with `opts` (`drive/work.rs`: what
    /// shards and checkpoints split it at), or why it cannot be split.
    fn work_items(&self, _scene: &Scene, _opts: &RenderOptions) -> Result<u64, String> {
        Err(format!(
            "the {} integrator cannot be split into shards or resumed from a checkpoint \
             (its passes build on each other's state); render it in one process",
            self.name()
        ))
    }
}

/// The integrators this build can run.
#[derive(Clone, Debug)]
pub enum Integrator {
    /// Arbitrary output variables: normals, albedo, depth, ambient occlusion.
    Aov(Aov),
    /// Path tracing and its restrictions (Whitted, Nori's and the courses' variants).
    Path(PathConfig),
    /// Mitsuba's `volpath`: path tracing through participating media.
    VolPath(volpath::VolPathConfig),
    /// Mitsuba's `direct`: emitter and BSDF samples combined with MIS.
    Direct(DirectConfig),
    /// Stochastic progressive photon mapping (and PPM).
    Sppm(sppm::SppmConfig),
    /// Photon mapping.
    Photon(photon::PhotonConfig),
    /// Light tracing (Mitsuba 3's particle tracer).
    Ptracer(ptracer::PtracerConfig),
    /// Bidirectional path tracing.
    Bdpt(bdpt::BdptConfig),
    /// Metropolis light transport over BDPT.
    Mlt(mlt::MltConfig),
}

/// An integrator the scene asks for that this build does not have.
#[derive(Clone, Debug, thiserror::Error)]
#[error("integrator '{0}' is not implemented yet")]
pub struct UnsupportedIntegrator(pub String);

/// `$e` with `$i` bound to the integrator inside `$s`, whichever it is.
macro_rules! dispatch {
    ($s:expr, $i:ident => $e:expr) => {
        dispatch!(@ $s, $i, $e; Aov Path VolPath Direct Sppm Photon Ptracer Bdpt Mlt; )
    };
    (@ $s:expr, $i:ident, $e:expr; $($v:ident)*; $($n:ident)*) => {
        match $s {
            $(Integrator::$v($i) => $e,)*
            $(Integrator::$n(_) => None,)*
        }
    };
}

/// `Some($e)` with `$i` bound to the per-sample estimator inside `$s`; `None` for the
/// integrators that are not one.
macro_rules! per_sample {
    ($s:expr, $i:ident => $e:expr) => {
        dispatch!(@ $s, $i, Some($e); Aov Path VolPath Direct; Sppm Photon Ptracer Bdpt Mlt)
    };
}

impl Integrator {
    pub fn name(&self) -> &'static str {
        dispatch!(self, i => i.name())
    }

    /// See [`IntegratorModel::unsupported`].
    pub fn unsupported(&self, scene: &Scene) -> Option<String> {
        dispatch!(self, i => i.unsupported(scene))
    }

    /// See [`IntegratorModel::work_items`].
    pub fn work_items(&self, scene: &Scene, opts: &RenderOptions) -> Result<u64, String> {
        dispatch!(self, i => i.work_items(scene, opts))
    }

    /// See [`IntegratorModel::memory`].
    pub fn memory(&self, scene: &Scene) -> Option<(&'static str, u64)> {
        dispatch!(self, i => i.memory(scene))
    }

    /// Whether the integrator estimates each camera sample on its own (what adaptive
    /// sampling and Nori's statistical tests need).
    pub fn per_sample(&self) -> bool {
        per_sample!(self, _i => ()).is_some()
    }

    /// Render in the colour mode `M` (`render::render` picks it, once).
    pub fn render_in<M: PathMode + Send>(&self, job: &Job) -> RenderOutcome {
        dispatch!(self, i => i.render::<M>(job))
    }

    /// One camera sample's estimate in the colour mode `M` (`None`: not a per-sample
    /// integrator).
    pub fn li_in<M: PathMode>(
        &self,
        scene: &Scene,
        cray: &CameraRay,
        sampler: &mut Sampler,
    ) -> Option<Vec3> {
        per_sample!(self, i => Estimator::<M>::li(i, scene, cray, sampler))
    }

    /// A stream of camera samples' estimates in the colour mode `M` (see
    /// [`Estimator::li_stream`]); `false` when the integrator is not a per-sample one.
    pub fn li_stream_in<M: PathMode, T>(
        &self,
        scene: &Scene,
        template: &Sampler,
        next: impl FnMut(&mut Sampler) -> Option<(T, CameraRay)>,
        done: impl FnMut(T, Vec3),
    ) -> bool {
        per_sample!(self, i => Estimator::<M>::li_stream(i, scene, template, next, done)).is_some()
    }

    /// Adaptive sampling in the colour mode `M` (`None`: not a per-sample integrator).
    pub fn render_adaptive_in<M: PathMode>(
        &self,
        job: &Job,
        settings: &adaptive::AdaptiveSettings,
    ) -> Option<adaptive::AdaptiveOutcome> {
        per_sample!(self, i => adaptive::render_adaptive::<M, _>(job, i, settings))
    }
}

/// A per-sample estimator `$t` named `$name` as an integrator: rendered by the tile loop
/// ([`drive::render_tiles`]).
macro_rules! per_sample_model {
    ($t:ty, $name:expr) => {
        impl IntegratorModel for $t {
            fn name(&self) -> &'static str {
                $name
            }

            fn render<M: PathMode + Send>(&self, job: &Job) -> RenderOutcome {
                drive::render_tiles::<M, Self>(job, self)
            }

            fn work_items(&self, scene: &Scene, opts: &RenderOptions) -> Result<u64, String> {
                Ok(drive::TileWork::new(scene, opts).len())
            }
        }
    };
}

impl IntegratorModel for PathConfig {
    fn name(&self) -> &'static str {
        "path"
    }

    /// The tile loop; with guiding, in training phases (`path/guided.rs`), and a line on the
    /// SD-tree's memory for the user.
    fn render<M: PathMode + Send>(&self, job: &Job) -> RenderOutcome {
        match &self.guiding {
            None => drive::render_tiles::<M, Self>(job, self),
            Some(g) => {
                let (outcome, stats) = path::guided::render::<M>(job, self, g);
                job.observer.note(&format!(
                    "path guiding: {} spatial leaves, {} directional nodes, {:.1} MB of {:.1} MB{}",
                    stats.leaves,
                    stats.directional_nodes,
                    stats.bytes as f64 / (1u64 << 20) as f64,
                    g.max_bytes as f64 / (1u64 << 20) as f64,
                    if stats.capped { " (capped)" } else { "" }
                ));
                outcome
            }
        }
    }

    fn work_items(&self, scene: &Scene, opts: &RenderOptions) -> Result<u64, String> {
        if self.guiding.is_some() {
            return Err(
                "a guided render (--guiding on) cannot be split into shards or \
                        resumed from a checkpoint (each training phase learns from the ones \
                        before); render it in one process"
                    .into(),
            );
        }
        Ok(drive::TileWork::new(scene, opts).len())
    }
}
per_sample_model!(volpath::VolPathConfig, "volpath");
per_sample_model!(DirectConfig, "direct");

/// Why light paths cannot be connected to the camera (an orthographic one), for the
/// integrators that connect them.
fn camera_unsupported(name: &str, scene: &Scene) -> Option<String> {
    (!scene.camera.supports_importance()).then(|| {
        format!("{name}: light paths cannot be connected to an orthographic camera (use path)")
    })
}

/// Why light paths cannot start in the scene's emitting media (see
/// [`photons::volume_emitters`]), for the integrators that trace photons.
fn volume_unsupported(name: &str, scene: &Scene) -> Option<String> {
    photons::volume_emitters(scene)
        .err()
        .map(|why| format!("{name}: {why}"))
}
