//! The top of a render: the colour mode chosen once, as Mitsuba's variant is — every
//! integrator, estimator and loop below runs monomorphised in it ([`in_mode`]) — and the
//! entry points that run an integrator ([`render`], [`render_adaptive`], [`li`]).

use crate::adaptive::{AdaptiveOutcome, AdaptiveSettings};
use crate::camera::CameraRay;
use crate::film::Film;
use crate::integrators::Integrator;
use crate::math::Vec3;
use crate::sampling::Sampler;
use crate::spectral::lanes::{PathMode, RgbMode, SpectralMode};
use crate::world::Scene;
use base::RenderMode;

pub use crate::session::{
    Job, Progress, RenderObserver, RenderOptions, RenderOutcome, Silent, camera_sample,
};

/// Something run in a colour mode: RGB, or spectral with the built-in sRGB upsampling.
pub trait InMode {
    type Out;
    fn run<M: PathMode + Send>(self) -> Self::Out;
}

/// Run `task` in the colour mode `mode`: the one place a mode becomes a type.
pub fn in_mode<T: InMode>(mode: RenderMode, task: T) -> T::Out {
    match mode {
        RenderMode::Rgb => task.run::<RgbMode>(),
        RenderMode::Spectral => task.run::<SpectralMode<'static>>(),
    }
}

/// Peak bytes of the film state a render on the current rayon pool allocates for `scene`
/// (see [`Film::memory_needed`]).
pub fn memory_needed(scene: &Scene, opts: &RenderOptions) -> u64 {
    let f = &scene.film;
    let workers = rayon::current_num_threads();
    Film::memory_needed(
        f.width,
        f.height,
        f.crop,
        &f.filter,
        opts.tile_size,
        workers,
    )
}

/// Render `scene` with `integrator` on the current rayon pool, in the scene's colour mode.
pub fn render(
    scene: &Scene,
    integrator: &Integrator,
    opts: &RenderOptions,
    observer: &dyn RenderObserver,
) -> RenderOutcome {
    struct Task<'a>(&'a Integrator, Job<'a>);
    impl InMode for Task<'_> {
        type Out = RenderOutcome;
        fn run<M: PathMode + Send>(self) -> RenderOutcome {
            self.0.render_in::<M>(&self.1)
        }
    }
    let job = Job {
        scene,
        opts,
        observer,
    };
    in_mode(scene.mode, Task(integrator, job))
}

/// CS184's adaptive sampling of `scene` with a per-sample `integrator` (`None` for the
/// others), in the scene's colour mode.
pub fn render_adaptive(
    scene: &Scene,
    integrator: &Integrator,
    opts: &RenderOptions,
    settings: &AdaptiveSettings,
    observer: &dyn RenderObserver,
) -> Option<AdaptiveOutcome> {
    struct Task<'a>(&'a Integrator, Job<'a>, &'a AdaptiveSettings);
    impl InMode for Task<'_> {
        type Out = Option<AdaptiveOutcome>;
        fn run<M: PathMode + Send>(self) -> Option<AdaptiveOutcome> {
            self.0.render_adaptive_in::<M>(&self.1, self.2)
        }
    }
    let job = Job {
        scene,
        opts,
        observer,
    };
    in_mode(scene.mode, Task(integrator, job, settings))
}

/// One camera sample's estimate by a per-sample `integrator` (`None` for the others), in the
/// scene's colour mode, as linear sRGB.
pub fn li(
    scene: &Scene,
    integrator: &Integrator,
    cray: &CameraRay,
    sampler: &mut Sampler,
) -> Option<Vec3> {
    struct Task<'a> {
        scene: &'a Scene,
        integrator: &'a Integrator,
        cray: &'a CameraRay,
        sampler: &'a mut Sampler,
    }
    impl InMode for Task<'_> {
        type Out = Option<Vec3>;
        fn run<M: PathMode + Send>(self) -> Option<Vec3> {
            self.integrator
                .li_in::<M>(self.scene, self.cray, self.sampler)
        }
    }
    let task = Task {
        scene,
        integrator,
        cray,
        sampler,
    };
    in_mode(scene.mode, task)
}
