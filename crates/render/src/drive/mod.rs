//! The loops that drive a render, one place for all of them: what runs when, in which order,
//! and when it stops (sample counts, time budgets, cancellation, progress). The integrators
//! say what a sample, a pass or a chain computes; these say how many run and how their
//! results merge (always in a fixed order, so that an image never depends on the thread
//! count).
//!
//! - `tiles.rs`: [`render_tiles`], the progressive loop of per-sample estimators
//!   ([`Estimator`]): passes of whole samples per pixel over tiles in parallel, sized to
//!   about a second each, stopping at the sample count, a time budget or Ctrl-C;
//! - `passes.rs`: [`run_passes`], the pass loop of the integrators that render a whole pass
//!   themselves (SPPM's iterations, light tracing, BDPT), and [`rows`], one pass over the
//!   film's rows with their tiles and splats merged in row order;
//! - `adaptive.rs`: CS184's adaptive sampling, rounds of batches over the pixels that have
//!   not converged (a per-sample estimator);
//! - `chains.rs`: [`run_chains`], Markov chains (MLT) in blocks merged in chain order;
//! - `work.rs`: work items, the fixed units shards, passes and resumed renders split a
//!   render into ([`Resume`], the pass loop over items).

pub mod adaptive;
mod chains;
mod passes;
mod tiles;
pub mod work;

pub use chains::run_chains;
pub use passes::{rows, run_passes};
pub use tiles::{CHUNK_SPP, Phased, TileWork, render_tiles, render_tiles_phased};
pub use work::Resume;

use crate::camera::CameraRay;
use crate::math::Vec3;
use crate::sampling::Sampler;
use crate::spectral::lanes::PathMode;
use crate::world::Scene;

/// An integrator that estimates each camera sample on its own, its paths in the colour mode
/// `M`: what the tile loop and adaptive sampling drive.
pub trait Estimator<M: PathMode>: Sync {
    /// The radiance along one camera ray as linear sRGB (the mode, if it draws anything,
    /// set up from `sampler` after the camera's dimensions).
    fn li(&self, scene: &Scene, cray: &CameraRay, sampler: &mut Sampler) -> Vec3;

    /// Estimates for a stream of camera samples: `next` sets the sampler up for the next
    /// sample and returns its tag and camera ray (`None`: no more); `done` receives each
    /// estimate with its tag, not necessarily in order. One at a time with [`Self::li`]
    /// unless an estimator keeps several paths in flight.
    fn li_stream<T>(
        &self,
        scene: &Scene,
        template: &Sampler,
        next: impl FnMut(&mut Sampler) -> Option<(T, CameraRay)>,
        done: impl FnMut(T, Vec3),
    ) {
        one_at_a_time::<M, Self, T>(self, scene, template, next, done)
    }
}

/// [`Estimator::li_stream`] one sample at a time, by [`Estimator::li`].
pub fn one_at_a_time<M: PathMode, E: Estimator<M> + ?Sized, T>(
    e: &E,
    scene: &Scene,
    template: &Sampler,
    mut next: impl FnMut(&mut Sampler) -> Option<(T, CameraRay)>,
    mut done: impl FnMut(T, Vec3),
) {
    let mut sampler = template.clone();
    while let Some((tag, cray)) = next(&mut sampler) {
        done(tag, e.li(scene, &cray, &mut sampler));
    }
}
