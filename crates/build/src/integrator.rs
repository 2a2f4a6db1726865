//! Integrator factories: the scene's integrator description to the runtime integrator.

use render::integrators::bdpt::{BdptConfig, StrategyImages};
use render::integrators::mlt::MltConfig;
use render::integrators::path::guided::Guiding;
use render::integrators::path::{Combine, PathConfig};
use render::integrators::photon::{Lookup, PhotonConfig};
use render::integrators::ptracer::PtracerConfig;
use render::integrators::sppm::{Progressive, SppmConfig};
use render::integrators::volpath::VolPathConfig;
use render::integrators::{Aov, DirectConfig, Integrator, UnsupportedIntegrator};
use scene::{DirectionSampling, IntegratorDesc, MisHeuristic, NoriIntegrator, PathDesc};

/// The integrator a scene description asks for.
/// `scene_radius`: the bounding-sphere radius of the scene's geometry (relative lookup radii).
pub fn integrator(
    desc: &IntegratorDesc,
    scene_radius: f32,
) -> Result<Integrator, UnsupportedIntegrator> {
    Ok(match desc {
        IntegratorDesc::Normals => Integrator::Aov(Aov::Normals),
        IntegratorDesc::Albedo => Integrator::Aov(Aov::Albedo),
        IntegratorDesc::Depth => Integrator::Aov(Aov::Depth),
        IntegratorDesc::AmbientOcclusion { samples, length } => {
            Integrator::Aov(Aov::AmbientOcclusion {
                samples: (*samples).max(1),
                length: length.unwrap_or(f32::INFINITY),
            })
        }
        IntegratorDesc::Path(d) => Integrator::Path(path_config(d)),
        IntegratorDesc::VolPath {
            max_depth,
            rr_depth,
            hide_emitters,
            equiangular,
            transmittance,
            sample_emission,
        } => Integrator::VolPath(VolPathConfig {
            max_depth: if *max_depth < 0 {
                u32::MAX
            } else {
                *max_depth as u32
            },
            rr_depth: *rr_depth,
            hide_emitters: *hide_emitters,
            equiangular: *equiangular,
            transmittance: *transmittance,
            sample_emission: *sample_emission,
        }),
        IntegratorDesc::Direct {
            emitter_samples,
            bsdf_samples,
        } => Integrator::Direct(DirectConfig {
            emitter_samples: *emitter_samples,
            bsdf_samples: *bsdf_samples,
        }),
        IntegratorDesc::Sppm(d) => Integrator::Sppm(SppmConfig {
            max_depth: d.max_depth,
            rr_depth: d.rr_depth,
            photons: d.photons,
            initial_radius: d.initial_radius,
            alpha: d.alpha,
            kind: match d.fixed_eye_samples {
                None => Progressive::Stochastic,
                Some(eye_samples) => Progressive::Fixed { eye_samples },
            },
        }),
        IntegratorDesc::Mlt {
            max_depth,
            bootstrap,
            chains,
            large_step,
            sigma,
            direct_samples,
            multiplexed,
        } => Integrator::Mlt(MltConfig {
            direct_samples: *direct_samples,
            multiplexed: *multiplexed,
            max_depth: if *max_depth < 0 { 6 } else { *max_depth as u32 },
            bootstrap: *bootstrap,
            chains: *chains,
            large_step: *large_step,
            sigma: *sigma,
        }),
        IntegratorDesc::Bdpt {
            max_depth,
            visualize_strategies,
            visualize_weights,
        } => Integrator::Bdpt(BdptConfig {
            max_depth: *max_depth,
            min_edges: 0,
            strategy_images: match (visualize_strategies, visualize_weights) {
                (_, true) => Some(StrategyImages::Weighted),
                (true, false) => Some(StrategyImages::Unweighted),
                (false, false) => None,
            },
        }),
        IntegratorDesc::Ptracer {
            max_depth,
            hide_emitters,
        } => Integrator::Ptracer(PtracerConfig {
            max_depth: *max_depth,
            hide_emitters: *hide_emitters,
        }),
        IntegratorDesc::Photon(d) => {
            let lookup = |l: &scene::PhotonLookupDesc| {
                let r = l
                    .radius
                    .map(|r| if l.relative { r * scene_radius } else { r });
                match (l.k, r) {
                    (Some(k), None) if l.calibrated => Lookup::Calibrated { k },
                    (Some(k), r) => Lookup::Nearest {
                        k,
                        max_radius: r.unwrap_or(f32::INFINITY),
                    },
                    (None, Some(r)) => Lookup::Radius(r),
                    (None, None) => Lookup::Nearest {
                        k: 64,
                        max_radius: f32::INFINITY,
                    },
                }
            };
            Integrator::Photon(PhotonConfig {
                max_depth: d.max_depth,
                photons: d.photons,
                global: lookup(&d.global),
                caustic: lookup(&d.caustic),
                volume: lookup(&d.volume),
                kernel: d.kernel,
                final_gather: d.final_gather,
                direct_samples: d.direct_samples,
            })
        }
        IntegratorDesc::Whitted { max_depth } => Integrator::Path(PathConfig::whitted(*max_depth)),
        IntegratorDesc::NoriSimple => Integrator::Path(PathConfig::nori(2, Combine::EmitterOnly)),
        IntegratorDesc::Nori(n) => Integrator::Path(match n {
            NoriIntegrator::DirectEms => PathConfig::nori(2, Combine::EmitterOnly),
            NoriIntegrator::DirectMats => PathConfig::nori(2, Combine::BsdfOnly),
            NoriIntegrator::DirectMis => PathConfig::nori(2, Combine::Balance),
            NoriIntegrator::PathEms => PathConfig::nori(u32::MAX, Combine::EmitterOnly),
            NoriIntegrator::PathMats => PathConfig::nori(u32::MAX, Combine::BsdfOnly),
            NoriIntegrator::PathMis => PathConfig::nori(u32::MAX, Combine::Balance),
        }),
    })
}

/// The path tracer a scene description asks for.
pub fn path_config(d: &PathDesc) -> PathConfig {
    let combine = match (d.nee, d.mis) {
        (false, _) => Combine::BsdfOnly,
        (true, MisHeuristic::Power) => Combine::Power,
        (true, MisHeuristic::Balance) => Combine::Balance,
    };
    PathConfig {
        rr: d.rr,
        directions: d.directions,
        light_samples: d.light_samples.max(1),
        all_lights: d.all_lights,
        splitting: d.splitting.max(1),
        caustics: d.caustics,
        clamp: d.clamp,
        only_depth: d.only_depth,
        guiding: (d.guiding
            && d.directions == DirectionSampling::Bsdf
            && d.splitting <= 1
            && d.only_depth.is_none())
        .then(Guiding::default),
        ..PathConfig::mitsuba(d.max_depth, 0, d.hide_emitters, combine)
    }
}
