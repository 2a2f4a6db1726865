//! Penumbra's renderer: everything that runs per ray.
//!
//! Data flow: `build` turns a `scene::SceneDesc` into a [`build::Scene`] (BVH, lights, textures,
//! camera, film), `render` runs the integrator over tiles and passes, the film accumulates.

pub mod accel;
pub mod bsdf;
pub mod compare;
pub mod film;
pub mod geometry;
pub mod image_io;
pub mod math;
pub mod sampling;
pub mod stats;
