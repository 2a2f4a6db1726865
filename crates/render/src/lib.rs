//! Penumbra's renderer: everything that runs per ray.
//!
//! Data flow: `build` turns a `scene::SceneDesc` into a [`world::Scene`] (BVH, textures,
//! camera, film settings), `render` runs an integrator over tiles and passes into a film.

pub mod accel;
pub mod adaptive;
pub mod bsdf;
pub mod build;
pub mod camera;
pub mod compare;
pub mod film;
pub mod geometry;
pub mod image_io;
pub mod integrators;
pub mod layers;
pub mod lights;
pub mod materials;
pub mod math;
pub mod nori_tests;
pub mod post;
pub mod render;
pub mod sampling;
pub mod shapes;
pub mod stats;
pub mod textures;
pub mod world;
