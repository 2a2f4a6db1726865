//! The transport layer: what every integrator's paths are made of, one copy each.
//!
//! - `walk.rs`: [`Walker`], a ray followed to its next event (medium collision, surface,
//!   `null` surface, escape) with media and index-matched boundaries;
//! - `shadow.rs`: the shadow query, the transmittance of a connection through media and
//!   `null` surfaces ([`transmittance`]);
//! - `nee.rs`: next-event estimation's parts — an emitter sample by the scene's light
//!   selection ([`sample_emitter`]) and what scatters at the vertex ([`Scatterer`]);
//! - `emission.rs`: emission found by a ray — an emitter hit, the environment on escape —
//!   and its MIS weight against emitter sampling from the vertex the ray left
//!   ([`Previous`]);
//! - `mis.rs`: the power and balance heuristics;
//! - `roulette.rs`: Russian roulette, on the throughput (with pbrt-v4's η² scale) or on a
//!   photon's change of power.
//!
//! `docs/architecture.md` has the table of which integrator uses which.

pub mod emission;
pub mod mis;
pub mod nee;
pub mod roulette;
pub mod shadow;
pub mod walk;

pub use emission::{Previous, emitter_density, emitter_hit, environment};
pub use mis::MisHeuristic;
pub use nee::{EmitterSample, Scatterer, sample_emitter, sample_towards};
pub use shadow::{Connection, From, transmittance};
pub use walk::{Ahead, Event, Pass, Walker};
