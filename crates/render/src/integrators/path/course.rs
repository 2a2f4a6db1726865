//! The course tracers, as configurations of the one path loop.
//!
//! Every course's integrator is a [`PathConfig`]; the loop (`vertex.rs`) knows no courses,
//! only the switches. Each tracer changes a few fields of Mitsuba's `path`
//! ([`PathConfig::mitsuba`]):
//!
//! - Whitted (COMP30019 without `-l`/`-c`, CENG795 without a path renderer, Nori's
//!   `whitted`): [`PathConfig::whitted`] — every emitter sampled (`all_lights`), emitter
//!   sampling only (`EmitterOnly`), the scene's ambient term, only delta chains followed
//!   (`continue_diffuse: false`), no Russian roulette.
//! - Nori's `path_ems`, `path_mats`, `path_mis`, `direct_*` and `simple`: [`PathConfig::nori`] — emitter
//!   sampling only, BSDF sampling only, or the balance heuristic; roulette from the third
//!   segment; `direct_*` and `simple` stop after 2 segments.
//! - CS184's `pathtracer` (the COLLADA loader's `cs184_path`): every emitter sampled `-l`
//!   times, roulette with a fixed probability, `-H` uniform hemisphere directions without
//!   next-event estimation, `-o 0` only the last bounce (`only_depth`).
//! - COMP30019 `-l`/`-c` (the `comp30019` command): caustic paths dropped unless `-c`.
//! - CENG795's path renderers (its loader): brute force with uniform hemisphere directions
//!   unless `RendererParams` ask otherwise, splitting at the first vertex, sample clamping.
//! - CS-E5520 (the OBJ/MTL loader): roulette with a fixed probability.
//!
//! The last four come as a `PathDesc` of the scene model, turned into a `PathConfig` by the
//! build crate (`build::integrator::path_config`).
//!
//! The strategies these switches select live with their purpose: several emitter samples or
//! every emitter in `nee.rs`, uniform directions and fixed-probability roulette in
//! `scatter.rs`, splitting and the ambient term in `vertex.rs`, clamping in
//! [`Integrator::li_stream`](crate::integrators::Integrator::li_stream). Every combination
//! converges to the same image except `caustics: false`, `clamp` and `only_depth`, which
//! change the mean on purpose (`tests/it/path_variants.rs`).

use base::{DirectionSampling, RussianRoulette};

use super::{Combine, PathConfig};

impl PathConfig {
    /// A Whitted-style ray tracer: every emitter sampled at the first non-delta vertex (plus
    /// the scene's ambient term), delta chains followed up to `max_depth` segments.
    pub fn whitted(max_depth: u32) -> Self {
        PathConfig {
            max_depth,
            rr: RussianRoulette::Off,
            hide_emitters: false,
            combine: Combine::EmitterOnly,
            continue_diffuse: false,
            directions: DirectionSampling::Bsdf,
            light_samples: 1,
            all_lights: true,
            splitting: 1,
            caustics: true,
            clamp: None,
            only_depth: None,
            media_absorption: false,
            guiding: None,
        }
    }

    /// Nori's unbiased estimators: Russian roulette from the third bounce, no depth limit
    /// unless `max_depth` (direct lighting: 2 segments).
    pub fn nori(max_depth: u32, combine: Combine) -> Self {
        PathConfig {
            max_depth,
            ..PathConfig::mitsuba(-1, 3, false, combine)
        }
    }
}
