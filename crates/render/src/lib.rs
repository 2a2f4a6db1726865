//! Penumbra's renderer: everything that runs per ray.
//!
//! Data flow: the `penumbra-build` crate turns a scene description into a [`world::Scene`] (BVH, textures,
//! camera, film settings), `render` picks the colour mode and runs an integrator, whose loops
//! (`drive`) fill a film.

pub mod accel;
pub mod bsdf;

pub mod camera;
pub mod compare;
pub mod denoise;
pub mod display;
pub mod drive;
pub mod film;
pub mod geometry;
pub mod image_io;
pub mod integrators;
pub mod layers;
pub mod lights;
pub mod materials;
pub mod math;
pub mod media;

pub mod post;
pub mod render;
pub mod sampling;
pub mod session;
pub mod shapes;
pub mod spectral;
pub mod stats;
pub mod textures;
pub mod world;

pub use drive::adaptive;
